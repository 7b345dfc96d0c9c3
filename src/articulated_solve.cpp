// X ← 𝓜⁻¹ X for many right-hand sides with the articulated-body factor (the innovations
// factorization behind the note's factored inverse mass matrix): the articulated inertias P⁺_i,
// U_i = P_i G_i and 𝒟_i⁻¹ = (G_iᵀ U_i)⁻¹ that aba's tip-to-base sweep (dynamics.cpp) leaves in Data.
// For one right-hand side b (zero velocity, no gravity: a force alone) the recursion is
//   tip to base:  u_i = b_i − G_iᵀ Z_i,   Z_p += D_iᵀ (Z_i + U_i 𝒟_i⁻¹ u_i)
//   base to tip:  A'_i = D_i A_p,  x_i = 𝒟_i⁻¹ (u_i − U_iᵀ A'_i),  A_i = A'_i + G_i x_i
// O(N) per right-hand side whatever the tree, where LᵀDL costs the sum of the DOFs' depths.  The
// right-hand sides are the rows of Xt, k at a time: body i's Z_i (then A_i) is a k×6 block and
// each line of the sweeps one vectorized pass over the k rows.
#include "soadyn/algorithms.hpp"
#include "soadyn/operators.hpp"

#include <algorithm>

namespace soadyn {

void articulated_solve(const Model& model, const Data& data, Eigen::Ref<MatX> Xt, MatX& work) {
  const int N = model.nbodies;
  if (Xt.cols() != model.nv || work.cols() != 6 * (N + 1) || work.rows() < 1)
    throw Error("articulated_solve: expected Xt with " + std::to_string(model.nv) + " columns and a workspace of " +
                std::to_string(6 * (N + 1)) + " columns; got " + std::to_string(Xt.cols()) + " and " +
                std::to_string(work.cols()));
  const DOperator D{data.d};
  for (Eigen::Index r0 = 0; r0 < Xt.rows(); r0 += work.rows()) {
    const Eigen::Index k = std::min(work.rows(), Xt.rows() - r0);
    auto W = work.topRows(k);             // Z_i, then A_i, at columns 6i..6i+5
    auto T = W.middleCols<6>(6 * N);      // a multi-DOF joint's scratch
    auto X = Xt.middleRows(r0, k);
    W.leftCols(6 * N).setZero();
    // tip to base: u_i = b_i − G_iᵀ Z_i (kept in X), Z_p += D_iᵀ (Z_i + U_i 𝒟_i⁻¹ u_i)
    for (int i = N - 1; i >= 0; --i) {
      const int vi = model.idx_v[i], ni = model.nv_i[i], p = model.parent[i];
      auto Z = W.middleCols<6>(6 * i);
      if (ni == 1) {
        auto u = X.col(vi);
        const Vec6 g = data.G.col(vi);
        u -= g(0) * Z.col(0) + g(1) * Z.col(1) + g(2) * Z.col(2) + g(3) * Z.col(3) + g(4) * Z.col(4) + g(5) * Z.col(5);
        if (p < 0) continue;
        const Vec6 UD = data.Dinv1(i) * data.U1.col(i);
        for (int c = 0; c < 6; ++c) Z.col(c) += UD(c) * u;
      } else {
        auto u = X.middleCols(vi, ni);
        u.noalias() -= Z.lazyProduct(data.G.middleCols(vi, ni));
        if (p < 0) continue;
        const Mat6G UD = data.U[i] * data.Dinv[i];
        Z.noalias() += u.lazyProduct(UD.transpose());
      }
      D.add_apply_transpose_rows(i, Z, W.middleCols<6>(6 * p));
    }
    // base to tip: A'_i = D_i A_p, x_i = 𝒟_i⁻¹ (u_i − U_iᵀ A'_i) (into X), A_i = A'_i + G_i x_i
    for (int i = 0; i < N; ++i) {
      const int vi = model.idx_v[i], ni = model.nv_i[i], p = model.parent[i];
      auto A = W.middleCols<6>(6 * i);
      A.setZero();
      if (p >= 0) D.add_apply_rows(i, W.middleCols<6>(6 * p), A);
      if (ni == 1) {
        auto x = X.col(vi);
        const Vec6 U = data.U1.col(i), g = data.G.col(vi);
        if (p >= 0) x -= U(0) * A.col(0) + U(1) * A.col(1) + U(2) * A.col(2) + U(3) * A.col(3) + U(4) * A.col(4) + U(5) * A.col(5);
        x *= data.Dinv1(i);
        for (int c = 0; c < 6; ++c) A.col(c) += g(c) * x;
      } else {
        auto x = X.middleCols(vi, ni);
        if (p >= 0) x.noalias() -= A.lazyProduct(data.U[i]);
        T.leftCols(ni).noalias() = x.lazyProduct(data.Dinv[i].transpose());
        x = T.leftCols(ni);
        A.noalias() += x.lazyProduct(data.G.middleCols(vi, ni).transpose());
      }
    }
  }
}

}  // namespace soadyn
