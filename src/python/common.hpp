// Shared pieces of the Python module: reading numpy arguments, read-only views of Data, owning
// arrays built without a copy, and the Data wrapper that the views keep alive.
#pragma once

#include "soadyn/sim/trajectory.hpp"
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/multibody/data.hpp"
#include "soadyn/algorithm/derivatives.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/multibody/model.hpp"
#include "soadyn/sim/settings.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace soadyn::python {

namespace py = pybind11;
using namespace pybind11::literals;

// A float64 array of any layout passes through untouched; lists, ints, float32 … are converted
// once by numpy.
using ArrayIn = py::array_t<double, py::array::forcecast>;

// Copies the 1-D array `a` into `out` (sized once, no allocation) after the library's own size
// check, so the message is the C++ one: "mass_matrix: q: expected 7 entries, got 3".  A native
// float64 ndarray is read in place through its strides; anything else goes through numpy.
void read_vector(const Model& model, const Data& data, const char* where, const char* what, py::handle a,
                 int expected, VecX& out);
// The same for a function without a Data (the model's own methods): out is resized as needed.
VecX read_vector(const char* where, const char* what, const ArrayIn& a, int expected);
// A 2-D array (samples × columns) as a MatX; soadyn::Error "where: what: expected a 2-D array …" otherwise.
MatX read_matrix(const char* where, const char* what, const ArrayIn& a);

// An array that owns `values` (moved, not copied), shaped `shape` (row-major).
py::array owned(std::vector<double>&& values, std::vector<py::ssize_t> shape);
py::array owned(VecX&& v);
py::array owned(MatX&& m);  // column-major, shape (rows, cols)
py::array owned(SampleRows&& m, std::vector<py::ssize_t> shape);  // C order, rows × cols numbers in `shape`

// The Python-side Data: the library's Data (shared with every view's base, so a view outlives
// the Data object safely), scratch vectors for the arguments, and the cached read-only views.
struct PyData {
  explicit PyData(const Model& model);

  std::shared_ptr<Data> data;
  py::object model;  // the Python Model it was made for (pickle and deepcopy carry it)
  int nq, nv, nbodies;
  VecX q, v, x;  // arguments copied here: the library takes VecX, this copy does not allocate
  // another function's results kept across a call whose C++ counterpart fills them as a by-product
  // (forward_dynamics 'dense'/'sparse': data.M and data.bias; forward_dynamics_derivatives: data.qdd;
  // forward_dynamics_parameter_derivative: all four; regressor: data.tau)
  MatX kept_M;
  VecX kept_bias, kept_qdd, kept_tau;
  py::array M, bias, tau, qdd;          // the results the algorithms fill
  py::array R, eta, d, s, r, G, V, Vbar;  // kinematics
  // the derivative algorithms' arrays (nv×nv each: made by the first call that needs them) and
  // their views; id_result and fd_result are the tuples inverse_dynamics_derivatives and
  // forward_dynamics_derivatives return
  // Each returned array belongs to one function, the only one that writes it (src/python/README.md,
  // "What a call overwrites"): minverse's 𝓜⁻¹ (Minv) is its own, apart from the 𝓜⁻¹ =
  // ∂q̈/∂τ forward_dynamics_derivatives returns (dqdd_dtau, the DerivativeData's)
  std::shared_ptr<DerivativeData> derivatives;
  std::shared_ptr<MatX> minverse_result;
  py::array dtau_dq, dtau_dv, dqdd_dq, dqdd_dv, dqdd_dtau, Minv;
  py::tuple id_result, fd_result;
  DerivativeData& derivative_data(const Model& model);

  // throws soadyn::Error when this Data was built for another model
  void check(const Model& model, const char* where) const { data->check(model, where, "data", 0, 0); }
};

// The Python exception for the C++ exception being handled (soadyn::Error → soadyn.Error, …);
// for the entry points that bypass pybind11's dispatcher.
void set_python_error();
extern PyObject* error_type;  // soadyn.Error

// On Python's main thread: a poll that runs Python's signal handlers every 10 ms; one that raises
// (Ctrl-C: KeyboardInterrupt) has its exception kept in `pending` and sets `stop`.  Elsewhere none
// (handlers run on the main thread only).  simulate.cpp
std::function<void()> signal_poll(std::atomic<int>& stop, py::object& pending);

// one simulation setting of setting_table() (settings.hpp) as a Python value, and back (a value of
// the wrong type raises TypeError; ranges and words are checked where the run starts, as in C++)
py::object setting_value(const SimulationSettings& s, const SettingInfo& info);
void set_setting_value(SimulationSettings& s, const SettingInfo& info, const py::handle& value);

void bind_model(py::module_& m);
void bind_algorithms(py::module_& m);
void bind_simulate(py::module_& m);
void bind_batch(py::module_& m);  // soadyn.batch and soadyn._rollout (batch.cpp)
void bind_frames(py::module_& m);  // after bind_model: it adds Model's frame members
void bind_regressor(py::module_& m);  // parameters, with_parameters, regressor (regressor.cpp)
void bind_adjoint(py::module_& m);  // Cost, _tracking_cost, _gradient (adjoint.cpp)
void bind_pickle(py::module_& m);  // after bind_model: pickle and deepcopy of Model and Data (pickle.cpp)
void bind_identify(py::module_& m);  // soadyn._identify (identify.cpp)
void bind_run_file(py::module_& m);  // soadyn._read_run_file (run_file.cpp), behind read_log
void bind_loops(py::module_& m);  // after bind_model: Scenario.loop_rows, loop_forward_dynamics, loop_inverse_dynamics (loops.cpp)

}  // namespace soadyn::python
