// The run file read back (run_file.hpp): the inverse of log_layout and h5log.cpp, by the same
// names (kViewPaths, column_stem) and the same HDF5 helpers (h5_util).
#include "soadyn/run_file.hpp"

#include "soadyn/input_file.hpp"

#include "h5_util.hpp"
#include "log_layout.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace soadyn {

using h5::Id;

struct RunReader::Impl {
  std::string path;
  Id file, samples;
  std::vector<std::string> names, units;
  hsize_t rows = 0;

  // a group of the file, or an Error naming it
  Id group(const char* name) const {
    const hid_t g = H5Gopen2(file, name, H5P_DEFAULT);
    if (g < 0) throw Error(path + ": " + name + ": cannot be opened (corrupt or truncated file?)");
    return Id(g, H5Gclose, name);
  }
  std::vector<std::string> strings_if(hid_t obj, const char* name, const std::string& where) const {
    return h5::has_attribute(obj, name) ? h5::strings(obj, name, true, where) : std::vector<std::string>();
  }
  std::string string_if(hid_t obj, const char* name, const std::string& where) const {
    return h5::has_attribute(obj, name) ? h5::one_string(obj, name, true, where) : std::string();
  }
  void read_metadata(RunContents& r) const;
  void read_series(RunContents& r) const;
  void read_groups(RunContents& r) const;
};

RunReader::RunReader(const std::string& path) : impl_(std::make_unique<Impl>()) {
  Impl& im = *impl_;
  im.path = path;
  im.file = h5::open_run_file(path);
  if (!h5::exists(im.file, "/samples")) return;  // layouts 1 and 2: the series are datasets of their own
  const std::vector<hsize_t> d = h5::dims(im.file, "samples", path + ": /");
  if (d.size() != 2) throw Error(path + ": /samples: expected a T×W table, got " + std::to_string(d.size()) + " dimensions");
  im.samples = Id(H5Dopen2(im.file, "samples", H5P_DEFAULT), H5Dclose, path + ": opening /samples");
  im.rows = d[0];
  im.names = h5::strings(im.samples, "column_names", true, path + ": /samples");
  im.units = h5::strings(im.samples, "column_units", true, path + ": /samples");
  for (const auto* v : {&im.names, &im.units})
    if (v->size() != d[1])
      throw Error(path + ": /samples has " + std::to_string(d[1]) + " columns but " + std::to_string(v->size()) +
                  (v == &im.names ? " column_names" : " column_units"));
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
  if (h5::has_attribute(file, "layout_version")) r.layout_version = long(h5::numbers(file, "layout_version", true, root)(0, 0));
  // the scenario's text: a dataset /scenario, or (files written before it) a root attribute
  if (h5::exists(file, "/scenario")) r.scenario_text = h5::one_string(file, "scenario", false, root);
  else r.scenario_text = string_if(file, "scenario", root);
  if (h5::exists(file, "/robot")) {  // layout 4: the robot file a scenario named, and its path
    r.robot_text = h5::one_string(file, "robot", false, root);
    const Id d(H5Dopen2(file, "robot", H5P_DEFAULT), H5Dclose, path + ": opening /robot");
    r.robot_path = h5::one_string(d, "path", true, path + ": /robot");
  }
  if (h5::exists(file, "/model")) {
    const Id g = group("/model");
    const std::string at = path + ": /model";
    if (h5::has_attribute(g, "nq")) r.nq = long(h5::numbers(g, "nq", true, at)(0, 0));
    if (h5::has_attribute(g, "nv")) r.nv = long(h5::numbers(g, "nv", true, at)(0, 0));
    r.q_names = strings_if(g, "q_names", at);
    r.v_names = strings_if(g, "v_names", at);
    r.joint_types = strings_if(g, "joint_types", at);
    r.body_names = strings_if(g, "body_names", at);
    // layout 3: an attribute; layout 2: a dataset of fixed-length strings
    if (h5::has_attribute(g, "joint_names")) r.joint_names = h5::strings(g, "joint_names", true, at);
    else if (H5Lexists(g, "joint_names", H5P_DEFAULT) > 0) r.joint_names = h5::strings(g, "joint_names", false, at);
    if (H5Lexists(g, "parents", H5P_DEFAULT) > 0) {
      const h5::RowMatrix p = h5::numbers(g, "parents", false, at);
      for (Eigen::Index k = 0; k < p.size(); ++k) r.parents.push_back(int(p.data()[k]));
    }
  }
  if (h5::exists(file, "/solver")) {
    // fixed settings are attributes; run-time values scalar datasets (SWMR layout) or attributes (earlier files)
    const Id g = group("/solver");
    const std::string at = path + ": /solver";
    auto text = [&](const char* k) {
      return H5Lexists(g, k, H5P_DEFAULT) > 0 ? h5::one_string(g, k, false, at) : string_if(g, k, at);
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
    s.steps = long(number("steps")), s.rhs_evals = long(number("rhs_evals")), s.jac_evals = long(number("jac_evals"));
    s.error_test_failures = long(number("error_test_failures"));
    s.nonlinear_iterations = long(number("nonlinear_iterations"));
  }
}

void RunReader::Impl::read_series(RunContents& r) const {
  r.column_names = names, r.column_units = units;
  if (samples.ok()) {
    // each view's columns of /samples, found by its name (log_layout: kViewPaths, column_stem),
    // shaped as its view is
    h5::RowMatrix all(Eigen::Index(rows), Eigen::Index(names.size()));
    if (all.size() > 0) h5::read_rows(samples, 0, rows, names.size(), all.data(), path + ": /samples");
    for (const char* view : log::kViewPaths) {
      const std::string stem = log::column_stem(view);
      std::vector<size_t> cols;
      for (size_t c = 0; c < names.size(); ++c)
        if (log::column_of(names[c], stem)) cols.push_back(c);
      const bool has_view = h5::exists(file, view);
      if (cols.empty()) {
        if (has_view) throw Error(path + ": " + view + ": a view of no column of /samples (none named " + stem + ".*)");
        continue;
      }
      if (cols.back() - cols.front() + 1 != cols.size())
        throw Error(path + ": /samples: the columns " + stem + ".* are not side by side");
      RunSeries s;
      s.path = view;
      const Eigen::Index n = Eigen::Index(cols.size());
      if (has_view) {
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
  if (h5::exists(file, "/frames/names")) r.frame_names = h5::strings(file, "/frames/names", false, path);
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
      const bool dof_ok = std::isfinite(e(k, 1)) && e(k, 1) >= 0 && (r.v_names.empty() || e(k, 1) < double(r.v_names.size()));
      if (!std::isfinite(e(k, 0)) || !dof_ok)
        throw Error(path + ": /events: row " + std::to_string(k) + " names no time or joint of the model");
      r.events.push_back({e(k, 0), int(e(k, 1)), e(k, 2) < 0 ? -1 : 1, std::isfinite(e(k, 3)) ? int(e(k, 3)) : -1, e(k, 4),
                          e(k, 5), e(k, 6)});
    }
  }
}

RunContents RunReader::read() const {
  RunContents r;
  r.path = impl_->path;
  impl_->read_metadata(r);
  impl_->read_series(r);
  impl_->read_groups(r);
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
