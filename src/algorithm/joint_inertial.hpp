// The per-kind pieces of the inertial sweeps (update_velocities, rnea.cpp, mass_matrix.cpp,
// articulated*.cpp): G_i as update_kinematics stored it in data.G, applied with what the kind
// fixes known at compile time.  A revolute joint's column is [g; 0] and a prismatic one's [0; g],
// so half of each product is skipped; the free joint's G_i = e is no product at all; the ball's
// and planar's 6×3 blocks are fixed-size products.
#pragma once

#include "soadyn/multibody/joint_model.hpp"
#include "soadyn/multibody/types.hpp"

#include <type_traits>

namespace soadyn::inertial {

template <class J>
inline constexpr bool angular = false;  // G_i = [g; 0]
template <int k>
inline constexpr bool angular<joints::RevoluteAxis<k>> = true;
template <int k>
inline constexpr bool angular<joints::TurnedRevoluteAxis<k>> = true;
template <>
inline constexpr bool angular<joints::Revolute> = true;

template <class J>
inline constexpr bool linear = false;  // G_i = [0; g]
template <int k>
inline constexpr bool linear<joints::PrismaticAxis<k>> = true;
template <>
inline constexpr bool linear<joints::Prismatic> = true;

template <class J>
inline constexpr bool identity = std::is_same_v<J, joints::Free>;  // G_i = e

// G_i x_i = [w; u], x at the joint's first v
template <class J>
inline void motion(const Mat6X& G, int iv, const double* x, Vec3& w, Vec3& u) {
  if constexpr (angular<J>) {
    w = x[0] * G.col(iv).head<3>();
    u.setZero();
  } else if constexpr (linear<J>) {
    w.setZero();
    u = x[0] * G.col(iv).tail<3>();
  } else if constexpr (identity<J>) {
    w = Vec3(x[0], x[1], x[2]);
    u = Vec3(x[3], x[4], x[5]);
  } else {
    const Vec6 out = G.middleCols<J::nv>(iv) * Eigen::Map<const Eigen::Matrix<double, J::nv, 1>>(x);
    w = out.head<3>();
    u = out.tail<3>();
  }
}

// G_iᵀ [n; f] into out[0 .. nv)
template <class J>
inline void project(const Mat6X& G, int iv, const Vec3& n, const Vec3& f, double* out) {
  if constexpr (angular<J>) {
    out[0] = G.col(iv).head<3>().dot(n);
  } else if constexpr (linear<J>) {
    out[0] = G.col(iv).tail<3>().dot(f);
  } else if constexpr (identity<J>) {
    for (int c = 0; c < 3; ++c) out[c] = n[c], out[3 + c] = f[c];
  } else {
    for (int c = 0; c < J::nv; ++c) out[c] = G.col(iv + c).head<3>().dot(n) + G.col(iv + c).tail<3>().dot(f);
  }
}

// U = P G_i for a 6×6 P (the articulated inertia): a revolute column reads the left half of P,
// a prismatic one the right half
template <class J, class U_t>
inline void times(const Mat6& P, const Mat6X& G, int iv, U_t&& U) {
  if constexpr (angular<J>) U.noalias() = P.leftCols<3>() * G.col(iv).head<3>();
  else if constexpr (linear<J>) U.noalias() = P.rightCols<3>() * G.col(iv).tail<3>();
  else if constexpr (identity<J>) U = P;
  else U.noalias() = P * G.middleCols<J::nv>(iv);
}

}  // namespace soadyn::inertial
