// The articulated-body recursion's steps at one body: the factor step and aba's two sweeps'
// steps (articulated.cpp's forward dynamics; hybrid.cpp's hybrid dynamics at its free joints).
// Internal.
#pragma once

#include "soadyn/multibody/data.hpp"
#include "soadyn/multibody/model.hpp"
#include "multibody/articulated_inertia.hpp"
#include "joint_inertial.hpp"

namespace soadyn::detail {

// The factor both articulated-body sweeps share, at body i once its children are in P_i:
// U_i = P_i G_i, 𝒟_i⁻¹ = (G_iᵀ U_i)⁻¹ and, below a parent, P⁺_i = P_i − U_i 𝒟_i⁻¹ U_iᵀ in place
// (P_i is not needed after this step).  The caller adds D_iᵀ P⁺_i D_i to P_p.  J is body i's joint
// kind, which the caller's one dispatch for the body has chosen.
template <class J>
inline void articulated_factor_step(const Model& model, Data& data, int i) {
  const int vi = model.idx_v[i], p = model.parent[i];
  Mat6& P = data.work.articulated.P[i];
  if constexpr (J::nv == 1) {
    // U = P g,  𝒟 = gᵀ U;  P⁺ = P − U Uᵀ / 𝒟
    Vec6 U;
    inertial::times<J>(P, data.G, vi, U);
    const double Dinv = 1.0 / data.G.col(vi).dot(U);
    data.work.articulated.U1.col(i) = U;
    data.work.articulated.Dinv1(i) = Dinv;
    if (p < 0) return;
    articulated_inertia::remove_column(P, U, Dinv);
  } else {
    // the same with U_i = P_i G_i (6×n) and 𝒟_i = G_iᵀ U_i (n×n)
    Eigen::Matrix<double, 6, J::nv> U;
    inertial::times<J>(P, data.G, vi, U);
    const Eigen::Matrix<double, J::nv, J::nv> joint_inertia = data.G.middleCols<J::nv>(vi).transpose() * U;  // 𝒟_i
    data.work.articulated.U[i] = U;
    data.work.articulated.Dinv[i] = articulated_inertia::joint_inertia_inverse<J::nv>(joint_inertia);
    if (p < 0) return;
    const Eigen::Matrix<double, 6, J::nv> UD = U * data.work.articulated.Dinv[i];
    P.noalias() -= UD * U.transpose();
  }
}

// aba's tip-to-base step, the factor step first, then: u_i = τ_i − G_iᵀ z_i, then at a parent
// z⁺ = z + P⁺ a + U 𝒟⁻¹ u, P_p += D_iᵀ P⁺ D_i, z_p += D_iᵀ z⁺ = [z_ω + d_i × z_f; z_f] (added in
// 3-vector halves: a 6-vector built whole went through the stack and was read back across two stores)
template <class J>
[[gnu::noinline]] void aba_backward_step(const Model& model, Data& data, const VecX& tau, int i) {
  articulated_factor_step<J>(model, data, i);
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

}  // namespace soadyn::detail
