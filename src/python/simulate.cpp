// soadyn._simulate: a run on the calling thread without the GIL.  On Python's main thread it stops
// every 10 ms between integrator steps to let Python's signal handlers run; one that raises
// (Ctrl-C: KeyboardInterrupt) sets the library's stop flag, the run ends before its next step, and
// the log is finished.  (Elsewhere handlers cannot run: Python runs them on the main thread only.)
// No thread of its own: a short run in a loop or a sweep pays no thread start and no hand-over.
#include "common.hpp"

#include "soadyn/io/run.hpp"
#include "soadyn/sim/sensitivity.hpp"
#include "soadyn/sim/simulate.hpp"
#include "soadyn/multibody/text.hpp"
#include "soadyn/io/version.hpp"

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <exception>
#include <memory>

namespace soadyn::python {

namespace {

py::dict summary_dict(const RunSummary& r) {
  return py::dict("method"_a = r.method, "status"_a = r.status, "completed"_a = r.completed, "t_reached"_a = r.t_reached,
                  "steps"_a = r.stats.steps, "rhs_evals"_a = r.stats.rhs_evals, "jac_evals"_a = r.stats.jac_evals,
                  "error_test_failures"_a = r.stats.error_test_failures,
                  "nonlinear_iterations"_a = r.stats.nonlinear_iterations, "cpu_seconds"_a = r.cpu_seconds,
                  "quaternion_handling"_a = r.quaternion_handling, "output_dt"_a = r.output_dt,
                  "max_energy_balance_error"_a = r.max_energy_balance_error,
                  "final_energy_balance_error"_a = r.final_energy_balance_error);
}


// (arrays, summary, exception raised by a signal handler or None, warnings)
// A Python controller f(t, q, v) -> tau as a ControlFunction: the GIL taken for the call only.  An
// exception it raises is kept (`raised`, re-raised by soadyn.simulate once the file is finished)
// and ends the run; so does a τ that is not nv finite numbers, kept as a soadyn.Error naming the
// time and what was wrong.
ControlFunction python_controller(const py::object& f, const Model& model, py::object& raised) {
  return [&f, &raised, nv = model.nv, names = model.v_names()](double t, const VecX& q, const VecX& v,
                                                                 Eigen::Ref<VecX> tau) {
    py::gil_scoped_acquire gil;
    char at[32];
    std::snprintf(at, sizeof at, "%.9g", t);
    // a τ the run cannot take: soadyn.Error, raised by soadyn.simulate once the file is finished
    auto fail = [&](const std::string& why) {
      raised = py::handle(error_type)(why);
      throw SimulationError(why, t);
    };
    py::object out;
    try {
      out = f(t, py::array_t<double>(q.size(), q.data()), py::array_t<double>(v.size(), v.data()));
    } catch (py::error_already_set& e) {
      raised = e.value();
      throw SimulationError(std::string("the controller raised at t = ") + at + " s: " + e.what(), t);
    }
    py::array_t<double, py::array::forcecast> a;
    try {
      a = py::array_t<double, py::array::forcecast>::ensure(out);
    } catch (py::error_already_set&) {
    }
    if (!a || a.ndim() != 1 || a.shape(0) != nv) {
      std::string got = a ? "shape (" : "";
      if (a)
        for (py::ssize_t k = 0; k < a.ndim(); ++k) got += (k ? ", " : "") + std::to_string(a.shape(k));
      got = a ? got + (a.ndim() == 1 ? ",)" : ")") : std::string(py::str(py::type::of(out).attr("__name__")));
      fail(std::string("the controller returned ") + got + " at t = " + at + " s; expected " + std::to_string(nv) +
           " torques, shape (" + std::to_string(nv) + ",)");
    }
    for (int k = 0; k < nv; ++k)
      if (!std::isfinite(a.at(k)))
        fail(std::string("the controller returned a non-finite torque at t = ") + at + " s (" + printable(names[size_t(k)]) +
             " = " + short_number(a.at(k)) + ")");
    for (int k = 0; k < nv; ++k) tau(k) += a.at(k);
  };
}

// A Python motion f(t) -> (q, qd, qdd) as a prescribed joint's function: the GIL taken for the
// call only; an exception it raises (kept in `raised`) or a result that is not three finite
// numbers ends the run there, as a controller's does.
std::function<void(double, double&, double&, double&)> python_motion(const py::object& callable,
                                                                     const std::string& joint, py::object& raised) {
  // held by a shared pointer, so that copies of the function made without the GIL touch no
  // reference count; the last one lets go of the callable with the GIL
  std::shared_ptr<py::object> held(new py::object(callable), [](py::object* o) {
    py::gil_scoped_acquire gil;
    delete o;
  });
  return [held, joint, &raised](double t, double& q, double& qd, double& qdd) {
    py::gil_scoped_acquire gil;
    const py::object& f = *held;
    char at[32];
    std::snprintf(at, sizeof at, "%.9g", t);
    std::string why;
    try {
      const py::tuple out = py::tuple(f(t));
      if (out.size() == 3) {
        q = out[0].cast<double>(), qd = out[1].cast<double>(), qdd = out[2].cast<double>();
        if (std::isfinite(q) && std::isfinite(qd) && std::isfinite(qdd)) return;
        why = "prescribed motion of joint '" + joint + "' returned a non-finite value at t = " + at + " s";
      } else {
        why = "prescribed motion of joint '" + joint + "' returned " + std::to_string(out.size()) +
              " values at t = " + at + " s; expected (q, qd, qdd)";
      }
    } catch (py::error_already_set& e) {
      raised = e.value();
      throw SimulationError("the prescribed motion of joint '" + joint + "' raised at t = " + at + " s: " + e.what(), t);
    } catch (const py::cast_error&) {
      why = "prescribed motion of joint '" + joint + "' returned something other than (q, qd, qdd) at t = " + at + " s";
    }
    raised = py::handle(error_type)(why);
    throw SimulationError(why, t);
  };
}

// scene with the caller's prescribed joints: {joint: f(t) -> (q, qd, qdd)} over the scene's own
// (a joint the scene prescribes too takes the caller's); each joint's start from f(0)
Scenario with_prescribed(const Scenario& scene, const py::dict& prescribed, py::object& raised) {
  Scenario sc = scene;
  const Model& m = sc.model;
  for (const auto& [key, f] : prescribed) {
    const std::string joint = py::str(key);
    const int i = m.joint_index(joint);
    if (i < 0) throw Error("prescribed: no joint named '" + joint + "'" + did_you_mean(joint, m.joint_names));
    if (m.nv_i[i] != 1 || m.nq_i[i] != 1)
      throw Error("prescribed: joint '" + joint + "' is " + std::string(to_string(m.joint_type[i])) +
                  "; prescribed motion is for 1-DOF joints (revolute, prismatic, helical)");
    if (!PyCallable_Check(f.ptr())) throw Error("prescribed: joint '" + joint + "': expected a callable f(t) -> (q, qd, qdd)");
    std::erase_if(sc.inputs.prescribed, [&](const PrescribedInput& p) { return p.body == i; });
    PrescribedInput p;
    p.joint = joint, p.body = i, p.dof = m.idx_v[i], p.coord = m.idx_q[i];
    p.function = python_motion(py::reinterpret_borrow<py::object>(f), joint, raised);
    double q = 0, qd = 0, qdd = 0;
    p.at(0.0, q, qd, qdd);  // the GIL is held: the start, checked now
    sc.q0(p.coord) = q, sc.v0(p.dof) = qd;
    sc.inputs.prescribed.push_back(std::move(p));
  }
  return sc;
}

py::tuple run(const Scenario& scene, const SimulationSettings& settings, const std::optional<std::string>& output,
              const py::object& controller, const py::object& prescribed) {
  py::object raised = py::none();  // the controller's or a prescribed motion's exception
  const Scenario sc = prescribed.is_none() ? scene : with_prescribed(scene, prescribed.cast<py::dict>(), raised);
  // the run as C++'s simulate(sc, options) does it: everything checked before any file is touched
  SimulateOptions o;
  o.settings = settings;
  o.output = output.value_or("");
  std::atomic<int> stop{0};
  o.stop = &stop;
  py::object pending = py::none();
  o.poll = signal_poll(stop, pending);
  if (!controller.is_none()) o.controller = python_controller(controller, sc.model, raised);
  Trajectory tr;
  {
    py::gil_scoped_release nogil;
    tr = simulate(sc, o);
  }
  const RunSummary& summary = tr.summary;

  const py::ssize_t T = py::ssize_t(tr.size()), nq = sc.model.nq, nv = sc.model.nv, nb = sc.model.nbodies;
  py::dict arrays("t"_a = owned(std::move(tr.t)), "q"_a = owned(std::move(tr.q), {T, nq}),
                  "v"_a = owned(std::move(tr.v), {T, nv}), "qdd"_a = owned(std::move(tr.qdd), {T, nv}),
                  "kinetic_energy"_a = owned(std::move(tr.kinetic_energy)),
                  "potential_energy"_a = owned(std::move(tr.potential_energy)),
                  "total_energy"_a = owned(std::move(tr.total_energy)), "work_inputs"_a = owned(std::move(tr.work_inputs)),
                  "dissipated"_a = owned(std::move(tr.dissipated)), "impact_loss"_a = owned(std::move(tr.impact_loss)),
                  "control"_a = owned(std::move(tr.control), {T, nv}),
                  "body_position"_a = owned(std::move(tr.body_position), {T, nb, 3}),
                  "body_orientation"_a = owned(std::move(tr.body_orientation), {T, nb, 4}),
                  "body_com"_a = owned(std::move(tr.body_com), {T, nb, 3}),
                  "linear_momentum"_a = owned(std::move(tr.linear_momentum), {T, 3}),
                  "angular_momentum"_a = owned(std::move(tr.angular_momentum), {T, 3}),
                  "work_prescribed"_a = owned(std::move(tr.work_prescribed)),
                  "prescribed_torque"_a =
                      owned(std::move(tr.prescribed_torque), {T, py::ssize_t(tr.prescribed_joints.size())}),
                  "prescribed_joints"_a = tr.prescribed_joints,
                  "loop_forces"_a = owned(std::move(tr.loop_force), {T, py::ssize_t(tr.loop_rows.size())}),
                  "loop_rows"_a = tr.loop_rows, "loop_closure"_a = owned(std::move(tr.loop_closure)));
  if (settings.sensitivities.any()) {
    // (T, nx, nx) and (T, nx, np), with the names of x and π (sensitivity.hpp)
    const SensitivityPlan plan = plan_sensitivities(sc.model, settings.sensitivities, sc.inputs.prescribed);
    const py::ssize_t nx = plan.nx;
    arrays["sensitivity_initial_state"] =
        plan.initial_state ? py::object(owned(std::move(tr.sensitivity_initial_state), {T, nx, nx})) : py::object(py::none());
    arrays["sensitivity_parameters"] =
        plan.np() > 0 ? py::object(owned(std::move(tr.sensitivity_parameters), {T, nx, py::ssize_t(plan.np())}))
                      : py::object(py::none());
    arrays["sensitivity_names"] = py::dict("state"_a = plan.state_names, "state_units"_a = plan.state_units,
                                           "parameters"_a = plan.parameter_names, "parameter_units"_a = plan.parameter_units);
  }
  py::list events;
  for (const LimitEvent& e : summary.events)
    events.append(py::dict("t"_a = e.t, "joint"_a = e.joint, "side"_a = e.side < 0 ? "lower" : "upper", "kind"_a = e.kind,
                           "v_before"_a = e.v_before, "v_after"_a = e.v_after, "energy_lost"_a = e.energy_lost));
  py::dict sd = summary_dict(summary);
  sd["events"] = events;
  sd["control_ticks"] = summary.control_ticks;
  sd["stiffness_index"] = summary.stiffness_index;
  sd["stiffness_hint"] = summary.stiffness_hint;
  return py::make_tuple(arrays, sd, pending.is_none() ? raised : pending, tr.warnings);
}

}  // namespace

namespace {

// Python's main thread (where signal handlers run), as threading.main_thread().ident
unsigned long main_thread() {
  static const unsigned long ident = py::module_::import("threading").attr("main_thread")().attr("ident").cast<unsigned long>();
  return ident;
}

}  // namespace

// On Python's main thread: a poll that runs Python's signal handlers every 10 ms; one that raises
// (Ctrl-C: KeyboardInterrupt) has its exception kept in `pending` and sets `stop`.  Elsewhere none
// (handlers run on the main thread only).
std::function<void()> signal_poll(std::atomic<int>& stop, py::object& pending) {
  if (PyThread_get_thread_ident() != main_thread()) return {};
  return [&stop, &pending, last = std::chrono::steady_clock::now()]() mutable {
    if (stop.load(std::memory_order_relaxed) != 0) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last < std::chrono::milliseconds(10)) return;
    last = now;
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) {
      PyObject *type = nullptr, *value = nullptr, *trace = nullptr;
      PyErr_Fetch(&type, &value, &trace);
      PyErr_NormalizeException(&type, &value, &trace);
      if (trace) PyException_SetTraceback(value, trace);
      pending = py::reinterpret_steal<py::object>(value);
      Py_XDECREF(type);
      Py_XDECREF(trace);
      stop = PyErr_GivenExceptionMatches(pending.ptr(), PyExc_KeyboardInterrupt) ? SIGINT : -1;
    }
  };
}

void bind_simulate(py::module_& m) {
  m.def("_simulate", &run, "scene"_a, "settings"_a, "output"_a = py::none(), "controller"_a = py::none(),
        "prescribed"_a = py::none(),
        "The run behind soadyn.simulate: (arrays, summary, exception from a signal handler or the controller, or None, "
        "warnings).");
}

}  // namespace soadyn::python
