// X ← 𝓜⁻¹ X for many right-hand sides with the articulated-body factor (the innovations
// factorization behind the note's factored inverse mass matrix): the articulated inertias P⁺_i,
// U_i = P_i G_i and 𝒟_i⁻¹ = (G_iᵀ U_i)⁻¹ that aba's tip-to-base sweep (articulated.cpp) leaves in Data.
// For one right-hand side b (zero velocity, no gravity: a force alone) the recursion is
//   tip to base:  u_i = b_i − G_iᵀ Z_i,   Z_p += D_iᵀ (Z_i + U_i 𝒟_i⁻¹ u_i)
//   base to tip:  A'_i = D_i A_p,  x_i = 𝒟_i⁻¹ (u_i − U_iᵀ A'_i),  A_i = A'_i + G_i x_i
// O(N) per right-hand side whatever the tree, where LᵀDL costs the sum of the DOFs' depths.  The
// right-hand sides go K at a time, turned into rows: body i's Z_i (then A_i) is a K×6 block of fixed
// size, each of its columns one SIMD register or two, so every line below is a few vector
// instructions and the blocks of all bodies stay in the first cache levels.
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/operators.hpp"

#include "row_blocks.hpp"

#include <algorithm>

namespace soadyn {

namespace {

using Stride = Eigen::OuterStride<>;

// right-hand sides per pass (row_blocks.hpp): 16, a column of a body's block two AVX-512 registers
// (measured against 4 and 8: the fastest on chains of 16 and more bodies); fewer for a last group
constexpr int kRows = detail::kMaxRows;

// the K right-hand sides held as the rows of x (column stride ld) solved in place; w: the K×6
// blocks of N bodies
template <int K>
void solve_rows(const Model& model, const Data& data, double* x, Eigen::Index ld, double* w) {
  using Col = Eigen::Matrix<double, K, 1>;
  using Block = detail::RowBlock<K, 6>;
  using Cols = detail::RowBlock<K, Eigen::Dynamic, 6>;
  const int N = model.nbodies;
  const DOperator D{data.d};
  std::fill(w, w + 6 * K * N, 0.0);
  // tip to base: u_i = b_i − G_iᵀ Z_i (kept in X), Z_p += D_iᵀ (Z_i + U_i 𝒟_i⁻¹ u_i).  Each block is
  // read into a local once and written once: a block written and read back at once would wait on
  // the stores
  for (int i = N - 1; i >= 0; --i) visit_joint(model, i, [&](const auto& joint) {
    using J = std::decay_t<decltype(joint)>;
    const int vi = model.idx_v[i], ni = J::nv, p = model.parent[i];
    Block Z = Eigen::Map<const Block>(w + 6 * K * i);
    if constexpr (J::nv == 1) {
      Eigen::Map<Col> u(x + vi * ld);
      u -= Z.lazyProduct(data.G.col(vi));
      if (p < 0) return;
      const Vec6 UD = data.work.articulated.Dinv1(i) * data.work.articulated.U1.col(i);
      Z += u.lazyProduct(UD.transpose());
    } else {
      Eigen::Map<Cols, 0, Stride> u(x + vi * ld, K, ni, Stride(ld));
      u -= Z.lazyProduct(data.G.middleCols(vi, ni));
      if (p < 0) return;
      const Mat6G UD = data.work.articulated.U[i] * data.work.articulated.Dinv[i];
      Z += u.lazyProduct(UD.transpose());
    }
    D.add_apply_transpose_rows(i, Z, Eigen::Map<Block>(w + 6 * K * p));
  });
  // base to tip: A'_i = D_i A_p, x_i = 𝒟_i⁻¹ (u_i − U_iᵀ A'_i) (into X), A_i = A'_i + G_i x_i (in Z_i's place)
  for (int i = 0; i < N; ++i) visit_joint(model, i, [&](const auto& joint) {
    using J = std::decay_t<decltype(joint)>;
    const int vi = model.idx_v[i], ni = J::nv, p = model.parent[i];
    Block A;
    if (p >= 0)
      D.apply_rows(i, Eigen::Map<const Block>(w + 6 * K * p), A);
    else
      A.setZero();
    if constexpr (J::nv == 1) {
      Eigen::Map<Col> xi(x + vi * ld);
      Col xv = xi;
      if (p >= 0) xv -= A.lazyProduct(data.work.articulated.U1.col(i));
      xv *= data.work.articulated.Dinv1(i);
      xi = xv;
      A += xv.lazyProduct(data.G.col(vi).transpose());
    } else {
      Eigen::Map<Cols, 0, Stride> xi(x + vi * ld, K, ni, Stride(ld));
      if (p >= 0) xi -= A.lazyProduct(data.work.articulated.U[i]);
      const Cols t = xi.lazyProduct(data.work.articulated.Dinv[i].transpose());
      xi = t;
      A += t.lazyProduct(data.G.middleCols(vi, ni).transpose());
    }
    Eigen::Map<Block>(w + 6 * K * i) = A;
  });
}

}  // namespace

void articulated_solve(const Model& model, const Data& data, Eigen::Ref<MatX> X, MatX& work) {
  const int N = model.nbodies, nv = model.nv;
  constexpr int K = kRows;
  if (X.rows() != nv || work.rows() != 6 * K || work.cols() != N + (nv + 5) / 6)
    throw Error("articulated_solve: expected X with " + std::to_string(nv) + " rows and a workspace of " +
                std::to_string(6 * K) + " × " + std::to_string(N + (nv + 5) / 6) + " (articulated_solve_work); got " +
                std::to_string(X.rows()) + " rows and " + std::to_string(work.rows()) + " × " + std::to_string(work.cols()));
  // K columns of X at a time, turned into the K rows of `rows` (after the bodies' blocks): each
  // DOF's K entries contiguous; a last, narrower group in 4, 8 or 12 rows, zero-padded
  for (Eigen::Index c0 = 0; c0 < X.cols(); c0 += K) {
    const Eigen::Index n = std::min<Eigen::Index>(K, X.cols() - c0);
    detail::with_rows(int(n), [&]<int R>() {
      Eigen::Map<detail::RowBlock<R, Eigen::Dynamic>> rows(work.data() + 6 * K * N, R, nv);
      if (n < R) rows.setZero();
      rows.topRows(n) = X.middleCols(c0, n).transpose();
      solve_rows<R>(model, data, rows.data(), R, work.data());
      X.middleCols(c0, n) = rows.topRows(n).transpose();
    });
  }
}

MatX articulated_solve_work(const Model& model) {
  return MatX::Zero(6 * kRows, model.nbodies + (model.nv + 5) / 6);
}

}  // namespace soadyn
