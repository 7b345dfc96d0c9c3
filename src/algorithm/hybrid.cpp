// Hybrid dynamics (hybrid.hpp): the articulated-body recursion (articulated.cpp) with the
// prescribed joints locked at their known acceleration.
#include "soadyn/algorithm/hybrid.hpp"
#include "soadyn/algorithm/algorithms.hpp"
#include "multibody/articulated_inertia.hpp"
#include "articulated_factor.hpp"
#include "joint_inertial.hpp"

#include <Eigen/Cholesky>

namespace soadyn {

PrescribedJoints::PrescribedJoints(const Model& model, const std::vector<int>& bodies)
    : locked(size_t(model.nbodies), 0) {
  for (const int i : bodies) {
    if (i < 0 || i >= model.nbodies) throw Error("PrescribedJoints: no body " + std::to_string(i));
    if (!locked[size_t(i)]) nv_locked += model.nv_i[i];
    locked[size_t(i)] = 1;
  }
}

namespace {

// tip to base at a prescribed body i: U_i = 0, 𝒟_i⁻¹ = 0 (locked), P⁺ = P and z⁺ = z + P (𝔞 + G q̈*),
// then at the parent P_p += D_iᵀ P⁺ D_i, z_p += D_iᵀ z⁺; P_i itself is kept whole (τ_i needs it).
// A free body takes aba's own step (articulated_factor.hpp).
template <class J>
[[gnu::noinline]] void locked_backward_step(const Model& model, Data& data, const VecX& qdd_given, int i) {
  auto& ab = data.work.articulated;
  const int vi = model.idx_v[i], p = model.parent[i];
  if constexpr (J::nv == 1) {
    ab.U1.col(i).setZero();
    ab.Dinv1(i) = 0.0;
  } else {
    ab.U[i] = Eigen::Matrix<double, 6, J::nv>::Zero();
    ab.Dinv[i] = Eigen::Matrix<double, J::nv, J::nv>::Zero();
  }
  ab.u.segment<J::nv>(vi).setZero();
  if (p < 0) return;
  Vec3 gw, gu;
  inertial::motion<J>(data.G, vi, qdd_given.data() + vi, gw, gu);
  Vec6 a = data.coriolis.col(i);
  a.head<3>() += gw;
  a.tail<3>() += gu;
  Vec6 za = ab.z.col(i);
  za.noalias() += ab.P[i] * a;
  articulated_inertia::add_to_parent(ab.P[p], ab.P[i], data.d.col(i));
  const Vec3 zf = za.tail<3>();
  ab.z.col(p).head<3>() += za.head<3>() + Vec3(data.d.col(i)).cross(zf);
  ab.z.col(p).tail<3>() += zf;
}

// base to tip at a prescribed body i: A_i = D_i A_p + 𝔞_i + G_i q̈*_i, q̈_i = q̈*_i and
// τ_i = G_iᵀ (P_i A_i + z_i).  A free body takes aba's own step.
template <class J>
[[gnu::noinline]] void locked_forward_step(const Model& model, Data& data, const VecX& qdd_given, VecX& tau_out, int i) {
  auto& ab = data.work.articulated;
  const int vi = model.idx_v[i], p = model.parent[i];
  Vec6 A = data.coriolis.col(i);
  if (p >= 0) {
    const Vec3 wp = data.A.col(p).head<3>();
    A.head<3>() += wp;
    A.tail<3>() += data.A.col(p).tail<3>() + wp.cross(Vec3(data.d.col(i)));
  }
  data.qdd.segment<J::nv>(vi) = qdd_given.segment<J::nv>(vi);
  Vec3 gw, gu;
  inertial::motion<J>(data.G, vi, data.qdd.data() + vi, gw, gu);
  A.head<3>() += gw;
  A.tail<3>() += gu;
  data.A.col(i) = A;
  const Vec6 f = ab.P[i] * A + ab.z.col(i);
  inertial::project<J>(data.G, vi, f.head<3>(), f.tail<3>(), tau_out.data() + vi);
}

void check_sizes(const Model& model, const Data& data, const PrescribedJoints& pj, const VecX& tau,
                 const VecX& qdd_given, const char* where) {
  data.check(model, where, "tau", tau.size(), model.nv);
  data.check(model, where, "qdd_given", qdd_given.size(), model.nv);
  if (int(pj.locked.size()) != model.nbodies)
    throw Error(std::string(where) + ": the prescribed joints were set up for another model (" +
                std::to_string(pj.locked.size()) + " bodies, not " + std::to_string(model.nbodies) + ")");
  data.require(where, true);
}

}  // namespace

void hybrid_dynamics(const Model& model, Data& data, const PrescribedJoints& pj, const VecX& tau, const VecX& qdd_given,
                     VecX& tau_out) {
  check_sizes(model, data, pj, tau, qdd_given, "hybrid_dynamics");
  if (tau_out.size() != model.nv) tau_out.resize(model.nv);
  tau_out = tau;
  auto& ab = data.work.articulated;
  // tip to base: articulated inertias P_i = M_i and bias forces z_i = 𝔟_i, then the children's
  for (int i = 0; i < model.nbodies; ++i) {
    const SpatialInertia& M = data.inertia[i];
    articulated_inertia::set_inertia(ab.P[i], M.I, M.h, M.m);
    ab.z.col(i) = data.gyroscopic.col(i);
  }
  for (int i = model.nbodies - 1; i >= 0; --i)
    visit_joint(model, i, [&](const auto& j) {
      using J = std::decay_t<decltype(j)>;
      if (pj.locked[size_t(i)]) locked_backward_step<J>(model, data, qdd_given, i);
      else detail::aba_backward_step<J>(model, data, tau, i);
    });
  // base to tip: q̈ at the free joints, τ at the prescribed ones
  for (int i = 0; i < model.nbodies; ++i)
    visit_joint(model, i, [&](const auto& j) {
      using J = std::decay_t<decltype(j)>;
      if (pj.locked[size_t(i)]) locked_forward_step<J>(model, data, qdd_given, tau_out, i);
      else detail::aba_forward_step<J>(model, data, i);
    });
}

void hybrid_dynamics_derivatives(const Model& model, Data& data, const PrescribedJoints& pj, const VecX& v,
                                 const VecX& tau, const VecX& qdd_given, DerivativeData& dd, VecX& tau_out,
                                 const Inputs* inputs, MatX& work) {
  hybrid_dynamics(model, data, pj, tau, qdd_given, tau_out);
  // ∂ID/∂x at (q, v, q̈ hybrid), then ∂τ_in/∂x − ∂ID/∂x
  inverse_dynamics_derivatives(model, data, v, data.qdd, dd);
  dd.dqdd_dq = -dd.dtau_dq;
  dd.dqdd_dv = -dd.dtau_dv;
  if (inputs) inputs->add_derivatives(dd.dqdd_dq, dd.dqdd_dv);
  // 𝓜_ff⁻¹ on the free rows, zero on the prescribed ones (the locked factor)
  articulated_solve(model, data, dd.dqdd_dq, work);
  articulated_solve(model, data, dd.dqdd_dv, work);
}

void hybrid_dynamics_dense(const Model& model, Data& data, const PrescribedJoints& pj, const VecX& tau,
                           const VecX& qdd_given, VecX& tau_out) {
  check_sizes(model, data, pj, tau, qdd_given, "hybrid_dynamics_dense");
  mass_matrix(model, data);
  bias_forces(model, data);
  std::vector<int> f, p;  // the free and the prescribed DOFs
  for (int k = 0; k < model.nv; ++k) (pj.dof_locked(model, k) ? p : f).push_back(k);
  const int nf = int(f.size()), np = int(p.size());
  MatX Mff(nf, nf), Mfp(nf, np);
  VecX rhs(nf), qp(np);
  for (int b = 0; b < np; ++b) qp(b) = qdd_given(p[size_t(b)]);
  for (int a = 0; a < nf; ++a) {
    for (int b = 0; b < nf; ++b) Mff(a, b) = data.M(f[size_t(a)], f[size_t(b)]);
    for (int b = 0; b < np; ++b) Mfp(a, b) = data.M(f[size_t(a)], p[size_t(b)]);
    rhs(a) = tau(f[size_t(a)]) - data.bias(f[size_t(a)]);
  }
  // 𝓜_ff q̈_f = τ_f − bias_f − 𝓜_fp q̈*_p
  rhs -= Mfp * qp;
  const VecX qf = Mff.llt().solve(rhs);
  data.qdd.resize(model.nv);
  for (int a = 0; a < nf; ++a) data.qdd(f[size_t(a)]) = qf(a);
  for (int b = 0; b < np; ++b) data.qdd(p[size_t(b)]) = qp(b);
  // τ_p = (𝓜 q̈ + bias)_p
  tau_out = tau;
  const VecX full = data.M * data.qdd + data.bias;
  for (int b = 0; b < np; ++b) tau_out(p[size_t(b)]) = full(p[size_t(b)]);
}

}  // namespace soadyn
