// One joint interface: every joint type answers the same questions, so the sweeps never
// branch on joint type.
//
//   revolute   q = angle about the axis (right-hand rule)          nq = nv = 1, G_i = [g_i; 0]
//   prismatic  q = displacement along the axis                     nq = nv = 1, G_i = [0; g_i]
//   free       q = [x, y, z, qw, qx, qy, qz] (position of the body
//              frame, unit quaternion body → inertial),
//              v = [ω; η̇] inertial, as in the note's Example 3   nq = 7, nv = 6, G_i = e_6
//   fixed      merged into its parent when a model is built        nq = nv = 0
#pragma once

#include "soadyn/types.hpp"

#include <string_view>

namespace soadyn {

enum class JointType { Revolute, Prismatic, Free, Fixed };

std::string_view to_string(JointType t);

int joint_nq(JointType t);
int joint_nv(JointType t);

// The joint's motion: body frame = joint frame · (R, p)(q).  q points at joint_nq(t) numbers.
void joint_motion(JointType t, const Vec3& axis, const double* q, Mat3& R, Vec3& p);

// G_i in inertial coordinates, given the joint frame's orientation Rj (joint → inertial).
void joint_subspace(JointType t, const Vec3& axis, const Mat3& Rj, Eigen::Ref<Mat6X> G);

// q̇ of the joint from its q and v (differs from v only for the free joint's quaternion).
void joint_qdot(JointType t, const double* q, const double* v, double* qdot);

// The reverse map, for initial conditions: v from q̇.  Free joint: ω = 2 quaṫ ⊗ quat* (the part
// of quaṫ along quat, which would change its norm, is ignored), η̇ = ṗ.
void joint_velocity(JointType t, const double* q, const double* qdot, double* v);

// q ← q ⊕ h v: exact for revolute/prismatic; for the free joint, position + h η̇ and the
// attitude rotated by exp(h ω) about inertial axes.
void joint_integrate(JointType t, const double* q, const double* v, double h, double* q_out);

// the neutral configuration (zero angle, identity quaternion)
void joint_neutral(JointType t, double* q);

}  // namespace soadyn
