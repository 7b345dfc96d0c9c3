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
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/multibody/joint_model.hpp"

#include "multibody/articulated_inertia.hpp"
#include "minverse.hpp"

#include <algorithm>

namespace soadyn {

namespace detail {

namespace {

// Tip to base over the subtree's m positions x (Z: 6 columns at stride lz; row: n columns at stride
// lr): r_a = −z·(S 𝒟⁻¹)_a, the rows of 𝓜⁻¹; then, below a parent, z += U r.  One pass over x.
template <int n, bool root>
void subtree_rows(double* z, Eigen::Index lz, double* row, Eigen::Index lr, const double (&SD)[n][6],
                  const double (&U)[n][6], int m) {
#pragma GCC ivdep
  for (int x = 0; x < m; ++x) {
    double zc[6], r[n];
    for (int c = 0; c < 6; ++c) zc[c] = z[c * lz + x];
    for (int a = 0; a < n; ++a) {
      double t = 0.0;
      for (int c = 0; c < 6; ++c) t -= zc[c] * SD[a][c];
      row[a * lr + x] = r[a] = t;
    }
    if constexpr (!root)
      for (int c = 0; c < 6; ++c) {
        double t = zc[c];
        for (int a = 0; a < n; ++a) t += U[a][c] * r[a];
        z[c * lz + x] = t;
      }
  }
}

// Base to tip over k ≥ the first DOF of i (q: the n columns of Minv from that row, stride lq; a_p,
// a_i: 6 columns at stride la, a_i possibly a_p itself): q̈ −= (U 𝒟⁻¹)ᵀ a_p, a_i = a_p + S q̈.  One pass.
template <int n, bool root>
void row_accelerations(double* q, Eigen::Index lq, const double* ap, double* ai, Eigen::Index la,
                       const double (&UD)[n][6], const double (&S)[n][6], int rows) {
#pragma GCC ivdep
  for (int k = 0; k < rows; ++k) {
    double a[6], qk[n];
    for (int c = 0; c < 6; ++c) a[c] = root ? 0.0 : ap[c * la + k];
    for (int j = 0; j < n; ++j) {
      double t = q[j * lq + k];
      if constexpr (!root)
        for (int c = 0; c < 6; ++c) t -= UD[j][c] * a[c];
      q[j * lq + k] = qk[j] = t;
    }
    for (int c = 0; c < 6; ++c) {
      double t = a[c];
      for (int j = 0; j < n; ++j) t += S[j][c] * qk[j];
      ai[c * la + k] = t;
    }
  }
}

template <int n, class M>
void columns_of(const M& from, double (&to)[n][6]) {
  for (int a = 0; a < n; ++a)
    for (int c = 0; c < 6; ++c) to[a][c] = from(c, a);
}

// What both sweeps' steps read, and the step at body i for a joint of n DOFs (one copy per n:
// every joint kind of n DOFs alike)
struct Sweep {
  const Model& model;
  Data& data;
  const Mat6X& S;
  MatX& Minv;
  bool depth_first;
  Eigen::Index lz, lm, la;
  int nv;

  // tip to base
  template <int n>
  [[gnu::noinline]] void backward(int i) {
    auto& o = data.work.origin;
    using MatN = Eigen::Matrix<double, n, n>;
    using Mat6N = Eigen::Matrix<double, 6, n>;
    const int vi = model.idx_v[i], p = model.parent[i];
    const int b = model.dfs_begin[i], s = b + n, m = model.dfs_end[i] - s;
    const Mat6N Si = S.middleCols<n>(vi);
    // U = P S,  𝒟⁻¹ = (Sᵀ U)⁻¹
    const Mat6N U = o.P[i] * Si;
    const MatN Dinv = articulated_inertia::joint_inertia_inverse<n>(MatN(Si.transpose() * U));
    const Mat6N UD = U * Dinv, SD = Si * Dinv;
    o.UD.middleCols<n>(vi) = UD;
    // the rows of i over its own DOFs (𝒟⁻¹) and over its strict subtree (−𝒟⁻¹ Sᵀ z), then z += U r;
    // straight into Minv when the model is numbered depth-first, else through o.row and scattered
    Minv.block<n, n>(vi, vi) = Dinv;
    double sd[n][6], u[n][6];
    columns_of<n>(SD, sd);
    columns_of<n>(U, u);
    double* row = depth_first ? Minv.col(vi).data() + s : o.row.data();
    const Eigen::Index lr = depth_first ? lm : nv;
    if (p < 0)
      subtree_rows<n, true>(o.Z.data() + s, lz, row, lr, sd, u, m);
    else
      subtree_rows<n, false>(o.Z.data() + s, lz, row, lr, sd, u, m);
    if (!depth_first)
      for (int a = 0; a < n; ++a)
        for (int x = 0; x < m; ++x) Minv(model.dfs_dof[size_t(s + x)], vi + a) = row[a * lr + x];
    if (p < 0) return;
    // the own positions' z (u = e there): U 𝒟⁻¹;  P_p += P⁺ = P − U 𝒟⁻¹ Uᵀ
    o.Z.middleRows<n>(b) = UD.transpose();
    if constexpr (n == 1)
      articulated_inertia::remove_column(o.P[i], U, Dinv(0, 0));
    else
      o.P[i].noalias() -= UD * U.transpose();
    o.P[p] += o.P[i];
  }

  // base to tip
  template <int n>
  [[gnu::noinline]] void forward(int i) {
    auto& o = data.work.origin;
    const int vi = model.idx_v[i], p = model.parent[i], rows = nv - vi;
    double ud[n][6], si[n][6];
    columns_of<n>(o.UD.middleCols<n>(vi), ud);
    columns_of<n>(S.middleCols<n>(vi), si);
    double* q = Minv.data() + vi * lm + vi;
    double* ai = o.A.data() + 6 * model.path[i] * la + vi;
    if (p < 0)
      row_accelerations<n, true>(q, lm, nullptr, ai, la, ud, si, rows);
    else
      row_accelerations<n, false>(q, lm, o.A.data() + 6 * model.path[p] * la + vi, ai, la, ud, si, rows);
  }
};

}  // namespace

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
  Sweep sweep{model, data, S, Minv, depth_first, o.Z.outerStride(), Minv.outerStride(), o.A.outerStride(), nv};
  // tip to base, then base to tip
  for (int i = N - 1; i >= 0; --i)
    visit_joint(model, i, [&](const auto& joint) { sweep.backward<std::decay_t<decltype(joint)>::nv>(i); });
  for (int i = 0; i < N; ++i)
    visit_joint(model, i, [&](const auto& joint) { sweep.forward<std::decay_t<decltype(joint)>::nv>(i); });
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
  data.require("minverse", false);
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
