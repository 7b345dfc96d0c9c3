// The steps of the articulated-body factorization on one body's 6×6 articulated inertia P (in world
// axes): setting it from a body's inertia, projecting out a joint column, moving it to the parent,
// and inverting a joint's 𝒟.  Shared by the articulated-body route (articulated.cpp), 𝓜⁻¹ about
// the origin (minverse.cpp) and Model::build's check that 𝓜 is positive definite
// (model_checks.cpp).  Pure algebra on P: no Model, no Data, so the model layer may use it without
// reaching up to the dynamics.
#pragma once

#include "soadyn/multibody/types.hpp"

#include <Eigen/LU>

namespace soadyn::articulated_inertia {

// P = [I h̃; −h̃ m e], the spatial inertia of a body of mass m with first moment h and inertia I
// about P's point, written in place entry by entry: a 6×6 assembled from 3×3 temporaries goes
// through the stack in 8-byte pieces read back at once in 16-byte ones, which the CPU cannot forward
inline void set_inertia(Mat6& P, const Mat3& I, const Vec3& h, double m) {
  const double h0 = h(0), h1 = h(1), h2 = h(2);
  P.topLeftCorner<3, 3>() = I;
  P.col(3) << 0.0, h2, -h1, m, 0.0, 0.0;
  P.col(4) << -h2, 0.0, h0, 0.0, m, 0.0;
  P.col(5) << h1, -h0, 0.0, 0.0, 0.0, m;
  P.block<3, 3>(3, 0) << 0.0, h2, -h1, -h2, 0.0, h0, h1, -h0, 0.0;  // −h̃ = h̃ᵀ, row by row
}

// One joint column g projected out: U = P g, 𝒟 = gᵀ U, P⁺ = P − U 𝒟⁻¹ Uᵀ, given U and 𝒟⁻¹;
// column by column (inlined, unlike Eigen's outer product)
inline void remove_column(Mat6& P, const Vec6& U, double Dinv) {
  const Vec6 UD = Dinv * U;
  for (int c = 0; c < 6; ++c) P.col(c) -= U(c) * UD;
}

// out += Dᵀ P D for a symmetric 6×6 P = [A B; Bᵀ C] and D = [e 0; −d̃ e] (the move of an
// inertia from a child's joint point to its parent's, d the child's point less the parent's):
//   [A + X + Xᵀ + d̃ C d̃ᵀ,  B + d̃ C;  (B + d̃ C)ᵀ,  C]   with X = d̃ Bᵀ,
// each d̃ product taken as three cross products.
inline void add_to_parent(Mat6& out, const Mat6& P, const Vec3& d) {
  const Mat3 B = P.topRightCorner<3, 3>(), C = P.bottomRightCorner<3, 3>();
  Mat3 W, X, Y;  // W = d̃ C, X = d̃ Bᵀ, Y = d̃ Wᵀ = (W d̃ᵀ)ᵀ = d̃ C d̃ᵀ (symmetric)
  for (int c = 0; c < 3; ++c) {
    W.col(c) = d.cross(Vec3(C.col(c)));
    X.col(c) = d.cross(Vec3(B.row(c).transpose()));
  }
  for (int c = 0; c < 3; ++c) Y.col(c) = d.cross(Vec3(W.row(c).transpose()));
  out.topLeftCorner<3, 3>() += P.topLeftCorner<3, 3>() + X + X.transpose() + Y;
  out.topRightCorner<3, 3>() += B + W;
  out.bottomLeftCorner<3, 3>() += (B + W).transpose();
  out.bottomRightCorner<3, 3>() += C;
}

// 𝒟⁻¹ of a joint's n×n 𝒟 = Gᵀ P G (symmetric positive definite): Eigen's closed forms up to
// n = 4; for the free joint's 6×6, by its 3×3 blocks 𝒟 = [A B; Bᵀ C] with X = A⁻¹ B and the Schur
// complement Σ = C − Bᵀ X: 𝒟⁻¹ = [A⁻¹ + X Σ⁻¹ Xᵀ, −X Σ⁻¹; −Σ⁻¹ Xᵀ, Σ⁻¹] (Eigen's general 6×6 inverse,
// an LU with pivoting, costs several times as much)
template <int n>
inline Eigen::Matrix<double, n, n> joint_inertia_inverse(const Eigen::Matrix<double, n, n>& D) {
  if constexpr (n != 6) {
    return D.inverse();
  } else {
    const Mat3 Ai = Mat3(D.template topLeftCorner<3, 3>()).inverse();
    const Mat3 B = D.template topRightCorner<3, 3>();
    const Mat3 X = Ai * B;
    const Mat3 Si = (Mat3(D.template bottomRightCorner<3, 3>()) - B.transpose() * X).inverse();
    const Mat3 XS = X * Si;
    Eigen::Matrix<double, 6, 6> out;
    out.template topLeftCorner<3, 3>() = Ai + XS * X.transpose();
    out.template topRightCorner<3, 3>() = -XS;
    out.template bottomLeftCorner<3, 3>() = -XS.transpose();
    out.template bottomRightCorner<3, 3>() = Si;
    return out;
  }
}

}  // namespace soadyn::articulated_inertia
