#include "soadyn/io/h5log.hpp"

#include "soadyn/multibody/data.hpp"
#include "soadyn/sim/limits.hpp"
#include "soadyn/multibody/text.hpp"

#include "h5_util.hpp"
#include "log_layout.hpp"

#include <hdf5.h>

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <sstream>

namespace soadyn {

using h5::attribute;
using h5::check;
using h5::Id;
using h5::Scalar;
using H5Failure = h5::Failure;

namespace {

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

// the conventions a reader needs to make sense of q and v
const char* kFreeJoint =
    "q = [x y z qw qx qy qz]: the body frame's origin in inertial coordinates (m) and the unit quaternion of its "
    "attitude, body to inertial, w first; v = qd = [wx wy wz vx vy vz] = [omega; eta_dot]: the body's angular "
    "velocity and the velocity of its frame's origin, both in inertial coordinates (qd is v, not the derivative of q)";
const char* kBallJoint =
    "q = [qw qx qy qz]: the unit quaternion of the child's frame relative to the joint frame (child to joint "
    "frame), w first; v = qd = [wx wy wz]: the child's angular velocity relative to the parent, in the child's frame";
const char* kHelicalJoint =
    "q = [theta]: a screw: the child turns by theta about the axis and slides pitch * theta along it "
    "(joint_pitches, m/rad; 0 for the other joint types); v = its rate";
const char* kPlanarJoint =
    "q = [x y theta]: translation along e1 and e2 spanning the plane normal to the axis n, then rotation theta "
    "about n (e1: the coordinate axis least aligned with n, made orthogonal to it; e2 = n x e1); v = their rates";
const char* kUnits = "SI: s, m, kg, rad, J; quaternion components are dimensionless (1)";
const char* kModelFiles =
    "the MJCF model's files as MuJoCo's compiler was handed them at run time (the main text, its includes, "
    "mesh, skin, height-field and texture files): dataset k (0 .. count-1) holds one file's bytes, its "
    "attribute name the name given to MuJoCo's virtual file system; soadyn view compiles the model from these alone";
const char* kBodies =
    "N bodies, those of the model after fixed joints are merged (a body welded by a fixed joint moves with the one "
    "it is welded to); position: each body frame's origin (its joint point), orientation: the unit quaternion "
    "[w x y z] of its attitude, body to inertial, with w >= 0, com: its centre of mass (merged bodies included); "
    "all in inertial coordinates";

const char* kFrames =
    "F named frames (a scenario's log: frames:), each fixed on a body: a body's own frame, a link merged by a fixed "
    "joint or a scenario's frames: entry; position: the frame's origin, orientation: the unit quaternion [w x y z] "
    "of its attitude, frame to inertial, with w >= 0; all in inertial coordinates";

const char* kSensitivities =
    "forward sensitivities by CVODES under its error control: initial_state[t, i, j] = dx_i(t)/dx0_j, "
    "parameters[t, i, j] = dx_i(t)/dpi_j, with x = [q along the tangent; v] (2 nv numbers, state_names): the "
    "tangent increment of q is the coordinate's own on revolute, prismatic and planar joints, [dtheta; dp] on a free "
    "joint (attitude turned about inertial axes, exp(dtheta) * Q, origin moved by dp) and dtheta in the child's axes "
    "on a ball joint (Q * exp(dtheta)); pi the 10 inertial parameters of each body named (parameter_names: m, m c, "
    "and the inertia about the body frame's origin in the body's axes, ordered Ixx Ixy Iyy Ixz Iyz Izz)";

// "rad", or one unit per column when they differ
void units_attribute(hid_t obj, const std::vector<std::string>& units) {
  if (std::all_of(units.begin(), units.end(), [&](const std::string& u) { return u == units.front(); }))
    attribute(obj, "units", units.front());
  else
    attribute(obj, "units", units);
}

}  // namespace

LogGroups LogGroups::parse(const std::string& text) {
  LogGroups g{false, false, false, false, {}};
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item == "state") g.state = true;
    else if (item == "energy") g.energy = true;
    else if (item == "momentum") g.momentum = true;
    else if (item == "bodies") g.bodies = true;
    else if (item == "all") g = LogGroups{};
    else
      throw Error("--log: expected a comma-separated list of state, energy, momentum, bodies (or all); got '" + item +
                  "' in '" + text + "'");
  }
  if (text.empty() || text.back() == ',') throw Error("--log: expected a comma-separated list of groups, got '" + text + "'");
  return g;
}

std::string LogGroups::str() const {
  std::string out;
  for (const auto& [on, name] : {std::pair{state, "state"}, {energy, "energy"}, {momentum, "momentum"}, {bodies, "bodies"}})
    if (on) out += (out.empty() ? "" : ",") + std::string(name);
  return out;
}

std::uint64_t row_bytes(const Model& model, const LogGroups& groups) {
  return std::uint64_t(log::layout(model, groups).columns.size()) * sizeof(double);
}

LogGroups logged_groups(const Scenario& sc, const SimulationSettings& settings, const LogGroups& groups) {
  LogGroups g = groups;
  g.impacts = settings.limits && sc.model.has_limits();
  g.control = groups.control || !sc.inputs.controllers.empty();
  if (settings.sensitivities.any())
    g.sensitivities = std::make_shared<const SensitivityPlan>(plan_sensitivities(sc.model, settings.sensitivities));
  for (const std::string& name : sc.log_frames)
    if (const int f = sc.model.frame_index(name); f >= 0 && std::find(g.frames.begin(), g.frames.end(), f) == g.frames.end())
      g.frames.push_back(f);
  return g;
}

struct H5Log::Impl {
  std::string path, tmp_path;
  bool published = false, closed = false, broken = false;
  Id file, samples, events;
  std::vector<double> event_rows;  // events not yet written, 7 numbers each
  hsize_t event_count = 0;
  int width = 0;
  hsize_t rows = 0;            // rows in the file
  std::vector<double> buffer;  // rows not yet written
  double t_last = 0.0, t_flushed = -1.0;
  LogGroups groups;
  std::unique_ptr<Model> model;  // for the frames' poses (groups.frames)
  std::unique_ptr<Data> data;
  Scalar status, quaternion, t_reached, cpu, steps, rhs, jac, etf, nli, max_balance, final_balance, ticks, stiffness,
      stiffness_hint;
  std::vector<Scalar*> scalars() {
    return {&status, &quaternion, &t_reached, &cpu, &steps, &rhs, &jac, &etf, &nli, &max_balance, &final_balance, &ticks,
            &stiffness, &stiffness_hint};
  }
  std::chrono::steady_clock::time_point last_flush;
  std::chrono::duration<double> flush_interval{0.5};
  long flushes = 0;
  double flush_seconds = 0.0;

  // after a failed write: give every id up unclosed, so nothing writes to the file again
  void abandon() {
    broken = true;
    for (Scalar* s : scalars()) s->release();
    samples.release();
    events.release();
    file.release();
  }
  [[noreturn]] void io_error(const H5Failure& e) {
    abandon();
    std::string msg = (e.cause.empty() ? std::string(e.what()) : e.cause) + " while writing " + path + " at t = " +
                      number(t_last) + " s";
    if (published)
      msg += t_flushed >= 0 ? " (rows up to t = " + number(t_flushed) + " s are kept)" : " (no rows are kept)";
    else
      msg += " (the output was not written; an existing file there is unchanged)";
    if (!published) std::remove(tmp_path.c_str());
    throw IoError(msg);
  }
};

namespace {

// a view of /samples' columns (log_layout.hpp): rank 1, 2, or 3 (T × bodies × cols)
void create_view(hid_t file, const log::View& v, int width) {
  const hsize_t c = hsize_t(std::max(1, v.cols)), nb = hsize_t(v.bodies), n = v.bodies > 0 ? nb * c : c;
  const int rank = v.bodies > 0 ? 3 : v.cols > 0 ? 2 : 1;
  hsize_t dims[3] = {0, v.bodies > 0 ? nb : c, c}, maxdims[3] = {H5S_UNLIMITED, dims[1], c};
  Id vspace(H5Screate_simple(rank, dims, maxdims), H5Sclose, "H5Screate_simple");
  // one block per row: the row's n numbers, in row-major order
  hsize_t start[3] = {0, 0, 0}, stride[3] = {1, 1, 1}, count[3] = {H5S_UNLIMITED, 1, 1}, block[3] = {1, dims[1], c};
  check(H5Sselect_hyperslab(vspace, H5S_SELECT_SET, start, stride, count, block), "selecting a view");
  hsize_t sdims[2] = {0, hsize_t(width)}, smax[2] = {H5S_UNLIMITED, hsize_t(width)};
  Id sspace(H5Screate_simple(2, sdims, smax), H5Sclose, "H5Screate_simple");
  hsize_t sstart[2] = {0, hsize_t(v.first)}, sblock[2] = {1, n};
  check(H5Sselect_hyperslab(sspace, H5S_SELECT_SET, sstart, stride, count, sblock), "selecting a view's source");
  Id props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "H5Pcreate");
  check(H5Pset_virtual(props, vspace, ".", "/samples", sspace), "mapping view " + v.path);
  Id d(H5Dcreate2(file, v.path.c_str(), H5T_NATIVE_DOUBLE, vspace, H5P_DEFAULT, props, H5P_DEFAULT), H5Dclose,
       "creating view " + v.path);
  units_attribute(d, v.units);
}

}  // namespace

H5Log::H5Log(const std::string& path, const Scenario& sc, const SimulationSettings& settings, const std::string& version,
             const LogGroups& groups)
    : impl_(std::make_unique<Impl>()) {
  H5dont_atexit();  // no flush at exit of a file a failed write left behind
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // our messages, not HDF5's stack dumps
  Impl& im = *impl_;
  im.path = path;
  im.tmp_path = temporary_path(path);
  im.groups = logged_groups(sc, settings, groups);
  const Model& m = sc.model;
  im.model = std::make_unique<Model>(m);
  im.data = std::make_unique<Data>(m);
  const log::Layout lay = log::layout(m, im.groups);
  im.width = int(lay.columns.size());
  try {
    Id fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "H5Pcreate");
    check(H5Pset_libver_bounds(fapl, H5F_LIBVER_LATEST, H5F_LIBVER_LATEST), "H5Pset_libver_bounds");
    // a new file, never an existing one's target: a name left there (a killed run's file, or a
    // symlink) is removed, not followed, and H5F_ACC_EXCL (O_CREAT | O_EXCL) opens no symlink
    ::unlink(im.tmp_path.c_str());
    const hid_t f = H5Fcreate(im.tmp_path.c_str(), H5F_ACC_EXCL, H5P_DEFAULT, fapl);
    if (f < 0) {
      h5::record_cause();
      const std::string& cause = h5::last_cause;
      if (h5::last_errno == ENOSPC || h5::last_errno == EDQUOT || h5::last_errno == EIO || h5::last_errno == EFBIG) {
        std::remove(im.tmp_path.c_str());
        throw IoError(cause + " while creating " + path + " (the output was not written; an existing file there is unchanged)");
      }
      throw Error(path + ": cannot create the output file " + im.tmp_path + (cause.empty() ? std::string() : " (" + cause + ")") +
                  "; is the directory writable?");
    }
    im.file = Id(f, H5Fclose, "H5Fcreate");
    attribute(im.file, "soadyn_version", version);
    attribute(im.file, "scenario_path", sc.path);
    attribute(im.file, "layout_version", long(kLayoutVersion));
    attribute(im.file, "log_groups", groups.str());
    h5::text_dataset(im.file, "scenario", sc.text);
    if (!sc.robot_text.empty()) {
      // the robot file the scenario named, so the run can be shown without it (soadyn view)
      Id d = h5::text_dataset(im.file, "robot", sc.robot_text);
      attribute(d, "path", sc.robot_path);
    }
    if (!sc.model_files.empty()) {
      // every file MuJoCo's compiler was handed for an MJCF model, as handed: soadyn view compiles
      // the run's model from these alone, never from the files on disk (which may have changed)
      Id g = h5::group(im.file, "model_files");
      attribute(g, "count", long(sc.model_files.size()));
      attribute(g, "description", std::string(kModelFiles));
      for (size_t k = 0; k < sc.model_files.size(); ++k) {
        Id d = h5::byte_dataset(g, std::to_string(k).c_str(), sc.model_files[k].data);
        attribute(d, "name", sc.model_files[k].name);
      }
    }

    {
      // the model: names and units of every column of q and v, the joints, the tree, the conventions
      Id g = h5::group(im.file, "model");
      attribute(g, "nq", long(m.nq));
      attribute(g, "nv", long(m.nv));
      attribute(g, "q_names", m.q_names());
      attribute(g, "v_names", m.v_names());
      attribute(g, "q_units", log::q_units(m));
      attribute(g, "v_units", log::v_units(m));
      std::vector<std::string> types;
      for (JointType t : m.joint_type) types.emplace_back(to_string(t));
      attribute(g, "joint_names", m.joint_names);
      attribute(g, "joint_types", types);
      attribute(g, "body_names", m.body_names);
      attribute(g, "gravity", std::vector<double>(m.gravity.data(), m.gravity.data() + 3));
      attribute(g, "gravity_units", std::string("m/s^2"));
      attribute(g, "units", std::string(kUnits));
      attribute(g, "free_joint", std::string(kFreeJoint));
      attribute(g, "ball_joint", std::string(kBallJoint));
      attribute(g, "planar_joint", std::string(kPlanarJoint));
      attribute(g, "helical_joint", std::string(kHelicalJoint));
      attribute(g, "joint_pitches", m.pitch);
      h5::int_dataset(g, "parents", std::vector<int>(m.parent.begin(), m.parent.end()), "1");
      h5::int_dataset(g, "joint_q_index", std::vector<int>(m.idx_q.begin(), m.idx_q.end()), "1");
      h5::int_dataset(g, "joint_v_index", std::vector<int>(m.idx_v.begin(), m.idx_v.end()), "1");
    }

    Id g_solver = h5::group(im.file, "solver");
    // every setting of the table (settings.hpp) under its own name: numbers as doubles, words as
    // strings, flags as "true"/"false"; output_dt as the interval the rows really have
    for (const SettingInfo& info : setting_table()) {
      const std::string name(info.name);
      if (name == "output_dt") attribute(g_solver, "output_dt", output_interval(settings));
      else if (info.kind == SettingKind::Real || info.kind == SettingKind::Count)
        attribute(g_solver, name.c_str(), setting_number(settings, info));
      else attribute(g_solver, name.c_str(), setting_text(settings, info));
    }
    im.status = h5::string_scalar(g_solver, "status", 1024);
    im.quaternion = h5::string_scalar(g_solver, "quaternion_handling", 256);
    im.t_reached = Scalar(g_solver, "t_reached", H5T_NATIVE_DOUBLE);
    im.cpu = Scalar(g_solver, "cpu_seconds", H5T_NATIVE_DOUBLE);
    im.steps = Scalar(g_solver, "steps", H5T_NATIVE_LONG);
    im.rhs = Scalar(g_solver, "rhs_evals", H5T_NATIVE_LONG);
    im.jac = Scalar(g_solver, "jac_evals", H5T_NATIVE_LONG);
    im.etf = Scalar(g_solver, "error_test_failures", H5T_NATIVE_LONG);
    im.nli = Scalar(g_solver, "nonlinear_iterations", H5T_NATIVE_LONG);
    im.max_balance = Scalar(g_solver, "max_energy_balance_error", H5T_NATIVE_DOUBLE);
    im.final_balance = Scalar(g_solver, "final_energy_balance_error", H5T_NATIVE_DOUBLE);
    im.ticks = Scalar(g_solver, "control_ticks", H5T_NATIVE_LONG);
    // RunSummary::stiffness_index and stiffness_hint (simulate.hpp)
    im.stiffness = Scalar(g_solver, "stiffness_index", H5T_NATIVE_DOUBLE);
    im.stiffness_hint = h5::string_scalar(g_solver, "stiffness_hint", 1024);
    for (Scalar* s : {&im.t_reached, &im.cpu}) attribute(s->dset, "units", std::string("s"));
    for (Scalar* s : {&im.steps, &im.rhs, &im.jac, &im.etf, &im.nli, &im.max_balance, &im.final_balance, &im.ticks,
                      &im.stiffness})
      attribute(s->dset, "units", std::string("1"));
    im.status.write(std::string("running"));
    im.quaternion.write(std::string());
    im.stiffness_hint.write(std::string());
    for (Scalar* s : {&im.t_reached, &im.cpu, &im.max_balance, &im.final_balance, &im.stiffness}) s->write(0.0);
    for (Scalar* s : {&im.steps, &im.rhs, &im.jac, &im.etf, &im.nli, &im.ticks}) s->write(0L);

    {
      // the table every series is a view of: chunks of about 64 KiB
      const hsize_t w = hsize_t(im.width);
      hsize_t dims[2] = {0, w}, maxdims[2] = {H5S_UNLIMITED, w}, chunk[2] = {std::max<hsize_t>(1, 8192 / w), w};
      Id space(H5Screate_simple(2, dims, maxdims), H5Sclose, "H5Screate_simple");
      Id props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "H5Pcreate");
      check(H5Pset_chunk(props, 2, chunk), "H5Pset_chunk");
      im.samples = Id(H5Dcreate2(im.file, "samples", H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, props, H5P_DEFAULT), H5Dclose,
                      "creating /samples");
      std::vector<std::string> names, units;
      for (const log::Column& c : lay.columns) names.push_back(c.name), units.push_back(c.unit);
      attribute(im.samples, "column_names", names);
      attribute(im.samples, "column_units", units);
    }
    if (im.groups.impacts) {
      // the joint limits' events, 7 numbers a row, appended at each flush
      hsize_t dims[2] = {0, 7}, maxdims[2] = {H5S_UNLIMITED, 7}, chunk[2] = {64, 7};
      Id space(H5Screate_simple(2, dims, maxdims), H5Sclose, "H5Screate_simple");
      Id props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "H5Pcreate");
      check(H5Pset_chunk(props, 2, chunk), "H5Pset_chunk");
      im.events = Id(H5Dcreate2(im.file, "events", H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, props, H5P_DEFAULT), H5Dclose,
                     "creating /events");
      attribute(im.events, "column_names",
                std::vector<std::string>{"t", "dof", "side", "kind", "v_before", "v_after", "energy_lost"});
      attribute(im.events, "description",
                std::string("joint-limit events: t (s), dof (index into v, /model v_names), side (-1 lower, +1 upper), "
                            "kind (0 impact, 1 hold: an impact that stopped it at the limit, 2 release), v_before and "
                            "v_after (the DOF's speed, rad/s or m/s), energy_lost (J, kinetic energy the impact took)"));
    }
    for (const std::string& g : lay.groups) h5::group(im.file, g.c_str() + 1);
    if (groups.bodies) {
      Id g(H5Gopen2(im.file, "bodies", H5P_DEFAULT), H5Gclose, "opening /bodies");
      attribute(g, "description", std::string(kBodies));
      h5::string_dataset(g, "names", m.body_names);
    }
    if (!im.groups.frames.empty()) {
      Id g(H5Gopen2(im.file, "frames", H5P_DEFAULT), H5Gclose, "opening /frames");
      attribute(g, "description", std::string(kFrames));
      std::vector<std::string> names;
      for (const int f : im.groups.frames) names.push_back(m.frame_names[size_t(f)]);
      h5::string_dataset(g, "names", names);
    }
    if (const SensitivityPlan* p = im.groups.sensitivities.get()) {
      Id g(H5Gopen2(im.file, "sensitivities", H5P_DEFAULT), H5Gclose, "opening /sensitivities");
      attribute(g, "description", std::string(kSensitivities));
      attribute(g, "state_names", p->state_names);
      attribute(g, "state_units", p->state_units);
      if (p->np() > 0) {
        attribute(g, "parameter_names", p->parameter_names);
        attribute(g, "parameter_units", p->parameter_units);
      }
    }
    for (const log::View& v : lay.views) create_view(im.file, v, im.width);
    check(H5Fstart_swmr_write(im.file), "H5Fstart_swmr_write");  // writes everything so far
  } catch (const H5Failure& e) {
    im.io_error(e);
  } catch (...) {
    im.abandon();
    std::remove(im.tmp_path.c_str());
    throw;
  }
  im.last_flush = std::chrono::steady_clock::now();
}

H5Log::~H5Log() {
  Impl& im = *impl_;
  if (im.closed || im.broken) return;
  if (!im.published) {  // never reached its first flush: nothing to keep
    im.abandon();
    std::remove(im.tmp_path.c_str());
    return;
  }
  try {
    flush();
  } catch (...) {
  }
}

void H5Log::on_sample(const Sample& s) {
  log::append_row(*impl_->model, *impl_->data, impl_->groups, s, impl_->buffer);
  impl_->t_last = s.t;
}

void H5Log::on_event(const LimitEvent& e) {
  impl_->event_rows.insert(impl_->event_rows.end(), {e.t, double(e.dof), double(e.side), double(limit_event_code(e.kind)),
                                                     e.v_before, e.v_after, e.energy_lost});
}

void H5Log::flush(const RunSummary* summary) {
  Impl& im = *impl_;
  if (im.broken || im.closed) return;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    const hsize_t w = hsize_t(im.width), n = im.buffer.size() / w;
    if (n > 0) {
      hsize_t size[2] = {im.rows + n, w};
      check(H5Dset_extent(im.samples, size), "extending /samples");
      Id file_space(H5Dget_space(im.samples), H5Sclose, "H5Dget_space");
      hsize_t start[2] = {im.rows, 0}, count[2] = {n, w};
      check(H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start, nullptr, count, nullptr), "H5Sselect_hyperslab");
      Id mem_space(H5Screate_simple(2, count, nullptr), H5Sclose, "H5Screate_simple");
      check(H5Dwrite(im.samples, H5T_NATIVE_DOUBLE, mem_space, file_space, H5P_DEFAULT, im.buffer.data()), "writing /samples");
      check(H5Dflush(im.samples), "H5Dflush");  // the rows, then the extent that shows them
    }
    if (const hsize_t ne = im.event_rows.size() / 7; ne > 0 && hid_t(im.events) >= 0) {
      hsize_t size[2] = {im.event_count + ne, 7};
      check(H5Dset_extent(im.events, size), "extending /events");
      Id file_space(H5Dget_space(im.events), H5Sclose, "H5Dget_space");
      hsize_t start[2] = {im.event_count, 0}, count[2] = {ne, 7};
      check(H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start, nullptr, count, nullptr), "H5Sselect_hyperslab");
      Id mem_space(H5Screate_simple(2, count, nullptr), H5Sclose, "H5Screate_simple");
      check(H5Dwrite(im.events, H5T_NATIVE_DOUBLE, mem_space, file_space, H5P_DEFAULT, im.event_rows.data()),
            "writing /events");
      check(H5Dflush(im.events), "H5Dflush");
      im.event_count += ne;
      im.event_rows.clear();
    }
    if (summary) {
      im.status.write(summary->status);
      im.quaternion.write(summary->quaternion_handling);
      im.t_reached.write(summary->t_reached);
      im.cpu.write(summary->cpu_seconds);
      im.steps.write(summary->stats.steps);
      im.rhs.write(summary->stats.rhs_evals);
      im.jac.write(summary->stats.jac_evals);
      im.etf.write(summary->stats.error_test_failures);
      im.nli.write(summary->stats.nonlinear_iterations);
      im.max_balance.write(summary->max_energy_balance_error);
      im.final_balance.write(summary->final_energy_balance_error);
      im.ticks.write(summary->control_ticks);
      im.stiffness.write(summary->stiffness_index);
      im.stiffness_hint.write(summary->stiffness_hint);
    }
    check(H5Fflush(im.file, H5F_SCOPE_LOCAL), "H5Fflush");
    im.rows += n;
    if (n > 0) im.t_flushed = im.buffer[(n - 1) * w];
    im.buffer.clear();
  } catch (const H5Failure& e) {
    im.io_error(e);
  }
  if (!im.published) {  // the file is whole: put it in place of whatever was there
    if (std::rename(im.tmp_path.c_str(), im.path.c_str()) != 0) {
      const int err = errno;
      im.abandon();
      std::remove(im.tmp_path.c_str());
      throw IoError(std::string(std::strerror(err)) + " while renaming " + im.tmp_path + " to " + im.path);
    }
    im.published = true;
  }
  im.last_flush = std::chrono::steady_clock::now();
  ++im.flushes;
  im.flush_seconds += std::chrono::duration<double>(im.last_flush - t0).count();
}

void H5Log::on_progress(const RunSummary& summary) {
  if (!impl_->published || std::chrono::steady_clock::now() - impl_->last_flush >= impl_->flush_interval)
    flush(&summary);
}

void H5Log::on_finish(const RunSummary& summary) {
  Impl& im = *impl_;
  if (!im.published && summary.status.rfind("interrupted", 0) == 0 && im.buffer.size() <= size_t(im.width)) {
    // interrupted before its first step: an existing file stays as it was
    im.abandon();
    std::remove(im.tmp_path.c_str());
    im.closed = true;
    return;
  }
  flush(&summary);
  if (im.broken) return;
  for (Scalar* s : im.scalars()) s->reset();
  im.samples.reset();
  im.events.reset();
  // closing ends SWMR writing: the file then opens without the SWMR-read flag
  if (H5Fclose(im.file) < 0) {
    h5::record_cause();
    im.file.release();
    im.abandon();
    throw IoError((h5::last_cause.empty() ? std::string("an HDF5 error") : h5::last_cause) + " while closing " + im.path +
                  " (rows up to t = " + number(im.t_flushed) + " s are kept)");
  }
  im.file.release();
  im.closed = true;
}

std::string H5Log::temporary_path(const std::string& path) { return soadyn::temporary_path(path); }

void H5Log::set_flush_interval(double seconds) { impl_->flush_interval = std::chrono::duration<double>(seconds); }

const std::string& H5Log::current_path() const { return impl_->published ? impl_->path : impl_->tmp_path; }
bool H5Log::published() const { return impl_->published; }
long H5Log::flushes() const { return impl_->flushes; }
double H5Log::flush_seconds() const { return impl_->flush_seconds; }

}  // namespace soadyn
