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
//   Ball, Planar, Free        as joint.hpp describes them
//
// The unit-axis kinds are what URDFs mostly hold (axis "0 0 1", "1 0 0"): a turn by θ about e_k
// mixes two components by (cos θ, sin θ), with no 3×3 product, and k is a template argument so
// the step's indices are constants.  JointType (joint.hpp) stays the user's word for a joint;
// JointModel is what the algorithms run on.
#pragma once

#include "soadyn/multibody/joint.hpp"
#include "soadyn/multibody/types.hpp"

#include <cmath>
#include <variant>

namespace soadyn {

namespace joints {

// Each kind: nv; motion(q, R, p), the joint's motion (body frame = joint frame · (R, p)(q), as
// joint_motion); subspace(Rj, Rb, G), G_i in inertial axes into the 6×nv block G, given the joint
// frame's orientation Rj and the body's Rb = Rj R(q) (as joint_subspace); carries(k, m), whether
// column k of G_i carries column m, ∂G_m/∂δ_k = G_k × G_m (as joint_carries).

// the rotation of a unit quaternion stored [w x y z] (normalized here)
inline Mat3 quaternion_rotation(const double* q) {
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
}

template <int k>
struct RevoluteAxis {
  static constexpr int axis = k, nv = 1;
  static constexpr bool carries(int, int) { return false; }  // G × G = 0
  double sign = 1.0;  // the axis is sign · e_k
  void motion(const double* q, Mat3& R, Vec3& p) const {
    R.setIdentity();
    turn_frame(Mat3::Identity(), k, std::cos(q[0]), sign * std::sin(q[0]), R);
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
struct PrismaticAxis {
  static constexpr int axis = k, nv = 1;
  static constexpr bool carries(int, int) { return false; }  // G × G = 0
  double sign = 1.0;
  bool turned = false;  // the placement turns the frame
  void motion(const double* q, Mat3& R, Vec3& p) const {
    R.setIdentity();
    p = (sign * q[0]) * Vec3::Unit(k);
  }
  template <class G>
  void subspace(const Mat3& Rj, const Mat3&, G&& out) const {
    out.col(0) << Vec3::Zero(), sign * Rj.col(k);
  }
};
struct Revolute {
  static constexpr int nv = 1;
  static constexpr bool carries(int, int) { return false; }  // G × G = 0
  Vec3 axis;  // unit, joint frame
  void motion(const double* q, Mat3& R, Vec3& p) const {
    R = Eigen::AngleAxisd(q[0], axis).toRotationMatrix();
    p.setZero();
  }
  template <class G>
  void subspace(const Mat3& Rj, const Mat3&, G&& out) const {
    out.col(0) << Rj * axis, Vec3::Zero();
  }
};
struct Prismatic {
  static constexpr int nv = 1;
  static constexpr bool carries(int, int) { return false; }  // G × G = 0
  Vec3 axis;
  void motion(const double* q, Mat3& R, Vec3& p) const {
    R.setIdentity();
    p = q[0] * axis;
  }
  template <class G>
  void subspace(const Mat3& Rj, const Mat3&, G&& out) const {
    out.col(0) << Vec3::Zero(), Rj * axis;
  }
};
// q = [w x y z], the child's attitude in the joint frame; G_i = [C_i; 0]
struct Ball {
  static constexpr int nv = 3;
  static constexpr bool carries(int, int) { return true; }  // all three turn with the child
  void motion(const double* q, Mat3& R, Vec3& p) const {
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
struct Planar {
  static constexpr int nv = 3;
  static constexpr bool carries(int k, int m) { return k < 2 && m == 2; }  // x, y carry θ's axis
  Vec3 n, e1, e2;  // the plane's normal and the two directions of travel (plane_basis), joint frame
  void motion(const double* q, Mat3& R, Vec3& p) const {
    R = Eigen::AngleAxisd(q[2], n).toRotationMatrix();
    p = q[0] * e1 + q[1] * e2;
  }
  template <class G>
  void subspace(const Mat3& Rj, const Mat3&, G&& out) const {
    out.col(0) << Vec3::Zero(), Rj * e1;
    out.col(1) << Vec3::Zero(), Rj * e2;
    out.col(2) << Rj * n, Vec3::Zero();
  }
};
// q = [x y z, qw qx qy qz]; G_i = e
struct Free {
  static constexpr int nv = 6;
  static constexpr bool carries(int k, int m) { return k >= 3 && m < 3; }  // η̇ carries the rotations' arm
  void motion(const double* q, Mat3& R, Vec3& p) const {
    R = quaternion_rotation(q + 3);
    p = Vec3(q[0], q[1], q[2]);
  }
  template <class G>
  void subspace(const Mat3&, const Mat3&, G&& out) const {
    out.setIdentity();
  }
};

}  // namespace joints

using JointModel =
    std::variant<joints::RevoluteAxis<0>, joints::RevoluteAxis<1>, joints::RevoluteAxis<2>,
                 joints::TurnedRevoluteAxis<0>, joints::TurnedRevoluteAxis<1>, joints::TurnedRevoluteAxis<2>,
                 joints::PrismaticAxis<0>, joints::PrismaticAxis<1>, joints::PrismaticAxis<2>, joints::Revolute,
                 joints::Prismatic, joints::Ball, joints::Planar, joints::Free>;

// The kind of a moving joint (not Fixed: Model::build merges those away) along the unit axis
// `axis`, its joint frame turned by `placement_rotation` from its parent's.  Throws
// soadyn::Error for JointType::Fixed.
JointModel classify_joint(JointType type, const Vec3& axis, const Mat3& placement_rotation);

// whether the kind is a revolute joint along a unit axis, whose (cos θ, sin θ) the sweeps take
// in one batch (joint_turns, kinematics.hpp)
bool turns_by_angle(const JointModel& joint);

// the kind's name, for messages and tests ("revolute-axis-z", "turned-revolute-axis-x", …)
const char* kind_name(const JointModel& joint);

}  // namespace soadyn
