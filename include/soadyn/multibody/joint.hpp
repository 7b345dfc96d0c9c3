// One joint interface: every joint type answers the same questions, so the sweeps never
// branch on joint type.  The joint-traits table (joint_traits) holds the per-type constants; the
// functions below hold the per-type formulas.
//
//   type       q                                   v (the note's q̇)               G_i (inertial)
//   revolute   angle about the axis               its rate            nq=nv=1     [g_i; 0]
//   prismatic  displacement along the axis        its rate            nq=nv=1     [0; g_i]
//   ball       unit quaternion [w x y z], child   ω of the child rel. nq=4 nv=3   [C_i; 0] (the child's
//              frame rel. to the joint frame      to the parent, in               axes in inertial)
//                                                 the child's frame
//   planar     [x, y, θ]: translation along e1,   their rates         nq=nv=3     [0 0 n; e1 e2 0]
//              e2 in the plane normal to the
//              axis n, then rotation θ about n
//   free       [x y z, qw qx qy qz]: position of  [ω; η̇], both        nq=7 nv=6   e (identity)
//              the body frame and its attitude    inertial (the
//              body → inertial                    note's Example 3)
//   helical    angle θ of a screw about the axis:  its rate         nq=nv=1     [g_i; h g_i]
//              turn θ about it, slide h θ along
//              it (pitch h, m/rad; h = 0 is revolute)
//   fixed      merged into its parent when a model is built            nq=nv=0
//
// Each function below answers for a JointType by the kind it names (joint_model.hpp, with_kind):
// the formulas live once, in the kinds and their configuration spaces (joint_space.hpp).
//
// The plane of a planar joint: e1 is the coordinate axis least aligned with n, made orthogonal to
// it, and e2 = n × e1 (n = z gives e1 = x, e2 = y).
//
// The derivative term.  Every G_i is fixed in the parent's frame, except the ball's, which turns
// with the child; in both cases the velocity-product term is Ġ_i q̇_i = ω_parent × (G_i q̇_i),
// because for the ball Ġ_i q̇_i = ω_i × ω_rel = (ω_parent + ω_rel) × ω_rel (update_velocities forms it).
#pragma once

#include "soadyn/multibody/types.hpp"

#include <string_view>
#include <vector>

namespace soadyn {

// the user's word for a joint (a scenario's `type:`, a URDF's or MJCF's joint type): Model::build
// classifies each into a kind (joint_model.hpp) once; Fixed stays last (pickles check against it)
enum class JointType { Revolute, Prismatic, Ball, Planar, Free, Helical, Fixed };

// What every algorithm needs to know about a joint type.
struct JointTraits {
  JointType type;
  std::string_view name;                    // as written in scenario files and logs
  int nq, nv;
  int quaternion;                           // offset of a unit quaternion [w x y z] in the joint's q, or -1
  bool has_axis;                            // revolute, prismatic, helical: the axis; planar: the plane's normal
  bool root_only;                           // free joints hang only from the world
  std::vector<std::string_view> q_labels;   // one suffix per q ("" for a 1-DOF joint)
  std::vector<std::string_view> v_labels;   // one suffix per v
  std::vector<std::string_view> q_units;    // SI unit of each q: "m", "rad", or "1" (quaternion parts)
  std::vector<std::string_view> v_units;    // of each v: "m/s" or "rad/s"
};

const JointTraits& joint_traits(JointType t);
const std::vector<JointTraits>& joint_traits_table();  // every type, in enum order

std::string_view to_string(JointType t);
inline int joint_nq(JointType t) { return joint_traits(t).nq; }
inline int joint_nv(JointType t) { return joint_traits(t).nv; }

// The joint's motion: body frame = joint frame · (R, p)(q).  q points at joint_nq(t) numbers;
// pitch: a helical joint's (m/rad)
void joint_motion(JointType t, const Vec3& axis, const double* q, Mat3& R, Vec3& p, double pitch = 0.0);

// R = Rj Rot_k(θ) for a revolute joint along e_k, given (c, s) = (cos θ, sin θ): the turn mixes
// the other two columns of Rj only (Rot_k takes e_a → c e_a + s e_b, e_b → −s e_a + c e_b, with
// a = k + 1, b = k + 2); R must not be Rj
inline void turn_frame(const Mat3& Rj, int k, double c, double s, Mat3& R) {
  const int a = (k + 1) % 3, b = (k + 2) % 3;
  R.col(k) = Rj.col(k);
  R.col(a) = c * Rj.col(a) + s * Rj.col(b);
  R.col(b) = c * Rj.col(b) - s * Rj.col(a);
}

// G_i in inertial coordinates, given the joint frame's orientation Rj (joint → inertial) and the
// body's, Rb = Rj · R(q).
void joint_subspace(JointType t, const Vec3& axis, const Mat3& Rj, const Mat3& Rb, Eigen::Ref<Mat6X> G,
                    double pitch = 0.0);

// q̇ of the joint from its q and v (differs from v only where q holds a quaternion).
void joint_qdot(JointType t, const double* q, const double* v, double* qdot);

// The reverse map, for initial conditions: v from q̇.  A quaternion's rate along itself, which
// would change its norm, is ignored.
void joint_velocity(JointType t, const double* q, const double* qdot, double* v);

// q ← q ⊕ h v: exact for revolute, prismatic, helical and planar; a quaternion is turned by exp(h ω) (about
// inertial axes for the free joint, body axes for the ball) and the free joint's position moves by h η̇.
void joint_integrate(JointType t, const double* q, const double* v, double h, double* q_out);

// Derivatives along the tangent space (derivatives.hpp).  A joint's configuration moves by the
// increment δ (nv numbers) as q ⊕ δ = joint_integrate(q, δ, 1): δ is in the frame its velocity is,
// so a perturbation δ moves the child like the velocity δ would, and the increment of a free
// joint's attitude is about inertial axes, of a ball's about the child's axes.
//
// Whether column k of G_i carries column m: ∂G_m/∂δ_k = G_k × G_m (true) or 0 (false), with ×
// the motion cross product.  Ball: every column carries every other (they turn with the child);
// planar: the translations carry the rotation's axis (it moves with the body's origin); free:
// the translations carry the rotations; 1-DOF joints: nothing (G × G = 0).
bool joint_carries(JointType t, int k, int m);

// dδ = T dq (T: nv×nq, column-major at T): the tangent increment a change dq of the coordinates
// makes.  The identity where q has no quaternion; for a quaternion Q, dθ = 2 vec(Q* ⊗ dQ) / |Q|²
// (ball) or 2 vec(dQ ⊗ Q*) / |Q|² (free): a change of Q along itself gives none, since
// joint_motion normalizes.
void joint_tangent_map(JointType t, const double* q, Eigen::Ref<MatX> T);

// ∂q̇/∂q (nq×nq) and ∂q̇/∂v (nq×nv) of joint_qdot.
void joint_qdot_jacobian(JointType t, const double* q, const double* v, Eigen::Ref<MatX> dq, Eigen::Ref<MatX> dv);

// the neutral configuration (zero coordinates, identity quaternion)
void joint_neutral(JointType t, double* q);

// q1 ⊖ q0: the v with joint_integrate(q0, v, 1) = q1 (a quaternion's shorter turn)
void joint_difference(JointType t, const double* q0, const double* q1, double* v);

// The unit vectors e1, e2 spanning the plane normal to n (planar joints; see above).
void plane_basis(const Vec3& n, Vec3& e1, Vec3& e2);

}  // namespace soadyn
