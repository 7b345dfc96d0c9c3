// 𝓜 = Lᵀ D L factored along the tree (no fill-in off the ancestor chains) and its solve
// (algorithms.hpp): the sparse forward-dynamics route and the derivatives' 𝓜⁻¹ on small trees.
#include "soadyn/algorithm/algorithms.hpp"

namespace soadyn {

// f(m, len) for each stretch m..m+len−1 of consecutive DOFs making up DOF j and its ancestors
// (Model::dof_run), from j down to the root
template <class F>
void for_each_ancestor_run(const Model& model, int j, F&& f) {
  while (j >= 0) {
    const int m = model.dof_run[j];
    f(m, j - m + 1);
    j = model.dof_parent[m];
  }
}

// from this many DOFs on, a chain's LᵀDL is the blocked dense factorization (below)
constexpr int kChainBlocked = 16;

void ltdl_factor(const Model& model, Data& data) {
  // 𝓜 = Lᵀ D L along the DOF tree λ (Featherstone's LTDL): entries off ancestor chains stay zero.
  // Row i of the update H(i, j) −= a H(k, j), j over i and its ancestors, runs over the few
  // stretches of consecutive DOFs the chain is made of (one stretch on a chain): each is one
  // vectorized row-segment operation.
  auto& H = data.work.factor.L;
  const int n = model.nv;
  if (model.chain && n >= kChainBlocked) {
    // A chain has no sparsity to use: 𝓜 = Lᵀ D L is then the dense factorization of the reversed
    // matrix, done by Eigen's blocked Cholesky.  With J the reversal, J 𝓜 J = C Cᵀ (C lower), so
    // 𝓜 = U Uᵀ with U = J C J upper, and Lᵀ = U diag(U)⁻¹, D = diag(U)²:
    //   L(k, i) = C(n−1−i, n−1−k) / C(n−1−k, n−1−k),  D(k) = C(n−1−k, n−1−k)²
    data.work.factor.llt.compute(data.M.reverse());
    if (data.work.factor.llt.info() != Eigen::Success) throw Error("forward dynamics: the mass matrix is not positive definite");
    const MatX& C = data.work.factor.llt.matrixLLT();
    for (int k = 0; k < n; ++k) {
      const double ckk = C(n - 1 - k, n - 1 - k), inv = 1.0 / ckk;
      for (int i = 0; i < k; ++i) H(k, i) = C(n - 1 - i, n - 1 - k) * inv;
      H(k, k) = ckk * ckk;
    }
    return;
  }
  H = data.M.transpose();  // 𝓜 is symmetric: a straight copy into row-major storage
  const auto& lambda = model.dof_parent;
  for (int k = model.nv - 1; k >= 0; --k) {
    for (int i = lambda[k]; i >= 0; i = lambda[i]) {
      const double a = H(k, i) / H(k, k);
      for_each_ancestor_run(model, i, [&](int m, int len) { H.row(i).segment(m, len) -= a * H.row(k).segment(m, len); });
      H(k, i) = a;
    }
  }
}

void ltdl_solve(const Model& model, const Data& data, Eigen::Ref<VecX> x) {
  const auto& H = data.work.factor.L;
  const auto& lambda = model.dof_parent;
  // Lᵀ y = x (tip to base), D w = y, L x = w (base to tip); each over the stretches of
  // consecutive ancestors (dof_run), as one vectorized segment operation each
  for (int k = model.nv - 1; k >= 0; --k)
    for_each_ancestor_run(model, lambda[k], [&](int m, int len) {
      x.segment(m, len) -= x(k) * H.row(k).segment(m, len).transpose();
    });
  for (int k = 0; k < model.nv; ++k) x(k) /= H(k, k);
  for (int k = 0; k < model.nv; ++k)
    for_each_ancestor_run(model, lambda[k], [&](int m, int len) {
      x(k) -= H.row(k).segment(m, len).dot(x.segment(m, len));
    });
}

}  // namespace soadyn
