// soadyn.batch (many states per call) and soadyn.rollout (many simulations per call), both
// without the GIL.  Arrays are (K, n) row-major: batch.hpp's n×K column-major matrices in place,
// so a C-contiguous float64 array goes in without a copy (anything else is converted once) and
// results come out as new arrays written in place by the library.
#include "common.hpp"

#include "soadyn/algorithm/batch.hpp"
#include "soadyn/sim/rollout.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/multibody/text.hpp"

#include <csignal>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <exception>
#include <memory>
#include <mutex>

namespace soadyn::python {

namespace {

using CArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Map = Eigen::Map<const MatX>;
using MapOut = Eigen::Map<MatX>;

std::string shape_of(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t k = 0; k < a.ndim(); ++k) s += (k ? ", " : "") + std::to_string(a.shape(k));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// (K, n) → n×K, checked: K from the first array (K < 0), then the same K for the others
struct Arg {
  CArray array;
  Map map{nullptr, 0, 0};
};

Arg read_states(const char* where, const char* what, py::handle h, int n, const char* n_name, py::ssize_t& K,
                const char* K_from) {
  Arg a;
  a.array = CArray::ensure(h);
  if (!a.array)
    throw py::type_error(std::string(where) + ": " + what + ": expected an array of numbers, got " +
                         std::string(py::str(py::type::handle_of(h).attr("__name__"))));
  const bool ok = a.array.ndim() == 2 && a.array.shape(1) == n && (K < 0 || a.array.shape(0) == K);
  if (!ok) {
    std::string expected = K < 0 ? "(K, " + std::to_string(n) + ")" : "(" + std::to_string(K) + ", " + std::to_string(n) + ")";
    throw Error(std::string(where) + ": " + what + ": expected shape " + expected + " (K states × " + n_name +
                (K < 0 ? "" : std::string(", K from ") + K_from) + "), got " + shape_of(a.array));
  }
  if (K < 0) K = a.array.shape(0);
  new (&a.map) Map(a.array.data(), n, K);
  if (!a.map.allFinite()) {
    for (py::ssize_t k = 0; k < K; ++k)
      for (int i = 0; i < n; ++i)
        if (!std::isfinite(a.map(i, k))) {
          char value[32];
          std::snprintf(value, sizeof value, "%g", a.map(i, k));
          throw Error(std::string(where) + ": " + what + "[" + std::to_string(k) + ", " + std::to_string(i) +
                      "] = " + value + ": expected a finite number");
        }
  }
  return a;
}

py::array new_array(std::vector<py::ssize_t> shape) { return py::array_t<double>(std::move(shape)); }
double* ptr(py::array& a) { return static_cast<double*>(a.mutable_data()); }
// (K, nv, nv) whose block k is the column-major nv×nv of state k: the C array read transposed
py::object blocks(py::array a) { return a.attr("transpose")(0, 2, 1); }

int threads_arg(const char* where, int threads) {
  if (threads < 0) throw Error(std::string(where) + ": threads: expected ≥ 0 (0: one per core), got " + std::to_string(threads));
  return threads;
}

// the library call without the GIL; its exceptions rethrown with the GIL held
template <class F>
void nogil(F&& f) {
  std::exception_ptr failure;
  {
    py::gil_scoped_release release;
    try {
      f();
    } catch (...) {
      failure = std::current_exception();
    }
  }
  if (failure) std::rethrow_exception(failure);
}

// A Pool for Python: the library's Pool (one Data per thread, kept between calls) and a lock, so
// that two Python threads sharing it take turns rather than share a Data.
struct PyPool {
  PyPool(const Model& m, int threads) : pool(m, threads) {}
  batch::Pool pool;
  std::mutex busy;
};

// the library call on the pool, without the GIL; its exceptions rethrown with the GIL held
template <class F>
void on(PyPool& p, F&& f) {
  nogil([&] {
    std::lock_guard<std::mutex> lock(p.busy);
    f(p.pool);
  });
}

py::object forward_dynamics(PyPool& p, py::handle q, py::handle v, py::handle tau, const std::string& method) {
  const Model& m = p.pool.model();
  const char* where = "batch.forward_dynamics";
  py::ssize_t K = -1;
  const Arg Q = read_states(where, "q", q, m.nq, "nq", K, "q");
  const Arg V = read_states(where, "v", v, m.nv, "nv", K, "q");
  const Arg T = read_states(where, "tau", tau, m.nv, "nv", K, "q");
  const FdMethod fd = parse_fd_method(method);
  py::array out = new_array({K, m.nv});
  MapOut QDD(ptr(out), m.nv, K);
  on(p, [&](batch::Pool& pool) { batch::forward_dynamics(pool, Q.map, V.map, T.map, QDD, fd); });
  return out;
}

py::object mass_matrix(PyPool& p, py::handle q) {
  const Model& m = p.pool.model();
  py::ssize_t K = -1;
  const Arg Q = read_states("batch.mass_matrix", "q", q, m.nq, "nq", K, "q");
  py::array out = new_array({K, m.nv, m.nv});
  MapOut M(ptr(out), m.nv, m.nv * K);
  on(p, [&](batch::Pool& pool) { batch::mass_matrix(pool, Q.map, M); });
  return out;  // symmetric: each block reads the same either way
}

py::object bias_forces(PyPool& p, py::handle q, py::handle v) {
  const Model& m = p.pool.model();
  py::ssize_t K = -1;
  const Arg Q = read_states("batch.bias_forces", "q", q, m.nq, "nq", K, "q");
  const Arg V = read_states("batch.bias_forces", "v", v, m.nv, "nv", K, "q");
  py::array out = new_array({K, m.nv});
  MapOut B(ptr(out), m.nv, K);
  on(p, [&](batch::Pool& pool) { batch::bias_forces(pool, Q.map, V.map, B); });
  return out;
}

py::object inverse_dynamics(PyPool& p, py::handle q, py::handle v, py::handle qdd) {
  const Model& m = p.pool.model();
  const char* where = "batch.inverse_dynamics";
  py::ssize_t K = -1;
  const Arg Q = read_states(where, "q", q, m.nq, "nq", K, "q");
  const Arg V = read_states(where, "v", v, m.nv, "nv", K, "q");
  const Arg A = read_states(where, "qdd", qdd, m.nv, "nv", K, "q");
  py::array out = new_array({K, m.nv});
  MapOut TAU(ptr(out), m.nv, K);
  on(p, [&](batch::Pool& pool) { batch::inverse_dynamics(pool, Q.map, V.map, A.map, TAU); });
  return out;
}

py::object inverse_dynamics_derivatives(PyPool& p, py::handle q, py::handle v, py::handle qdd) {
  const Model& m = p.pool.model();
  const char* where = "batch.inverse_dynamics_derivatives";
  py::ssize_t K = -1;
  const Arg Q = read_states(where, "q", q, m.nq, "nq", K, "q");
  const Arg V = read_states(where, "v", v, m.nv, "nv", K, "q");
  const Arg A = read_states(where, "qdd", qdd, m.nv, "nv", K, "q");
  py::array dq = new_array({K, m.nv, m.nv}), dv = new_array({K, m.nv, m.nv});
  MapOut DQ(ptr(dq), m.nv, m.nv * K), DV(ptr(dv), m.nv, m.nv * K);
  on(p, [&](batch::Pool& pool) { batch::inverse_dynamics_derivatives(pool, Q.map, V.map, A.map, DQ, DV); });
  return py::make_tuple(blocks(dq), blocks(dv));
}

// (∂q̈/∂q, ∂q̈/∂v, 𝓜⁻¹ or None): always three, the last None with minv=False
py::object forward_dynamics_derivatives(PyPool& p, py::handle q, py::handle v, py::handle tau, bool minv) {
  const Model& m = p.pool.model();
  const char* where = "batch.forward_dynamics_derivatives";
  py::ssize_t K = -1;
  const Arg Q = read_states(where, "q", q, m.nq, "nq", K, "q");
  const Arg V = read_states(where, "v", v, m.nv, "nv", K, "q");
  const Arg T = read_states(where, "tau", tau, m.nv, "nv", K, "q");
  py::array dq = new_array({K, m.nv, m.nv}), dv = new_array({K, m.nv, m.nv});
  py::array mi = new_array({minv ? K : 0, m.nv, m.nv});
  MapOut DQ(ptr(dq), m.nv, m.nv * K), DV(ptr(dv), m.nv, m.nv * K), MI(ptr(mi), m.nv, minv ? m.nv * K : 0);
  on(p, [&](batch::Pool& pool) {
    batch::Out mi_out(MI);
    batch::forward_dynamics_derivatives(pool, Q.map, V.map, T.map, DQ, DV, minv ? &mi_out : nullptr);
  });
  return py::make_tuple(blocks(dq), blocks(dv), minv ? py::object(blocks(mi)) : py::object(py::none()));
}

// The old names, kept one release: a DeprecationWarning naming the new one, then the same call
// (fd_derivatives with its old shapes: two arrays with minv=False)
void deprecated(const char* old, const char* now) {
  const std::string what = std::string("soadyn.batch: ") + old + " is deprecated and goes in the next release: use " + now;
  if (PyErr_WarnEx(PyExc_DeprecationWarning, what.c_str(), 1) < 0) throw py::error_already_set();
}
py::object bias_old(PyPool& p, py::handle q, py::handle v) {
  deprecated("bias", "bias_forces");
  return bias_forces(p, q, v);
}
py::object id_derivatives_old(PyPool& p, py::handle q, py::handle v, py::handle qdd) {
  deprecated("id_derivatives", "inverse_dynamics_derivatives");
  return inverse_dynamics_derivatives(p, q, v, qdd);
}
py::object fd_derivatives_old(PyPool& p, py::handle q, py::handle v, py::handle tau, bool minv) {
  deprecated("fd_derivatives", "forward_dynamics_derivatives");
  py::tuple r = forward_dynamics_derivatives(p, q, v, tau, minv);
  return minv ? py::object(r) : py::object(py::make_tuple(r[0], r[1]));
}

// a frame by name (KeyError with the nearest one) or by index
int frame_of(const Model& m, const py::object& f, const char* where) {
  if (py::isinstance<py::str>(f)) {
    const std::string name = f.cast<std::string>();
    const int i = m.frame_index(name);
    if (i < 0) throw py::key_error("no frame named '" + printable(name) + "'" + did_you_mean(name, m.frame_names));
    return i;
  }
  if (py::isinstance<py::int_>(f) && !py::isinstance<py::bool_>(f)) return int(f.cast<long>());  // range: the library
  throw py::type_error(std::string(where) + ": frame: expected a frame name or index, got " +
                       std::string(py::str(py::type::handle_of(f).attr("__name__"))));
}

py::object frame_jacobian(PyPool& p, py::handle q, const py::object& frame, const std::string& reference) {
  const Model& m = p.pool.model();
  const char* where = "batch.frame_jacobian";
  const int f = frame_of(m, frame, where);
  const Reference r = parse_reference(reference);
  py::ssize_t K = -1;
  const Arg Q = read_states(where, "q", q, m.nq, "nq", K, "q");
  py::array out = new_array({K, m.nv, 6});
  MapOut J(ptr(out), 6, m.nv * K);
  on(p, [&](batch::Pool& pool) { batch::frame_jacobian(pool, Q.map, f, r, J); });
  return blocks(out);
}

// Each function twice: soadyn.batch.f(model, …, threads=1), with a Pool made for the call, and
// Pool.f(…) on a Pool kept by the caller (no Data made per call)
struct Doc {
  const char* forward_dynamics = "q̈ = 𝓜⁻¹ (τ − bias) of each state: q (K, nq), v and tau (K, nv) → (K, nv).";
  const char* mass_matrix =
      "𝓜(q) of each state, as mass_matrix(…, kinematics=False) (body axes): q (K, nq) → (K, nv, nv).";
  const char* bias_forces =
      "bias(q, q̇) of each state, as bias_forces(…, kinematics=False) (body axes): q (K, nq), v (K, nv) → (K, nv).";
  const char* inverse_dynamics = "τ = 𝓜 q̈ + bias of each state: q (K, nq), v and qdd (K, nv) → (K, nv).";
  const char* inverse_dynamics_derivatives =
      "(∂τ/∂q, ∂τ/∂v) of each state, as inverse_dynamics_derivatives: q (K, nq), v and qdd (K, nv) → two (K, nv, nv).";
  const char* forward_dynamics_derivatives =
      "(∂q̈/∂q, ∂q̈/∂v, 𝓜⁻¹) of each state, as forward_dynamics_derivatives: q (K, nq), v and tau (K, nv) → three\n"
      "(K, nv, nv), always three: with minv=False the last is None (∂q̈/∂τ = 𝓜⁻¹ is then not copied out).";
  const char* bias_old = "Deprecated: bias_forces (the same arguments and results).";
  const char* id_derivatives_old = "Deprecated: inverse_dynamics_derivatives (the same arguments and results).";
  const char* fd_derivatives_old =
      "Deprecated: forward_dynamics_derivatives (the same arguments; two arrays with minv=False, where the new name "
      "returns three, the last None).";
  const char* frame_jacobian =
      "J of the frame (a name or index of model.frame_names) at each state, as frame_jacobian: q (K, nq) → (K, 6, nv)\n"
      "(reference: world, local or local_world_aligned).";
};

void bind_batch_functions(py::module_& b) {
  b.doc() = R"(Many states per call: each function takes (K, nq) and (K, nv) arrays, one row per state, and
returns new arrays, (K, nv) or (K, nv, nv), computed without the GIL on `threads` threads
(0: one per core; a batch too small to be worth a thread start stays on the calling thread).
Results are bitwise those of the single-state functions in a loop, whatever the thread count.
C-contiguous float64 inputs are read in place.  Pool(model, threads) keeps the per-thread Data
between calls, for small batches called often: pool.forward_dynamics(q, v, tau), ….)";
  const Doc doc;
  auto pool = [](const Model& m, int threads) { return std::make_unique<PyPool>(m, threads_arg("batch", threads)); };
  b.def("forward_dynamics", [pool](const Model& m, py::handle q, py::handle v, py::handle tau, const std::string& method,
                                   int threads) { return forward_dynamics(*pool(m, threads), q, v, tau, method); },
        "model"_a, "q"_a, "v"_a, "tau"_a, "method"_a = "aba", "threads"_a = 1, doc.forward_dynamics);
  b.def("mass_matrix", [pool](const Model& m, py::handle q, int threads) { return mass_matrix(*pool(m, threads), q); },
        "model"_a, "q"_a, "threads"_a = 1, doc.mass_matrix);
  b.def("bias_forces", [pool](const Model& m, py::handle q, py::handle v, int threads) {
        return bias_forces(*pool(m, threads), q, v);
      }, "model"_a, "q"_a, "v"_a, "threads"_a = 1, doc.bias_forces);
  b.def("inverse_dynamics", [pool](const Model& m, py::handle q, py::handle v, py::handle qdd, int threads) {
        return inverse_dynamics(*pool(m, threads), q, v, qdd);
      }, "model"_a, "q"_a, "v"_a, "qdd"_a, "threads"_a = 1, doc.inverse_dynamics);
  b.def("inverse_dynamics_derivatives", [pool](const Model& m, py::handle q, py::handle v, py::handle qdd, int threads) {
        return inverse_dynamics_derivatives(*pool(m, threads), q, v, qdd);
      }, "model"_a, "q"_a, "v"_a, "qdd"_a, "threads"_a = 1, doc.inverse_dynamics_derivatives);
  b.def("forward_dynamics_derivatives", [pool](const Model& m, py::handle q, py::handle v, py::handle tau, bool minv,
                                               int threads) {
        return forward_dynamics_derivatives(*pool(m, threads), q, v, tau, minv);
      }, "model"_a, "q"_a, "v"_a, "tau"_a, "minv"_a = true, "threads"_a = 1, doc.forward_dynamics_derivatives);
  b.def("bias", [pool](const Model& m, py::handle q, py::handle v, int threads) { return bias_old(*pool(m, threads), q, v); },
        "model"_a, "q"_a, "v"_a, "threads"_a = 1, doc.bias_old);
  b.def("id_derivatives", [pool](const Model& m, py::handle q, py::handle v, py::handle qdd, int threads) {
        return id_derivatives_old(*pool(m, threads), q, v, qdd);
      }, "model"_a, "q"_a, "v"_a, "qdd"_a, "threads"_a = 1, doc.id_derivatives_old);
  b.def("fd_derivatives", [pool](const Model& m, py::handle q, py::handle v, py::handle tau, bool minv, int threads) {
        return fd_derivatives_old(*pool(m, threads), q, v, tau, minv);
      }, "model"_a, "q"_a, "v"_a, "tau"_a, "minv"_a = true, "threads"_a = 1, doc.fd_derivatives_old);
  b.def("frame_jacobian", [pool](const Model& m, py::handle q, const py::object& frame, const std::string& reference,
                                 int threads) { return frame_jacobian(*pool(m, threads), q, frame, reference); },
        "model"_a, "q"_a, "frame"_a, "reference"_a = "local_world_aligned", "threads"_a = 1, doc.frame_jacobian);

  py::class_<PyPool>(b, "Pool", "One Data per thread for a model, kept between batched calls (soadyn::batch::Pool).")
      .def(py::init([](const Model& m, int threads) { return new PyPool(m, threads_arg("batch.Pool", threads)); }),
           "model"_a, "threads"_a = 1, py::keep_alive<1, 2>())
      .def_property_readonly("threads", [](const PyPool& p) { return p.pool.threads(); })
      .def("forward_dynamics", &forward_dynamics, "q"_a, "v"_a, "tau"_a, "method"_a = "aba", doc.forward_dynamics)
      .def("mass_matrix", &mass_matrix, "q"_a, doc.mass_matrix)
      .def("bias_forces", &bias_forces, "q"_a, "v"_a, doc.bias_forces)
      .def("inverse_dynamics", &inverse_dynamics, "q"_a, "v"_a, "qdd"_a, doc.inverse_dynamics)
      .def("inverse_dynamics_derivatives", &inverse_dynamics_derivatives, "q"_a, "v"_a, "qdd"_a,
           doc.inverse_dynamics_derivatives)
      .def("forward_dynamics_derivatives", &forward_dynamics_derivatives, "q"_a, "v"_a, "tau"_a, "minv"_a = true,
           doc.forward_dynamics_derivatives)
      .def("bias", &bias_old, "q"_a, "v"_a, doc.bias_old)
      .def("id_derivatives", &id_derivatives_old, "q"_a, "v"_a, "qdd"_a, doc.id_derivatives_old)
      .def("fd_derivatives", &fd_derivatives_old, "q"_a, "v"_a, "tau"_a, "minv"_a = true, doc.fd_derivatives_old)
      .def("frame_jacobian", &frame_jacobian, "q"_a, "frame"_a, "reference"_a = "local_world_aligned", doc.frame_jacobian);
}

// soadyn sweep's runs of one scenario from K initial states (simulate_states, rollout.hpp): per run
// (refusal or None, summary dict, warnings, E at t = 0, t (T,) and [q v] (T, nq + nv) or None);
// a Python signal handler's exception (Ctrl-C) is raised once the runs have stopped
py::list run_states(const Scenario& sc, const SimulationSettings& settings, py::handle q0, py::handle v0, int threads,
                    bool states) {
  const char* where = "simulate_states";
  py::ssize_t K = -1;
  const Arg Q0 = read_states(where, "q0", q0, sc.model.nq, "nq", K, "");
  const Arg V0 = read_states(where, "v0", v0, sc.model.nv, "nv", K, "q0");
  std::atomic<int> stop{0};
  py::object pending = py::none();
  const std::function<void()> poll = signal_poll(stop, pending);
  std::vector<StateRun> runs;
  nogil([&] { runs = simulate_states(sc, settings, Q0.map, V0.map, threads_arg(where, threads), states, &stop, poll); });
  if (!pending.is_none()) {  // the handler's exception as raised (KeyboardInterrupt): the runs are dropped
    PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(pending.ptr())), pending.ptr());
    throw py::error_already_set();
  }
  const py::ssize_t ny = sc.model.nq + sc.model.nv;
  py::list out;
  for (StateRun& r : runs) {
    if (!r.ran) {
      out.append(py::make_tuple(r.refused, py::none(), py::list(), 0.0, py::none(), py::none()));
      continue;
    }
    const RunSummary& s = r.summary;
    py::dict summary("status"_a = s.status, "completed"_a = s.completed, "t_reached"_a = s.t_reached,
                     "steps"_a = s.stats.steps, "rhs_evals"_a = s.stats.rhs_evals, "cpu_seconds"_a = s.cpu_seconds,
                     "max_energy_balance_error"_a = s.max_energy_balance_error,
                     "final_energy_balance_error"_a = s.final_energy_balance_error);
    const py::ssize_t T = py::ssize_t(r.t.size());
    out.append(py::make_tuple(py::none(), summary, r.warnings, r.initial_energy,
                              states ? py::object(owned(std::move(r.t), {T})) : py::none(),
                              states ? py::object(owned(std::move(r.y), {T, ny})) : py::none()));
  }
  return out;
}

// The scene: a Model (no inputs, rk4 at dt = 1e-3 unless told), a Scenario or a scenario file
struct Scene {
  std::optional<Scenario> loaded;  // a scenario file's
  const Model* model = nullptr;
  const Inputs* inputs = nullptr;
  RolloutSettings rs;
};
// `scene` read: its model, its inputs and settings (a scenario's) or none and the defaults (a Model's)
void read_scene(const char* where, const py::object& scene, Scene& out) {
  static const Inputs no_inputs;
  out.inputs = &no_inputs;
  if (py::isinstance<py::str>(scene)) out.loaded = load_scenario(scene.cast<std::string>());
  if (out.loaded || py::isinstance<Scenario>(scene)) {
    const Scenario& sc = out.loaded ? *out.loaded : scene.cast<const Scenario&>();
    check_rollout_scene(sc);  // its controllers and limits: not applied, so refused
    out.model = &sc.model;
    out.inputs = &sc.inputs;
    out.rs = rollout_settings(sc.simulation);
  } else if (py::isinstance<Model>(scene)) {
    out.model = &scene.cast<const Model&>();
  } else {
    throw py::type_error(std::string(where) + ": scene: expected a soadyn.Model, a soadyn.Scenario or a scenario path, got " +
                         std::string(py::str(py::type::handle_of(scene).attr("__name__"))));
  }
}

// a control callback control(k, s, t, y) -> (nv,) as the library calls it: τ for rollout k at step s
ControlFn control_callback(const py::object& controls, int nv, int ny) {
  return [fn = &controls, nv, ny](long k, long s, double t, const double* y, double* tau) {
    py::gil_scoped_acquire gil;
    py::array_t<double> state(ny);
    std::memcpy(state.mutable_data(), y, sizeof(double) * size_t(ny));
    const py::object r = (*fn)(k, s, t, state);
    const CArray u = CArray::ensure(r);
    if (!u || u.ndim() != 1 || u.shape(0) != nv)
      throw Error("rollout: controls: the callback must return " + std::to_string(nv) + " numbers (nv,), got " +
                  (u ? shape_of(u) : std::string(py::str(py::type::handle_of(r).attr("__name__")))) +
                  " for rollout " + std::to_string(k) + ", step " + std::to_string(s));
    for (int i = 0; i < nv; ++i)
      if (!std::isfinite(u.data()[i])) {
        char value[32];
        std::snprintf(value, sizeof value, "%g", u.data()[i]);
        throw Error("rollout: controls: the callback returned " + std::string(value) + " at entry " + std::to_string(i) +
                    " for rollout " + std::to_string(k) + ", step " + std::to_string(s) + ": expected finite numbers");
      }
    std::memcpy(tau, u.data(), sizeof(double) * size_t(nv));
  };
}

// The controls: an array (K, T, nv) or a callable control(k, s, t, y) -> (nv,)
struct Controls {
  CArray U;
  std::optional<Map> U_map;  // U's K T columns of nv
  ControlFn callback;
};
// controls: None, an array (K, T, nv), or a callable control(k, s, t, y) -> (nv,); sets rs.steps (T)
void read_controls(const py::object& controls, std::optional<long> steps, int nv, int ny, py::ssize_t K,
                   RolloutSettings& rs, Controls& c) {
  if (!controls.is_none() && PyCallable_Check(controls.ptr())) {
    if (!steps) throw Error("rollout: steps: expected the number of steps T with a control callback");
    rs.steps = *steps;
    c.callback = control_callback(controls, nv, ny);
  } else if (!controls.is_none()) {
    c.U = CArray::ensure(controls);
    const CArray& U = c.U;
    if (!U || U.ndim() != 3 || U.shape(0) != K || U.shape(2) != nv || (steps && U.shape(1) != *steps))
      throw Error("rollout: controls: expected shape (" + std::to_string(K) + ", " + (steps ? std::to_string(*steps) : "T") +
                  ", " + std::to_string(nv) + ") (K rollouts × T steps × nv, K from initial_states), got " +
                  (U ? shape_of(U) : "no array"));
    rs.steps = long(U.shape(1));
    c.U_map.emplace(U.data(), nv, rs.steps * K);
    if (!c.U_map->allFinite()) {  // named by (k, s, i), as the caller indexes it
      const auto u = U.unchecked<3>();
      for (py::ssize_t k = 0; k < K; ++k)
        for (py::ssize_t s = 0; s < U.shape(1); ++s)
          for (int i = 0; i < nv; ++i)
            if (!std::isfinite(u(k, s, i))) {
              char value[32];
              std::snprintf(value, sizeof value, "%g", u(k, s, i));
              throw Error("rollout: controls[" + std::to_string(k) + ", " + std::to_string(s) + ", " + std::to_string(i) +
                          "] = " + value + ": expected a finite number");
            }
    }
  } else {
    if (!steps) throw Error("rollout: steps: expected the number of steps T (or controls of shape (K, T, nv))");
    rs.steps = *steps;
  }
}

// (states, energies or None, status list, exception raised by a signal handler or None)
py::tuple run_rollout(py::object scene, py::handle initial_states, py::object controls, std::optional<long> steps,
                      std::optional<double> dt, std::optional<std::string> method, int threads,
                      std::optional<std::string> dynamics, std::optional<double> rtol, std::optional<double> atol,
                      bool energies) {
  const char* where = "rollout";
  Scene scn;
  read_scene(where, scene, scn);
  const Model& m = *scn.model;
  RolloutSettings& rs = scn.rs;
  // the words as a scenario takes them (the table's, settings.hpp): the same refusals, on for aba
  SimulationSettings words;
  if (method) {
    set_setting(words, *find_setting("method"), *method);
    rs.method = words.method;
  }
  if (dynamics) {
    set_setting(words, *find_setting("dynamics"), *dynamics);
    rs.dynamics = words.dynamics;
  }
  if (dt) rs.dt = *dt;
  if (rtol) rs.rtol = *rtol;
  if (atol) rs.atol = *atol;
  rs.threads = threads_arg(where, threads);
  rs.energies = energies;
  const int ny = m.nq + m.nv;
  py::ssize_t K = -1;
  const Arg Y0 = read_states(where, "initial_states", initial_states, ny, "nq + nv", K, "");
  Controls c;
  read_controls(controls, steps, m.nv, ny, K, rs, c);
  if (rs.steps < 0) throw Error("rollout: steps: expected T ≥ 0, got " + std::to_string(rs.steps));
  const py::ssize_t T = rs.steps;
  py::array states = new_array({K, T, ny});
  py::array energy = new_array({K, energies ? T : 0});
  MapOut S(ptr(states), ny, T * K), E(ptr(energy), energies ? T : 0, K);
  // Ctrl-C: on Python's main thread the library polls Python's signal handlers every 10 ms
  std::atomic<int> stop{0};
  py::object pending = py::none();
  const std::function<void()> poll = signal_poll(stop, pending);
  RolloutReport report;
  nogil([&] {
    const batch::In Y(Y0.map);
    std::optional<batch::In> Uin;
    if (c.U_map) Uin.emplace(*c.U_map);
    report = rollout(m, *scn.inputs, Y, Uin ? &*Uin : nullptr, c.callback ? &c.callback : nullptr, rs, S, E, &stop, poll);
  });
  return py::make_tuple(states, energies ? py::object(energy) : py::none(), report.status, pending);
}

}  // namespace

void bind_batch(py::module_& m) {
  py::module_ b = m.def_submodule("batch", "Many states per call (soadyn::batch)");
  bind_batch_functions(b);
  m.def("_rollout", &run_rollout, "scene"_a, "initial_states"_a, "controls"_a = py::none(), "steps"_a = py::none(),
        "dt"_a = py::none(), "method"_a = py::none(), "threads"_a = 1, "dynamics"_a = py::none(), "rtol"_a = py::none(),
        "atol"_a = py::none(), "energies"_a = true,
        "The rollouts behind soadyn.rollout: (states, energies or None, status per rollout, exception from a signal "
        "handler or None).");
  m.def("_simulate_states", &run_states, "scene"_a, "settings"_a, "q0"_a, "v0"_a, "threads"_a = 1, "states"_a = false,
        "soadyn sweep's runs of one scene from K initial states, each exactly soadyn.simulate's: per run (refusal or "
        "None, summary, warnings, E(0), t or None, [q v] or None).");
}

}  // namespace soadyn::python
