// The joint kinds a built model is made of: each moving body's joint classified once, by
// Model::build, into a closed set of types, so that every sweep is one driver plus one step per
// kind, chosen once per body by std::visit (a jump, not a chain of tests), and a kind the step
// set forgets is a compile error, not a silent fallback.
//
//   kind                      joint                                   G_i (inertial)     Ĝ_i (body axes)
//   RevoluteAxis<k>           revolute along ±e_k of its joint frame, ±[C_j e_k; 0]     ±[e_k; 0]
//                             the placement not turning the frame
//   TurnedRevoluteAxis<k>     the same, the placement turning it      ±[C_j e_k; 0]     ±[e_k; 0]
//   PrismaticAxis<k>          prismatic along ±e_k of its joint frame ±[0; C_j e_k]     ±[0; e_k]
//   Revolute, Prismatic       along any other unit axis a             [C_j a; 0] / [0; C_j a]
//   Helical                   a screw: turn θ about the unit axis a,  [C_j a; h C_j a]   [a; h a]
//                             slide h θ along it (pitch h, m/rad)
//   Ball, Planar, Free        as joint.hpp describes them
//
// A kind is one struct here holding its geometry (its configuration space from joint_space.hpp,
// motion, subspace, carries), registered in JointModel, kind_name and visit_joint (model.hpp), in
// classify_joint, and given its body-axes subspace in src/algorithm/joint_local.hpp.
//
// The unit-axis kinds are what URDFs mostly hold (axis "0 0 1", "1 0 0"): a turn by θ about e_k
// mixes two components by (cos θ, sin θ), with no 3×3 product, and k is a template argument so
// the step's indices are constants.  JointType (joint.hpp) stays the user's word for a joint;
// JointModel is what the algorithms run on.
#pragma once

#include "soadyn/multibody/joint.hpp"
#include "soadyn/multibody/types.hpp"
#include "soadyn/multibody/joint_space.hpp"

#include <cmath>
#include <type_traits>
#include <variant>

namespace soadyn {

namespace joints {

// Each kind: its configuration space (joint_space.hpp: nq, nv, integrate, difference, qdot,
// tangent, qdot_jacobian, neutral, random, all templates on the scalar); motion(q, R, p), the
// joint's motion (body frame = joint frame · (R, p)(q)), a template on the scalar too;
// subspace(Rj, Rb, G), G_i in inertial axes into the 6×nv block G, given the joint frame's
// orientation Rj and the body's Rb = Rj R(q); carries(k, m), whether column k of G_i carries
// column m, ∂G_m/∂δ_k = G_k × G_m.

// the rotation of a unit quaternion stored [w x y z] (normalized here)
template <class S>
inline Mat3T<S> quaternion_rotation(const S* q) {
  return quaternion_at(q).normalized().toRotationMatrix();
}

// R = Rot_k(θ): e_a → c e_a + s e_b, e_b → −s e_a + c e_b (a = k + 1, b = k + 2)
template <int k, class S>
inline void axis_rotation(const S& c, const S& s, Mat3T<S>& R) {
  constexpr int a = (k + 1) % 3, b = (k + 2) % 3;
  R.setIdentity();
  R(a, a) = c, R(b, a) = s, R(a, b) = -s, R(b, b) = c;
}

template <int k>
struct RevoluteAxis : VectorSpace<1> {
  static constexpr int axis = k;
  static constexpr bool carries(int, int) { return false; }  // G × G = 0
  double sign = 1.0;  // the axis is sign · e_k
  template <class S>
  void motion(const S* q, Mat3T<S>& R, Vec3T<S>& p) const {
    using std::cos, std::sin;
    axis_rotation<k>(S(cos(q[0])), S(sign * sin(q[0])), R);
    p.setZero();
  }
  template <class G>
  void subspace(const Mat3& Rj, const Mat3&, G&& out) const {
    out.col(0) << sign * Rj.col(k), Vec3::Zero();
  }
};
template <int k>
struct TurnedRevoluteAxis : RevoluteAxis<k> {};
template <int k>
struct PrismaticAxis : VectorSpace<1> {
  static constexpr int axis = k;
  static constexpr bool carries(int, int) { return false; }  // G × G = 0
  double sign = 1.0;
  bool turned = false;  // the placement turns the frame
  template <class S>
  void motion(const S* q, Mat3T<S>& R, Vec3T<S>& p) const {
    R.setIdentity();
    p = (sign * q[0]) * Vec3T<S>::Unit(k);
  }
  template <class G>
  void subspace(const Mat3& Rj, const Mat3&, G&& out) const {
    out.col(0) << Vec3::Zero(), sign * Rj.col(k);
  }
};
struct Revolute : VectorSpace<1> {
  static constexpr bool carries(int, int) { return false; }  // G × G = 0
  Vec3 axis;  // unit, joint frame
  template <class S>
  void motion(const S* q, Mat3T<S>& R, Vec3T<S>& p) const {
    R = Eigen::AngleAxis<S>(q[0], axis.cast<S>()).toRotationMatrix();
    p.setZero();
  }
  template <class G>
  void subspace(const Mat3& Rj, const Mat3&, G&& out) const {
    out.col(0) << Rj * axis, Vec3::Zero();
  }
};
struct Prismatic : VectorSpace<1> {
  static constexpr bool carries(int, int) { return false; }  // G × G = 0
  Vec3 axis;
  template <class S>
  void motion(const S* q, Mat3T<S>& R, Vec3T<S>& p) const {
    R.setIdentity();
    p = q[0] * axis.cast<S>();
  }
  template <class G>
  void subspace(const Mat3& Rj, const Mat3&, G&& out) const {
    out.col(0) << Vec3::Zero(), Rj * axis;
  }
};
// q = θ: a turn by θ about the unit axis a and a slide by pitch · θ along it (a screw; pitch in
// m/rad, 0 is a revolute joint); the body's origin stays on the axis, so G_i = [C_j a; pitch C_j a]
// is fixed in the parent's frame, and in body axes Ĝ_i = [a; pitch a]
struct Helical : VectorSpace<1> {
  static constexpr bool carries(int, int) { return false; }  // G × G = 0
  Vec3 axis;
  double pitch = 0.0;
  template <class S>
  void motion(const S* q, Mat3T<S>& R, Vec3T<S>& p) const {
    R = Eigen::AngleAxis<S>(q[0], axis.cast<S>()).toRotationMatrix();
    p = (pitch * q[0]) * axis.cast<S>();
  }
  template <class G>
  void subspace(const Mat3& Rj, const Mat3&, G&& out) const {
    const Vec3 g = Rj * axis;
    out.col(0) << g, pitch * g;
  }
};
// q = [w x y z], the child's attitude in the joint frame; G_i = [C_i; 0]
struct Ball : Rotation {
  static constexpr bool carries(int, int) { return true; }  // all three turn with the child
  template <class S>
  void motion(const S* q, Mat3T<S>& R, Vec3T<S>& p) const {
    R = quaternion_rotation(q);
    p.setZero();
  }
  template <class G>
  void subspace(const Mat3&, const Mat3& Rb, G&& out) const {
    out.template topRows<3>() = Rb;
    out.template bottomRows<3>().setZero();
  }
};
// q = [x, y, θ]; G_i = [0 0 n; e1 e2 0] in inertial axes
struct Planar : VectorSpace<3> {
  static constexpr bool carries(int k, int m) { return k < 2 && m == 2; }  // x, y carry θ's axis
  Vec3 n, e1, e2;  // the plane's normal and the two directions of travel (plane_basis), joint frame
  template <class S>
  void motion(const S* q, Mat3T<S>& R, Vec3T<S>& p) const {
    R = Eigen::AngleAxis<S>(q[2], n.cast<S>()).toRotationMatrix();
    p = q[0] * e1.cast<S>() + q[1] * e2.cast<S>();
  }
  template <class G>
  void subspace(const Mat3& Rj, const Mat3&, G&& out) const {
    out.col(0) << Vec3::Zero(), Rj * e1;
    out.col(1) << Vec3::Zero(), Rj * e2;
    out.col(2) << Rj * n, Vec3::Zero();
  }
};
// q = [x y z, qw qx qy qz]; G_i = e
struct Free : RigidMotion {
  static constexpr bool carries(int k, int m) { return k >= 3 && m < 3; }  // η̇ carries the rotations' arm
  template <class S>
  void motion(const S* q, Mat3T<S>& R, Vec3T<S>& p) const {
    R = quaternion_rotation(q + 3);
    p = Vec3T<S>(q[0], q[1], q[2]);
  }
  template <class G>
  void subspace(const Mat3&, const Mat3&, G&& out) const {
    out.setIdentity();
  }
};

// whether G_i turns with the child (Ġ_i = ω_i × G_i) rather than with the parent
// (Ġ_i = ω_parent × G_i): the ball's alone (joint.hpp)
template <class J>
inline constexpr bool turns_with_child = std::is_same_v<J, Ball>;

}  // namespace joints

using JointModel =
    std::variant<joints::RevoluteAxis<0>, joints::RevoluteAxis<1>, joints::RevoluteAxis<2>,
                 joints::TurnedRevoluteAxis<0>, joints::TurnedRevoluteAxis<1>, joints::TurnedRevoluteAxis<2>,
                 joints::PrismaticAxis<0>, joints::PrismaticAxis<1>, joints::PrismaticAxis<2>, joints::Revolute,
                 joints::Prismatic, joints::Ball, joints::Planar, joints::Free, joints::Helical>;

// The kind of a moving joint (not Fixed: Model::build merges those away) along the unit axis
// `axis`, its joint frame turned by `placement_rotation` from its parent's.  Throws
// soadyn::Error for JointType::Fixed.
JointModel classify_joint(JointType type, const Vec3& axis, const Mat3& placement_rotation, double pitch = 0.0);

// f(kind) for the kind a JointType names along the unit `axis` (its joint frame unturned): how the
// per-JointType functions of joint.hpp answer.  A fixed joint has no kind and no q or v: f is not called.
template <class F>
void with_kind(JointType type, const Vec3& axis, double pitch, F&& f) {
  if (type == JointType::Fixed) return;
  std::visit(std::forward<F>(f), classify_joint(type, axis, Mat3::Identity(), pitch));
}

// whether the kind is a revolute joint along a unit axis, whose (cos θ, sin θ) the sweeps take
// in one batch (joint_turns, kinematics.hpp)
bool turns_by_angle(const JointModel& joint);

// the kind's name, for messages and tests ("revolute-axis-z", "turned-revolute-axis-x", …)
const char* kind_name(const JointModel& joint);

}  // namespace soadyn
