// ∂q̈/∂q, ∂q̈/∂v and 𝓜⁻¹ of forward dynamics (derivatives.hpp): q̈ by the articulated-body route,
// the sweeps of the inverse-dynamics derivatives at that q̈ (derivatives.cpp), 𝓜⁻¹ about the
// inertial origin (minverse.cpp), then 𝓜⁻¹ times ∂τ/∂x without forming ∂τ/∂x, O(N²) on every tree.
#include "soadyn/algorithm/derivatives.hpp"

#include "soadyn/algorithm/algorithms.hpp"

#include "derivative_sweeps.hpp"
#include "minverse.hpp"

#include <algorithm>

namespace soadyn {

namespace {

// The two passes' steps for a joint of n DOFs, each one pass over k < nv (m, x, y: the joint's n
// columns of 𝓜⁻¹, X_q, X_v, at stride lx; Q, Qc, P: 6 or 9 columns at stride ld; the coefficients:
// the sweeps' 6- and 9-vectors of the n DOFs).
// Base to tip: x_a = −𝒬 ψ_a, y_a = −𝒬 ρ_a from 𝒬 (Q: 6 columns; zeros at a root), and into Qc
// 𝒬 + Σ_a m_a S_aᵀ, the children's 𝒬 (Qc may be Q: in place along a path; at a leaf no child reads
// it).  One copy per n, not one per root and leaf: the code a call runs stays small
// (one DOF: one pass over k for the whole step; several: one per output column, which keeps each
// loop to a few streams the compiler vectorizes)
template <int n>
void ancestors_step(const double* Q, double* Qc, Eigen::Index ld, const double* m, double* x, double* y, Eigen::Index lx,
                    const double (&S)[n][6], const double (&psi)[n][6], const double (&rho)[n][6], int nv) {
  constexpr bool fused = n == 1;
  for (int a = 0; a < (fused ? 1 : n); ++a) {
#pragma GCC ivdep
    for (int k = 0; k < nv; ++k) {
      double q[6];
      for (int c = 0; c < 6; ++c) q[c] = Q[c * ld + k];
      double sx = 0.0, sy = 0.0;
      for (int c = 0; c < 6; ++c) sx += q[c] * psi[a][c], sy += q[c] * rho[a][c];
      x[a * lx + k] = -sx, y[a * lx + k] = -sy;
      if constexpr (fused)
        for (int c = 0; c < 6; ++c) Qc[c * ld + k] = q[c] + m[k] * S[0][c];
    }
  }
  if constexpr (!fused)
    for (int c = 0; c < 6; ++c) {
      double* __restrict to = Qc + c * ld;
      const double* from = Q + c * ld;
#pragma GCC ivdep
      for (int k = 0; k < nv; ++k) {
        double t = from[k];
        for (int a = 0; a < n; ++a) t += m[a * lx + k] * S[a][c];
        to[k] = t;
      }
    }
}

// Tip to base: 𝒫 (9 columns) += Σ_a m_a row_aᵀ (zeroed first at a leaf), then x_a −= 𝒫 colq_a, y_a −= 𝒫 colv_a
template <int n>
void subtree_step(double* P, Eigen::Index ld, const double* m, double* x, double* y, Eigen::Index lx,
                  const double (&row)[n][9], const double (&cq)[n][9], const double (&cv)[n][9], int nv) {
  if constexpr (n == 1) {
#pragma GCC ivdep
    for (int k = 0; k < nv; ++k) {
      double sx = 0.0, sy = 0.0;
      for (int c = 0; c < 9; ++c) {
        const double t = P[c * ld + k] + m[k] * row[0][c];
        P[c * ld + k] = t;
        sx += t * cq[0][c], sy += t * cv[0][c];
      }
      x[k] -= sx, y[k] -= sy;
    }
  } else {
    for (int c = 0; c < 9; ++c) {
      double* __restrict pc = P + c * ld;
#pragma GCC ivdep
      for (int k = 0; k < nv; ++k) {
        double t = pc[k];
        for (int a = 0; a < n; ++a) t += m[a * lx + k] * row[a][c];
        pc[k] = t;
      }
    }
    for (int a = 0; a < n; ++a) {
      double* __restrict xa = x + a * lx;
      double* __restrict ya = y + a * lx;
#pragma GCC ivdep
      for (int k = 0; k < nv; ++k) {
        double sx = 0.0, sy = 0.0;
        for (int c = 0; c < 9; ++c) sx += P[c * ld + k] * cq[a][c], sy += P[c * ld + k] * cv[a][c];
        xa[k] -= sx, ya[k] -= sy;
      }
    }
  }
}

// The two passes' steps at joint j, one copy per number of DOFs n (every joint kind of n DOFs alike)
struct Products {
  const Model& model;
  DerivativeData& dd;
  Eigen::Index ld, lx;
  int nv;

  double* block(int body) const { return dd.blocks.data() + 9 * model.path[size_t(body)] * ld; }
  // the first `columns` columns of a block, each nv long, set to zero
  void zero(double* b, int columns) const {
    for (int c = 0; c < columns; ++c) std::fill(b + c * ld, b + c * ld + nv, 0.0);
  }
  // the coefficients of the joint's n DOFs
  template <int n, int C, class M>
  static void coefficients(const M& from, int vj, double (&to)[n][C]) {
    for (int a = 0; a < n; ++a)
      for (int c = 0; c < C; ++c) to[a][c] = from(c, vj + a);
  }

  // base to tip: X = −𝒬_j [ψ_c, ρ_c], then 𝒬 for the children: 𝒬_j + Σ_{r ∈ j} 𝓜⁻¹_r S_rᵀ
  template <int n>
  [[gnu::noinline]] void ancestors(int j) {
    const int vj = model.idx_v[j], p = model.parent[j];
    const double* m = dd.Minv.col(vj).data();
    double *x = dd.dqdd_dq.col(vj).data(), *y = dd.dqdd_dv.col(vj).data();
    double S[n][6], psi[n][6], rho[n][6];
    coefficients(dd.S, vj, S);
    coefficients(dd.psi, vj, psi);
    coefficients(dd.rho, vj, rho);
    double* Qc = block(j);
    if (p < 0) zero(Qc, 6);  // a root's 𝒬 = 0, in place in its own block
    ancestors_step<n>(p < 0 ? Qc : block(p), Qc, ld, m, x, y, lx, S, psi, rho, nv);
  }

  // tip to base: 𝒫_j = Σ_{r ∈ j} 𝓜⁻¹_r row_rᵀ + Σ_children 𝒫_c, then X −= 𝒫_j [colq_c, colv_c], and
  // 𝒫_j into the parent's block when the parent is on another path
  template <int n>
  [[gnu::noinline]] void subtree(int j) {
    const int vj = model.idx_v[j], p = model.parent[j];
    const double* m = dd.Minv.col(vj).data();
    double *x = dd.dqdd_dq.col(vj).data(), *y = dd.dqdd_dv.col(vj).data();
    double row[n][9], cq[n][9], cv[n][9];
    coefficients(dd.row, vj, row);
    coefficients(dd.colq, vj, cq);
    coefficients(dd.colv, vj, cv);
    double* Pj = block(j);
    if (dd.leaf[size_t(j)]) zero(Pj, 9);  // a leaf's 𝒫 starts from its own rows
    subtree_step<n>(Pj, ld, m, x, y, lx, row, cq, cv, nv);
    if (p >= 0 && model.path[size_t(p)] != model.path[size_t(j)]) {
      double* Pp = block(p);
      for (int c = 0; c < 9; ++c)
        for (int k = 0; k < nv; ++k) Pp[c * ld + k] += Pj[c * ld + k];
    }
  }
};

// X_q = 𝓜⁻¹ (∂τ_in/∂q − ∂ID/∂q) and X_v the same for v, from 𝓜⁻¹ and the sweeps' vectors.  With
// ∂ID(r, c) = row_r·colq_c for r ⪰ j (j: the joint of c) and S_r·ψ_c for r ≺ j (derivatives.cpp's
// header), column c of 𝓜⁻¹ ∂ID is
//   𝒫_j colq_c + 𝒬_j ψ_c,   𝒫_j = Σ_{r ⪰ j} 𝓜⁻¹_r row_rᵀ (nv×9),   𝒬_j = Σ_{r ≺ j} 𝓜⁻¹_r S_rᵀ (nv×6)
// (𝓜⁻¹_r: column r), plus, for a joint of several DOFs, 𝓜⁻¹_r S_r·φ_c for its r that c does not
// carry; the same for v with colv, ρ.  𝒬 grows base to tip and 𝒫 tip to base, each held per path
// (Model::path) and updated in place along it: O(nv) per DOF for each, O(N²) in all where the
// product with ∂ID would be O(N³) on a chain.
void minv_times_derivatives(const Model& model, DerivativeData& dd, const Inputs* inputs) {
  const int N = model.nbodies;
  const Eigen::Index lx = dd.Minv.outerStride();
  if (dd.dqdd_dq.outerStride() != lx || dd.dqdd_dv.outerStride() != lx)
    throw Error("forward_dynamics_derivatives: DerivativeData's sizes");
  Products products{model, dd, dd.blocks.outerStride(), lx, model.nv};
  for (int j = 0; j < N; ++j)
    visit_joint(model, j, [&](const auto& joint) { products.ancestors<std::decay_t<decltype(joint)>::nv>(j); });
  for (int j = N - 1; j >= 0; --j) visit_joint(model, j, [&](const auto& joint) {
    using J = std::decay_t<decltype(joint)>;
    products.subtree<J::nv>(j);
    // the joint's own rows that column c does not carry: S_r·φ_c
    if constexpr (J::nv > 1) {
      const int vj = model.idx_v[j];
      for (int a = 0; a < J::nv; ++a)
        for (int r = 0; r < J::nv; ++r)
          if (!J::carries(a, r)) dd.dqdd_dq.col(vj + a) -= dd.S.col(vj + r).dot(dd.phi.col(vj + a)) * dd.Minv.col(vj + r);
    }
  });
  if (inputs) inputs->add_derivatives_times(dd.Minv, dd.dqdd_dq, dd.dqdd_dv);
}

}  // namespace

void forward_dynamics_derivatives(const Model& model, Data& data, const VecX& v, const VecX& tau, DerivativeData& dd,
                                  const Inputs* inputs, bool /*minv: always formed*/) {
  data.require("forward_dynamics_derivatives", true);
  // q̈, then at that q̈ the sweeps ∂ID is made of, 𝓜⁻¹ about the origin with the sweeps' S, and the products
  forward_dynamics(model, data, tau, FdMethod::ArticulatedBody);
  detail::derivative_sweeps(model, data, v, data.qdd, dd, "forward_dynamics_derivatives");
  detail::minverse_origin(model, data, dd.S, dd.Minv);
  minv_times_derivatives(model, dd, inputs);
}

}  // namespace soadyn
