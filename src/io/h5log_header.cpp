// What a run file holds from its creation on (h5log_header.hpp): the sources, /model, the tables,
// the groups' conventions and the views, as H5Log's constructor writes them (h5log.cpp).
#include "h5log_header.hpp"

#include "soadyn/multibody/joint.hpp"

#include <algorithm>
#include <vector>

namespace soadyn::log {

using h5::attribute;
using h5::check;
using h5::Id;

namespace {

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

// a view of /samples' columns (log_layout.hpp): rank 1, 2, or 3 (T × bodies × cols)
void create_view(hid_t file, const View& v, int width) {
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

void write_sources(hid_t file, const Scenario& sc, const std::string& version, const LogGroups& groups) {
  attribute(file, "soadyn_version", version);
  attribute(file, "scenario_path", sc.path);
  attribute(file, "layout_version", long(kLayoutVersion));
  attribute(file, "log_groups", groups.str());
  h5::text_dataset(file, "scenario", sc.text);
  if (!sc.robot_text.empty()) {
    // the robot file the scenario named, so the run can be shown without it (soadyn view)
    Id d = h5::text_dataset(file, "robot", sc.robot_text);
    attribute(d, "path", sc.robot_path);
  }
  if (!sc.model_files.empty()) {
    // every file MuJoCo's compiler was handed for an MJCF model, as handed: soadyn view compiles
    // the run's model from these alone, never from the files on disk (which may have changed)
    Id g = h5::group(file, "model_files");
    attribute(g, "count", long(sc.model_files.size()));
    attribute(g, "description", std::string(kModelFiles));
    for (size_t k = 0; k < sc.model_files.size(); ++k) {
      Id d = h5::byte_dataset(g, std::to_string(k).c_str(), sc.model_files[k].data);
      attribute(d, "name", sc.model_files[k].name);
    }
  }
}

void write_model(hid_t file, const Model& m) {
  Id g = h5::group(file, "model");
  attribute(g, "nq", long(m.nq));
  attribute(g, "nv", long(m.nv));
  attribute(g, "q_names", m.q_names());
  attribute(g, "v_names", m.v_names());
  attribute(g, "q_units", q_units(m));
  attribute(g, "v_units", v_units(m));
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

Id create_samples(hid_t file, const Layout& lay) {
  const hsize_t w = hsize_t(lay.columns.size());
  hsize_t dims[2] = {0, w}, maxdims[2] = {H5S_UNLIMITED, w}, chunk[2] = {std::max<hsize_t>(1, 8192 / w), w};
  Id space(H5Screate_simple(2, dims, maxdims), H5Sclose, "H5Screate_simple");
  Id props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "H5Pcreate");
  check(H5Pset_chunk(props, 2, chunk), "H5Pset_chunk");
  Id samples(H5Dcreate2(file, "samples", H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, props, H5P_DEFAULT), H5Dclose,
             "creating /samples");
  std::vector<std::string> names, units;
  for (const Column& c : lay.columns) names.push_back(c.name), units.push_back(c.unit);
  attribute(samples, "column_names", names);
  attribute(samples, "column_units", units);
  return samples;
}

Id create_events(hid_t file) {
  hsize_t dims[2] = {0, 7}, maxdims[2] = {H5S_UNLIMITED, 7}, chunk[2] = {64, 7};
  Id space(H5Screate_simple(2, dims, maxdims), H5Sclose, "H5Screate_simple");
  Id props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "H5Pcreate");
  check(H5Pset_chunk(props, 2, chunk), "H5Pset_chunk");
  Id events(H5Dcreate2(file, "events", H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, props, H5P_DEFAULT), H5Dclose,
            "creating /events");
  attribute(events, "column_names",
            std::vector<std::string>{"t", "dof", "side", "kind", "v_before", "v_after", "energy_lost"});
  attribute(events, "description",
            std::string("joint-limit events: t (s), dof (index into v, /model v_names), side (-1 lower, +1 upper), "
                        "kind (0 impact, 1 hold: an impact that stopped it at the limit, 2 release), v_before and "
                        "v_after (the DOF's speed, rad/s or m/s), energy_lost (J, kinetic energy the impact took)"));
  return events;
}

void write_groups(hid_t file, const Layout& lay, const Model& m, const LogGroups& logged) {
  for (const std::string& g : lay.groups) h5::group(file, g.c_str() + 1);
  if (logged.bodies) {
    Id g(H5Gopen2(file, "bodies", H5P_DEFAULT), H5Gclose, "opening /bodies");
    attribute(g, "description", std::string(kBodies));
    h5::string_dataset(g, "names", m.body_names);
  }
  if (!logged.frames.empty()) {
    Id g(H5Gopen2(file, "frames", H5P_DEFAULT), H5Gclose, "opening /frames");
    attribute(g, "description", std::string(kFrames));
    std::vector<std::string> names;
    for (const int f : logged.frames) names.push_back(m.frame_names[size_t(f)]);
    h5::string_dataset(g, "names", names);
  }
  if (const SensitivityPlan* p = logged.sensitivities.get()) {
    Id g(H5Gopen2(file, "sensitivities", H5P_DEFAULT), H5Gclose, "opening /sensitivities");
    attribute(g, "description", std::string(kSensitivities));
    attribute(g, "state_names", p->state_names);
    attribute(g, "state_units", p->state_units);
    if (p->np() > 0) {
      attribute(g, "parameter_names", p->parameter_names);
      attribute(g, "parameter_units", p->parameter_units);
    }
  }
}

void create_views(hid_t file, const Layout& lay, int width) {
  for (const View& v : lay.views) create_view(file, v, width);
}

}  // namespace soadyn::log
