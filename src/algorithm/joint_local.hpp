// The per-kind pieces of the body-axes sweeps (mass_matrix_local.cpp, bias_local.cpp): for each
// joint kind (joint_model.hpp), the child's transform X_i and its motion subspace Ĝ_i in its own
// axes, as types whose operations have every index the kind fixes known at compile time.
//
// X_i = (R, p), the child's placement ∘ joint motion, takes a motion from the parent's axes and
// point to the child's and a force back (Featherstone's X and X*ᵀ):
//   [ω; u] → [Rᵀ ω; Rᵀ (u + ω × p)],     [n; f] → [R n + p × R f; R f]
// and a composite inertia K → X K Xᵀ into the parent's.  Two shapes:
//   AxisTurn<k>  R = Rot_k(θ) (an unturned placement, a revolute joint along ±e_k): R mixes two
//                components by (cos θ, sin θ), with Rot_k taking e_a → c e_a + s e_b,
//                e_b → −s e_a + c e_b (a = k + 1, b = k + 2)
//   Rigid        any (R, p)
// The subspaces: AngularAxis<k> ±[e_k; 0], LinearAxis<k> ±[0; e_k], Angular [a; 0], Linear [0; a],
// Screw [a; h a] (helical, pitch h), Spherical [e; 0], PlanarBody [0 0 n; t1 t2 0] (t = Rmᵀ e,
// turning with θ), FreeBody [Rᵀ 0; 0 Rᵀ] (the free joint's velocity is inertial).  Each answers:
//   add_motion(x, v̂, â)  v̂ += Ĝ x and â += v̂ × Ĝ x + c_J, c_J = Ġ̂ x at q̈ = 0: zero where Ĝ is
//                        constant, [0; −gw × gu] for the planar and free joints (d/dt Rᵀ e = −ω × Rᵀ e)
//   project(n, f, out)   Ĝᵀ [n; f] into out[0 .. nv)
//   entry(m, F col)      column m of Ĝ dotted with a force pair
//   times(K, F, c)       K Ĝ into columns c .. c + nv of F
#pragma once

#include "soadyn/multibody/data.hpp"
#include "soadyn/multibody/inertia.hpp"
#include "soadyn/multibody/joint_model.hpp"
#include "soadyn/multibody/model.hpp"

namespace soadyn::local {

// ---- transforms

template <int k>
struct AxisTurn {
  static constexpr int a = (k + 1) % 3, b = (k + 2) % 3;
  double c, s;
  const Vec3& p;
};

struct Rigid {
  Mat3 R;
  Vec3 p;
  bool turns = true;  // R ≠ e (an unturned prismatic axis moves K without turning it)
  Vec3 to_child(const Vec3& x) const { return R.transpose() * x; }
  Vec3 to_parent(const Vec3& x) const { return R * x; }
};

// Kp += X K Xᵀ.  A turn by θ about e_k: h' = Rot h, I' = Rot I Rotᵀ (its 2×2 block by double
// angles), then the move by p: w = h' + m p / 2, Kp.m += m, Kp.h += h' + m p,
// Kp.I += I' + 2 (p·w) e − (p wᵀ + w pᵀ).  In scalars: Kp is read back as soon as the sweep
// reaches the parent, and a load wider than the stores it reads stalls the CPU
template <int k>
inline void add_to_parent(const AxisTurn<k>& X, const SpatialInertia& K, SpatialInertia& Kp) {
  constexpr int a = AxisTurn<k>::a, b = AxisTurn<k>::b;
  const double c = X.c, s = X.s, m = K.m, c2 = c * c - s * s, s2 = 2.0 * c * s;
  const Vec3& d = X.p;
  const double avg = 0.5 * (K.I(a, a) + K.I(b, b)), dif = 0.5 * (K.I(a, a) - K.I(b, b)), iab = K.I(a, b);
  double h[3], I[3][3];
  h[k] = K.h(k);
  h[a] = c * K.h(a) - s * K.h(b);
  h[b] = s * K.h(a) + c * K.h(b);
  I[k][k] = K.I(k, k);
  I[k][a] = c * K.I(k, a) - s * K.I(k, b);
  I[k][b] = s * K.I(k, a) + c * K.I(k, b);
  I[a][a] = avg + dif * c2 - iab * s2;
  I[b][b] = avg - dif * c2 + iab * s2;
  I[a][b] = dif * s2 + iab * c2;
  I[a][k] = I[k][a], I[b][k] = I[k][b], I[b][a] = I[a][b];
  const double w[3] = {h[0] + 0.5 * m * d[0], h[1] + 0.5 * m * d[1], h[2] + 0.5 * m * d[2]};
  const double dw2 = 2.0 * (d[0] * w[0] + d[1] * w[1] + d[2] * w[2]);
  Kp.m += m;
  for (int r = 0; r < 3; ++r) {
    Kp.h(r) += h[r] + m * d[r];
    for (int col = 0; col < 3; ++col) Kp.I(r, col) += I[r][col] - d[r] * w[col] - w[r] * d[col];
    Kp.I(r, r) += dw2;
  }
}
inline void add_to_parent(const Rigid& X, const SpatialInertia& K, SpatialInertia& Kp) {
  if (!X.turns) return Kp.add_transformed(K, X.p);
  SpatialInertia Kr = K;
  rotate_symmetric(X.R, K.I, Kr.I);
  Kr.h = X.R * K.h;
  Kp.add_transformed(Kr, X.p);
}

// columns [c0, c1) of F, force pairs [n; f], moved to the parent: f' = R f, n' = R n + p × f'.
// Each column is read and written as six scalars, so a column one body's move writes is read
// back by the next at the same width
template <class X>
inline void move_to_parent(const X& x, Mat6X& F, int c0, int c1) {
  const Vec3& p = x.p;
  for (int j = c0; j < c1; ++j) {
    double* col = F.col(j).data();
    const Vec3 n = x.to_parent(Vec3(col[0], col[1], col[2])), f = x.to_parent(Vec3(col[3], col[4], col[5]));
    col[0] = n[0] + p.y() * f[2] - p.z() * f[1];
    col[1] = n[1] + p.z() * f[0] - p.x() * f[2];
    col[2] = n[2] + p.x() * f[1] - p.y() * f[0];
    col[3] = f[0], col[4] = f[1], col[5] = f[2];
  }
}

// the same for a turn about e_k: n' = Rot n + p × f', f' = Rot f, each component one scalar
// product with constant indices
template <int k>
inline void move_to_parent(const AxisTurn<k>& X, Mat6X& F, int c0, int c1) {
  constexpr int a = AxisTurn<k>::a, b = AxisTurn<k>::b;
  const double c = X.c, s = X.s;
  const Vec3& p = X.p;
  for (int j = c0; j < c1; ++j) {
    double* x = F.col(j).data();
    double n[3], f[3];
    n[k] = x[k], f[k] = x[3 + k];
    n[a] = c * x[a] - s * x[b], n[b] = s * x[a] + c * x[b];
    f[a] = c * x[3 + a] - s * x[3 + b], f[b] = s * x[3 + a] + c * x[3 + b];
    x[0] = n[0] + p.y() * f[2] - p.z() * f[1];
    x[1] = n[1] + p.z() * f[0] - p.x() * f[2];
    x[2] = n[2] + p.x() * f[1] - p.y() * f[0];
    x[3] = f[0], x[4] = f[1], x[5] = f[2];
  }
}

// ---- subspaces (spatial inertia K [ω; u] = [I ω + h × u; m u − h × ω])

inline void store(Mat6X& F, int c, const Vec3& n, const Vec3& f) {
  double* x = F.col(c).data();
  x[0] = n[0], x[1] = n[1], x[2] = n[2], x[3] = f[0], x[4] = f[1], x[5] = f[2];
}

template <int k>
struct AngularAxis {
  static constexpr int nv = 1, a = (k + 1) % 3, b = (k + 2) % 3;
  double sign;
  // v̂ × Ĝ q̇ with Ĝ q̇ = r e_k: [ω × e_k; u × e_k] r, two components each; Ĝ constant
  void add_motion(const double* x, Vec3& w, Vec3& u, Vec3& aw, Vec3& au) const {
    const double r = sign * x[0];
    w(k) += r;
    aw(a) += r * w(b), aw(b) -= r * w(a);
    au(a) += r * u(b), au(b) -= r * u(a);
  }
  void project(const Vec3& n, const Vec3&, double* out) const { out[0] = sign * n(k); }
  double entry(int, const double* col) const { return sign * col[k]; }
  // K Ĝ = ±[I e_k; −h × e_k]
  void times(const SpatialInertia& K, Mat6X& F, int c) const {
    double* x = F.col(c).data();
    x[0] = sign * K.I(0, k), x[1] = sign * K.I(1, k), x[2] = sign * K.I(2, k);
    x[3 + k] = 0.0, x[3 + a] = -sign * K.h(b), x[3 + b] = sign * K.h(a);
  }
};

template <int k>
struct LinearAxis {
  static constexpr int nv = 1, a = (k + 1) % 3, b = (k + 2) % 3;
  double sign;
  // v̂ × Ĝ q̇ = [0; ω × e_k r]
  void add_motion(const double* x, Vec3& w, Vec3& u, Vec3&, Vec3& au) const {
    const double r = sign * x[0];
    u(k) += r;
    au(a) += r * w(b), au(b) -= r * w(a);
  }
  void project(const Vec3&, const Vec3& f, double* out) const { out[0] = sign * f(k); }
  double entry(int, const double* col) const { return sign * col[3 + k]; }
  // K Ĝ = ±[h × e_k; m e_k]
  void times(const SpatialInertia& K, Mat6X& F, int c) const {
    double* x = F.col(c).data();
    x[k] = 0.0, x[a] = sign * K.h(b), x[b] = -sign * K.h(a);
    x[3 + k] = sign * K.m, x[3 + a] = 0.0, x[3 + b] = 0.0;
  }
};

// k for AngularAxis<k>, else −1
template <class S>
inline constexpr int angular_axis = -1;
template <int k>
inline constexpr int angular_axis<AngularAxis<k>> = k;

struct Angular {
  static constexpr int nv = 1;
  const Vec3& g;
  void add_motion(const double* x, Vec3& w, Vec3& u, Vec3& aw, Vec3& au) const {
    const Vec3 gw = x[0] * g;
    aw += w.cross(gw);
    au += u.cross(gw);
    w += gw;
  }
  void project(const Vec3& n, const Vec3&, double* out) const { out[0] = g.dot(n); }
  double entry(int, const double* col) const { return g[0] * col[0] + g[1] * col[1] + g[2] * col[2]; }
  void times(const SpatialInertia& K, Mat6X& F, int c) const { store(F, c, K.I * g, g.cross(K.h)); }
};

struct Linear {
  static constexpr int nv = 1;
  const Vec3& g;
  void add_motion(const double* x, Vec3& w, Vec3& u, Vec3&, Vec3& au) const {
    const Vec3 gu = x[0] * g;
    au += w.cross(gu);
    u += gu;
  }
  void project(const Vec3&, const Vec3& f, double* out) const { out[0] = g.dot(f); }
  double entry(int, const double* col) const { return g[0] * col[3] + g[1] * col[4] + g[2] * col[5]; }
  void times(const SpatialInertia& K, Mat6X& F, int c) const { store(F, c, K.h.cross(g), K.m * g); }
};

// [a; h a]: the helical joint's, constant in body axes (the turn about a keeps a, and the body's
// origin stays on the axis)
struct Screw {
  static constexpr int nv = 1;
  const Vec3& g;
  double pitch;
  // v̂ += Ĝ q̇ = [gw; gu],  â += v̂ × [gw; gu] = [ω × gw; ω × gu + u × gw]
  void add_motion(const double* x, Vec3& w, Vec3& u, Vec3& aw, Vec3& au) const {
    const Vec3 gw = x[0] * g, gu = pitch * gw;
    aw += w.cross(gw);
    au += w.cross(gu) + u.cross(gw);
    w += gw;
    u += gu;
  }
  void project(const Vec3& n, const Vec3& f, double* out) const { out[0] = g.dot(n) + pitch * g.dot(f); }
  double entry(int, const double* col) const {
    return g[0] * (col[0] + pitch * col[3]) + g[1] * (col[1] + pitch * col[4]) + g[2] * (col[2] + pitch * col[5]);
  }
  // K Ĝ = [I a + h_K × h a; m h a − h_K × a]
  void times(const SpatialInertia& K, Mat6X& F, int c) const {
    store(F, c, K.I * g + pitch * K.h.cross(g), pitch * K.m * g - K.h.cross(g));
  }
};

struct Spherical {
  static constexpr int nv = 3;
  void add_motion(const double* x, Vec3& w, Vec3& u, Vec3& aw, Vec3& au) const {
    const Vec3 gw(x[0], x[1], x[2]);
    aw += w.cross(gw);
    au += u.cross(gw);
    w += gw;
  }
  void project(const Vec3& n, const Vec3&, double* out) const { out[0] = n[0], out[1] = n[1], out[2] = n[2]; }
  double entry(int m, const double* col) const { return col[m]; }
  void times(const SpatialInertia& K, Mat6X& F, int c) const {
    for (int m = 0; m < 3; ++m) store(F, c + m, K.I.col(m), Vec3::Unit(m).cross(K.h));
  }
};

// v̂ += [gw; gu], â += v̂ × [gw; gu] + c_J with c_J = [0; −gw × gu]: a Ĝ that turns with the body's
// rotation about its own joint (planar, free)
inline void add_turning_motion(const Vec3& gw, const Vec3& gu, Vec3& w, Vec3& u, Vec3& aw, Vec3& au) {
  aw += w.cross(gw);
  au += w.cross(gu) + u.cross(gw) - gw.cross(gu);
  w += gw;
  u += gu;
}

// columns [0; t1], [0; t2], [n; 0]
struct PlanarBody {
  static constexpr int nv = 3;
  Vec3 t1, t2;
  const Vec3& n;
  void motion(const double* x, Vec3& gw, Vec3& gu) const { gw = x[2] * n, gu = x[0] * t1 + x[1] * t2; }
  void add_motion(const double* x, Vec3& w, Vec3& u, Vec3& aw, Vec3& au) const {
    Vec3 gw, gu;
    motion(x, gw, gu);
    add_turning_motion(gw, gu, w, u, aw, au);
  }
  void project(const Vec3& nn, const Vec3& f, double* out) const { out[0] = t1.dot(f), out[1] = t2.dot(f), out[2] = n.dot(nn); }
  double entry(int m, const double* col) const {
    const Vec3 f(col[3], col[4], col[5]);
    return m == 0 ? t1.dot(f) : m == 1 ? t2.dot(f) : n.dot(Vec3(col[0], col[1], col[2]));
  }
  void times(const SpatialInertia& K, Mat6X& F, int c) const {
    store(F, c, K.h.cross(t1), K.m * t1);
    store(F, c + 1, K.h.cross(t2), K.m * t2);
    store(F, c + 2, K.I * n, n.cross(K.h));
  }
};

// [Rᵀ 0; 0 Rᵀ]: the free joint's inertial [ω; η̇] in its body's axes
struct FreeBody {
  static constexpr int nv = 6;
  Mat3 R;
  void motion(const double* x, Vec3& gw, Vec3& gu) const {
    gw.noalias() = R.transpose() * Vec3(x[0], x[1], x[2]);
    gu.noalias() = R.transpose() * Vec3(x[3], x[4], x[5]);
  }
  void add_motion(const double* x, Vec3& w, Vec3& u, Vec3& aw, Vec3& au) const {
    Vec3 gw, gu;
    motion(x, gw, gu);
    add_turning_motion(gw, gu, w, u, aw, au);
  }
  void project(const Vec3& n, const Vec3& f, double* out) const {
    const Vec3 a = R * n, b = R * f;
    out[0] = a[0], out[1] = a[1], out[2] = a[2], out[3] = b[0], out[4] = b[1], out[5] = b[2];
  }
  double entry(int m, const double* col) const {
    // (Rᵀ e_m)ᵀ x = row m of R times x
    return m < 3 ? R.row(m).dot(Vec3(col[0], col[1], col[2])) : R.row(m - 3).dot(Vec3(col[3], col[4], col[5]));
  }
  void times(const SpatialInertia& K, Mat6X& F, int c) const {
    for (int m = 0; m < 3; ++m) {
      const Vec3 r = R.row(m).transpose();  // Rᵀ e_m
      store(F, c + m, K.I * r, r.cross(K.h));
      store(F, c + 3 + m, K.h.cross(r), K.m * r);
    }
  }
};

// ---- each kind's X_i, from q and the batched (cos θ, sin θ) of data.work.turn, and its Ĝ_i given X_i

template <int k>
inline AxisTurn<k> transform(const joints::RevoluteAxis<k>& j, const Model& model, const Data& data, const VecX&, int i) {
  return {data.work.turn(0, i), j.sign * data.work.turn(1, i), model.placement[i].p};
}
template <int k>
inline Rigid transform(const joints::TurnedRevoluteAxis<k>& j, const Model& model, const Data& data, const VecX&, int i) {
  const Placement& X = model.placement[i];
  Rigid out{Mat3(), X.p};
  turn_frame(X.R, k, data.work.turn(0, i), j.sign * data.work.turn(1, i), out.R);
  return out;
}
template <int k>
inline Rigid transform(const joints::PrismaticAxis<k>& j, const Model& model, const Data&, const VecX& q, int i) {
  const Placement& X = model.placement[i];
  return {X.R, X.p + (j.sign * q(model.idx_q[i])) * X.R.col(k), j.turned};
}
inline Rigid transform(const joints::Prismatic& j, const Model& model, const Data&, const VecX& q, int i) {
  const Placement& X = model.placement[i];
  return {X.R, X.p + q(model.idx_q[i]) * (X.R * j.axis), X.R != Mat3::Identity()};
}
// any other joint: placement ∘ the joint's motion
template <class J>
inline Rigid transform(const J& joint, const Model& model, const Data&, const VecX& q, int i) {
  static_assert(std::is_same_v<J, joints::Revolute> || std::is_same_v<J, joints::Ball> ||
                std::is_same_v<J, joints::Planar> || std::is_same_v<J, joints::Free> || std::is_same_v<J, joints::Helical>);
  const Placement& X = model.placement[i];
  Mat3 Rm;
  Vec3 pm;
  joint.motion(q.data() + model.idx_q[i], Rm, pm);
  return {X.R * Rm, X.p + X.R * pm};
}

template <int k, class T>
inline AngularAxis<k> subspace(const joints::RevoluteAxis<k>& j, const T&, const Model&, int) { return {j.sign}; }
template <int k, class T>
inline AngularAxis<k> subspace(const joints::TurnedRevoluteAxis<k>& j, const T&, const Model&, int) { return {j.sign}; }
template <int k, class T>
inline LinearAxis<k> subspace(const joints::PrismaticAxis<k>& j, const T&, const Model&, int) { return {j.sign}; }
inline Angular subspace(const joints::Revolute& j, const Rigid&, const Model&, int) { return {j.axis}; }
inline Linear subspace(const joints::Prismatic& j, const Rigid&, const Model&, int) { return {j.axis}; }
inline Screw subspace(const joints::Helical& j, const Rigid&, const Model&, int) { return {j.axis, j.pitch}; }
inline Spherical subspace(const joints::Ball&, const Rigid&, const Model&, int) { return {}; }
// t = Rmᵀ e with Rm = X.Rᵀ of the placement times X's R
inline PlanarBody subspace(const joints::Planar& j, const Rigid& X, const Model& model, int i) {
  const Mat3 Rm = model.placement[i].R.transpose() * X.R;
  return {Rm.transpose() * j.e1, Rm.transpose() * j.e2, j.n};
}
inline FreeBody subspace(const joints::Free&, const Rigid& X, const Model&, int) { return {X.R}; }

}  // namespace soadyn::local
