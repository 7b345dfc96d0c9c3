// Products with the inverse-dynamics derivatives without forming them (derivatives.hpp): after the
// sweeps (inverse_dynamics_derivative_sweeps), entry (r, c) of ∂τ/∂q, with c a column of joint j and
// r a row of body i, is (derivatives.cpp)
//   row_r·colq_c                 i ⪰ j   (plus S_r·φ_c within joint j where c does not carry r)
//   S_r·ψ_c                      i ≺ j
// and of ∂τ/∂q̇ row_r·colv_c (i ⪰ j), S_r·ρ_c (i ≺ j).  So a product's row r is one dot product with
// a sum over body i's ancestors (base to tip) and one with a sum over its subtree (tip to base), O(N)
// per vector, and the transpose the same with the roles of the sums exchanged.
#include "soadyn/algorithm/derivatives.hpp"

#include "row_blocks.hpp"

#include <algorithm>

namespace soadyn {

void inverse_dynamics_derivatives_transpose_times(const Model& model, DerivativeData& dd, const VecX& mu,
                                                  Eigen::Ref<VecX> gq, Eigen::Ref<VecX> gv) {
  if (mu.size() != model.nv || gq.size() != model.nv || gv.size() != model.nv || dd.S.cols() != model.nv)
    throw Error("inverse_dynamics_derivatives_transpose_times: mu, gq, gv: expected " + std::to_string(model.nv) +
                " entries each, for a DerivativeData of this model");
  const int N = model.nbodies;
  // The fill's sums, column by column, with μ folded in: s_i = Σ_{r ∈ i} S_r μ_r; the ancestors' rows
  // give w_p·ψ_c (w_i = w_p + s_i, base to tip), body i's and its descendants' rows [T1; T2]·col with
  // T1_i = Σ_{k ⪰ i} Y_k s_k and T2_i = Σ_{k ⪰ i} (B_kᵀ s_k)_ω (Y, B composite; tip to base; Bᵀ s has no lower half), so that
  //   (∂τ/∂q)ᵀμ at c = T1_j·κ_c + T2_j·β_c + w_p·ψ_c + Σ_{r ∈ j, c does not carry r} μ_r S_r·φ_c
  //   (∂τ/∂q̇)ᵀμ at c = −T1_j·λ_c + T2_j·S_c + w_p·ρ_c
  Mat6X &w = dd.w, &T1 = dd.T1;
  Mat3X &T2 = dd.T2;
  for (int i = 0; i < N; ++i) {
    const int p = model.parent[i], vi = model.idx_v[i], ni = model.nv_i[i];
    const Vec6 si = dd.S.middleCols(vi, ni) * mu.segment(vi, ni);
    w.col(i) = (p < 0 ? Vec6::Zero() : Vec6(w.col(p))) + si;
    T1.col(i) = dd.Y[i] * si;
    T2.col(i) = dd.B[i].transpose_times(si);
  }
  for (int i = N - 1; i >= 0; --i)
    if (const int p = model.parent[i]; p >= 0) T1.col(p) += T1.col(i), T2.col(p) += T2.col(i);
  for (int j = 0; j < N; ++j) visit_joint(model, j, [&](const auto& joint) {
    using J = std::decay_t<decltype(joint)>;
    const int p = model.parent[j], vj = model.idx_v[j], nj = model.nv_i[j];
    const Vec6 wp = p < 0 ? Vec6::Zero() : Vec6(w.col(p));
    for (int k = 0; k < nj; ++k) {
      const int c = vj + k;
      double q = T1.col(j).dot(dd.colq.col(c).head<6>()) + T2.col(j).dot(dd.colq.col(c).tail<3>()) + wp.dot(dd.psi.col(c));
      for (int r = 0; r < nj; ++r)
        if (!J::carries(k, r)) q += mu(vj + r) * dd.S.col(vj + r).dot(dd.phi.col(c));
      gq(c) = q;
      gv(c) = T1.col(j).dot(dd.colv.col(c).head<6>()) + T2.col(j).dot(dd.colv.col(c).tail<3>()) + wp.dot(dd.rho.col(c));
    }
  });
}

static_assert(DerivativeData::kDirections == detail::kMaxRows);

namespace {

// the K directions held as rows (K × nv, column stride K): xq, xv in, out written; w: K×9 then K×6
// blocks of N bodies, each column j of a block K numbers at K·j.  Up to 16 rows, a column then two
// AVX-512 registers (row_blocks.hpp); every step below is a loop of such columns, each block read and
// written once per body
template <int K>
void times_rows(const Model& model, const DerivativeData& dd, const double* xq, const double* xv, double* out,
                double* w) {
  using Col = Eigen::Matrix<double, K, 1>;
  using In = Eigen::Map<const Col>;
  using Out = Eigen::Map<Col>;
  const int N = model.nbodies;
  double* const a = w;
  double* const z = w + 9 * K * N;
  // base to tip: A_i = A_p + Σ_{c ∈ i} (x_c colq_cᵀ + y_c colv_cᵀ), the columns of i and its ancestors
  for (int i = 0; i < N; ++i) {
    const int p = model.parent[i], vi = model.idx_v[i], ni = model.nv_i[i];
    double* const Ai = a + 9 * K * i;
    for (int j = 0; j < 9; ++j) {
      Col s = p < 0 ? Col::Zero() : Col(In(a + 9 * K * p + K * j));
      for (int c = vi; c < vi + ni; ++c) s += In(xq + K * c) * dd.colq(j, c) + In(xv + K * c) * dd.colv(j, c);
      Out(Ai + K * j) = s;
    }
    std::fill(z + 6 * K * i, z + 6 * K * (i + 1), 0.0);  // the tip-to-base sums start here
  }
  // tip to base: Z_i = Σ_{c ≻ i} (x_c ψ_cᵀ + y_c ρ_cᵀ), the columns of i's subtree below it; then
  // out_r = A_i row_r + Z_i S_r for the rows of i
  for (int i = N - 1; i >= 0; --i) visit_joint(model, i, [&](const auto& joint) {
    using J = std::decay_t<decltype(joint)>;
    const int p = model.parent[i], vi = model.idx_v[i];
    const double* const Ai = a + 9 * K * i;
    const double* const Zi = z + 6 * K * i;
    for (int r = vi; r < vi + J::nv; ++r) {
      Col o = In(Ai) * dd.row(0, r);
      for (int j = 1; j < 9; ++j) o += In(Ai + K * j) * dd.row(j, r);
      for (int j = 0; j < 6; ++j) o += In(Zi + K * j) * dd.S(j, r);
      Out(out + K * r) = o;
    }
    // within a joint of several DOFs, S_r·φ_c where c does not carry r (one DOF: S_c·φ_c = 0)
    if constexpr (J::nv > 1)
      for (int k = 0; k < J::nv; ++k)
        for (int m = 0; m < J::nv; ++m)
          if (!J::carries(k, m)) Out(out + K * (vi + m)) += dd.S.col(vi + m).dot(dd.phi.col(vi + k)) * In(xq + K * (vi + k));
    if (p < 0) return;
    double* const Zp = z + 6 * K * p;
    for (int j = 0; j < 6; ++j) {
      Col s = In(Zi + K * j);
      for (int c = vi; c < vi + J::nv; ++c) s += In(xq + K * c) * dd.psi(j, c) + In(xv + K * c) * dd.rho(j, c);
      Out(Zp + K * j) += s;
    }
  });
}

}  // namespace

void inverse_dynamics_derivatives_times(const Model& model, DerivativeData& dd, const Eigen::Ref<const MatX>& xq,
                                        const Eigen::Ref<const MatX>& xv, Eigen::Ref<MatX> out) {
  constexpr int K = DerivativeData::kDirections;
  const int N = model.nbodies, nv = model.nv;
  if (xq.rows() != nv || xv.rows() != nv || out.rows() != nv || xv.cols() != xq.cols() || out.cols() != xq.cols() ||
      dd.S.cols() != nv)
    throw Error("inverse_dynamics_derivatives_times: xq, xv, out: expected " + std::to_string(nv) +
                " rows and as many columns each, for a DerivativeData of this model");
  // K columns at a time, turned into rows after the bodies' blocks (each DOF's K entries
  // contiguous); a last, narrower group in fewer rows (row_blocks.hpp), zero-padded
  double* const w = dd.directions.data();
  for (Eigen::Index c0 = 0; c0 < xq.cols(); c0 += K) {
    const Eigen::Index n = std::min<Eigen::Index>(K, xq.cols() - c0);
    detail::with_rows(int(n), [&]<int R>() {
      Eigen::Map<detail::RowBlock<R, Eigen::Dynamic>> rq(w + 15 * K * N, R, nv), rv(rq.data() + R * nv, R, nv),
          ro(rv.data() + R * nv, R, nv);
      if (n < R) rq.setZero(), rv.setZero();
      rq.topRows(n) = xq.middleCols(c0, n).transpose();
      rv.topRows(n) = xv.middleCols(c0, n).transpose();
      times_rows<R>(model, dd, rq.data(), rv.data(), ro.data(), w);
      out.middleCols(c0, n) = ro.topRows(n).transpose();
    });
  }
}

}  // namespace soadyn
