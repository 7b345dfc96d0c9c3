// soadyn._read_run_file: the library's reader of run files (run_file.hpp) for soadyn.read_log
// (_trajectory.py), which builds the Trajectory from what it returns.
#include "common.hpp"

#include "soadyn/io/run_file.hpp"

namespace soadyn::python {

namespace {

// a series as a C-ordered array (T, *shape): the row-major rows the file holds
py::array series_array(const RunSeries& s) {
  const MatX& v = s.values;
  std::vector<double> flat(size_t(v.size()));
  for (Eigen::Index r = 0; r < v.rows(); ++r)
    for (Eigen::Index c = 0; c < v.cols(); ++c) flat[size_t(r * v.cols() + c)] = v(r, c);
  std::vector<py::ssize_t> shape{py::ssize_t(v.rows())};
  for (const Eigen::Index n : s.shape) shape.push_back(py::ssize_t(n));
  return owned(std::move(flat), std::move(shape));
}

// text as str: a file's string that is not UTF-8 (the writer tags such text ASCII) has U+FFFD in
// place of its bad bytes, never a UnicodeDecodeError
py::str text(const std::string& s) {
  PyObject* o = PyUnicode_DecodeUTF8(s.data(), Py_ssize_t(s.size()), "replace");
  if (!o) throw py::error_already_set();
  return py::reinterpret_steal<py::str>(o);
}
py::list texts(const std::vector<std::string>& v) {
  py::list out;
  for (const std::string& s : v) out.append(text(s));
  return out;
}

// /model_files: (name, bytes) of each file the run handed MuJoCo
py::list model_files(const RunContents& c) {
  py::list out;
  for (const ModelFile& f : c.model_files) out.append(py::make_tuple(text(f.name), py::bytes(f.data)));
  return out;
}

py::dict read(const std::string& path) {
  RunContents c;
  {
    py::gil_scoped_release free;
    c = read_run_file(path);
  }
  const RunContents::Solver& s = c.solver;
  py::dict solver("method"_a = text(s.method), "dynamics"_a = text(s.dynamics), "status"_a = text(s.status),
                  "quaternion_handling"_a = text(s.quaternion_handling), "rtol"_a = s.rtol, "atol"_a = s.atol,
                  "output_dt"_a = s.output_dt, "t_end"_a = s.t_end, "t_reached"_a = s.t_reached,
                  "cpu_seconds"_a = s.cpu_seconds, "max_energy_balance_error"_a = s.max_energy_balance_error,
                  "final_energy_balance_error"_a = s.final_energy_balance_error, "steps"_a = s.steps,
                  "rhs_evals"_a = s.rhs_evals, "jac_evals"_a = s.jac_evals, "error_test_failures"_a = s.error_test_failures,
                  "nonlinear_iterations"_a = s.nonlinear_iterations, "control_ticks"_a = s.control_ticks,
                  "stiffness_index"_a = s.stiffness_index, "stiffness_hint"_a = s.stiffness_hint);
  py::dict series;
  for (const RunSeries& r : c.series) series[text(r.path)] = series_array(r);
  py::list events;
  for (const RunEvent& e : c.events)
    events.append(py::make_tuple(e.t, e.dof, e.side, e.kind, e.v_before, e.v_after, e.energy_lost));
  return py::dict("path"_a = text(c.path), "soadyn_version"_a = text(c.soadyn_version),
                  "scenario_path"_a = text(c.scenario_path), "log_groups"_a = text(c.log_groups),
                  "layout_version"_a = c.layout_version, "scenario"_a = text(c.scenario_text), "robot"_a = text(c.robot_text),
                  "robot_path"_a = text(c.robot_path), "model_files"_a = model_files(c), "nq"_a = c.nq, "nv"_a = c.nv, "q_names"_a = texts(c.q_names),
                  "v_names"_a = texts(c.v_names), "joint_names"_a = texts(c.joint_names),
                  "joint_types"_a = texts(c.joint_types), "body_names"_a = texts(c.body_names), "parents"_a = c.parents,
                  "joint_v_index"_a = c.joint_v_index, "solver"_a = solver, "column_names"_a = texts(c.column_names),
                  "column_units"_a = texts(c.column_units), "series"_a = series, "frame_names"_a = texts(c.frame_names),
                  "state_names"_a = texts(c.state_names), "state_units"_a = texts(c.state_units),
                  "parameter_names"_a = texts(c.parameter_names), "parameter_units"_a = texts(c.parameter_units),
                  "events"_a = events);
}

}  // namespace

void bind_run_file(py::module_& m) {
  m.def("_read_run_file", &read, "path"_a,
        "A run file's contents (run_file.hpp) as a dict: metadata, solver, series {view path: array (T, *shape)}.");
}

}  // namespace soadyn::python
