// The run file read back (run_file.hpp): the inverse of log_layout and h5log.cpp, by the same
// names (kViewPaths, column_stem) and the same HDF5 helpers (h5_util).
#include "soadyn/io/run_file.hpp"

#include "soadyn/io/input_file.hpp"

#include "h5_util.hpp"
#include "log_layout.hpp"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <numeric>
#include <thread>

namespace soadyn {

using h5::Id;

struct RunReader::Impl {
  std::string path;
  Id file, samples;
  std::vector<std::string> names, units;
  hsize_t rows = 0;
  long layout = 0;  // the root attribute layout_version (0: none)
  // layout 5 on: no variable-length data anywhere, and the views (whose mappings HDF5 keeps in the
  // global heap) are never opened; the global heap is what HDF5 reads without checksums or bounds
  bool heap_free() const { return layout >= 5; }

  // a group of the file, or an Error naming it
  Id group(const char* name) const {
    const hid_t g = H5Gopen2(file, name, H5P_DEFAULT);
    if (g < 0) throw Error(path + ": " + name + ": cannot be opened (corrupt or truncated file?)");
    return Id(g, H5Gclose, name);
  }
  std::vector<std::string> strings(hid_t obj, const char* name, bool attribute, const std::string& where) const {
    return h5::strings(obj, name, attribute, where, !heap_free());
  }
  std::string one_string(hid_t obj, const char* name, bool attribute, const std::string& where) const {
    return h5::one_string(obj, name, attribute, where, !heap_free());
  }
  std::vector<std::string> strings_if(hid_t obj, const char* name, const std::string& where) const {
    return h5::has_attribute(obj, name) ? strings(obj, name, true, where) : std::vector<std::string>();
  }
  std::string string_if(hid_t obj, const char* name, const std::string& where) const {
    return h5::has_attribute(obj, name) ? one_string(obj, name, true, where) : std::string();
  }
  void open_samples();
  void read_metadata(RunContents& r) const;
  void read_series(RunContents& r, bool all_rows = true) const;
  void read_groups(RunContents& r) const;
  void probe() const;
};

void RunReader::Impl::open_samples() {
  if (!h5::exists(file, "/samples")) return;  // layouts 1 and 2: the series are datasets of their own
  const std::vector<hsize_t> d = h5::dims(file, "samples", path + ": /");
  if (d.size() != 2) throw Error(path + ": /samples: expected a T×W table, got " + std::to_string(d.size()) + " dimensions");
  samples = Id(H5Dopen2(file, "samples", H5P_DEFAULT), H5Dclose, path + ": opening /samples");
  rows = d[0];
  names = strings(samples, "column_names", true, path + ": /samples");
  units = strings(samples, "column_units", true, path + ": /samples");
  for (const auto* v : {&names, &units})
    if (v->size() != d[1])
      throw Error(path + ": /samples has " + std::to_string(d[1]) + " columns but " + std::to_string(v->size()) +
                  (v == &names ? " column_names" : " column_units"));
}

namespace {
constexpr double kProbeSeconds = 5.0;
constexpr double kMaxModelFiles = 1999;  // MuJoCo 2.2's virtual file system holds mjMAXVFS − 1 (1999) files
constexpr std::uint64_t kMaxModelFilesBytes = 4 * kMaxAssetBytes;  // 1 GiB: a corrupt file claims no more
// a count read from the file (raw data, not checksummed): −1 when it is not one
long to_count(double x) { return x >= 0 && x < 9e15 ? long(x) : -1; }
}  // namespace

// A file of layout 4 or earlier keeps strings and the views' mappings in the global heap, which
// libhdf5 1.10 follows without bounds checks: one changed byte there faults inside the library
// (H5HG_read).  Such a file is first read in a forked child, everything but the rows between the
// first and last; only when the child ends by itself (read or refused) does this process read it.
void RunReader::Impl::probe() const {
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) return;  // no child to be had: read as before
  if (pid == 0) {
    // the child says nothing (a fault's message from the C library included): the caller's one line
    // is the parent's; no controlling terminal, so glibc's fatal messages go to stderr too
    ::setsid();
    if (const int null = ::open("/dev/null", O_WRONLY); null >= 0) ::dup2(null, 2), ::dup2(null, 1);
    int code = 0;
    try {
      Impl copy;  // this process's own open ids, inherited, read through once
      copy.path = path, copy.layout = layout;
      copy.file = Id(H5Freopen(file), H5Fclose, path);
      copy.open_samples();
      RunContents r;
      copy.read_metadata(r);
      copy.read_groups(r);
      copy.read_series(r, false);
    } catch (...) {
      code = 1;
    }
    ::_exit(code);
  }
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(kProbeSeconds);
  int status = 0, polls = 0;
  for (;;) {
    const pid_t w = ::waitpid(pid, &status, WNOHANG);
    if (w == pid) break;
    if (w < 0 && errno != EINTR) return;
    if (std::chrono::steady_clock::now() > end) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      throw Error(path + ": corrupt run file: reading its metadata did not end within " + std::to_string(int(kProbeSeconds)) +
                  " s (layout " + std::to_string(layout) + ")");
    }
    // about the child's own time to read the metadata (milliseconds), then coarser
    std::this_thread::sleep_for(std::chrono::microseconds(polls++ < 100 ? 100 : 2000));
  }
  if (WIFSIGNALED(status))
    throw Error(path + ": corrupt run file: the HDF5 library faults reading it (" + std::string(strsignal(WTERMSIG(status))) +
                " in a test read of this layout-" + std::to_string(layout) + " file)");
}

RunReader::RunReader(const std::string& path) : impl_(std::make_unique<Impl>()) {
  Impl& im = *impl_;
  im.path = path;
  im.file = h5::open_run_file(path);
  // a number in the root's object header (checksummed metadata): safe to read in any file
  if (h5::has_attribute(im.file, "layout_version")) {
    const h5::RowMatrix v = h5::numbers(im.file, "layout_version", true, path + ": /");
    if (v.size() != 1 || !(std::abs(v(0, 0)) < 1e6)) throw Error(path + ": /: layout_version: expected one number");
    im.layout = long(v(0, 0));
  }
  if (!im.heap_free()) im.probe();
  im.open_samples();
}

RunReader::~RunReader() = default;
RunReader::RunReader(RunReader&&) noexcept = default;
RunReader& RunReader::operator=(RunReader&&) noexcept = default;

const std::string& RunReader::path() const { return impl_->path; }
const std::vector<std::string>& RunReader::column_names() const { return impl_->names; }
const std::vector<std::string>& RunReader::column_units() const { return impl_->units; }
std::uint64_t RunReader::rows() const { return impl_->rows; }

void RunReader::read_rows(std::uint64_t first, std::uint64_t count, double* out) const {
  const Impl& im = *impl_;
  if (!im.samples.ok()) throw Error(im.path + ": no /samples (not a run file from soadyn run?)");
  if (first + count > im.rows)
    throw Error(im.path + ": /samples: rows " + std::to_string(first) + " to " + std::to_string(first + count - 1) +
                " asked for, it has " + std::to_string(im.rows));
  if (count > 0) h5::read_rows(im.samples, first, count, im.names.size(), out, im.path + ": /samples");
}

void RunReader::Impl::read_metadata(RunContents& r) const {
  const std::string root = path + ": /";
  r.soadyn_version = string_if(file, "soadyn_version", root);
  r.scenario_path = string_if(file, "scenario_path", root);
  r.log_groups = string_if(file, "log_groups", root);
  r.layout_version = layout;
  // the scenario's text: a dataset /scenario, or (files written before it) a root attribute
  if (h5::exists(file, "/scenario")) r.scenario_text = one_string(file, "scenario", false, root);
  else r.scenario_text = string_if(file, "scenario", root);
  if (h5::exists(file, "/robot")) {  // layout 4: the robot file a scenario named, and its path
    r.robot_text = one_string(file, "robot", false, root);
    const Id d(H5Dopen2(file, "robot", H5P_DEFAULT), H5Dclose, path + ": opening /robot");
    r.robot_path = one_string(d, "path", true, path + ": /robot");
  }
  if (h5::exists(file, "/model_files")) {  // an MJCF model's files: count datasets "0" .. "count-1"
    const Id g = group("/model_files");
    const std::string at = path + ": /model_files";
    const h5::RowMatrix n = h5::numbers(g, "count", true, at);
    if (n.size() != 1 || !(n(0, 0) >= 1 && n(0, 0) <= kMaxModelFiles && n(0, 0) == std::floor(n(0, 0))))
      throw Error(at + ": count: expected a number of files from 1 to " + std::to_string(kMaxModelFiles));
    std::uint64_t total = 0;
    for (long k = 0; k < long(n(0, 0)); ++k) {
      const std::string name = std::to_string(k);
      ModelFile f;
      f.data = h5::bytes(g, name.c_str(), kMaxAssetBytes, at);
      if ((total += f.data.size()) > kMaxModelFilesBytes)
        throw Error(at + ": more than the " + std::to_string(kMaxModelFilesBytes) + " bytes a model's files may hold together");
      const Id d(H5Dopen2(g, name.c_str(), H5P_DEFAULT), H5Dclose, at + "/" + name + ": opening");
      f.name = one_string(d, "name", true, at + "/" + name);
      r.model_files.push_back(std::move(f));
    }
  }
  if (h5::exists(file, "/model")) {
    const Id g = group("/model");
    const std::string at = path + ": /model";
    if (h5::has_attribute(g, "nq")) r.nq = to_count(h5::numbers(g, "nq", true, at)(0, 0));
    if (h5::has_attribute(g, "nv")) r.nv = to_count(h5::numbers(g, "nv", true, at)(0, 0));
    r.q_names = strings_if(g, "q_names", at);
    r.v_names = strings_if(g, "v_names", at);
    r.joint_types = strings_if(g, "joint_types", at);
    r.body_names = strings_if(g, "body_names", at);
    // layout 3: an attribute; layout 2: a dataset of fixed-length strings
    if (h5::has_attribute(g, "joint_names")) r.joint_names = strings(g, "joint_names", true, at);
    else if (H5Lexists(g, "joint_names", H5P_DEFAULT) > 0) r.joint_names = strings(g, "joint_names", false, at);
    for (auto [name, out] : {std::pair{"parents", &r.parents}, {"joint_v_index", &r.joint_v_index}})
      if (H5Lexists(g, name, H5P_DEFAULT) > 0) {
        const h5::RowMatrix p = h5::numbers(g, name, false, at);
        for (Eigen::Index k = 0; k < p.size(); ++k) {
          const double x = p.data()[k];
          if (!(x >= -1 && x < 1e9)) throw Error(at + ": " + name + ": entry " + std::to_string(k) + " is not an index");
          out->push_back(int(x));
        }
      }
  }
  if (h5::exists(file, "/solver")) {
    // fixed settings are attributes; run-time values scalar datasets (SWMR layout) or attributes (earlier files)
    const Id g = group("/solver");
    const std::string at = path + ": /solver";
    auto text = [&](const char* k) {
      return H5Lexists(g, k, H5P_DEFAULT) > 0 ? one_string(g, k, false, at) : string_if(g, k, at);
    };
    auto number = [&](const char* k) {
      const bool dataset = H5Lexists(g, k, H5P_DEFAULT) > 0;
      return dataset || h5::has_attribute(g, k) ? h5::numbers(g, k, !dataset, at)(0, 0) : 0.0;
    };
    RunContents::Solver& s = r.solver;
    s.method = text("method"), s.dynamics = text("dynamics"), s.status = text("status");
    s.quaternion_handling = text("quaternion_handling");
    s.rtol = number("rtol"), s.atol = number("atol"), s.output_dt = number("output_dt"), s.t_end = number("t_end");
    s.t_reached = number("t_reached"), s.cpu_seconds = number("cpu_seconds");
    s.max_energy_balance_error = number("max_energy_balance_error");
    s.final_energy_balance_error = number("final_energy_balance_error");
    s.steps = to_count(number("steps")), s.rhs_evals = to_count(number("rhs_evals")), s.jac_evals = to_count(number("jac_evals"));
    s.error_test_failures = to_count(number("error_test_failures"));
    s.nonlinear_iterations = to_count(number("nonlinear_iterations"));
    s.control_ticks = to_count(number("control_ticks"));
    s.stiffness_index = number("stiffness_index");
    s.stiffness_hint = text("stiffness_hint");
  }
}

void RunReader::Impl::read_series(RunContents& r, bool all_rows) const {
  r.column_names = names, r.column_units = units;
  if (samples.ok()) {
    // each view's columns of /samples, found by its name (log_layout: kViewPaths, column_stem),
    // shaped as its view is (all rows; a probe reads the first and the last)
    const hsize_t read = all_rows ? rows : std::min<hsize_t>(rows, 1);
    h5::RowMatrix all(Eigen::Index(read), Eigen::Index(names.size()));
    if (all.size() > 0) h5::read_rows(samples, 0, read, names.size(), all.data(), path + ": /samples");
    if (!all_rows && rows > 1) h5::read_rows(samples, rows - 1, 1, names.size(), all.data(), path + ": /samples");
    for (const char* view : log::kViewPaths) {
      const std::string stem = log::column_stem(view);
      std::vector<size_t> cols;
      for (size_t c = 0; c < names.size(); ++c)
        if (log::column_of(names[c], stem)) cols.push_back(c);
      const bool has_view = h5::exists(file, view);  // the link only: the view itself is not opened
      if (cols.empty()) {
        if (has_view) throw Error(path + ": " + view + ": a view of no column of /samples (none named " + stem + ".*)");
        continue;
      }
      if (cols.back() - cols.front() + 1 != cols.size())
        throw Error(path + ": /samples: the columns " + stem + ".* are not side by side");
      RunSeries s;
      s.path = view;
      const Eigen::Index n = Eigen::Index(cols.size());
      if (heap_free()) {
        // layout 5: the shape the layout gives the view (log_layout.cpp), from the columns alone
        const bool rank3 = std::string(view).rfind("/bodies/", 0) == 0 || std::string(view).rfind("/frames/", 0) == 0 ||
                           std::string(view).rfind("/sensitivities/", 0) == 0;
        long items = 0, per = 0;
        if (rank3 && !log::rank3_shape(view, long(n), long(r.state_names.size()), items, per))
          throw Error(path + ": " + view + ": " + std::to_string(n) + " columns named " + stem + ".*, not the shape of its view");
        if (rank3) s.shape = {Eigen::Index(items), Eigen::Index(per)};
        else if (!(n == 1 && names[cols[0]] == stem)) {
          s.shape = {n};
        }
      } else if (has_view) {
        const std::vector<hsize_t> d = h5::dims(file, view, path);
        for (size_t k = 1; k < d.size(); ++k) s.shape.push_back(Eigen::Index(d[k]));
        const Eigen::Index per_row = std::accumulate(s.shape.begin(), s.shape.end(), Eigen::Index(1), std::multiplies<>());
        if (per_row != n)
          throw Error(path + ": " + view + ": its view has " + std::to_string(per_row) + " numbers a row, /samples " +
                      std::to_string(n) + " columns named " + stem + ".*");
      } else if (!(n == 1 && names[cols[0]] == stem)) {
        s.shape = {n};
      }
      s.columns.assign(names.begin() + long(cols.front()), names.begin() + long(cols.back()) + 1);
      s.units.assign(units.begin() + long(cols.front()), units.begin() + long(cols.back()) + 1);
      s.values = all.middleCols(Eigen::Index(cols.front()), n);
      r.series.push_back(std::move(s));
    }
  } else {
    // layouts 1 and 2: each view a dataset of its own, cut to the rows all of them have
    Eigen::Index T = -1;
    for (const char* view : log::kViewPaths) {
      if (!h5::exists(file, view)) continue;
      RunSeries s;
      s.path = view;
      std::vector<hsize_t> d;
      s.values = h5::numbers(file, view, false, path, &d);
      for (size_t k = 1; k < d.size(); ++k) s.shape.push_back(Eigen::Index(d[k]));
      T = T < 0 ? s.values.rows() : std::min(T, s.values.rows());
      r.series.push_back(std::move(s));
    }
    for (RunSeries& s : r.series) s.values.conservativeResize(T, Eigen::NoChange);
  }
  if (!r.find("/time")) throw Error(path + ": not a soadyn run file (no /samples, no /time)");
  if (const RunSeries* q = r.find("/q"); q && !r.q_names.empty() && q->values.cols() != Eigen::Index(r.q_names.size()))
    throw Error(path + ": /q: expected " + std::to_string(r.q_names.size()) + " columns (/model q_names), the file has " +
                std::to_string(q->values.cols()));
}

void RunReader::Impl::read_groups(RunContents& r) const {
  if (h5::exists(file, "/frames/names")) r.frame_names = strings(file, "/frames/names", false, path);
  if (h5::exists(file, "/sensitivities")) {
    const Id g = group("/sensitivities");
    const std::string at = path + ": /sensitivities";
    r.state_names = strings_if(g, "state_names", at), r.state_units = strings_if(g, "state_units", at);
    r.parameter_names = strings_if(g, "parameter_names", at), r.parameter_units = strings_if(g, "parameter_units", at);
  }
  if (h5::exists(file, "/events")) {  // E×7: t, dof, side, kind, v_before, v_after, energy_lost
    const h5::RowMatrix e = h5::numbers(file, "/events", false, path);
    if (e.rows() > 0 && e.cols() != 7) throw Error(path + ": /events: expected 7 columns, got " + std::to_string(e.cols()));
    for (Eigen::Index k = 0; k < e.rows(); ++k) {
      const bool dof_ok = e(k, 1) >= 0 && e(k, 1) < (r.v_names.empty() ? 1e9 : double(r.v_names.size()));
      if (!std::isfinite(e(k, 0)) || !dof_ok)
        throw Error(path + ": /events: row " + std::to_string(k) + " names no time or joint of the model");
      const int kind = e(k, 3) == 0 || e(k, 3) == 1 || e(k, 3) == 2 ? int(e(k, 3)) : -1;
      r.events.push_back({e(k, 0), int(e(k, 1)), e(k, 2) < 0 ? -1 : 1, kind, e(k, 4), e(k, 5), e(k, 6)});
    }
  }
}

RunContents RunReader::read() const {
  RunContents r;
  r.path = impl_->path;
  impl_->read_metadata(r);
  impl_->read_groups(r);  // first: /sensitivities' state_names shape its views
  impl_->read_series(r);
  return r;
}

RunContents read_run_file(const std::string& path) { return RunReader(path).read(); }

bool is_hdf5_file(const std::string& path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // our messages, not HDF5's stack dumps
  const InputFile in(path, "a file", kNoSizeLimit);  // a regular file: H5Fis_hdf5 would block on a FIFO
  return H5Fis_hdf5(in.name_for_library().c_str()) > 0;
}

Eigen::Index RunContents::rows() const {
  const RunSeries* t = find("/time");
  return t ? t->values.rows() : 0;
}

const RunSeries* RunContents::find(const std::string& p) const {
  const auto it = std::find_if(series.begin(), series.end(), [&](const RunSeries& s) { return s.path == p; });
  return it == series.end() ? nullptr : &*it;
}

const MatX& RunContents::values(const std::string& p) const {
  if (const RunSeries* s = find(p)) return s->values;
  throw Error(path + ": dataset " + p + " is missing (a run logged without it: soadyn run --log)");
}

}  // namespace soadyn
