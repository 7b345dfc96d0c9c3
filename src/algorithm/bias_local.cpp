// bias(q, q̇) from (q, q̇) alone, in body frames: the fast path beside bias_forces' inertial sweep
// (rnea.cpp), which stays the reference it is tested against.
//
// The same two sweeps as the note's bias = Gᵀ Ψ_Dᵀ (M Ψ_D 𝔞 + 𝔟), with each body's velocity,
// acceleration and force in its own axes about its joint point η_i (Featherstone's recursive
// Newton–Euler), so no inertial frame is formed and each body's inertia M̂_i is the model's
// constant one:
//   base to tip:  v̂_i = X_i v̂_p + Ĝ_i q̇_i,   â_i = X_i â_p + v̂_i × Ĝ_i q̇_i   (â = [0; −g] at the ground)
//                 f̂_i = M̂_i â_i + v̂_i ×* M̂_i v̂_i
//   tip to base:  bias_i = Ĝ_iᵀ f̂_i,   f̂_p += X_iᵀ f̂_i
// with Ĝ_i the joint's motion subspace in body i's axes and X_i taking a motion from the
// parent's axes and point to the child's (joint_local.hpp: each joint kind's X_i and Ĝ_i).
// Where Ĝ_i turns with q (planar, free), â_i gains c_J = Ġ̂_i q̇_i too.  One driver per sweep, the
// kind chosen once per body.
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"

#include "joint_local.hpp"

namespace soadyn {

namespace {

// f̂ = M̂ â + v̂ ×* M̂ v̂ with M̂ [ω; u] = [I ω + h × u; m u − h × ω] and
// [ω; u] ×* [n; f] = [ω × n + u × f; ω × f], in halves.  A call of its own: inlined into every
// kind's step, it made the sweeps' loop bodies spill registers (about 15 % on binary trees)
[[gnu::noinline]] void body_force(const SpatialInertia& K, const Vec3& w, const Vec3& u, const Vec3& aw, const Vec3& au,
                       Mat6X& F, int i) {
  const Vec3 hn = K.I * w + K.h.cross(u), hf = K.m * u - K.h.cross(w);
  F.col(i).head<3>() = K.I * aw + K.h.cross(au) + w.cross(hn) + u.cross(hf);
  F.col(i).tail<3>() = K.m * au - K.h.cross(aw) + w.cross(hf);
}

// base to tip, body i: v̂_i = X_i v̂_p + Ĝ_i q̇_i,  â_i = X_i â_p + v̂_i × Ĝ_i q̇_i + c_J,
// f̂_i = M̂_i â_i + v̂_i ×* M̂_i v̂_i (â = [0; −g] at the ground).  Every kind but RevoluteAxis
// (written out below) has a general X_i = (R, p), kept for the tip-to-base sweep
template <class J>
[[gnu::flatten]] void forward_step(const J& joint, const Model& model, Data& data, const VecX& q, const VecX& v, int i) {
  const local::Rigid X = local::transform(joint, model, data, q, i);
  data.work.local.Xr[i] = X.R;
  data.work.local.Xp.col(i) = X.p;
  const int p = model.parent[i];
  // M̂_i, constant in body axes
  const SpatialInertia K = SpatialInertia::from_origin(model.mass[i], model.com[i], model.inertia_origin[i]);
  Vec3 w, u, aw, au;
  if (p < 0) {
    w.setZero(), u.setZero(), aw.setZero();
    au = X.to_child(-model.gravity);
  } else {
    const Vec3 wp = data.work.local.V.col(p).head<3>(), awp = data.work.local.A.col(p).head<3>();
    w = X.to_child(wp);
    u = X.to_child(Vec3(data.work.local.V.col(p).tail<3>() + wp.cross(X.p)));
    aw = X.to_child(awp);
    au = X.to_child(Vec3(data.work.local.A.col(p).tail<3>() + awp.cross(X.p)));
  }
  local::subspace(joint, X, model, i).add_motion(v.data() + model.idx_v[i], w, u, aw, au);
  data.work.local.V.col(i).head<3>() = w, data.work.local.V.col(i).tail<3>() = u;
  data.work.local.A.col(i).head<3>() = aw, data.work.local.A.col(i).tail<3>() = au;
  body_force(K, w, u, aw, au, data.work.local.F, i);
}

// the same two steps for a revolute joint along ±e_k of an unturned placement, written out: X_i is
// a turn by θ about e_k (two components mixed by (cos θ, sin θ)) and Ĝ_i q̇_i = ±q̇ e_k, so every
// product is a few scalars with constant indices (inline, not flattened: body_force stays a call)
template <int k>
inline void forward_step(const joints::RevoluteAxis<k>& joint, const Model& model, Data& data, const VecX&,
                                   const VecX& v, int i) {
  constexpr int a = (k + 1) % 3, b = (k + 2) % 3;
  const SpatialInertia K = SpatialInertia::from_origin(model.mass[i], model.com[i], model.inertia_origin[i]);
  const int p = model.parent[i];
  const double c = data.work.turn(0, i), s = joint.sign * data.work.turn(1, i);
  const Vec3& offset = model.placement[i].p;
  Workspace::BodyAxes& w_ = data.work.local;
  // X_i v̂_p, X_i â_p  (the ground: v̂ = 0, â = [0; −g]), Rot_kᵀ x = [.., c x_a + s x_b, c x_b − s x_a]
  auto back = [&](const Vec3& x) {
    Vec3 y;
    y(k) = x(k), y(a) = c * x(a) + s * x(b), y(b) = c * x(b) - s * x(a);
    return y;
  };
  Vec3 w, u, aw, au;
  if (p < 0) {
    w.setZero(), u.setZero(), aw.setZero();
    au = back(-model.gravity);
  } else {
    const Vec3 wp = w_.V.col(p).head<3>(), awp = w_.A.col(p).head<3>();
    w = back(wp);
    u = back(Vec3(w_.V.col(p).tail<3>() + wp.cross(offset)));
    aw = back(awp);
    au = back(Vec3(w_.A.col(p).tail<3>() + awp.cross(offset)));
  }
  // + Ĝ q̇ = ±q̇ e_k;  â += v̂ × Ĝ q̇ = [ω × e_k; u × e_k] (±q̇)
  const double r = joint.sign * v(model.idx_v[i]);
  w(k) += r;
  aw(a) += r * w(b), aw(b) -= r * w(a);
  au(a) += r * u(b), au(b) -= r * u(a);
  w_.V.col(i).head<3>() = w, w_.V.col(i).tail<3>() = u;
  w_.A.col(i).head<3>() = aw, w_.A.col(i).tail<3>() = au;
  body_force(K, w, u, aw, au, w_.F, i);
}

template <int k>
inline void backward_step(const joints::RevoluteAxis<k>& joint, const Model& model, Data& data, const VecX&,
                                    int i) {
  constexpr int a = (k + 1) % 3, b = (k + 2) % 3;
  Mat6X& F = data.work.local.F;
  const int p = model.parent[i];
  const Vec3 n = F.col(i).head<3>(), f = F.col(i).tail<3>();
  data.bias(model.idx_v[i]) = joint.sign * n(k);
  if (p < 0) return;
  const double c = data.work.turn(0, i), s = joint.sign * data.work.turn(1, i);
  // Rot_k x = [.., c x_a − s x_b, c x_b + s x_a]
  auto turn = [&](const Vec3& x) {
    Vec3 y;
    y(k) = x(k), y(a) = c * x(a) - s * x(b), y(b) = c * x(b) + s * x(a);
    return y;
  };
  const Vec3 fp = turn(f);
  F.col(p).head<3>() += turn(n) + model.placement[i].p.cross(fp);
  F.col(p).tail<3>() += fp;
}

// tip to base, body i: bias_i = Ĝ_iᵀ f̂_i,  f̂_p += X_iᵀ f̂_i (X_i as the forward step found it)
template <class J>
[[gnu::flatten]] void backward_step(const J& joint, const Model& model, Data& data, const VecX&, int i) {
  const local::Rigid X{data.work.local.Xr[i], data.work.local.Xp.col(i)};
  const Vec3 n = data.work.local.F.col(i).head<3>(), f = data.work.local.F.col(i).tail<3>();
  local::subspace(joint, X, model, i).project(n, f, data.bias.data() + model.idx_v[i]);
  const int p = model.parent[i];
  if (p < 0) return;
  const Vec3 fp = X.to_parent(f);
  data.work.local.F.col(p).head<3>() += X.to_parent(n) + X.p.cross(fp);
  data.work.local.F.col(p).tail<3>() += fp;
}

}  // namespace

void bias_forces(const Model& model, Data& data, const VecX& q, const VecX& v) {
  data.check(model, "bias_forces", "q", q.size(), model.nq);
  data.check(model, "bias_forces", "v", v.size(), model.nv);
  joint_turns(model, q, data.work.turn);
  for (int i = 0; i < model.nbodies; ++i)
    visit_joint(model, i, [&](const auto& joint) { forward_step(joint, model, data, q, v, i); });
  for (int i = model.nbodies - 1; i >= 0; --i)
    visit_joint(model, i, [&](const auto& joint) { backward_step(joint, model, data, q, i); });
}

}  // namespace soadyn
