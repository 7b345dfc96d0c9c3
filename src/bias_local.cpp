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
// parent's axes and point to the child's: [ω; u] → [Rᵀ ω; Rᵀ (u + ω × p)], (R, p) the child's
// placement ∘ joint motion; its transpose takes a force back: [n; f] → [R n + p × R f; R f].  A
// revolute joint along ±e_k of an unturned placement makes R a turn by θ about e_k (two
// components mixed by (cos θ, sin θ), no 3×3 product).
//
// Ĝ_i is constant in body axes for revolute, prismatic and ball joints; the free joint's
// velocity is inertial (Ĝ = [Rᵀ 0; 0 Rᵀ]) and its q̈ = 0 leaves the spatial acceleration
// [0; −ω × η̇]; a planar joint's Ĝ turns with θ, and a model with one takes the inertial route.
#include "soadyn/algorithms.hpp"
#include "soadyn/kinematics.hpp"

#include <cmath>

namespace soadyn {

namespace {

// Rot_kᵀ x and Rot_k x, Rot_k(θ) taking e_a → c e_a + s e_b, e_b → −s e_a + c e_b (a = k + 1, b = k + 2)
template <int k>
inline Vec3 turn_back(const Vec3& x, double c, double s) {
  constexpr int a = (k + 1) % 3, b = (k + 2) % 3;
  Vec3 y;
  y(k) = x(k), y(a) = c * x(a) + s * x(b), y(b) = c * x(b) - s * x(a);
  return y;
}
template <int k>
inline Vec3 turn(const Vec3& x, double c, double s) {
  constexpr int a = (k + 1) % 3, b = (k + 2) % 3;
  Vec3 y;
  y(k) = x(k), y(a) = c * x(a) - s * x(b), y(b) = c * x(b) + s * x(a);
  return y;
}

// f̂ = M̂ â + v̂ ×* M̂ v̂ with M̂ [ω; u] = [I ω + h × u; m u − h × ω] and
// [ω; u] ×* [n; f] = [ω × n + u × f; ω × f], in halves
inline void body_force(const SpatialInertia& K, const Vec3& w, const Vec3& u, const Vec3& aw, const Vec3& au,
                       Mat6X& F, int i) {
  const Vec3 hn = K.I * w + K.h.cross(u), hf = K.m * u - K.h.cross(w);
  F.col(i).head<3>() = K.I * aw + K.h.cross(au) + w.cross(hn) + u.cross(hf);
  F.col(i).tail<3>() = K.m * au - K.h.cross(aw) + w.cross(hf);
}

// a revolute joint along ±e_k of an unturned placement: both sweeps' steps with every index
// known at compile time
template <int k>
inline void revolute_forward(const Model& model, Data& data, const SpatialInertia& K, int i, double sign, double qd) {
  const int p = model.parent[i];
  const double c = data.turn(0, i), s = sign * data.turn(1, i);
  const Vec3& offset = model.placement[i].p;
  // X_i v̂_p, X_i â_p  (the ground: v̂ = 0, â = [0; −g])
  Vec3 w, u, aw, au;
  if (p < 0) {
    w.setZero(), u.setZero(), aw.setZero();
    au = turn_back<k>(-model.gravity, c, s);
  } else {
    const Vec3 wp = data.Vb.col(p).head<3>(), awp = data.Ab.col(p).head<3>();
    w = turn_back<k>(wp, c, s);
    u = turn_back<k>(Vec3(data.Vb.col(p).tail<3>() + wp.cross(offset)), c, s);
    aw = turn_back<k>(awp, c, s);
    au = turn_back<k>(Vec3(data.Ab.col(p).tail<3>() + awp.cross(offset)), c, s);
  }
  // + Ĝ q̇ = ±q̇ e_k;  â += v̂ × Ĝ q̇ = [ω × e_k; u × e_k] (±q̇)
  const double r = sign * qd;
  w(k) += r;
  constexpr int a = (k + 1) % 3, b = (k + 2) % 3;
  aw(a) += r * w(b), aw(b) -= r * w(a);
  au(a) += r * u(b), au(b) -= r * u(a);
  data.Vb.col(i).head<3>() = w, data.Vb.col(i).tail<3>() = u;
  data.Ab.col(i).head<3>() = aw, data.Ab.col(i).tail<3>() = au;
  body_force(K, w, u, aw, au, data.Fb, i);
}

template <int k>
inline void revolute_backward(const Model& model, Data& data, int i, double sign) {
  const int p = model.parent[i];
  const Vec3 n = data.Fb.col(i).head<3>(), f = data.Fb.col(i).tail<3>();
  data.bias(model.idx_v[i]) = sign * n(k);
  if (p < 0) return;
  const double c = data.turn(0, i), s = sign * data.turn(1, i);
  const Vec3 fp = turn<k>(f, c, s);
  data.Fb.col(p).head<3>() += turn<k>(n, c, s) + model.placement[i].p.cross(fp);
  data.Fb.col(p).tail<3>() += fp;
}

}  // namespace

void bias_forces(const Model& model, Data& data, const VecX& q, const VecX& v) {
  data.check(model, "bias_forces", "q", q.size(), model.nq);
  data.check(model, "bias_forces", "v", v.size(), model.nv);
  if (model.has_planar) {
    update_kinematics(model, data, q);
    update_velocities(model, data, v);
    bias_forces(model, data);
    return;
  }
  joint_turns(model, q, data.turn);
  const int N = model.nbodies;
  for (int i = 0; i < N; ++i) {
    const JointType type = model.joint_type[i];
    const int p = model.parent[i], unit = model.unit_axis[i], iv = model.idx_v[i];
    // M̂_i, constant in body axes
    const SpatialInertia K = SpatialInertia::from_origin(model.mass[i], model.com[i], model.inertia_origin[i]);
    const double sign = unit > 0 ? 1.0 : -1.0;
    if (unit != 0 && type == JointType::Revolute && !model.placement_turns[i]) {
      switch (std::abs(unit) - 1) {
        case 0: revolute_forward<0>(model, data, K, i, sign, v(iv)); break;
        case 1: revolute_forward<1>(model, data, K, i, sign, v(iv)); break;
        default: revolute_forward<2>(model, data, K, i, sign, v(iv)); break;
      }
      continue;
    }
    // X_i = placement ∘ joint motion, kept for the tip-to-base sweep
    const Placement& X = model.placement[i];
    Mat3& R = data.Xr[i];
    Vec3 offset = X.p;
    if (unit != 0) {
      // along ±e_k of a placement that turns the frame (as URDFs' rpy mostly do): a revolute
      // joint's turn mixes two columns of X.R with the batched (cos θ, sin θ), a prismatic one
      // slides along X.R e_k
      const int k = std::abs(unit) - 1;
      if (type == JointType::Revolute) {
        turn_frame(X.R, k, data.turn(0, i), sign * data.turn(1, i), R);
      } else {
        R = X.R;
        offset += (sign * q(model.idx_q[i])) * X.R.col(k);
      }
    } else {
      Mat3 Rm;
      Vec3 pm;
      joint_motion(type, model.axis[i], q.data() + model.idx_q[i], Rm, pm);
      R.noalias() = X.R * Rm;
      offset += X.R * pm;
    }
    data.Xp.col(i) = offset;
    Vec3 w, u, aw, au;
    if (p < 0) {
      w.setZero(), u.setZero(), aw.setZero();
      au.noalias() = R.transpose() * (-model.gravity);
    } else {
      const Vec3 wp = data.Vb.col(p).head<3>(), awp = data.Ab.col(p).head<3>();
      w.noalias() = R.transpose() * wp;
      u.noalias() = R.transpose() * (data.Vb.col(p).tail<3>() + wp.cross(offset));
      aw.noalias() = R.transpose() * awp;
      au.noalias() = R.transpose() * (data.Ab.col(p).tail<3>() + awp.cross(offset));
    }
    // Ĝ_i q̇_i = [gw; gu] and â += v̂ × Ĝ q̇ = [ω × gw; ω × gu + u × gw]; the free joint's
    // Ĝ q̇ = [Rᵀ ω; Rᵀ η̇] with spatial acceleration [0; −ω × η̇] at q̈ = 0
    Vec3 gw = Vec3::Zero(), gu = Vec3::Zero();
    switch (type) {
      case JointType::Revolute: gw = model.axis[i] * v(iv); break;
      case JointType::Prismatic: gu = model.axis[i] * v(iv); break;
      case JointType::Ball: gw = v.segment<3>(iv); break;
      default: gw.noalias() = R.transpose() * v.segment<3>(iv), gu.noalias() = R.transpose() * v.segment<3>(iv + 3); break;
    }
    if (type == JointType::Free) {
      au -= gw.cross(gu);
    } else {
      aw += w.cross(gw);
      au += w.cross(gu) + u.cross(gw);
    }
    w += gw;
    u += gu;
    data.Vb.col(i).head<3>() = w, data.Vb.col(i).tail<3>() = u;
    data.Ab.col(i).head<3>() = aw, data.Ab.col(i).tail<3>() = au;
    body_force(K, w, u, aw, au, data.Fb, i);
  }
  for (int i = N - 1; i >= 0; --i) {
    const JointType type = model.joint_type[i];
    const int p = model.parent[i], unit = model.unit_axis[i], iv = model.idx_v[i];
    const double sign = unit > 0 ? 1.0 : -1.0;
    if (unit != 0 && type == JointType::Revolute && !model.placement_turns[i]) {
      switch (std::abs(unit) - 1) {
        case 0: revolute_backward<0>(model, data, i, sign); break;
        case 1: revolute_backward<1>(model, data, i, sign); break;
        default: revolute_backward<2>(model, data, i, sign); break;
      }
      continue;
    }
    // bias_i = Ĝ_iᵀ f̂_i
    const Vec3 n = data.Fb.col(i).head<3>(), f = data.Fb.col(i).tail<3>();
    const Mat3& R = data.Xr[i];
    switch (type) {
      case JointType::Revolute: data.bias(iv) = model.axis[i].dot(n); break;
      case JointType::Prismatic: data.bias(iv) = model.axis[i].dot(f); break;
      case JointType::Ball: data.bias.segment<3>(iv) = n; break;
      default: data.bias.segment<3>(iv).noalias() = R * n, data.bias.segment<3>(iv + 3).noalias() = R * f; break;
    }
    if (p < 0) continue;
    // f̂_p += X_iᵀ f̂_i
    const Vec3 fp = R * f;
    data.Fb.col(p).head<3>() += R * n + Vec3(data.Xp.col(i)).cross(fp);
    data.Fb.col(p).tail<3>() += fp;
  }
}

}  // namespace soadyn
