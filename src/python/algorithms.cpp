// The algorithms: f(model, data, q, …), each one update of the pipeline plus the algorithm, and a
// read-only view of the Data it filled (or a new array for results Data does not hold).
//
// These are the calls made in loops, so they are plain CPython functions with the vectorcall
// convention (positional or keyword arguments, no pybind11 dispatcher): a call adds a few hundred
// nanoseconds to the C++ time (tools/bench/python_overhead.py).
#include "common.hpp"

#include "soadyn/algorithm/derivatives.hpp"

#include <array>
#include <chrono>

namespace soadyn::python {

namespace {

// [kin] at q
void kin(const Model& model, PyData& d, const char* where, PyObject* q) {
  read_vector(model, *d.data, where, "q", q, model.nq, d.q);
  update_kinematics(model, *d.data, d.q);
}

// [kin] at q, then [vel] at v
void kin_vel(const Model& model, PyData& d, const char* where, PyObject* q, PyObject* v) {
  read_vector(model, *d.data, where, "v", v, model.nv, d.v);  // both sizes checked before any work
  kin(model, d, where, q);
  update_velocities(model, *d.data, d.v);
}

py::object none() { return py::none(); }

// the keyword kinematics=: True (the default when absent) or False, nothing else
bool kinematics_wanted(const char* where, PyObject* flag) {
  if (!flag) return true;
  if (!PyBool_Check(flag))
    throw py::type_error(std::string(where) + ": kinematics: expected True or False, got " +
                         std::string(py::str(py::type::handle_of(flag).attr("__name__"))));
  return flag == Py_True;
}

// Each algorithm: its name, parameters after (model, data), how many of the last ones may be left
// out (optional, 0 when not declared), and the signature and docstring CPython shows (the first
// line is its __text_signature__).
struct UpdateKinematics {
  static constexpr const char* name = "update_kinematics";
  static constexpr std::array<const char*, 1> params{"q"};
  static constexpr const char* doc = R"(update_kinematics(model, data, q)
--

Fill data's kinematics at q (nq,): R_i, η_i, d_i, s_i, r_i, G_i, M_i (see soadyn.Data).

Every algorithm that takes q does it first; call it directly to read body poses.)";
  static py::object run(const Model& m, PyData& d, PyObject** a) {
    kin(m, d, name, a[0]);
    return none();
  }
};

struct UpdateVelocities {
  static constexpr const char* name = "update_velocities";
  static constexpr std::array<const char*, 2> params{"q", "v"};
  static constexpr const char* doc = R"(update_velocities(model, data, q, v)
--

Kinematics at q, then v = Ψ_D G q̇ (eq. 4) and v̄ = S v (eq. 5) into data.V and data.Vbar.
q: (nq,), v: (nv,).)";
  static py::object run(const Model& m, PyData& d, PyObject** a) {
    kin_vel(m, d, name, a[0], a[1]);
    return none();
  }
};

struct MassMatrix {
  static constexpr const char* name = "mass_matrix";
  static constexpr std::array<const char*, 2> params{"q", "kinematics"};
  static constexpr int optional = 1;  // kinematics
  static constexpr const char* doc = R"(mass_matrix(model, data, q, kinematics=True)
--

The system mass matrix 𝓜(q) = Gᵀ Ψ_Dᵀ M Ψ_D G (eq. 14), by composite inertias.

q: (nq,).  Returns data.M, shape (nv, nv), symmetric positive definite: a read-only view, not a
copy (the next call on this Data overwrites it; .copy() to keep it).
kinematics=False: 𝓜 from q alone in body axes (C++ mass_matrix(model, data, q)), the same 𝓜 to
rounding in 0.55–0.9 of the C++ time at robot sizes; data's kinematics views (R, eta, …) keep what
they held (not this q): update_kinematics before reading them.)";
  static py::object run(const Model& m, PyData& d, PyObject** a) {
    if (kinematics_wanted(name, a[1])) {
      kin(m, d, name, a[0]);
      mass_matrix(m, *d.data);
    } else {
      read_vector(m, *d.data, name, "q", a[0], m.nq, d.q);
      mass_matrix(m, *d.data, d.q);
    }
    return d.M;
  }
};

struct MassMatrixLiteral {
  static constexpr const char* name = "mass_matrix_literal";
  static constexpr std::array<const char*, 1> params{"q"};
  static constexpr const char* doc = R"(mass_matrix_literal(model, data, q)
--

𝓜(q) by the note's three-step procedure: J = Ψ_D G column by column, Q = M J, 𝓜 = Jᵀ Q.

O(N²), the readable reference for mass_matrix.  q: (nq,).  Returns a new array (nv, nv).)";
  static py::object run(const Model& m, PyData& d, PyObject** a) {
    kin(m, d, name, a[0]);
    MatX M(m.nv, m.nv);
    mass_matrix_literal(m, *d.data, M);
    return owned(std::move(M));
  }
};

struct Minverse {
  static constexpr const char* name = "minverse";
  static constexpr std::array<const char*, 1> params{"q"};
  static constexpr const char* doc = R"(minverse(model, data, q)
--

𝓜(q)⁻¹ without forming 𝓜: the articulated-body recursion for every unit force at once, O(N²) on a
chain (C++ minverse, as Pinocchio's computeMinverse).  q: (nq,).  Returns data.Minv, shape (nv, nv),
a read-only view (this function's own; forward_dynamics_derivatives returns its 𝓜⁻¹ as data.dqdd_dtau).)";
  static py::object run(const Model& m, PyData& d, PyObject** a) {
    DerivativeData& dd = d.derivative_data(m);
    kin(m, d, name, a[0]);
    (void)dd;  // made with its views, minverse's own array among them
    minverse(m, *d.data, *d.minverse_result);
    return d.Minv;
  }
};

struct Bias {
  static constexpr const char* name = "bias_forces";
  static constexpr std::array<const char*, 3> params{"q", "v", "kinematics"};
  static constexpr int optional = 1;  // kinematics
  static constexpr const char* doc = R"(bias_forces(model, data, q, v, kinematics=True)
--

bias(q, q̇) = Gᵀ Ψ_Dᵀ (M Ψ_D a + b): Coriolis, centrifugal, gyroscopic and gravity forces.

𝓜(q) q̈ + bias(q, q̇) = τ.  q: (nq,), v: (nv,).  Returns data.bias, shape (nv,), a read-only view.
kinematics=False: the recursive Newton–Euler from (q, v) alone in body axes (C++
bias_forces(model, data, q, v)), the same bias to rounding in 0.6–0.85 of the C++ time; data's
kinematics and velocity views keep what they held (not this q, v).)";
  static py::object run(const Model& m, PyData& d, PyObject** a) {
    if (kinematics_wanted(name, a[2])) {
      kin_vel(m, d, name, a[0], a[1]);
      bias_forces(m, *d.data);
    } else {
      read_vector(m, *d.data, name, "v", a[1], m.nv, d.v);  // both sizes checked before any work
      read_vector(m, *d.data, name, "q", a[0], m.nq, d.q);
      bias_forces(m, *d.data, d.q, d.v);
    }
    return d.bias;
  }
};

struct InverseDynamics {
  static constexpr const char* name = "inverse_dynamics";
  static constexpr std::array<const char*, 3> params{"q", "v", "qdd"};
  static constexpr const char* doc = R"(inverse_dynamics(model, data, q, v, qdd)
--

τ = 𝓜(q) q̈ + bias(q, q̇), by the same two sweeps (no 𝓜 formed).

q: (nq,), v: (nv,), qdd: (nv,).  Returns data.tau, shape (nv,), a read-only view.)";
  static py::object run(const Model& m, PyData& d, PyObject** a) {
    read_vector(m, *d.data, name, "qdd", a[2], m.nv, d.x);
    kin_vel(m, d, name, a[0], a[1]);
    inverse_dynamics(m, *d.data, d.x);
    return d.tau;
  }
};

struct ForwardDynamics {
  static constexpr const char* name = "forward_dynamics";
  static constexpr std::array<const char*, 4> params{"q", "v", "tau", "method"};
  static constexpr int optional = 1;  // method
  static constexpr const char* doc = R"(forward_dynamics(model, data, q, v, tau, method='aba')
--

q̈ = 𝓜(q)⁻¹ (τ − bias(q, q̇)).

method: 'aba' (articulated-body recursion, O(N), 𝓜 never formed; 'on', its old word, is taken too), 'dense' (composite 𝓜 and
Cholesky) or 'sparse' (𝓜 factored as LᵀDL along the tree); data.M and data.bias keep what
mass_matrix and bias_forces left there.
q: (nq,), v: (nv,), tau: (nv,).  Returns data.qdd, shape (nv,), a read-only view.)";
  static py::object run(const Model& m, PyData& d, PyObject** a) {
    FdMethod fd = FdMethod::ArticulatedBody;
    if (a[3]) {
      Py_ssize_t n = 0;
      const char* s = PyUnicode_Check(a[3]) ? PyUnicode_AsUTF8AndSize(a[3], &n) : nullptr;
      if (!s) throw py::type_error("forward_dynamics: method: expected a string");
      fd = parse_fd_method(std::string_view(s, size_t(n)));
    }
    read_vector(m, *d.data, name, "tau", a[2], m.nv, d.x);
    kin_vel(m, d, name, a[0], a[1]);
    if (fd == FdMethod::ArticulatedBody) {
      forward_dynamics(m, *d.data, d.x, fd);
      return d.qdd;
    }
    // the composite routes form 𝓜 and bias in data.M and data.bias: mass_matrix's and
    // bias_forces' results, which stay as those calls left them
    d.kept_M = d.data->M;
    d.kept_bias = d.data->bias;
    forward_dynamics(m, *d.data, d.x, fd);
    d.data->M = d.kept_M;
    d.data->bias = d.kept_bias;
    return d.qdd;
  }
};

struct IdDerivatives {
  static constexpr const char* name = "inverse_dynamics_derivatives";
  static constexpr std::array<const char*, 3> params{"q", "v", "qdd"};
  static constexpr const char* doc = R"(inverse_dynamics_derivatives(model, data, q, v, qdd)
--

(∂τ/∂q, ∂τ/∂v) of τ = 𝓜(q) q̈ + bias(q, q̇), analytic, O(N·depth).

∂/∂q is along the tangent increment δ (nv,) with q ⊕ δ = joint_integrate(q, δ, 1): a free joint's
δ = [δθ (inertial axes); δp], a ball's δθ in the child's frame.  q: (nq,), v: (nv,), qdd: (nv,).
Returns (data.dtau_dq, data.dtau_dv), shape (nv, nv) each: read-only views, not copies (the next
call of this function on this Data overwrites them; .copy() to keep them).)";
  static py::object run(const Model& m, PyData& d, PyObject** a) {
    DerivativeData& dd = d.derivative_data(m);
    read_vector(m, *d.data, name, "qdd", a[2], m.nv, d.x);
    kin_vel(m, d, name, a[0], a[1]);
    inverse_dynamics_derivatives(m, *d.data, d.v, d.x, dd);
    return d.id_result;
  }
};

struct FdDerivatives {
  static constexpr const char* name = "forward_dynamics_derivatives";
  static constexpr std::array<const char*, 3> params{"q", "v", "tau"};
  static constexpr const char* doc = R"(forward_dynamics_derivatives(model, data, q, v, tau)
--

(∂q̈/∂q, ∂q̈/∂v, ∂q̈/∂τ = 𝓜⁻¹) of q̈ = 𝓜(q)⁻¹ (τ − bias(q, q̇)), τ held fixed; ∂/∂q along the
tangent as in inverse_dynamics_derivatives.  q: (nq,), v: (nv,), tau: (nv,).  Returns (data.dqdd_dq,
data.dqdd_dv, data.dqdd_dtau), shape (nv, nv) each: read-only views, not copies (the next call of
this function on this Data overwrites them; .copy() to keep them).  Leaves data.qdd (forward_dynamics')
and data.Minv (minverse's) as they were.  𝓜⁻¹ by the
articulated-body recursion, then its products with the inverse-dynamics derivatives' columns
without forming them: O(N²) on every tree.)";
  static py::object run(const Model& m, PyData& d, PyObject** a) {
    DerivativeData& dd = d.derivative_data(m);
    read_vector(m, *d.data, name, "tau", a[2], m.nv, d.x);
    kin_vel(m, d, name, a[0], a[1]);
    d.kept_qdd = d.data->qdd;  // forward_dynamics' result, which this call's q̈ passes through
    forward_dynamics_derivatives(m, *d.data, d.v, d.x, dd, nullptr, true);
    d.data->qdd = d.kept_qdd;
    return d.fd_result;
  }
};

struct Jacobian {
  static constexpr const char* name = "jacobian";
  static constexpr std::array<const char*, 1> params{"q"};
  static constexpr const char* doc = R"(jacobian(model, data, q)
--

J = S Ψ_D G (eq. 7): rows 6i…6i+5 map q̇ to v̄_i = [ω_i; ṙ_i] (centre-of-mass velocity).

q: (nq,).  Returns a new array, shape (6N, nv).  𝓜 = Jᵀ diag(M̄_i) J.)";
  static py::object run(const Model& m, PyData& d, PyObject** a) {
    kin(m, d, name, a[0]);
    MatX J;
    jacobian(m, *d.data, J);
    return owned(std::move(J));
  }
};

struct KineticEnergy {
  static constexpr const char* name = "kinetic_energy";
  static constexpr std::array<const char*, 2> params{"q", "v"};
  static constexpr const char* doc = R"(kinetic_energy(model, data, q, v)
--

T = ½ Σ (ω_iᵀ I_i ω_i + m_i ṙ_iᵀ ṙ_i) = ½ q̇ᵀ 𝓜 q̇ (eq. 9), J.  q: (nq,), v: (nv,).)";
  static py::object run(const Model& m, PyData& d, PyObject** a) {
    kin_vel(m, d, name, a[0], a[1]);
    return py::float_(kinetic_energy(m, *d.data));
  }
};

struct PotentialEnergy {
  static constexpr const char* name = "potential_energy";
  static constexpr std::array<const char*, 1> params{"q"};
  static constexpr const char* doc = R"(potential_energy(model, data, q)
--

V = −Σ m_i g·r_i over every body with mass (world-welded ones included), J; zero at the origin.
q: (nq,).)";
  static py::object run(const Model& m, PyData& d, PyObject** a) {
    kin(m, d, name, a[0]);
    return py::float_(potential_energy(m, *d.data));
  }
};

struct MomentumFn {
  static constexpr const char* name = "momentum";
  static constexpr std::array<const char*, 2> params{"q", "v"};
  static constexpr const char* doc = R"(momentum(model, data, q, v)
--

(linear, angular): p = Σ m_i ṙ_i and L = Σ I_i ω_i + r_i × m_i ṙ_i about the inertial origin.

q: (nq,), v: (nv,).  Returns two new arrays of shape (3,).)";
  static py::object run(const Model& m, PyData& d, PyObject** a) {
    kin_vel(m, d, name, a[0], a[1]);
    const Momentum h = momentum(m, *d.data);
    return py::make_tuple(owned(VecX(h.linear)), owned(VecX(h.angular)));
  }
};

// Arguments by position or by name into slots (model, data, params…); false with a TypeError set.
template <class Fn>
bool parse(PyObject* const* args, Py_ssize_t nargs, PyObject* kwnames, PyObject** slots) {
  constexpr int n = int(Fn::params.size()) + 2;
  constexpr int optional = [] {
    if constexpr (requires { Fn::optional; }) return Fn::optional;
    else return 0;
  }();
  constexpr int required = n - optional;
  auto param = [](int i) { return i == 0 ? "model" : i == 1 ? "data" : Fn::params[size_t(i - 2)]; };
  if (nargs > n) {
    PyErr_Format(PyExc_TypeError, "%s() takes %d arguments (%zd given)", Fn::name, n, nargs);
    return false;
  }
  for (int i = 0; i < n; ++i) slots[i] = i < nargs ? args[i] : nullptr;
  const Py_ssize_t nkw = kwnames ? PyTuple_GET_SIZE(kwnames) : 0;
  for (Py_ssize_t k = 0; k < nkw; ++k) {
    PyObject* key = PyTuple_GET_ITEM(kwnames, k);
    int i = 0;
    while (i < n && PyUnicode_CompareWithASCIIString(key, param(i)) != 0) ++i;
    if (i == n) {
      PyErr_Format(PyExc_TypeError, "%s() got an unexpected keyword argument '%U'", Fn::name, key);
      return false;
    }
    if (slots[i]) {
      PyErr_Format(PyExc_TypeError, "%s() got multiple values for argument '%s'", Fn::name, param(i));
      return false;
    }
    slots[i] = args[nargs + k];
  }
  for (int i = 0; i < required; ++i)
    if (!slots[i]) {
      PyErr_Format(PyExc_TypeError, "%s() missing required argument '%s'", Fn::name, param(i));
      return false;
    }
  return true;
}

template <class T>
T& instance(PyObject* obj, const char* fn, const char* what, const char* type) {
  // an object of exactly this class: its value straight from the instance (pybind11's caster
  // looks the class up by name on every call, a third of the call's overhead)
  static py::detail::type_info* const info = py::detail::get_type_info(typeid(T));
  if (info && Py_TYPE(obj) == info->type) {
    auto* inst = reinterpret_cast<py::detail::instance*>(obj);
    if (void* value = inst->get_value_and_holder(info, false).value_ptr()) return *static_cast<T*>(value);
  }
  py::detail::make_caster<T> caster;
  if (!caster.load(obj, false))
    throw py::type_error(std::string(fn) + ": " + what + ": expected a " + type + ", got " +
                         std::string(py::str(py::type::handle_of(obj).attr("__name__"))));
  return py::detail::cast_op<T&>(caster);
}

template <class Fn>
PyObject* vectorcall(PyObject*, PyObject* const* args, Py_ssize_t nargs, PyObject* kwnames) {
  PyObject* slots[Fn::params.size() + 2];
  if (!parse<Fn>(args, PyVectorcall_NARGS(nargs), kwnames, slots)) return nullptr;
  try {
    const Model& model = instance<Model>(slots[0], Fn::name, "model", "soadyn.Model");
    PyData& data = instance<PyData>(slots[1], Fn::name, "data", "soadyn.Data");
    return Fn::run(model, data, slots + 2).release().ptr();
  } catch (...) {
    set_python_error();
    return nullptr;
  }
}

template <class Fn>
PyMethodDef method() {
  return {Fn::name, reinterpret_cast<PyCFunction>(reinterpret_cast<void (*)()>(&vectorcall<Fn>)),
          METH_FASTCALL | METH_KEYWORDS, Fn::doc};
}

// body_poses: η_i and C_i^in of every body at each configuration
void bind_body_poses(py::module_& m) {
  m.def("body_poses", [](const Model& model, const ArrayIn& qs) {
        const bool one = qs.ndim() == 1;
        if (!(one || qs.ndim() == 2) || qs.shape(qs.ndim() - 1) != model.nq)
          throw Error("body_poses: q: expected shape (" + std::to_string(model.nq) + ",) or (T, " +
                      std::to_string(model.nq) + "), got " + std::string(py::str(qs.attr("shape"))));
        const py::ssize_t T = one ? 1 : qs.shape(0), N = model.nbodies;
        std::vector<double> pos(size_t(T * N * 3)), rot(size_t(T * N * 9));
        {
          py::gil_scoped_release nogil;
          Data data(model);
          VecX q(model.nq);
          for (py::ssize_t t = 0; t < T; ++t) {
            for (int k = 0; k < model.nq; ++k) q(k) = one ? qs.at(k) : qs.at(t, k);
            update_kinematics(model, data, q);
            for (py::ssize_t i = 0; i < N; ++i) {
              for (int r = 0; r < 3; ++r) {
                pos[size_t((t * N + i) * 3 + r)] = data.eta(r, i);
                for (int c = 0; c < 3; ++c) rot[size_t((t * N + i) * 9 + 3 * r + c)] = data.R[size_t(i)](r, c);
              }
            }
          }
        }
        if (one) return py::make_tuple(owned(std::move(pos), {N, 3}), owned(std::move(rot), {N, 3, 3}));
        return py::make_tuple(owned(std::move(pos), {T, N, 3}), owned(std::move(rot), {T, N, 3, 3}));
      }, "model"_a, "q"_a,
      R"((positions, rotations) of every body frame at each configuration: η_i and C_i^in.

q: (nq,) or (T, nq), e.g. a Trajectory's q.  Returns new arrays of shape (N, 3) and (N, 3, 3), or
(T, N, 3) and (T, N, 3, 3): the body frame's origin (its joint point) and its rotation body →
inertial.  Runs without the GIL.)");
}

// _time_cpp, for tools/bench/python_overhead.py: the same library calls in a C++ loop in this process, so
// the two sides are timed in adjacent windows on the same machine state (the derivative calls on
// the Data's own derivative arrays, as the Python functions use them)
void bind_time_cpp(py::module_& m) {
  m.def("_time_cpp", [](const Model& model, PyData& d, const ArrayIn& q, const ArrayIn& v, const ArrayIn& tau,
                        const std::string& which, long calls) {
        VecX qv(model.nq), vv(model.nv), tv(model.nv);
        read_vector(model, *d.data, "_time_cpp", "q", q, model.nq, qv);
        read_vector(model, *d.data, "_time_cpp", "v", v, model.nv, vv);
        read_vector(model, *d.data, "_time_cpp", "tau", tau, model.nv, tv);
        Data& data = *d.data;
        const auto t0 = std::chrono::steady_clock::now();
        if (which == "mass_matrix") {
          for (long k = 0; k < calls; ++k) update_kinematics(model, data, qv), mass_matrix(model, data);
        } else if (which == "forward_dynamics") {
          for (long k = 0; k < calls; ++k) {
            update_kinematics(model, data, qv);
            update_velocities(model, data, vv);
            forward_dynamics(model, data, tv, FdMethod::ArticulatedBody);
          }
        } else if (which == "fd_derivatives" || which == "id_derivatives" || which == "minverse") {
          DerivativeData& dd = d.derivative_data(model);
          for (long k = 0; k < calls; ++k) {
            update_kinematics(model, data, qv);
            if (which == "minverse") {
              minverse(model, data, dd.Minv);
              continue;
            }
            update_velocities(model, data, vv);
            if (which == "fd_derivatives") forward_dynamics_derivatives(model, data, vv, tv, dd, nullptr, true);
            else inverse_dynamics_derivatives(model, data, vv, tv, dd);  // τ's values as q̈
          }
        } else {
          throw Error("_time_cpp: which: expected mass_matrix, forward_dynamics, fd_derivatives, id_derivatives or "
                      "minverse, got '" + which + "'");
        }
        return std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count() / double(calls);
      }, "model"_a, "data"_a, "q"_a, "v"_a, "tau"_a, "which"_a, "calls"_a);
}

}  // namespace

void bind_algorithms(py::module_& m) {
  // CPython keeps pointers to these definitions for the life of the functions
  static PyMethodDef defs[] = {method<UpdateKinematics>(), method<UpdateVelocities>(), method<MassMatrix>(),
                               method<MassMatrixLiteral>(), method<Minverse>(), method<Bias>(), method<InverseDynamics>(),
                               method<ForwardDynamics>(), method<Jacobian>(),
                               method<IdDerivatives>(), method<FdDerivatives>(), method<KineticEnergy>(),
                               method<PotentialEnergy>(), method<MomentumFn>()};
  py::object module_name = m.attr("__name__");
  bind_body_poses(m);
  bind_time_cpp(m);
  for (PyMethodDef& def : defs) {
    PyObject* f = PyCFunction_NewEx(&def, nullptr, module_name.ptr());
    if (!f) throw py::error_already_set();
    m.add_object(def.ml_name, py::reinterpret_steal<py::object>(f));
  }
}

}  // namespace soadyn::python
