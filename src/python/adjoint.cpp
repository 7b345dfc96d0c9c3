// Adjoint gradients (adjoint.hpp) from Python: soadyn.Cost from Python callables or a tracked
// reference, and the run behind soadyn.gradient.
#include "common.hpp"

#include "soadyn/sim/adjoint.hpp"
#include "soadyn/sim/scenario.hpp"

namespace soadyn::python {

namespace {

// reads (value, d/dq, d/dv) returned by a Python cost part into dq (nq) and dv (nv)
double read_part(const py::object& out, const char* what, Eigen::Ref<VecX> dq, Eigen::Ref<VecX> dv) {
  if (!py::isinstance<py::tuple>(out) || py::len(out) != 3)
    throw Error(std::string("cost: ") + what + " must return a tuple (value, d/dq, d/dv), got " +
                std::string(py::str(py::type::of(out).attr("__name__"))));
  const auto parts = out.cast<py::tuple>();
  const auto vector = [&](const py::handle h, Eigen::Ref<VecX> into, const char* name) {
    const ArrayIn a = ArrayIn::ensure(h);
    if (!a || a.ndim() != 1 || a.shape(0) != into.size())
      throw Error(std::string("cost: ") + what + ": " + name + " must have shape (" + std::to_string(into.size()) + ",)");
    for (Eigen::Index k = 0; k < into.size(); ++k) into(k) = a.at(k);
  };
  vector(parts[1], dq, "d/dq");
  vector(parts[2], dv, "d/dv");
  return parts[0].cast<double>();
}

// a Python f(t, q, v) -> (ℓ, ∂ℓ/∂q, ∂ℓ/∂v) or phi(q, v) -> (Φ, ∂Φ/∂q, ∂Φ/∂v), the GIL taken for the
// call only; an exception it raises ends the gradient and is re-raised
Cost python_cost(const py::object& running, const py::object& terminal) {
  Cost cost;
  if (!running.is_none()) {
    auto f = std::make_shared<py::object>(running);
    cost.running = [f](double t, const VecX& q, const VecX& v, Eigen::Ref<VecX> dq, Eigen::Ref<VecX> dv) {
      py::gil_scoped_acquire gil;
      return read_part((*f)(t, py::array_t<double>(q.size(), q.data()), py::array_t<double>(v.size(), v.data())),
                       "running", dq, dv);
    };
  }
  if (!terminal.is_none()) {
    auto f = std::make_shared<py::object>(terminal);
    cost.terminal = [f](const VecX& q, const VecX& v, Eigen::Ref<VecX> dq, Eigen::Ref<VecX> dv) {
      py::gil_scoped_acquire gil;
      return read_part((*f)(py::array_t<double>(q.size(), q.data()), py::array_t<double>(v.size(), v.data())), "terminal",
                       dq, dv);
    };
  }
  return cost;
}

// a weight argument: None (none), a number (every column), or one per column
VecX weights(const py::object& w, int n, const char* what) {
  if (w.is_none()) return {};
  if (py::isinstance<py::float_>(w) || py::isinstance<py::int_>(w)) {
    const double x = w.cast<double>();
    return x == 0.0 ? VecX() : VecX::Constant(n, x);
  }
  return read_vector("tracking_cost", what, ArrayIn::ensure(w), n);
}

}  // namespace

void bind_adjoint(py::module_& m) {
  py::class_<Cost>(m, "Cost", R"(A run's cost G = ∫ ℓ(t, q, v) dt + Φ(q(T), v(T)) for soadyn.gradient.

Cost(running=f, terminal=phi): f(t, q, v) -> (ℓ, dℓ/dq (nq,), dℓ/dv (nv,)) and phi(q, v) -> (Φ, dΦ/dq,
dΦ/dv), either may be None.  q holds the coordinates (a quaternion's four).  soadyn.tracking_cost
makes the tracking of a logged run.)")
      .def(py::init(&python_cost), "running"_a = py::none(), "terminal"_a = py::none())
      .def_property_readonly("has_running", [](const Cost& c) { return bool(c.running); })
      .def_property_readonly("has_terminal", [](const Cost& c) { return bool(c.terminal); });
  m.def(
      "_tracking_cost",
      [](const Model& model, const py::object& t, const py::object& q, const py::object& v, const py::object& wq,
         const py::object& wv, const py::object& wq_final, const py::object& wv_final) {
        const ArrayIn ta = ArrayIn::ensure(t);
        if (!ta || ta.ndim() != 1) throw Error("tracking_cost: t must be a 1-D array");
        TrackingWeights w;
        w.q = weights(wq, model.nq, "q weights");
        w.v = weights(wv, model.nv, "v weights");
        w.q_final = weights(wq_final, model.nq, "q_final weights");
        w.v_final = weights(wv_final, model.nv, "v_final weights");
        return tracking_cost(model, read_vector("tracking_cost", "t", ta, int(ta.shape(0))),
                             read_matrix("tracking_cost", "q", ArrayIn::ensure(q)),
                             read_matrix("tracking_cost", "v", ArrayIn::ensure(v)), w);
      },
      "model"_a, "t"_a, "q"_a, "v"_a, "q_weights"_a, "v_weights"_a, "q_final_weights"_a, "v_final_weights"_a);
  m.def(
      "_gradient",
      [](const Scenario& sc, const SimulationSettings& settings, const Cost& cost, bool initial_state,
         const std::vector<std::string>& parameters, long steps_per_checkpoint) {
        CostGradient g;
        std::exception_ptr failure;
        {
          py::gil_scoped_release nogil;
          try {
            g = gradient(sc, settings, cost, SensitivitySettings{initial_state, parameters}, steps_per_checkpoint);
          } catch (...) {
            failure = std::current_exception();
          }
        }
        if (failure) std::rethrow_exception(failure);
        return py::dict("cost"_a = g.cost, "initial_state"_a = owned(std::move(g.d_initial_state)),
                        "parameters"_a = owned(std::move(g.d_parameters)), "state_names"_a = g.state_names,
                        "parameter_names"_a = g.parameter_names, "forward_steps"_a = g.forward_steps,
                        "backward_steps"_a = g.backward_steps, "checkpoints"_a = g.checkpoints,
                        "forward_rhs_evals"_a = g.forward_rhs_evals, "backward_rhs_evals"_a = g.backward_rhs_evals,
                        "cpu_seconds"_a = g.cpu_seconds);
      },
      "scene"_a, "settings"_a, "cost"_a, "initial_state"_a, "parameters"_a, "steps_per_checkpoint"_a,
      "The run behind soadyn.gradient: a dict of the cost, its gradients, their names and the runs' counters.");
}

}  // namespace soadyn::python
