// The articulated-body factor's step at one body (articulated.cpp's forward dynamics and
// hybrid.cpp's hybrid dynamics share it).  Internal.
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

}  // namespace soadyn::detail
