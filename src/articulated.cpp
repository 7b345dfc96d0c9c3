// The articulated-body recursion: O(N) forward dynamics (the factored inverse mass matrix) and
// 𝓜⁻¹ in O(N²) by the same factor (algorithms.hpp).
#include "soadyn/algorithms.hpp"
#include "soadyn/kinematics.hpp"
#include "soadyn/operators.hpp"
#include "dynamics_routes.hpp"
#include "articulated_inertia.hpp"
#include "joint_inertial.hpp"

namespace soadyn {

namespace {

// The factor both articulated-body sweeps share, at body i once its children are in P_i:
// U_i = P_i G_i, 𝒟_i⁻¹ = (G_iᵀ U_i)⁻¹ and, below a parent, P⁺_i = P_i − U_i 𝒟_i⁻¹ U_iᵀ in place
// (P_i is not needed after this step).  The caller adds D_iᵀ P⁺_i D_i to P_p.  J is body i's joint
// kind, which the caller's one dispatch for the body has chosen.
template <class J>
inline void articulated_factor_step(const Model& model, Data& data, int i) {
  const int vi = model.idx_v[i], p = model.parent[i];
  Mat6& P = data.work.articulated.P[i];
  if constexpr (J::nv == 1) {
    // U = P g,  𝒟 = gᵀ U;  P⁺ = P − U Uᵀ / 𝒟
    Vec6 U;
    inertial::times<J>(P, data.G, vi, U);
    const double Dinv = 1.0 / data.G.col(vi).dot(U);
    data.work.articulated.U1.col(i) = U;
    data.work.articulated.Dinv1(i) = Dinv;
    if (p < 0) return;
    articulated_inertia::remove_column(P, U, Dinv);
  } else {
    // the same with U_i = P_i G_i (6×n) and 𝒟_i = G_iᵀ U_i (n×n)
    Eigen::Matrix<double, 6, J::nv> U;
    inertial::times<J>(P, data.G, vi, U);
    const Eigen::Matrix<double, J::nv, J::nv> joint_inertia = data.G.middleCols<J::nv>(vi).transpose() * U;  // 𝒟_i
    data.work.articulated.U[i] = U;
    data.work.articulated.Dinv[i] = joint_inertia.inverse();
    if (p < 0) return;
    const Eigen::Matrix<double, 6, J::nv> UD = U * data.work.articulated.Dinv[i];
    P.noalias() -= UD * U.transpose();
  }
}

// aba's tip-to-base step, the factor step first, then: u_i = τ_i − G_iᵀ z_i, then at a parent
// z⁺ = z + P⁺ a + U 𝒟⁻¹ u, P_p += D_iᵀ P⁺ D_i, z_p += D_iᵀ z⁺ = [z_ω + d_i × z_f; z_f] (added in
// 3-vector halves: a 6-vector built whole went through the stack and was read back across two stores)
template <class J>
[[gnu::noinline]] void aba_backward_step(const Model& model, Data& data, const VecX& tau, int i) {
  articulated_factor_step<J>(model, data, i);
  const int vi = model.idx_v[i], p = model.parent[i];
  const Mat6& P = data.work.articulated.P[i];  // P⁺_i below a parent
  double gz[J::nv];
  inertial::project<J>(data.G, vi, data.work.articulated.z.col(i).head<3>(), data.work.articulated.z.col(i).tail<3>(), gz);
  for (int c = 0; c < J::nv; ++c) data.work.articulated.u(vi + c) = tau(vi + c) - gz[c];
  if (p < 0) return;
  Vec6 za = data.work.articulated.z.col(i);
  za.noalias() += P * data.coriolis.col(i);
  if constexpr (J::nv == 1) {
    za += (data.work.articulated.u(vi) * data.work.articulated.Dinv1(i)) * data.work.articulated.U1.col(i);
  } else {
    const Eigen::Matrix<double, J::nv, 1> Du = data.work.articulated.Dinv[i] * data.work.articulated.u.segment<J::nv>(vi);
    za.noalias() += data.work.articulated.U[i] * Du;
  }
  articulated_inertia::add_to_parent(data.work.articulated.P[p], P, data.d.col(i));
  const Vec3 zf = za.tail<3>();
  data.work.articulated.z.col(p).head<3>() += za.head<3>() + Vec3(data.d.col(i)).cross(zf);
  data.work.articulated.z.col(p).tail<3>() += zf;
}

// aba's base-to-tip step, in 3-vector halves, which stay in registers: A' = [ω; u],
// q̈_i = 𝒟⁻¹ (u_i − U_ωᵀ ω − U_vᵀ u), A_i = A' + G_i q̈_i
template <class J>
inline void aba_forward_step(const Model& model, Data& data, int i) {
  const int vi = model.idx_v[i], p = model.parent[i];
  Vec3 w = data.coriolis.col(i).head<3>(), v = data.coriolis.col(i).tail<3>();
  if (p >= 0) {
    const Vec3 wp = data.A.col(p).head<3>();
    w += wp;
    v += data.A.col(p).tail<3>() + wp.cross(Vec3(data.d.col(i)));
  }
  if constexpr (J::nv == 1) {
    data.qdd(vi) = data.work.articulated.Dinv1(i) * (data.work.articulated.u(vi) - data.work.articulated.U1.col(i).head<3>().dot(w) - data.work.articulated.U1.col(i).tail<3>().dot(v));
  } else {
    const auto U = data.work.articulated.U[i];
    const Eigen::Matrix<double, J::nv, 1> rhs =
        data.work.articulated.u.segment<J::nv>(vi) - U.topRows<3>().transpose() * w - U.bottomRows<3>().transpose() * v;
    data.qdd.segment<J::nv>(vi).noalias() = data.work.articulated.Dinv[i] * rhs;
  }
  Vec3 gw, gu;
  inertial::motion<J>(data.G, vi, data.qdd.data() + vi, gw, gu);
  data.A.col(i).head<3>() = w + gw;
  data.A.col(i).tail<3>() = v + gu;
}

}  // namespace

namespace detail {

void aba(const Model& model, Data& data, const VecX& tau) {
  // tip to base: articulated inertias P_i and bias forces z_i
  for (int i = 0; i < model.nbodies; ++i) {
    // P_i = M_i = [I, h̃; h̃ᵀ, m e], written in place entry by entry: a 6×6 assembled from 3×3
    // temporaries goes through the stack in 8-byte pieces read back at once in 16-byte ones,
    // which the CPU cannot forward (a tenth of this sweep's time)
    const SpatialInertia& M = data.inertia[i];
    Mat6& P = data.work.articulated.P[i];
    const double h0 = M.h(0), h1 = M.h(1), h2 = M.h(2), m = M.m;
    P.topLeftCorner<3, 3>() = M.I;
    P.col(3) << 0.0, h2, -h1, m, 0.0, 0.0;
    P.col(4) << -h2, 0.0, h0, 0.0, m, 0.0;
    P.col(5) << h1, -h0, 0.0, 0.0, 0.0, m;
    P.block<3, 3>(3, 0) << 0.0, h2, -h1, -h2, 0.0, h0, h1, -h0, 0.0;  // h̃ᵀ, row by row
    data.work.articulated.z.col(i) = data.gyroscopic.col(i);
  }
  for (int i = model.nbodies - 1; i >= 0; --i)
    visit_joint(model, i, [&](const auto& j) { aba_backward_step<std::decay_t<decltype(j)>>(model, data, tau, i); });
  // base to tip: A' = D_i A_p + a_i,  q̈_i = 𝒟⁻¹ (u_i − U_iᵀ A'),  A_i = A' + G_i q̈_i
  for (int i = 0; i < model.nbodies; ++i)
    visit_joint(model, i, [&](const auto& j) { aba_forward_step<std::decay_t<decltype(j)>>(model, data, i); });
}

}  // namespace detail

void minverse(const Model& model, Data& data, MatX& Minv) {
  const int N = model.nbodies;
  if (Minv.rows() != model.nv || Minv.cols() != model.nv) Minv.resize(model.nv, model.nv);
  const DOperator D{data.d};
  // The articulated-body recursion for every unit force at once (τ = e_k, no velocity, no gravity):
  // column k of 𝓜⁻¹ is that q̈.  Tip to base, the bias forces of all unit forces are the columns Z of
  // a 6×nv block in depth-first positions (body i's subtree at dfs_begin[i] … dfs_end[i] − 1, its own
  // DOFs first): u_i = E_i − G_iᵀ Z_i over the subtree's columns (E_i: 1 at i's own DOFs), kept in
  // 𝓜⁻¹'s rows of i; then Z_p = D_iᵀ (Z_i + U_i 𝒟_i⁻¹ u_i) in place (p's children's subtrees are
  // disjoint; p's own columns stay 0) and P_p += D_iᵀ (P_i − U_i 𝒟_i⁻¹ U_iᵀ) D_i.  O(N·depth).
  Mat6X& Z = data.work.articulated.Z;
  Mat6X& Acc = data.work.articulated.A;  // per-column body accelerations, not [fd]'s data.A
  Z.setZero();
  for (int i = 0; i < N; ++i) data.work.articulated.P[i] = data.inertia[i].matrix();
  for (int i = N - 1; i >= 0; --i) visit_joint(model, i, [&](const auto& joint) {
    using J = std::decay_t<decltype(joint)>;
    const int vi = model.idx_v[i], ni = J::nv, p = model.parent[i];
    const int b = model.dfs_begin[i], n = model.dfs_end[i] - b;
    articulated_factor_step<J>(model, data, i);
    if constexpr (J::nv == 1) {  // 𝒟⁻¹ a number
      const Vec6 g = data.G.col(vi), U = data.work.articulated.U1.col(i);
      const double Dinv = data.work.articulated.Dinv1(i);
      for (int x = 0; x < n; ++x) {
        auto z = Z.col(b + x);
        const double u = (x == 0 ? 1.0 : 0.0) - g.dot(z);
        Minv(vi, model.dfs_dof[size_t(b + x)]) = u;
        if (p < 0) continue;
        const Vec6 zp = z + (Dinv * u) * U;
        z.setZero();
        D.add_apply_transpose(i, zp, z);
      }
    } else {
      const auto Gi = data.G.middleCols(vi, ni);
      const Mat6G UD = data.work.articulated.U[i] * data.work.articulated.Dinv[i];
      for (int x = 0; x < n; ++x) {
        auto z = Z.col(b + x);
        VecG u = -(Gi.transpose() * z);
        if (x < ni) u(x) += 1.0;
        Minv.block(vi, model.dfs_dof[size_t(b + x)], ni, 1) = u;
        if (p < 0) continue;
        Vec6 zp = z;
        zp.noalias() += UD * u;
        z.setZero();
        D.add_apply_transpose(i, zp, z);
      }
    }
    if (p >= 0) articulated_inertia::add_to_parent(data.work.articulated.P[p], data.work.articulated.P[i], data.d.col(i));
  });
  // Base to tip, one column at a time: A'_i = D_i A_p, q̈_i = 𝒟_i⁻¹ (u_i − U_iᵀ A'_i), A_i = A'_i + G_i q̈_i,
  // u_i nonzero only where column k's joint lies in i's subtree.  O(N) per column.
  for (int k = 0; k < model.nv; ++k) {
    const int at = model.dfs_begin[model.dof_body[size_t(k)]];
    double* col = Minv.col(k).data();
    for (int i = 0; i < N; ++i) visit_joint(model, i, [&](const auto& joint) {
      using J = std::decay_t<decltype(joint)>;
      const int vi = model.idx_v[i], p = model.parent[i];
      const bool carries = model.dfs_begin[i] <= at && at < model.dfs_end[i];
      const auto& ab = data.work.articulated;
      if constexpr (J::nv == 1) {
        // in 3-vector halves, which stay in registers (as aba's forward sweep): A' = [ω; u]
        Vec3 w = Vec3::Zero(), v = Vec3::Zero();
        if (p >= 0) {
          w = Acc.col(p).head<3>();
          v = Acc.col(p).tail<3>() + w.cross(Vec3(data.d.col(i)));
        }
        const double qdd =
            ab.Dinv1(i) * ((carries ? col[vi] : 0.0) - ab.U1.col(i).head<3>().dot(w) - ab.U1.col(i).tail<3>().dot(v));
        col[vi] = qdd;
        Acc.col(i).head<3>() = w + qdd * data.G.col(vi).head<3>();
        Acc.col(i).tail<3>() = v + qdd * data.G.col(vi).tail<3>();
      } else {
        constexpr int ni = J::nv;
        Vec6 A = Vec6::Zero();
        if (p >= 0) D.add_apply(i, Acc.col(p), A);
        VecG u = -(ab.U[i].transpose() * A);
        if (carries) u += Minv.block(vi, k, ni, 1);
        const VecG qdd = ab.Dinv[i] * u;
        Minv.block(vi, k, ni, 1) = qdd;
        A.noalias() += data.G.middleCols(vi, ni) * qdd;
        Acc.col(i).head<3>() = A.head<3>();
        Acc.col(i).tail<3>() = A.tail<3>();
      }
    });
  }
}

}  // namespace soadyn
