// 𝓜⁻¹ in O(N²) without forming 𝓜 (algorithms.hpp): the articulated-body recursion for every unit
// force at once, written about the inertial origin, so that nothing is moved from body to body
// (no D_i) and the unit forces of a whole subtree share one block.
//
// S_i is G_i moved to the origin, Y_i the body's M_i moved there.  For the unit force at DOF k
// (τ = e_k, no velocity, no gravity), column k of 𝓜⁻¹ is the q̈ of
//   tip to base:  P_i = Y_i + Σ_c P⁺_c,  U_i = P_i S_i,  𝒟_i = S_iᵀ U_i,  P⁺_i = P_i − U_i 𝒟_i⁻¹ U_iᵀ
//                 u_i = [k ∈ i] e − S_iᵀ z_i,   z_p = Σ_c (z_c + U_c 𝒟_c⁻¹ u_c)
//   base to tip:  q̈_i = 𝒟_i⁻¹ (u_i − U_iᵀ a_p),  a_i = a_p + S_i q̈_i
// z_i is zero unless k lies in the subtree of i, so the first sweep visits, at body i, the k of its
// subtree (one run of depth-first positions; the subtrees of siblings are disjoint, so one nv×6
// block Z holds every z).  The second fills the row of 𝓜⁻¹ of each DOF r of i from its diagonal on
// (k ≥ r; the rest by symmetry), holding a_i for those k in an nv×6 block of i's path
// (Model::path), updated in place along it.  A row across k is held as a column of Minv (𝓜⁻¹ is
// symmetric), so every step is a few vector operations along k.
#include "soadyn/algorithms.hpp"
#include "soadyn/joint_model.hpp"

#include "articulated_inertia.hpp"
#include "minverse.hpp"

#include <algorithm>

namespace soadyn {

namespace detail {

void minverse_origin(const Model& model, Data& data, const Mat6X& S, MatX& Minv) {
  const int N = model.nbodies, nv = model.nv;
  auto& o = data.work.origin;
  if (Minv.rows() != nv || Minv.cols() != nv) Minv.resize(nv, nv);
  // the rows of 𝓜⁻¹ the first sweep does not write (k outside the subtree) start at zero
  Minv.triangularView<Eigen::Lower>().setZero();
  bool depth_first = true;
  for (int x = 0; x < nv; ++x) depth_first = depth_first && model.dfs_dof[size_t(x)] == x;
  for (int i = 0; i < N; ++i) {
    SpatialInertia Y;  // M_i moved from η_i to the origin
    Y.add_transformed(data.inertia[i], data.eta.col(i));
    articulated_inertia::set_inertia(o.P[i], Y.I, Y.h, Y.m);
  }
  o.Z.setZero();
  // tip to base
  for (int i = N - 1; i >= 0; --i) visit_joint(model, i, [&](const auto& joint) {
    using J = std::decay_t<decltype(joint)>;
    constexpr int n = J::nv;
    using MatN = Eigen::Matrix<double, n, n>;
    using Mat6N = Eigen::Matrix<double, 6, n>;
    const int vi = model.idx_v[i], p = model.parent[i];
    const int b = model.dfs_begin[i], s = b + n, m = model.dfs_end[i] - s;
    const Mat6N Si = S.middleCols<n>(vi);
    // U = P S,  𝒟⁻¹ = (Sᵀ U)⁻¹
    const Mat6N U = o.P[i] * Si;
    const MatN Dinv = MatN(Si.transpose() * U).inverse();
    const Mat6N UD = U * Dinv, SD = Si * Dinv;
    o.U.middleCols<n>(vi) = U;
    o.UD.middleCols<n>(vi) = UD;
    o.Dinv[i].topLeftCorner<n, n>() = Dinv;
    // the rows of i over its own DOFs (𝒟⁻¹) and over its strict subtree: −𝒟⁻¹ Sᵀ z (as columns: −Z S 𝒟⁻¹)
    Minv.block<n, n>(vi, vi) = Dinv;
    if constexpr (n == 1) {
      {
        // one pass over the subtree's positions x: r = −z·S 𝒟⁻¹ (the row), z += U r (for the parent);
        // the row straight into Minv when the model is numbered depth-first, else scattered after
        double* __restrict row = depth_first ? Minv.col(vi).data() + s : o.row.data();
        const auto scatter = [&] {
          if (!depth_first)
            for (int x = 0; x < m; ++x) Minv(model.dfs_dof[size_t(s + x)], vi) = row[x];
        };
        double* z = o.Z.data() + s;
        const Eigen::Index ld = o.Z.outerStride();
        const double sd0 = SD(0), sd1 = SD(1), sd2 = SD(2), sd3 = SD(3), sd4 = SD(4), sd5 = SD(5);
        if (p < 0) {
#pragma GCC ivdep
          for (int x = 0; x < m; ++x)
            row[x] = -(z[x] * sd0 + z[x + ld] * sd1 + z[x + 2 * ld] * sd2 + z[x + 3 * ld] * sd3 +
                       z[x + 4 * ld] * sd4 + z[x + 5 * ld] * sd5);
          scatter();
          return;
        }
        const double u0 = U(0), u1 = U(1), u2 = U(2), u3 = U(3), u4 = U(4), u5 = U(5);
#pragma GCC ivdep
        for (int x = 0; x < m; ++x) {
          const double r = -(z[x] * sd0 + z[x + ld] * sd1 + z[x + 2 * ld] * sd2 + z[x + 3 * ld] * sd3 +
                             z[x + 4 * ld] * sd4 + z[x + 5 * ld] * sd5);
          row[x] = r;
          z[x] += u0 * r, z[x + ld] += u1 * r, z[x + 2 * ld] += u2 * r;
          z[x + 3 * ld] += u3 * r, z[x + 4 * ld] += u4 * r, z[x + 5 * ld] += u5 * r;
        }
        scatter();
        o.Z.row(b) = UD.transpose();
        articulated_inertia::remove_column(o.P[i], U, Dinv(0, 0));
        o.P[p] += o.P[i];
        return;
      }
    }
    auto sub = o.Z.middleRows(s, m);
    for (int a = 0; a < n; ++a) {
      double* row = depth_first ? Minv.col(vi + a).data() + s : o.row.data();
      Eigen::Map<VecX> r(row, m);
      const Vec6 minus_sd = -SD.col(a);
      r.noalias() = sub * minus_sd;  // (a product negated whole would go through a temporary)
      if (!depth_first)
        for (int x = 0; x < m; ++x) Minv(model.dfs_dof[size_t(s + x)], vi + a) = r(x);
    }
    if (p < 0) return;
    // z_p = z_i + U 𝒟⁻¹ u over the subtree: its own positions (u = e) and the rest (u = 𝒟 · the rows above)
    o.Z.middleRows<n>(b) = UD.transpose();
    for (int a = 0; a < n; ++a) {
      const double* row = depth_first ? Minv.col(vi + a).data() + s : o.row.data();
      if (!depth_first)
        for (int x = 0; x < m; ++x) o.row(x) = Minv(model.dfs_dof[size_t(s + x)], vi + a);
      const Eigen::Map<const VecX> r(row, m);
      for (int c = 0; c < 6; ++c) sub.col(c) += U(c, a) * r;
    }
    // P_p += P⁺ = P − U 𝒟⁻¹ Uᵀ
    o.P[p] += o.P[i];
    o.P[p].noalias() -= UD * U.transpose();
  });
  // base to tip: q̈_i = 𝒟⁻¹ u − (U 𝒟⁻¹)ᵀ a_p,  a_i = a_p + S_i q̈_i, over k ≥ the first DOF of i
  for (int i = 0; i < N; ++i) visit_joint(model, i, [&](const auto& joint) {
    using J = std::decay_t<decltype(joint)>;
    constexpr int n = J::nv;
    const int vi = model.idx_v[i], p = model.parent[i], rows = nv - vi;
    if constexpr (n == 1) {
      // one pass over k ≥ vi: q̈ −= (U 𝒟⁻¹)ᵀ a_p, a_i = a_p + S q̈ (a_i in place of a_p along a path)
      const Eigen::Index ld = o.A.outerStride();
      double* __restrict qdd = Minv.col(vi).data() + vi;
      double* ai = o.A.data() + 6 * model.path[i] * ld + vi;
      const double s0 = S(0, vi), s1 = S(1, vi), s2 = S(2, vi), s3 = S(3, vi), s4 = S(4, vi), s5 = S(5, vi);
      if (p < 0) {
#pragma GCC ivdep
        for (int k = 0; k < rows; ++k) {
          const double q = qdd[k];
          ai[k] = s0 * q, ai[k + ld] = s1 * q, ai[k + 2 * ld] = s2 * q;
          ai[k + 3 * ld] = s3 * q, ai[k + 4 * ld] = s4 * q, ai[k + 5 * ld] = s5 * q;
        }
        return;
      }
      const double* ap = o.A.data() + 6 * model.path[p] * ld + vi;
      const double d0 = o.UD(0, vi), d1 = o.UD(1, vi), d2 = o.UD(2, vi), d3 = o.UD(3, vi), d4 = o.UD(4, vi),
                   d5 = o.UD(5, vi);
#pragma GCC ivdep
      for (int k = 0; k < rows; ++k) {
        const double a0 = ap[k], a1 = ap[k + ld], a2 = ap[k + 2 * ld], a3 = ap[k + 3 * ld], a4 = ap[k + 4 * ld],
                     a5 = ap[k + 5 * ld];
        const double q = qdd[k] - (d0 * a0 + d1 * a1 + d2 * a2 + d3 * a3 + d4 * a4 + d5 * a5);
        qdd[k] = q;
        ai[k] = a0 + s0 * q, ai[k + ld] = a1 + s1 * q, ai[k + 2 * ld] = a2 + s2 * q;
        ai[k + 3 * ld] = a3 + s3 * q, ai[k + 4 * ld] = a4 + s4 * q, ai[k + 5 * ld] = a5 + s5 * q;
      }
      return;
    }
    auto ai = o.A.middleCols<6>(6 * model.path[i]).middleRows(vi, rows);
    auto qdd = Minv.block(vi, vi, rows, n);
    if (p >= 0) {
      const auto ap = o.A.middleCols<6>(6 * model.path[p]).middleRows(vi, rows);
      for (int a = 0; a < n; ++a)
        for (int c = 0; c < 6; ++c) qdd.col(a) -= o.UD(c, vi + a) * ap.col(c);
      if (model.path[p] != model.path[i]) ai = ap;
    } else {
      ai.setZero();
    }
    for (int a = 0; a < n; ++a)
      for (int c = 0; c < 6; ++c) ai.col(c) += S(c, vi + a) * qdd.col(a);
  });
  // the upper triangle from the lower, in 8×8 tiles (a row of a column-major matrix read whole
  // touches a cache line per entry)
  constexpr int kTile = 8;
  for (int c0 = 0; c0 < nv; c0 += kTile)
    for (int r0 = 0; r0 <= c0; r0 += kTile)
      for (int c = c0; c < std::min(c0 + kTile, nv); ++c)
        for (int r = r0; r < std::min(r0 + kTile, c); ++r) Minv(r, c) = Minv(c, r);
}

}  // namespace detail

void minverse(const Model& model, Data& data, MatX& Minv) {
  auto& S = data.work.origin.S;
  for (int i = 0; i < model.nbodies; ++i) {
    const Vec3 eta = data.eta.col(i);
    for (int c = model.idx_v[i]; c < model.idx_v[i] + model.nv_i[i]; ++c) {
      const Vec6 g = data.G.col(c);
      S.col(c) << g.head<3>(), g.tail<3>() + eta.cross(g.head<3>());  // [a; b + η × a]
    }
  }
  detail::minverse_origin(model, data, S, Minv);
}

}  // namespace soadyn
