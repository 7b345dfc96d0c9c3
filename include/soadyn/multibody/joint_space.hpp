// The configuration spaces a joint's q lives on, Pinocchio's liegroups in spirit: every joint kind
// (joint_model.hpp) moves on one of three, and takes its geometry of q from it.  Each space
// answers, for any scalar S (double; later a SIMD lane pack or an AD number, with no second copy):
//
//   integrate(q, v, h, out)     out = q ⊕ h v
//   difference(q0, q1, v)       v = q1 ⊖ q0, the v with q0 ⊕ v = q1
//   qdot(q, v, qd)              q̇ = T̄(q) v  (the q̇ map)
//   velocity(q, qd, v)          v from q̇ (a quaternion's rate along itself ignored)
//   tangent(q)                  T(q) (nv×nq): dδ = T dq, the tangent increment a change dq makes
//   qdot_jacobian(q, v, dq, dv) ∂q̇/∂q (nq×nq) and ∂q̇/∂v (nq×nv) of qdot
//   increment_rate(u, v, r)     r = u̇ = dexp⁻¹_u(v): the rate of the increment u of q(t) = q0 ⊕ u(t)
//                               moving at v (Lie-group integrators' local coordinates, exact)
//   neutral(q), random(rng, q)  zero coordinates, identity quaternion / uniform coordinates in
//                               [−π, π], a uniformly random unit quaternion
//   nq, nv, quaternion          sizes; offset of a unit quaternion [w x y z] in q, or −1
//   euclidean                   q̇ = v and T = e (no quaternion): the callers' short path
//
//   space          q                        v                  ⊕
//   VectorSpace<n> ℝⁿ                       ℝⁿ                 q + h v
//   Rotation       [w x y z]                ω, child axes      Q ⊗ exp(h ω)         (ball)
//   RigidMotion    [x y z, w x y z]         [ω; η̇], inertial   [p + h η̇, exp(h ω) ⊗ Q] (free)
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <numbers>
#include <random>

namespace soadyn::joints {

template <class S>
using Vec3T = Eigen::Matrix<S, 3, 1>;
template <class S>
using Mat3T = Eigen::Matrix<S, 3, 3>;

// stored [w x y z]; Eigen's constructor takes (w, x, y, z) too
template <class S>
inline Eigen::Quaternion<S> quaternion_at(const S* q) {
  return Eigen::Quaternion<S>(q[0], q[1], q[2], q[3]);
}
template <class S>
inline void store_quaternion(const Eigen::Quaternion<S>& u, S* q) {
  q[0] = u.w(), q[1] = u.x(), q[2] = u.y(), q[3] = u.z();
}

// exp(h ω) as a unit quaternion
template <class S>
inline Eigen::Quaternion<S> rotation_by(const Vec3T<S>& w, const S& h) {
  const S wn = w.norm();
  return wn > S(0) ? Eigen::Quaternion<S>(Eigen::AngleAxis<S>(h * wn, w / wn)) : Eigen::Quaternion<S>::Identity();
}

// log(Q) = θ a for Q = exp(θ a), the shorter turn (θ ≤ π: Q and −Q are one rotation)
template <class S>
inline Vec3T<S> rotation_log(const Eigen::Quaternion<S>& Q) {
  const Eigen::AngleAxis<S> aa(Q.normalized());
  return aa.angle() * aa.axis();
}

// dexp⁻¹_u(w) on so(3) (the inverse of the exponential map's derivative; Iserles, Munthe-Kaas,
// Nørsett and Zanna, Acta Numerica 2000):  for exp(u(t)) ⊗ Q0 turning at w (inertial, left)
//   u̇ = w − ½ u × w + c(θ) u × (u × w),   c(θ) = (1 − (θ/2) cot(θ/2)) / θ²,  θ = |u| < 2π,
// and for Q0 ⊗ exp(u(t)) turning at w in its own axes (right), the same with + ½ u × w.
// c by its series 1/12 + θ²/720 + θ⁴/30240 where θ is small (the closed form cancels there)
template <class S>
inline Vec3T<S> rotation_increment_rate(const Vec3T<S>& u, const Vec3T<S>& w, bool right) {
  using std::sqrt, std::tan;
  const S t2 = u.squaredNorm();
  S c;
  if (t2 < S(1e-4)) {
    c = S(1) / S(12) + t2 * (S(1) / S(720) + t2 / S(30240));
  } else {
    const S t = sqrt(t2);
    c = (S(1) - S(0.5) * t / tan(S(0.5) * t)) / t2;
  }
  const Vec3T<S> uw = u.cross(w);
  return w + (right ? S(0.5) : S(-0.5)) * uw + c * u.cross(uw);
}

// a uniformly random unit quaternion (four normal deviates, normalized)
template <class S, class Rng>
inline Eigen::Quaternion<S> random_quaternion(Rng& rng) {
  std::normal_distribution<double> n;
  Eigen::Quaterniond Q(n(rng), n(rng), n(rng), n(rng));
  return Q.normalized().template cast<S>();
}

// ℝⁿ: q ⊕ h v = q + h v, q1 ⊖ q0 = q1 − q0, q̇ = v, T = e
template <int n>
struct VectorSpace {
  static constexpr int nq = n, nv = n, quaternion = -1;
  static constexpr bool euclidean = true;
  template <class S>
  static void integrate(const S* q, const S* v, const S& h, S* out) {
    for (int k = 0; k < n; ++k) out[k] = q[k] + h * v[k];
  }
  template <class S>
  static void difference(const S* q0, const S* q1, S* v) {
    for (int k = 0; k < n; ++k) v[k] = q1[k] - q0[k];
  }
  template <class S>
  static void qdot(const S*, const S* v, S* qd) {
    for (int k = 0; k < n; ++k) qd[k] = v[k];
  }
  template <class S>
  static void velocity(const S*, const S* qd, S* v) {
    for (int k = 0; k < n; ++k) v[k] = qd[k];
  }
  template <class S>
  static Eigen::Matrix<S, n, n> tangent(const S*) {
    return Eigen::Matrix<S, n, n>::Identity();
  }
  template <class S>
  static void qdot_jacobian(const S*, const S*, Eigen::Matrix<S, n, n>& dq, Eigen::Matrix<S, n, n>& dv) {
    dq.setZero(), dv.setIdentity();
  }
  template <class S>
  static void increment_rate(const S*, const S* v, S* r) {
    for (int k = 0; k < n; ++k) r[k] = v[k];
  }
  template <class S>
  static void neutral(S* q) {
    for (int k = 0; k < n; ++k) q[k] = S(0);
  }
  template <class S, class Rng>
  static void random(Rng& rng, S* q) {
    std::uniform_real_distribution<double> u(-std::numbers::pi, std::numbers::pi);
    for (int k = 0; k < n; ++k) q[k] = S(u(rng));
  }
};

// 2 vec(Q* ⊗ dQ) / |Q|² (right = false, increments in the child's axes) or 2 vec(dQ ⊗ Q*) / |Q|²
// (right = true, inertial): the 3×4 rows of T for a quaternion Q; a change along Q gives none
template <class S>
inline Eigen::Matrix<S, 3, 4> quaternion_tangent(const S* Q, bool right) {
  const S w = Q[0], x = Q[1], y = Q[2], z = Q[3];
  Eigen::Matrix<S, 3, 4> b;
  if (right) b << -x, w, -z, y, -y, z, w, -x, -z, -y, x, w;
  else b << -x, w, z, -y, -y, -z, w, x, -z, y, -x, w;
  return b * (S(2) / (w * w + x * x + y * y + z * z));
}

// SO(3) by a unit quaternion Q = [w x y z], ω in the child's axes (the ball joint):
// Q ⊕ h ω = Q ⊗ exp(h ω),  Q̇ = ½ Q ⊗ [0; ω],  Q1 ⊖ Q0 = log(Q0* ⊗ Q1)
struct Rotation {
  static constexpr int nq = 4, nv = 3, quaternion = 0;
  static constexpr bool euclidean = false;
  template <class S>
  static void integrate(const S* q, const S* v, const S& h, S* out) {
    store_quaternion((quaternion_at(q) * rotation_by(Vec3T<S>(v[0], v[1], v[2]), h)).normalized(), out);
  }
  template <class S>
  static void difference(const S* q0, const S* q1, S* v) {
    const Vec3T<S> w = rotation_log(quaternion_at(q0).normalized().conjugate() * quaternion_at(q1).normalized());
    v[0] = w[0], v[1] = w[1], v[2] = w[2];
  }
  template <class S>
  static void qdot(const S* q, const S* v, S* qd) {
    const S w = q[0], x = q[1], y = q[2], z = q[3], a = v[0], b = v[1], c = v[2];
    qd[0] = S(0.5) * (-x * a - y * b - z * c);
    qd[1] = S(0.5) * (w * a + y * c - z * b);
    qd[2] = S(0.5) * (w * b + z * a - x * c);
    qd[3] = S(0.5) * (w * c + x * b - y * a);
  }
  // [0; ω] = 2 Q* ⊗ Q̇ / |Q|²
  template <class S>
  static void velocity(const S* q, const S* qd, S* v) {
    const Eigen::Quaternion<S> Q = quaternion_at(q), w = Q.conjugate() * quaternion_at(qd);
    const S n2 = Q.squaredNorm();
    v[0] = S(2) * w.x() / n2, v[1] = S(2) * w.y() / n2, v[2] = S(2) * w.z() / n2;
  }
  template <class S>
  static Eigen::Matrix<S, 3, 4> tangent(const S* q) {
    return quaternion_tangent(q, false);
  }
  // Q0 ⊗ exp(u): u̇ = dexp⁻¹_{−u}(ω)
  template <class S>
  static void increment_rate(const S* u, const S* v, S* r) {
    const Vec3T<S> w = rotation_increment_rate(Vec3T<S>(u[0], u[1], u[2]), Vec3T<S>(v[0], v[1], v[2]), true);
    r[0] = w[0], r[1] = w[1], r[2] = w[2];
  }
  // Q̇ = ½ Q ⊗ [0; ω]: linear in Q and in ω
  template <class S>
  static void qdot_jacobian(const S* q, const S* v, Eigen::Matrix<S, 4, 4>& dq, Eigen::Matrix<S, 4, 3>& dv) {
    const S w = q[0], x = q[1], y = q[2], z = q[3], a = v[0], b = v[1], c = v[2];
    dq << S(0), -a, -b, -c, a, S(0), c, -b, b, -c, S(0), a, c, b, -a, S(0);
    dv << -x, -y, -z, w, -z, y, z, w, -x, -y, x, w;
    dq *= S(0.5), dv *= S(0.5);
  }
  template <class S>
  static void neutral(S* q) {
    q[0] = S(1), q[1] = q[2] = q[3] = S(0);
  }
  template <class S, class Rng>
  static void random(Rng& rng, S* q) {
    store_quaternion(random_quaternion<S>(rng), q);
  }
};

// ℝ³ × SO(3), q = [x y z, w x y z], v = [ω; η̇] both inertial (the free joint):
// q ⊕ h v = [p + h η̇, exp(h ω) ⊗ Q],  Q̇ = ½ [0; ω] ⊗ Q,  q1 ⊖ q0 = [log(Q1 ⊗ Q0*); p1 − p0]
struct RigidMotion {
  static constexpr int nq = 7, nv = 6, quaternion = 3;
  static constexpr bool euclidean = false;
  template <class S>
  static void integrate(const S* q, const S* v, const S& h, S* out) {
    for (int k = 0; k < 3; ++k) out[k] = q[k] + h * v[3 + k];
    store_quaternion((rotation_by(Vec3T<S>(v[0], v[1], v[2]), h) * quaternion_at(q + 3)).normalized(), out + 3);
  }
  template <class S>
  static void difference(const S* q0, const S* q1, S* v) {
    const Vec3T<S> w = rotation_log(quaternion_at(q1 + 3).normalized() * quaternion_at(q0 + 3).normalized().conjugate());
    v[0] = w[0], v[1] = w[1], v[2] = w[2];
    for (int k = 0; k < 3; ++k) v[3 + k] = q1[k] - q0[k];
  }
  template <class S>
  static void qdot(const S* q, const S* v, S* qd) {
    const S w = q[3], x = q[4], y = q[5], z = q[6], a = v[0], b = v[1], c = v[2];
    qd[0] = v[3], qd[1] = v[4], qd[2] = v[5];
    qd[3] = S(0.5) * (-a * x - b * y - c * z);
    qd[4] = S(0.5) * (a * w + b * z - c * y);
    qd[5] = S(0.5) * (-a * z + b * w + c * x);
    qd[6] = S(0.5) * (a * y - b * x + c * w);
  }
  // [0; ω] = 2 Q̇ ⊗ Q* / |Q|²,  η̇ = ṗ
  template <class S>
  static void velocity(const S* q, const S* qd, S* v) {
    const Eigen::Quaternion<S> Q = quaternion_at(q + 3), w = quaternion_at(qd + 3) * Q.conjugate();
    const S n2 = Q.squaredNorm();
    v[0] = S(2) * w.x() / n2, v[1] = S(2) * w.y() / n2, v[2] = S(2) * w.z() / n2;
    for (int k = 0; k < 3; ++k) v[3 + k] = qd[k];
  }
  template <class S>
  static Eigen::Matrix<S, 6, 7> tangent(const S* q) {
    Eigen::Matrix<S, 6, 7> T = Eigen::Matrix<S, 6, 7>::Zero();
    T.template block<3, 4>(0, 3) = quaternion_tangent(q + 3, true);
    T.template block<3, 3>(3, 0).setIdentity();
    return T;
  }
  // [exp(u_ω) ⊗ Q0, p0 + u_p]: u̇_ω = dexp⁻¹_{u_ω}(ω), u̇_p = η̇
  template <class S>
  static void increment_rate(const S* u, const S* v, S* r) {
    const Vec3T<S> w = rotation_increment_rate(Vec3T<S>(u[0], u[1], u[2]), Vec3T<S>(v[0], v[1], v[2]), false);
    r[0] = w[0], r[1] = w[1], r[2] = w[2];
    for (int k = 3; k < 6; ++k) r[k] = v[k];
  }
  // ṗ = η̇;  Q̇ = ½ [0; ω] ⊗ Q
  template <class S>
  static void qdot_jacobian(const S* q, const S* v, Eigen::Matrix<S, 7, 7>& dq, Eigen::Matrix<S, 7, 6>& dv) {
    const S w = q[3], x = q[4], y = q[5], z = q[6], a = v[0], b = v[1], c = v[2];
    dq.setZero(), dv.setZero();
    dq.template block<4, 4>(3, 3) << S(0), -a, -b, -c, a, S(0), -c, b, b, c, S(0), -a, c, -b, a, S(0);
    dv.template block<4, 3>(3, 0) << -x, -y, -z, w, z, -y, -z, w, x, y, -x, w;
    dq *= S(0.5), dv *= S(0.5);
    dv.template block<3, 3>(0, 3).setIdentity();
  }
  template <class S>
  static void neutral(S* q) {
    for (int k = 0; k < 7; ++k) q[k] = S(0);
    q[3] = S(1);
  }
  template <class S, class Rng>
  static void random(Rng& rng, S* q) {
    VectorSpace<3>::random(rng, q);
    store_quaternion(random_quaternion<S>(rng), q + 3);
  }
};

}  // namespace soadyn::joints
