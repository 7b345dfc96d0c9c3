// The algorithms: f(model, data, q, …), each one update of the pipeline plus the algorithm, and a
// read-only view of the Data it filled (or a new array for results Data does not hold).
#include "common.hpp"

namespace soadyn::python {

namespace {

// [kin] at q
void kin(const Model& model, PyData& d, const char* where, const ArrayIn& q) {
  read_vector(model, *d.data, where, "q", q, model.nq, d.q);
  update_kinematics(model, *d.data, d.q);
}

// [kin] at q, then [vel] at v
void kin_vel(const Model& model, PyData& d, const char* where, const ArrayIn& q, const ArrayIn& v) {
  read_vector(model, *d.data, where, "v", v, model.nv, d.v);  // both sizes checked before any work
  kin(model, d, where, q);
  update_velocities(model, *d.data, d.v);
}

}  // namespace

void bind_algorithms(py::module_& m) {
  m.def("update_kinematics", [](const Model& model, PyData& d, const ArrayIn& q) { kin(model, d, "update_kinematics", q); },
        "model"_a, "data"_a, "q"_a,
        R"(Fill data's kinematics at q (nq,): R_i, η_i, d_i, s_i, r_i, G_i, M_i (see soadyn.Data).

Every algorithm that takes q calls it first; call it directly to read body poses.)");
  m.def("update_velocities", [](const Model& model, PyData& d, const ArrayIn& q, const ArrayIn& v) {
        kin_vel(model, d, "update_velocities", q, v);
      }, "model"_a, "data"_a, "q"_a, "v"_a,
      "Kinematics at q, then v = Ψ_D G q̇ (eq. 4) and v̄ = S v (eq. 5) into data.V, data.Vbar; q (nq,), v (nv,).");

  m.def("mass_matrix", [](const Model& model, PyData& d, const ArrayIn& q) {
        kin(model, d, "mass_matrix", q);
        mass_matrix(model, *d.data);
        return d.M;
      }, "model"_a, "data"_a, "q"_a,
      R"(The system mass matrix 𝓜(q) = Gᵀ Ψ_Dᵀ M Ψ_D G (eq. 14), by composite inertias.

q: (nq,).  Returns data.M, shape (nv, nv), symmetric positive definite: a read-only view, not a
copy (the next call on this Data overwrites it; .copy() to keep it).)");
  m.def("mass_matrix_literal", [](const Model& model, PyData& d, const ArrayIn& q) {
        kin(model, d, "mass_matrix_literal", q);
        MatX M(model.nv, model.nv);
        mass_matrix_literal(model, *d.data, M);
        return owned(std::move(M));
      }, "model"_a, "data"_a, "q"_a,
      R"(𝓜(q) by the note's three-step procedure: J = Ψ_D G column by column, Q = M J, 𝓜 = Jᵀ Q.

O(N²), the readable reference for mass_matrix.  q: (nq,).  Returns a new array (nv, nv).)");
  m.def("bias", [](const Model& model, PyData& d, const ArrayIn& q, const ArrayIn& v) {
        kin_vel(model, d, "bias", q, v);
        bias_forces(model, *d.data);
        return d.bias;
      }, "model"_a, "data"_a, "q"_a, "v"_a,
      R"(bias(q, q̇) = Gᵀ Ψ_Dᵀ (M Ψ_D a + b): Coriolis, centrifugal, gyroscopic and gravity forces.

𝓜(q) q̈ + bias(q, q̇) = τ.  q: (nq,), v: (nv,).  Returns data.bias, shape (nv,), a read-only view.)");
  m.def("inverse_dynamics", [](const Model& model, PyData& d, const ArrayIn& q, const ArrayIn& v, const ArrayIn& qdd) {
        read_vector(model, *d.data, "inverse_dynamics", "qdd", qdd, model.nv, d.x);
        kin_vel(model, d, "inverse_dynamics", q, v);
        inverse_dynamics(model, *d.data, d.x);
        return d.tau;
      }, "model"_a, "data"_a, "q"_a, "v"_a, "qdd"_a,
      R"(τ = 𝓜(q) q̈ + bias(q, q̇), by the same two sweeps (no 𝓜 formed).

q: (nq,), v: (nv,), qdd: (nv,).  Returns data.tau, shape (nv,), a read-only view.)");
  m.def("forward_dynamics", [](const Model& model, PyData& d, const ArrayIn& q, const ArrayIn& v, const ArrayIn& tau,
                               const std::string& method) {
        const FdMethod fd = parse_fd_method(method);
        read_vector(model, *d.data, "forward_dynamics", "tau", tau, model.nv, d.x);
        kin_vel(model, d, "forward_dynamics", q, v);
        forward_dynamics(model, *d.data, d.x, fd);
        return d.qdd;
      }, "model"_a, "data"_a, "q"_a, "v"_a, "tau"_a, "method"_a = "on",
      R"(q̈ = 𝓜(q)⁻¹ (τ − bias(q, q̇)).

method: 'on' (articulated-body recursion, O(N), 𝓜 never formed), 'dense' (composite 𝓜 and
Cholesky; also fills data.M and data.bias) or 'sparse' (𝓜 factored as LᵀDL along the tree).
q: (nq,), v: (nv,), tau: (nv,).  Returns data.qdd, shape (nv,), a read-only view.)");
  m.def("jacobian", [](const Model& model, PyData& d, const ArrayIn& q) {
        kin(model, d, "jacobian", q);
        MatX J;
        jacobian(model, *d.data, J);
        return owned(std::move(J));
      }, "model"_a, "data"_a, "q"_a,
      R"(J = S Ψ_D G (eq. 7): rows 6i…6i+5 map q̇ to v̄_i = [ω_i; ṙ_i] (centre-of-mass velocity).

q: (nq,).  Returns a new array, shape (6N, nv).  𝓜 = Jᵀ diag(M̄_i) J.)");
  m.def("kinetic_energy", [](const Model& model, PyData& d, const ArrayIn& q, const ArrayIn& v) {
        kin_vel(model, d, "kinetic_energy", q, v);
        return kinetic_energy(model, *d.data);
      }, "model"_a, "data"_a, "q"_a, "v"_a,
      "T = ½ Σ (ω_iᵀ I_i ω_i + m_i ṙ_iᵀ ṙ_i) = ½ q̇ᵀ 𝓜 q̇ (eq. 9), J.  q: (nq,), v: (nv,).");
  m.def("potential_energy", [](const Model& model, PyData& d, const ArrayIn& q) {
        kin(model, d, "potential_energy", q);
        return potential_energy(model, *d.data);
      }, "model"_a, "data"_a, "q"_a,
      "V = −Σ m_i g·r_i over every body with mass (world-welded ones included), J; zero at the origin.  q: (nq,).");
  m.def("momentum", [](const Model& model, PyData& d, const ArrayIn& q, const ArrayIn& v) {
        kin_vel(model, d, "momentum", q, v);
        const Momentum h = momentum(model, *d.data);
        return py::make_tuple(owned(VecX(h.linear)), owned(VecX(h.angular)));
      }, "model"_a, "data"_a, "q"_a, "v"_a,
      R"((linear, angular): p = Σ m_i ṙ_i and L = Σ I_i ω_i + r_i × m_i ṙ_i about the inertial origin.

q: (nq,), v: (nv,).  Returns two new arrays of shape (3,).)");
}

}  // namespace soadyn::python
