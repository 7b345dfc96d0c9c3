// The articulated-body recursion: O(N) forward dynamics (the factored inverse mass matrix), whose
// factor articulated_solve reuses (algorithms.hpp).
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "dynamics_routes.hpp"
#include "multibody/articulated_inertia.hpp"
#include "articulated_factor.hpp"
#include "joint_inertial.hpp"

namespace soadyn {

namespace {

// aba's tip-to-base step, the factor step first, then: u_i = τ_i − G_iᵀ z_i, then at a parent
// z⁺ = z + P⁺ a + U 𝒟⁻¹ u, P_p += D_iᵀ P⁺ D_i, z_p += D_iᵀ z⁺ = [z_ω + d_i × z_f; z_f] (added in
// 3-vector halves: a 6-vector built whole went through the stack and was read back across two stores)
template <class J>
[[gnu::noinline]] void aba_backward_step(const Model& model, Data& data, const VecX& tau, int i) {
  detail::articulated_factor_step<J>(model, data, i);
  const int vi = model.idx_v[i], p = model.parent[i];
  const Mat6& P = data.work.articulated.P[i];  // P⁺_i below a parent
  double gz[J::nv];
  inertial::project<J>(data.G, vi, data.work.articulated.z.col(i).head<3>(), data.work.articulated.z.col(i).tail<3>(), gz);
  for (int c = 0; c < J::nv; ++c) data.work.articulated.u(vi + c) = tau(vi + c) - gz[c];
  if (p < 0) return;
  Vec6 za = data.work.articulated.z.col(i);
  za.noalias() += P * data.coriolis.col(i);
  if constexpr (J::nv == 1) {
    za += (data.work.articulated.u(vi) * data.work.articulated.Dinv1(i)) * data.work.articulated.U1.col(i);
  } else {
    const Eigen::Matrix<double, J::nv, 1> Du = data.work.articulated.Dinv[i] * data.work.articulated.u.segment<J::nv>(vi);
    za.noalias() += data.work.articulated.U[i] * Du;
  }
  articulated_inertia::add_to_parent(data.work.articulated.P[p], P, data.d.col(i));
  const Vec3 zf = za.tail<3>();
  data.work.articulated.z.col(p).head<3>() += za.head<3>() + Vec3(data.d.col(i)).cross(zf);
  data.work.articulated.z.col(p).tail<3>() += zf;
}

// aba's base-to-tip step, in 3-vector halves, which stay in registers: A' = [ω; u],
// q̈_i = 𝒟⁻¹ (u_i − U_ωᵀ ω − U_vᵀ u), A_i = A' + G_i q̈_i
template <class J>
inline void aba_forward_step(const Model& model, Data& data, int i) {
  const int vi = model.idx_v[i], p = model.parent[i];
  Vec3 w = data.coriolis.col(i).head<3>(), v = data.coriolis.col(i).tail<3>();
  if (p >= 0) {
    const Vec3 wp = data.A.col(p).head<3>();
    w += wp;
    v += data.A.col(p).tail<3>() + wp.cross(Vec3(data.d.col(i)));
  }
  if constexpr (J::nv == 1) {
    data.qdd(vi) = data.work.articulated.Dinv1(i) * (data.work.articulated.u(vi) - data.work.articulated.U1.col(i).head<3>().dot(w) - data.work.articulated.U1.col(i).tail<3>().dot(v));
  } else {
    const auto U = data.work.articulated.U[i];
    const Eigen::Matrix<double, J::nv, 1> rhs =
        data.work.articulated.u.segment<J::nv>(vi) - U.topRows<3>().transpose() * w - U.bottomRows<3>().transpose() * v;
    data.qdd.segment<J::nv>(vi).noalias() = data.work.articulated.Dinv[i] * rhs;
  }
  Vec3 gw, gu;
  inertial::motion<J>(data.G, vi, data.qdd.data() + vi, gw, gu);
  data.A.col(i).head<3>() = w + gw;
  data.A.col(i).tail<3>() = v + gu;
}

}  // namespace

namespace detail {

void aba(const Model& model, Data& data, const VecX& tau) {
  // tip to base: articulated inertias P_i and bias forces z_i
  for (int i = 0; i < model.nbodies; ++i) {
    // P_i = M_i = [I, h̃; h̃ᵀ, m e] (in place entry by entry: a tenth of this sweep's time otherwise)
    const SpatialInertia& M = data.inertia[i];
    articulated_inertia::set_inertia(data.work.articulated.P[i], M.I, M.h, M.m);
    data.work.articulated.z.col(i) = data.gyroscopic.col(i);
  }
  for (int i = model.nbodies - 1; i >= 0; --i)
    visit_joint(model, i, [&](const auto& j) { aba_backward_step<std::decay_t<decltype(j)>>(model, data, tau, i); });
  // base to tip: A' = D_i A_p + a_i,  q̈_i = 𝒟⁻¹ (u_i − U_iᵀ A'),  A_i = A' + G_i q̈_i
  for (int i = 0; i < model.nbodies; ++i)
    visit_joint(model, i, [&](const auto& j) { aba_forward_step<std::decay_t<decltype(j)>>(model, data, i); });
}

}  // namespace detail

}  // namespace soadyn
