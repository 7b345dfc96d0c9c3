#include "soadyn/io/h5log.hpp"

#include "soadyn/multibody/data.hpp"
#include "soadyn/sim/limits.hpp"
#include "soadyn/multibody/text.hpp"

#include "h5_util.hpp"
#include "h5log_header.hpp"
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
  g.prescribed.clear();
  for (const PrescribedInput& p : sc.inputs.prescribed) g.prescribed.push_back(p.dof);
  g.loop_rows = loop_row_names(sc.inputs.loops);
  g.loop_units = loop_row_units(sc.inputs.loops);
  if (settings.sensitivities.any())
    g.sensitivities = std::make_shared<const SensitivityPlan>(plan_sensitivities(sc.model, settings.sensitivities, sc.inputs.prescribed));
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

  // /solver: the settings as attributes, the scalars flush() rewrites (running, zeros until then)
  void create_solver(const SimulationSettings& settings);

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

// a new file at tmp_path, in HDF5's latest format (for SWMR), never an existing one's target
Id create_file(const std::string& path, const std::string& tmp_path) {
  Id fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "H5Pcreate");
  check(H5Pset_libver_bounds(fapl, H5F_LIBVER_LATEST, H5F_LIBVER_LATEST), "H5Pset_libver_bounds");
  // a new file, never an existing one's target: a name left there (a killed run's file, or a
  // symlink) is removed, not followed, and H5F_ACC_EXCL (O_CREAT | O_EXCL) opens no symlink
  ::unlink(tmp_path.c_str());
  const hid_t f = H5Fcreate(tmp_path.c_str(), H5F_ACC_EXCL, H5P_DEFAULT, fapl);
  if (f < 0) {
    h5::record_cause();
    const std::string& cause = h5::last_cause;
    if (h5::last_errno == ENOSPC || h5::last_errno == EDQUOT || h5::last_errno == EIO || h5::last_errno == EFBIG) {
      std::remove(tmp_path.c_str());
      throw IoError(cause + " while creating " + path + " (the output was not written; an existing file there is unchanged)");
    }
    throw Error(path + ": cannot create the output file " + tmp_path + (cause.empty() ? std::string() : " (" + cause + ")") +
                "; is the directory writable?");
  }
  return Id(f, H5Fclose, "H5Fcreate");
}

}  // namespace

void H5Log::Impl::create_solver(const SimulationSettings& settings) {
  Id g_solver = h5::group(file, "solver");
  // every setting of the table (settings.hpp) under its own name: numbers as doubles, words as
  // strings, flags as "true"/"false"; output_dt as the interval the rows really have
  for (const SettingInfo& info : setting_table()) {
    const std::string name(info.name);
    if (name == "output_dt") attribute(g_solver, "output_dt", output_interval(settings));
    else if (info.kind == SettingKind::Real || info.kind == SettingKind::Count)
      attribute(g_solver, name.c_str(), setting_number(settings, info));
    else attribute(g_solver, name.c_str(), setting_text(settings, info));
  }
  status = h5::string_scalar(g_solver, "status", 1024);
  quaternion = h5::string_scalar(g_solver, "quaternion_handling", 256);
  t_reached = Scalar(g_solver, "t_reached", H5T_NATIVE_DOUBLE);
  cpu = Scalar(g_solver, "cpu_seconds", H5T_NATIVE_DOUBLE);
  steps = Scalar(g_solver, "steps", H5T_NATIVE_LONG);
  rhs = Scalar(g_solver, "rhs_evals", H5T_NATIVE_LONG);
  jac = Scalar(g_solver, "jac_evals", H5T_NATIVE_LONG);
  etf = Scalar(g_solver, "error_test_failures", H5T_NATIVE_LONG);
  nli = Scalar(g_solver, "nonlinear_iterations", H5T_NATIVE_LONG);
  max_balance = Scalar(g_solver, "max_energy_balance_error", H5T_NATIVE_DOUBLE);
  final_balance = Scalar(g_solver, "final_energy_balance_error", H5T_NATIVE_DOUBLE);
  ticks = Scalar(g_solver, "control_ticks", H5T_NATIVE_LONG);
  // RunSummary::stiffness_index and stiffness_hint (simulate.hpp)
  stiffness = Scalar(g_solver, "stiffness_index", H5T_NATIVE_DOUBLE);
  stiffness_hint = h5::string_scalar(g_solver, "stiffness_hint", 1024);
  for (Scalar* s : {&t_reached, &cpu}) attribute(s->dset, "units", std::string("s"));
  for (Scalar* s : {&steps, &rhs, &jac, &etf, &nli, &max_balance, &final_balance, &ticks, &stiffness})
    attribute(s->dset, "units", std::string("1"));
  status.write(std::string("running"));
  quaternion.write(std::string());
  stiffness_hint.write(std::string());
  for (Scalar* s : {&t_reached, &cpu, &max_balance, &final_balance, &stiffness}) s->write(0.0);
  for (Scalar* s : {&steps, &rhs, &jac, &etf, &nli, &ticks}) s->write(0L);
}

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
    im.file = create_file(path, im.tmp_path);
    log::write_sources(im.file, sc, version, groups);
    log::write_model(im.file, m);
    im.create_solver(settings);
    im.samples = log::create_samples(im.file, lay);
    if (im.groups.impacts) im.events = log::create_events(im.file);
    log::write_groups(im.file, lay, m, im.groups);
    log::create_views(im.file, lay, im.width);
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
