// Derivatives of inverse and forward dynamics (derivatives.hpp has the frame and the conventions).
//
// Perturb column c of joint j by δ (ξ = S_c).  Everything in the subtree of j moves rigidly by ξ,
// so for i ⪰ j:  ∂S_i = ξ × S_i (i ≻ j),  ∂Y_i = ξ ×* Y_i − Y_i ξ×,  and with ν_c the part of v_j
// that the perturbation does not carry (ν_c = v_p + Σ_{m not carried by c} S_m q̇_m):
//   ∂v_i = ξ × v_i + β,                         β = −ξ × ν_c
//   ∂a_i = ξ × a_i + γ + β × (v_i − v_j),        γ = ∂a_j − ξ × a_j (the joint's own term)
//   ∂f_i = ξ ×* f_i + Y_i (γ − β × v_j) + B_i β, B_i β = Y_i (β × v_i) + β ×* Y_i v_i + v_i ×* Y_i β
// Summed over subtrees, and since (ξ × S)ᵀ F = −Sᵀ (ξ ×* F):
//   row i ≻ j:  ∂τ_i = S_iᵀ (Y_i κ_c + B_i β_c),  κ_c = γ − β × v_j      (Y_i, B_i composite)
//   row j:      the same, plus S_mᵀ φ_c for the columns m that c does not carry, φ_c = ξ ×* F_j
//   row i ≺ j:  ∂τ_i = S_iᵀ ψ_c,  ψ_c = Y_j κ_c + B_j β_c + φ_c
// The rates: ∂v_i/∂q̇_c = S_c and ∂a_i/∂q̇_c = S_c × v_i − λ_c for i ⪰ j, λ_c = S_c × (ν_c + μ_c)
// (μ_c: the velocity of the frame column c is fixed in, Ṡ_c = μ_c × S_c), so
//   row i ⪰ j:  ∂τ_i/∂q̇_c = S_iᵀ (B_i S_c − Y_i λ_c);   row i ≺ j:  S_iᵀ ρ_c,  ρ_c = B_j S_c − Y_j λ_c.
// Every (row, column) pair on an ancestor chain is one 12-term dot product: O(N·depth).  The
// forward dynamics' derivatives are made of the same sweeps' vectors (forward_derivatives.cpp).
#include "soadyn/algorithm/derivatives.hpp"

#include "soadyn/algorithm/algorithms.hpp"

#include "derivative_sweeps.hpp"

#include <algorithm>

namespace soadyn {

DerivativeData::DerivativeData(const Model& m)
    : S(Mat6X::Zero(6, m.nv)),
      v(Mat6X::Zero(6, m.nbodies)),
      a(Mat6X::Zero(6, m.nbodies)),
      F(Mat6X::Zero(6, m.nbodies)),
      Y(m.nbodies),
      B(m.nbodies),
      tau(VecX::Zero(m.nv)),
      row(Eigen::Matrix<double, 9, Eigen::Dynamic>::Zero(9, m.nv)),
      colq(Eigen::Matrix<double, 9, Eigen::Dynamic>::Zero(9, m.nv)),
      colv(Eigen::Matrix<double, 9, Eigen::Dynamic>::Zero(9, m.nv)),
      psi(Mat6X::Zero(6, m.nv)),
      rho(Mat6X::Zero(6, m.nv)),
      phi(Mat6X::Zero(6, m.nv)),
      dtau_dq(MatX::Zero(m.nv, m.nv)),
      dtau_dv(MatX::Zero(m.nv, m.nv)),
      dqdd_dq(MatX::Zero(m.nv, m.nv)),
      dqdd_dv(MatX::Zero(m.nv, m.nv)),
      Minv(MatX::Zero(m.nv, m.nv)),
      blocks(MatX::Zero(m.nv, 9 * m.npaths)),
      leaf(size_t(m.nbodies), 1),
      w(Mat6X::Zero(6, m.nbodies)),
      T1(Mat6X::Zero(6, m.nbodies)),
      T2(Mat3X::Zero(3, m.nbodies)),
      directions(MatX::Zero(kDirections, 15 * m.nbodies + 3 * m.nv)) {
  for (int i = 0; i < m.nbodies; ++i)
    if (m.parent[i] >= 0) leaf[size_t(m.parent[i])] = 0;
}

namespace {

// m × x = [ω × ω'; ω × u' + u × ω']   (motion cross product)
[[gnu::always_inline]] inline Vec6 mcross(const Vec6& m, const Vec6& x) {
  const Vec3 w = m.head<3>(), u = m.tail<3>(), w2 = x.head<3>(), u2 = x.tail<3>();
  Vec6 out;
  out << w.cross(w2), w.cross(u2) + u.cross(w2);
  return out;
}

// m ×* f = [ω × n + u × f; ω × f]   (force cross product)
[[gnu::always_inline]] inline Vec6 fcross(const Vec6& m, const Vec6& f) {
  const Vec3 w = m.head<3>(), u = m.tail<3>(), n = f.head<3>(), fl = f.tail<3>();
  Vec6 out;
  out << w.cross(n) + u.cross(fl), w.cross(fl);
  return out;
}

// B β = Y (β × v) + β ×* k + v ×* (Y β) with k = Y v = [k_n; k_f]:  B = −Y [v×] + H(k) + [v×*] Y,
// [v×] = [ω̃ 0; ũ ω̃], [v×*] = [ω̃ ũ; 0 ω̃], H(k) = [−k̃_n −k̃_f; −k̃_f 0].  With Y = [I h̃; −h̃ m e],
// ω̃ h̃ − h̃ ω̃ = (ω × h)~ and k_f = m u + ω × h, the right half vanishes:
//   B = [ω̃ I − I ω̃ − (ũ h̃ + h̃ ũ) − k̃_n, 0; −2 k̃_f, 0],   ũ h̃ + h̃ ũ = h uᵀ + u hᵀ − 2 (u·h) e,
// held as its CoriolisBlock: T and f = k_f (v = [w; u], k = [kn; kf])
// (entry by entry, each written once: a matrix updated in passes, its diagonal entry by entry,
// waited on its own stores)
CoriolisBlock coriolis_block(const SpatialInertia& Y, const Vec3& w, const Vec3& u, const Vec3& kn, const Vec3& kf) {
  const Vec3 h = Y.h;
  Mat3 WI;  // ω̃ I, column by column
  for (int c = 0; c < 3; ++c) WI.col(c) = w.cross(Vec3(Y.I.col(c)));
  const double uh2 = 2.0 * u.dot(h);
  // ω̃ I − I ω̃ = ω̃ I + (ω̃ I)ᵀ (I symmetric), − (h uᵀ + u hᵀ) + 2 (u·h) e − k̃_n
  const double t00 = 2.0 * WI(0, 0) - 2.0 * h(0) * u(0) + uh2, t11 = 2.0 * WI(1, 1) - 2.0 * h(1) * u(1) + uh2,
               t22 = 2.0 * WI(2, 2) - 2.0 * h(2) * u(2) + uh2;
  const double s01 = WI(0, 1) + WI(1, 0) - h(0) * u(1) - u(0) * h(1), s02 = WI(0, 2) + WI(2, 0) - h(0) * u(2) - u(0) * h(2),
               s12 = WI(1, 2) + WI(2, 1) - h(1) * u(2) - u(1) * h(2);
  CoriolisBlock B;
  B.T << t00, s01 + kn(2), s02 - kn(1),  //
      s01 - kn(2), t11, s12 + kn(0),      //
      s02 + kn(1), s12 - kn(0), t22;
  B.f = kf;
  return B;
}

void add(SpatialInertia& to, const SpatialInertia& K) {
  to.m += K.m;
  to.h += K.h;
  to.I += K.I;
}

// The two steps of one-DOF joints (every kind alike, so one copy of each, called from each kind's
// case of the sweeps), in 3-vector halves, which stay in registers: a 6-vector built from two
// halves and read back whole waits on its stores.
// Base to tip: S_i, v_i, a_i (μ = v_i, so a_i = a_p + S q̈ + q̇ v_i × S), Y_i, f_i, B_i
[[gnu::noinline]] void one_dof_forward(const Model& model, const Data& data, const VecX& qd, const VecX& qdd,
                                       DerivativeData& dd, int i) {
  const int p = model.parent[i], vi = model.idx_v[i];
  const Vec3 eta = data.eta.col(i);
  const Vec3 sw = data.G.col(vi).head<3>(), su = Vec3(data.G.col(vi).tail<3>()) + eta.cross(sw);
  dd.S.col(vi).head<3>() = sw;
  dd.S.col(vi).tail<3>() = su;
  const double q1 = qd(vi), q2 = qdd(vi);
  Vec3 vw = sw * q1, vu = su * q1, aw = sw * q2, au = su * q2;
  if (p >= 0) {
    vw += dd.v.col(p).head<3>(), vu += dd.v.col(p).tail<3>();
    aw += dd.a.col(p).head<3>(), au += dd.a.col(p).tail<3>();
  } else {
    au -= model.gravity;
  }
  aw += q1 * vw.cross(sw);
  au += q1 * (vw.cross(su) + vu.cross(sw));
  dd.v.col(i).head<3>() = vw, dd.v.col(i).tail<3>() = vu;
  dd.a.col(i).head<3>() = aw, dd.a.col(i).tail<3>() = au;
  SpatialInertia& Yi = dd.Y[i];  // M_i moved from η_i to the origin
  Yi = SpatialInertia();
  Yi.add_transformed(data.inertia[i], eta);
  // k = Y_i v_i,  f_i = Y_i a_i + v_i ×* k
  const Vec3 kn = Yi.I * vw + Yi.h.cross(vu), kf = Yi.m * vu - Yi.h.cross(vw);
  dd.F.col(i).head<3>() = Yi.I * aw + Yi.h.cross(au) + vw.cross(kn) + vu.cross(kf);
  dd.F.col(i).tail<3>() = Yi.m * au - Yi.h.cross(aw) + vw.cross(kf);
  dd.B[i] = coriolis_block(Yi, vw, vu, kn, kf);
}

// Per column (ξ = [xw; xu]): ν = v_p, μ = v_j, no own term; κ, β, λ, φ, ψ, ρ
[[gnu::noinline]] void one_dof_column(const Model& model, DerivativeData& dd, int j) {
  const int p = model.parent[j], vj = model.idx_v[j];
  const Vec3 xw = dd.S.col(vj).head<3>(), xu = dd.S.col(vj).tail<3>();
  const Vec3 pw = p < 0 ? Vec3::Zero() : Vec3(dd.v.col(p).head<3>()), pu = p < 0 ? Vec3::Zero() : Vec3(dd.v.col(p).tail<3>());
  const Vec3 vw = dd.v.col(j).head<3>(), vu = dd.v.col(j).tail<3>();
  const Vec3 aw = dd.a.col(j).head<3>(), au = dd.a.col(j).tail<3>();
  const Vec3 Fn = dd.F.col(j).head<3>(), Ff = dd.F.col(j).tail<3>();
  // β = −ξ × ν,  κ = −ξ × a_j − β × v_j,  λ = ξ × (ν + μ),  φ = ξ ×* F_j
  const Vec3 bw = -xw.cross(pw), bu = -(xw.cross(pu) + xu.cross(pw));
  const Vec3 kw = -xw.cross(aw) - bw.cross(vw), ku = -(xw.cross(au) + xu.cross(aw)) - (bw.cross(vu) + bu.cross(vw));
  const Vec3 sw = pw + vw, su = pu + vu;
  const Vec3 lw = xw.cross(sw), lu = xw.cross(su) + xu.cross(sw);
  const Vec3 phw = xw.cross(Fn) + xu.cross(Ff), phu = xw.cross(Ff);
  // ψ = Y_j κ + B_j β + φ,  ρ = B_j ξ − Y_j λ   (Y [ω; u] = [I ω + h × u; m u − h × ω], B x = [T x_ω; −2 f × x_ω])
  const SpatialInertia& Y = dd.Y[j];
  const CoriolisBlock& B = dd.B[j];
  dd.phi.col(vj).head<3>() = phw, dd.phi.col(vj).tail<3>() = phu;
  dd.psi.col(vj).head<3>() = Y.I * kw + Y.h.cross(ku) + B.T * bw + phw;
  dd.psi.col(vj).tail<3>() = Y.m * ku - Y.h.cross(kw) - 2.0 * B.f.cross(bw) + phu;
  dd.rho.col(vj).head<3>() = B.T * xw - (Y.I * lw + Y.h.cross(lu));
  dd.rho.col(vj).tail<3>() = -2.0 * B.f.cross(xw) - (Y.m * lu - Y.h.cross(lw));
  auto cq = dd.colq.col(vj);
  auto cv = dd.colv.col(vj);
  cq.segment<3>(0) = kw, cq.segment<3>(3) = ku, cq.segment<3>(6) = bw;
  cv.segment<3>(0) = -lw, cv.segment<3>(3) = -lu, cv.segment<3>(6) = xw;
}

// per column c of a joint j of several DOFs: κ_c, β_c, λ_c, φ_c, ψ_c, ρ_c
template <class J>
void multi_dof_columns(const Model& model, DerivativeData& dd, int j, const VecX& qd, const VecX& qdd) {
  constexpr int nj = J::nv;
  const int p = model.parent[j], vj = model.idx_v[j];
  const Vec6 vp = p < 0 ? Vec6::Zero() : Vec6(dd.v.col(p));
  const Vec6 vel = dd.v.col(j), acc = dd.a.col(j), Fj = dd.F.col(j);
  for (int k = 0; k < nj; ++k) {
    const int c = vj + k;
    const Vec6 xi = dd.S.col(c);
    Vec6 nu = vp, mu = vp;  // ν_c: not carried by c;  μ_c: carries c
    for (int m = 0; m < nj; ++m) {
      if (!J::carries(k, m)) nu += dd.S.col(vj + m) * qd(vj + m);
      if (J::carries(m, k)) mu += dd.S.col(vj + m) * qd(vj + m);
    }
    // the joint's own term ∂a_j: ∂(S_m q̈_m) = [c carries m] ξ × S_m q̈_m, and
    // ∂(μ_m × S_m) = ∂μ_m × S_m + [c carries m] μ_m × (ξ × S_m), ∂μ_m = ξ × Σ_l [l carries m][c carries l] S_l q̇_l;
    // zero for a one-DOF joint, whose every term has ξ × S_c = S_c × S_c = 0
    Vec6 da = Vec6::Zero();
    if constexpr (nj > 1) for (int m = 0; m < nj; ++m) {
      const Vec6 Sm = dd.S.col(vj + m);
      Vec6 dmu = Vec6::Zero(), mu_m = vp;
      for (int l = 0; l < nj; ++l) {
        if (J::carries(l, m)) mu_m += dd.S.col(vj + l) * qd(vj + l);
        if (J::carries(l, m) && J::carries(k, l)) dmu += dd.S.col(vj + l) * qd(vj + l);
      }
      if (J::carries(k, m)) {
        const Vec6 xS = mcross(xi, Sm);
        da += qdd(vj + m) * xS + qd(vj + m) * mcross(mu_m, xS);
      }
      if (!dmu.isZero(0)) da += qd(vj + m) * mcross(mcross(xi, dmu), Sm);
    }
    const Vec6 beta = -mcross(xi, nu);
    const Vec6 kappa = da - mcross(xi, acc) - mcross(beta, vel);
    const Vec6 lambda = mcross(xi, nu + mu);
    dd.phi.col(c) = fcross(xi, Fj);
    dd.psi.col(c) = dd.Y[j] * kappa + dd.B[j] * beta + dd.phi.col(c);
    dd.rho.col(c) = dd.B[j] * xi - dd.Y[j] * lambda;
    dd.colq.col(c).head<6>() = kappa;
    dd.colq.col(c).tail<3>() = beta.head<3>();
    dd.colv.col(c).head<6>() = -lambda;
    dd.colv.col(c).tail<3>() = xi.head<3>();
  }
}

}  // namespace

namespace detail {

void derivative_sweeps(const Model& model, const Data& data, const VecX& qd, const VecX& qdd, DerivativeData& dd,
                       const char* where) {
  data.check(model, where, "v", qd.size(), model.nv);
  data.check(model, where, "qdd", qdd.size(), model.nv);
  data.require(where, false);
  if (dd.S.cols() != model.nv || int(dd.Y.size()) != model.nbodies)
    throw Error(std::string(where) + ": this DerivativeData was built for another model");
  const int N = model.nbodies;
  Vec6 gravity_acc;
  gravity_acc << Vec3::Zero(), -model.gravity;

  // base to tip: S_i, v_i = v_p + S_i q̇_i, a_i = a_p + S_i q̈_i + Σ_c q̇_c μ_c × S_c, f_i, B_i
  for (int i = 0; i < N; ++i) visit_joint(model, i, [&](const auto& joint) {
    using J = std::decay_t<decltype(joint)>;
    constexpr int ni = J::nv;
    if constexpr (ni == 1) {
      one_dof_forward(model, data, qd, qdd, dd, i);
      return;
    }
    const int p = model.parent[i], vi = model.idx_v[i];
    const Vec3 eta = data.eta.col(i);
    const Vec6 vp = p < 0 ? Vec6::Zero() : Vec6(dd.v.col(p));
    Vec6 vel = vp, acc = p < 0 ? gravity_acc : Vec6(dd.a.col(p));
    for (int c = vi; c < vi + ni; ++c) {
      const Vec6 g = data.G.col(c);
      dd.S.col(c) << g.head<3>(), g.tail<3>() + eta.cross(g.head<3>());  // G_c moved to the origin
      vel += dd.S.col(c) * qd(c);
      acc += dd.S.col(c) * qdd(c);
    }
    for (int m = 0; m < ni; ++m) {
      Vec6 mu = vp;  // μ_m = v_p + Σ_k [k carries m] S_k q̇_k
      for (int k = 0; k < ni; ++k)
        if (J::carries(k, m)) mu += dd.S.col(vi + k) * qd(vi + k);
      acc += qd(vi + m) * mcross(mu, dd.S.col(vi + m));
    }
    dd.v.col(i) = vel;
    dd.a.col(i) = acc;
    SpatialInertia Yi;  // M_i moved from η_i to the origin
    Yi.add_transformed(data.inertia[i], eta);
    const Vec6 h = Yi * vel;
    dd.F.col(i) = Yi * acc + fcross(vel, h);  // f_i = Y_i a_i + v_i ×* Y_i v_i
    dd.Y[i] = Yi;
    dd.B[i] = coriolis_block(Yi, vel.head<3>(), vel.tail<3>(), h.head<3>(), h.tail<3>());
  });
  // tip to base: F_p += F_i, Y_p += Y_i, B_p += B_i (all about one point: plain sums); τ_i = S_iᵀ F_i
  for (int i = N - 1; i >= 0; --i) {
    const int p = model.parent[i], vi = model.idx_v[i], ni = model.nv_i[i];
    for (int c = vi; c < vi + ni; ++c) {
      dd.tau(c) = dd.S.col(c).dot(dd.F.col(i));
      dd.row.col(c).head<6>() = dd.Y[i] * dd.S.col(c);
      dd.row.col(c).tail<3>() = dd.B[i].transpose_times(dd.S.col(c));
    }
    if (p >= 0) {
      dd.F.col(p) += dd.F.col(i);
      add(dd.Y[p], dd.Y[i]);
      dd.B[p] += dd.B[i];
    }
  }

  // per column c of joint j: κ_c, β_c, λ_c, φ_c, ψ_c, ρ_c
  for (int j = 0; j < N; ++j) visit_joint(model, j, [&](const auto& joint) {
    using J = std::decay_t<decltype(joint)>;
    if constexpr (J::nv == 1) one_dof_column(model, dd, j);
    else multi_dof_columns<J>(model, dd, j, qd, qdd);
  });

}

}  // namespace detail

namespace {

// from this many DOFs on, a chain's fill is matrix products (below that, the products' packing costs
// more than the pairs' dot products: 8 DOFs 20 % slower, 16 even, 32 20 % faster)
constexpr int kChainProducts = 16;

// the fill's block of joint i with itself: (r, c) = row_r·col_c, plus S_r·φ_c where c does not carry r
void own_block(const Model& model, DerivativeData& dd, int i) {
  visit_joint(model, i, [&](const auto& joint) {
    using J = std::decay_t<decltype(joint)>;
    const int vi = model.idx_v[i];
    for (int r = vi; r < vi + J::nv; ++r)
      for (int c = vi; c < vi + J::nv; ++c) {
        double dq = dd.row.col(r).dot(dd.colq.col(c));
        if (!J::carries(c - vi, r - vi)) dq += dd.S.col(r).dot(dd.phi.col(c));
        dd.dtau_dq(r, c) = dq;
        dd.dtau_dv(r, c) = dd.row.col(r).dot(dd.colv.col(c));
      }
  });
}

}  // namespace

void inverse_dynamics_derivatives(const Model& model, const Data& data, const VecX& qd, const VecX& qdd,
                                  DerivativeData& dd) {
  detail::derivative_sweeps(model, data, qd, qdd, dd, "inverse_dynamics_derivatives");
  const int N = model.nbodies;
  if (model.chain && model.nv >= kChainProducts) {
    // a chain: every DOF before r is an ancestor of r, so the (body, ancestor) pairs below are four
    // triangular matrix products, (r, c ≤ r) = row_r·col_c and (c ≤ r, r) = S_c·ψ_r, S_c·ρ_r; the
    // joints' own blocks (the diagonal) are then written over
    dd.dtau_dq.triangularView<Eigen::Lower>() = dd.row.transpose() * dd.colq;
    dd.dtau_dv.triangularView<Eigen::Lower>() = dd.row.transpose() * dd.colv;
    dd.dtau_dq.triangularView<Eigen::Upper>() = dd.S.transpose() * dd.psi;
    dd.dtau_dv.triangularView<Eigen::Upper>() = dd.S.transpose() * dd.rho;
    for (int i = 0; i < N; ++i) own_block(model, dd, i);
    return;
  }
  // fill: the joint's own block, then every (body, ancestor) pair both ways; the rest is zero
  dd.dtau_dq.setZero();
  dd.dtau_dv.setZero();
  for (int i = 0; i < N; ++i) {
    const int vi = model.idx_v[i], ni = model.nv_i[i];
    own_block(model, dd, i);
    for (int j = model.parent[i]; j >= 0; j = model.parent[j]) {
      const int vj = model.idx_v[j], nj = model.nv_i[j];
      for (int r = vi; r < vi + ni; ++r)
        for (int c = vj; c < vj + nj; ++c) {
          // row r of the descendant i, column c of its ancestor j; and the mirror pair
          dd.dtau_dq(r, c) = dd.row.col(r).dot(dd.colq.col(c));
          dd.dtau_dv(r, c) = dd.row.col(r).dot(dd.colv.col(c));
          dd.dtau_dq(c, r) = dd.S.col(c).dot(dd.psi.col(r));
          dd.dtau_dv(c, r) = dd.S.col(c).dot(dd.rho.col(r));
        }
    }
  }
}

void inverse_dynamics_derivative_sweeps(const Model& model, const Data& data, const VecX& qd, const VecX& qdd,
                                        DerivativeData& dd) {
  detail::derivative_sweeps(model, data, qd, qdd, dd, "inverse_dynamics_derivative_sweeps");
}

}  // namespace soadyn
