// The note's influence operators as O(N) sweeps (never as matrices).
//
//   z = Ψ_A x = (e − Φ_A)⁻¹ x : base to tip,  z_i = A_i z_parent(i) + x_i
//   z = Ψ_Aᵀ x               : tip to base,  z_parent(i) += A_iᵀ z_i   (after z = x)
//
// Both are generic in what is carried: `at(i)` returns body i's block of the stacked vector
// (a 6-vector, or a 6×k block), and the operator A applies A_i or A_iᵀ to such a block.
#pragma once

#include "soadyn/multibody/types.hpp"

#include <cassert>
#include <vector>

namespace soadyn {

// z = Ψ_A z, in place (on entry z holds x).  Parents come before children.
template <class Op, class At>
void psi_base_to_tip(const std::vector<int>& parent, const Op& A, At&& at) {
  const int n = int(parent.size());
  for (int i = 0; i < n; ++i) {
    assert(parent[i] < i && "parent-first order");
    if (parent[i] >= 0) A.add_apply(i, at(parent[i]), at(i));  // z_i += A_i z_p
  }
}

// z = Ψ_Aᵀ z, in place (on entry z holds x).  Children come after parents.
template <class Op, class At>
void psi_tip_to_base(const std::vector<int>& parent, const Op& A, At&& at) {
  for (int i = int(parent.size()) - 1; i >= 0; --i) {
    assert(parent[i] < i && "parent-first order");
    if (parent[i] >= 0) A.add_apply_transpose(i, at(i), at(parent[i]));  // z_p += A_iᵀ z_i
  }
}

// A_i = D_i = [e 0; −d̃_i e]: carries a velocity pair from η_parent to η_i; D_iᵀ carries a
// force pair from η_i back to η_parent.
struct DOperator {
  const Mat3X& d;  // d_i = η_i − η_parent(i), inertial

  // dst += D_i src:  [ω; u] ↦ [ω; u + ω × d_i]
  template <class S, class T>
  void add_apply(int i, const Eigen::MatrixBase<S>& src, const Eigen::MatrixBase<T>& dst_) const {
    auto& dst = const_cast<Eigen::MatrixBase<T>&>(dst_);
    const Vec3 di = d.col(i);
    for (Eigen::Index c = 0; c < src.cols(); ++c) {
      const Vec3 w = src.col(c).template head<3>();
      dst.col(c).template head<3>() += w;
      dst.col(c).template tail<3>() += src.col(c).template tail<3>() + w.cross(di);
    }
  }

  // dst += D_iᵀ src:  [n; f] ↦ [n + d_i × f; f]
  template <class S, class T>
  void add_apply_transpose(int i, const Eigen::MatrixBase<S>& src, const Eigen::MatrixBase<T>& dst_) const {
    auto& dst = const_cast<Eigen::MatrixBase<T>&>(dst_);
    const Vec3 di = d.col(i);
    for (Eigen::Index c = 0; c < src.cols(); ++c) {
      const Vec3 f = src.col(c).template tail<3>();
      dst.col(c).template head<3>() += src.col(c).template head<3>() + di.cross(f);
      dst.col(c).template tail<3>() += f;
    }
  }

  // The same for k vectors held as the rows of a k×6 block (one right-hand side per row, so each
  // of the six components is a contiguous column and every line below one vectorized pass):
  // dst = src D_iᵀ, row by row [ω; u] ↦ [ω; u + ω × d_i] (written, not added: no zeroed block first)
  template <class S, class T>
  void apply_rows(int i, const Eigen::MatrixBase<S>& src, const Eigen::MatrixBase<T>& dst_) const {
    auto& dst = const_cast<Eigen::MatrixBase<T>&>(dst_);
    const double x = d(0, i), y = d(1, i), z = d(2, i);
    dst.template leftCols<3>() = src.template leftCols<3>();
    dst.col(3) = src.col(3) + z * src.col(1) - y * src.col(2);
    dst.col(4) = src.col(4) + x * src.col(2) - z * src.col(0);
    dst.col(5) = src.col(5) + y * src.col(0) - x * src.col(1);
  }
  // dst += src D_i, row by row [n; f] ↦ [n + d_i × f; f]
  template <class S, class T>
  void add_apply_transpose_rows(int i, const Eigen::MatrixBase<S>& src, const Eigen::MatrixBase<T>& dst_) const {
    auto& dst = const_cast<Eigen::MatrixBase<T>&>(dst_);
    const double x = d(0, i), y = d(1, i), z = d(2, i);
    dst.col(0) += src.col(0) + y * src.col(5) - z * src.col(4);
    dst.col(1) += src.col(1) + z * src.col(3) - x * src.col(5);
    dst.col(2) += src.col(2) + x * src.col(4) - y * src.col(3);
    dst.template rightCols<3>() += src.template rightCols<3>();
  }
};

// Any block-diagonal A = diag{A_i} of k×k blocks (A_i of a root is never used).
struct BlockOperator {
  const std::vector<MatX>& A;

  template <class S, class T>
  void add_apply(int i, const Eigen::MatrixBase<S>& src, const Eigen::MatrixBase<T>& dst_) const {
    const_cast<Eigen::MatrixBase<T>&>(dst_).noalias() += A[i] * src;
  }
  template <class S, class T>
  void add_apply_transpose(int i, const Eigen::MatrixBase<S>& src, const Eigen::MatrixBase<T>& dst_) const {
    const_cast<Eigen::MatrixBase<T>&>(dst_).noalias() += A[i].transpose() * src;
  }
};

}  // namespace soadyn
