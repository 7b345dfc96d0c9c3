// The constant tree: parents in parent-first order, joints, placements and mass properties.
//
// A Model is built once from a list of BodySpec and never changes while algorithms run; all
// per-state arrays live in Data (data.hpp).  Building it validates everything a user can get
// wrong and merges fixed joints into their parents, so a model carries only the DOFs its scene has.
#pragma once

#include "soadyn/multibody/joint.hpp"
#include "soadyn/multibody/joint_model.hpp"
#include "soadyn/multibody/types.hpp"

#include <limits>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace soadyn {

// A rigid transform: rotation R (child → parent) and translation p (in the parent frame).
struct Placement {
  Mat3 R = Mat3::Identity();
  Vec3 p = Vec3::Zero();
};

// A pose with position.{x, y, z} and rotation.{w, x, y, z} (urdfdom's urdf::Pose, which this
// header does not name) as a Placement, the quaternion normalized: the URDF import's and soadyn
// view's one conversion.
template <class Pose>
Placement placement_of_pose(const Pose& pose) {
  const auto& a = pose.position;
  const auto& r = pose.rotation;
  return {Eigen::Quaterniond(r.w, r.x, r.y, r.z).normalized().toRotationMatrix(), Vec3(a.x, a.y, a.z)};
}

// a then b: the frame b places in a's frame, placed in a's parent frame
inline Placement compose(const Placement& a, const Placement& b) { return {a.R * b.R, a.p + a.R * b.p}; }

// One body as a user describes it.
struct BodySpec {
  std::string name;
  std::string joint_name;               // defaults to the body's name
  int parent = -1;                      // index in the spec list; -1 = the ground
  JointType joint = JointType::Revolute;
  Vec3 axis = Vec3::UnitZ();            // joint axis in the joint frame (normalized on build)
  double pitch = 0.0;                   // a helical joint's slide per turn, m/rad (finite)
  Placement placement;                  // joint frame in the parent body frame (world for -1)
  double mass = 0.0;                    // must be > 0 (≥ 0 for a body merged by a fixed joint)
  Vec3 com = Vec3::Zero();              // centre of mass in the body frame
  Mat3 inertia = Mat3::Zero();          // about the centre of mass, body frame
  // a revolute or prismatic joint's travel (a URDF's <limit lower upper>, a scenario's limits:),
  // rad or m; ±inf: none.  Enforced only when a run asks (SimulationSettings::limits, limits.hpp)
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  // the joint's largest force or torque (a URDF's <limit effort>), N·m or N; inf: none given.  Used
  // only by a controller that asks for it (ControllerInput::at_effort, `max_torque: effort`)
  double effort = std::numeric_limits<double>::infinity();
};

// What Model::build does with an inertia whose largest principal moment exceeds the sum of the
// other two (the triangle inequality no rigid body breaks; CAD exports and rounded URDFs do):
//  Warn    (default) load it as given, with a warning, if the excess (l2 − l0 − l1)/(l0 + l1) is
//          at most kTriangleTolerance; refuse beyond it;
//  Balance raise the two smaller moments by half the excess each (same principal axes), warned;
//  Strict  refuse any excess beyond round-off.
// A refusal names every offending body, with its principal moments and excess.
enum class InertiaCheck { Warn, Balance, Strict };
inline constexpr double kTriangleTolerance = 0.05;

class Model {
 public:
  // Validates the specs and builds the model; throws soadyn::Error naming the body, the field,
  // what was expected and what was got.
  static Model build(const std::vector<BodySpec>& specs, const Vec3& gravity = Vec3::Zero(),
                     InertiaCheck inertia_check = InertiaCheck::Warn);

  int nbodies = 0;  // N, moving bodies after fixed joints are merged
  int nq = 0;       // configuration size
  int nv = 0;       // velocity size (rates of the note's q̇)

  std::vector<int> parent;                 // parent(i) < i, or -1 for the ground
  std::vector<JointType> joint_type;
  std::vector<Vec3> axis;                  // unit axis in the joint frame
  std::vector<double> pitch;               // a helical joint's pitch, m/rad (0 for the others)
  std::vector<Placement> placement;        // joint frame in the parent body frame
  std::vector<double> mass;
  std::vector<Vec3> com;                   // body frame
  std::vector<Mat3> inertia;               // about the cm, body frame
  std::vector<Mat3> inertia_origin;        // about the body frame's origin η_i, body frame
  std::vector<int> idx_q, idx_v;           // first q / v index of each body
  std::vector<int> nq_i, nv_i;             // sizes of each joint
  std::vector<std::string> body_names, joint_names;
  std::vector<std::vector<std::string>> merged_names;  // bodies welded into body i by fixed joints
  // named frames fixed on a body (frames.hpp): every body's own frame (identity placement), every
  // body merged away by a fixed joint (a URDF's tool flange, camera, foot sole; body −1 for those
  // welded to the world), in spec order, then those add_frame adds (a scenario's `frames:`)
  std::vector<std::string> frame_names;
  std::vector<int> frame_body;             // body the frame moves with, −1 = the world
  std::vector<Placement> frame_placement;  // the frame in that body's frame (the world's for −1)
  // each DOF's travel, rad or m (BodySpec::lower/upper; ±inf on joints without one and on free,
  // ball and planar joints)
  std::vector<double> lower, upper;
  std::vector<double> effort;              // each DOF's largest |τ| (BodySpec::effort; inf: none)
  bool has_limits() const;                 // a finite lower or upper somewhere
  std::vector<int> dof_parent;             // λ(k): parent DOF of DOF k, -1 at a root (for LᵀDL)
  std::vector<int> dof_body;               // body owning DOF k
  std::vector<int> dof_run;                // lowest m ≤ k with λ(x) = x − 1 for m < x ≤ k: the
                                           // ancestors m..k of k are consecutive (LᵀDL's inner loop)
  // the DOFs in depth-first (preorder) order, so that every subtree's DOFs are one contiguous
  // run (the local-frame 𝓜 sweep, mass_matrix_local.cpp): DOF dfs_dof[x] sits at position x, and
  // the DOFs of body i's subtree at positions dfs_begin[i] .. dfs_end[i] − 1, its own first
  std::vector<int> dfs_dof, dfs_begin, dfs_end;
  // the tree cut into paths: a body continues its parent's path when it is the parent's last child
  // (highest index), else starts one.  The O(N²) sweeps that keep an nv-long block per body
  // (minverse, forward_dynamics_derivatives) keep one per path instead, updated in place along it:
  // one on a chain, one per leaf on a tree
  std::vector<int> path;
  int npaths = 0;
  int depth = 0;                           // longest chain from the ground (nilpotency of Φ_D)
  bool chain = false;                      // every DOF's parent DOF is the one before it
  // each body's joint kind (joint_model.hpp): what every sweep dispatches on, once per body
  std::vector<JointModel> joint_model;
  // the angles whose (cos θ, sin θ) the sweeps take in one batch (joint_turns, kinematics.hpp):
  // the bodies whose kind turns_by_angle and their q indices, the `roots` hanging from the ground first
  struct AngleBatch {
    std::vector<int> body, q;
    int roots = 0;
  } angles;
  // joint_model and angles from joint_type, axis, pitch and placement (build calls it; so must whoever
  // changes those fields of a built model, as unpickling does)
  void classify_joints();
  std::vector<std::string> warnings;       // what build accepted but a user should hear (one line each)

  double world_mass = 0.0;                 // bodies welded to the world: mass and first moment,
  Vec3 world_first_moment = Vec3::Zero();  // kept for the potential energy only
  Vec3 gravity = Vec3::Zero();             // uniform gravity, m/s²

  // one name per column of q and of v: the joint's name for a 1-DOF joint, else
  // "joint.suffix" with the suffixes of joint_traits ("bus.x", …, "bus.qw", …; "bus.wx", …)
  std::vector<std::string> q_names() const;
  std::vector<std::string> v_names() const;

  int body_index(const std::string& name) const;   // -1 when absent
  int joint_index(const std::string& name) const;  // body index of the named joint, -1 when absent
  int frame_index(const std::string& name) const;  // -1 when absent
  // A frame placed by X on body `body` (−1: the world); returns its index.  Throws soadyn::Error
  // for a name already taken, an empty or non-UTF-8 name, a body out of range or a placement that
  // is not a finite proper rotation and translation.
  int add_frame(const std::string& name, int body, const Placement& X);
  bool has_free_joint() const;
  bool has_quaternions() const;              // a joint whose q holds a quaternion (free, ball)
  VecX neutral_configuration() const;
  void normalize(Eigen::Ref<VecX> q) const;  // unit quaternions of free and ball joints
  // A state given from outside (Python, C++ callers): each free or ball joint's quaternion within
  // kUnitQuaternionTolerance of unit norm (normalize() then makes it exact), as a scenario's
  // initial: q and --q require; otherwise (a zero, NaN or far-off quaternion) soadyn::Error
  // "where: joint 'j': expected a unit quaternion [w, x, y, z] …, got norm …"
  static constexpr double kUnitQuaternionTolerance = 1e-6;
  void check_unit_quaternions(const VecX& q, const std::string& where) const;
  // q̇ from (q, v), and q ⊕ h v, joint by joint by each kind (configuration.hpp has the rest)
  void qdot(const VecX& q, const VecX& v, Eigen::Ref<VecX> qd) const;
  VecX velocity(const VecX& q, const VecX& qd) const;  // the reverse map: v from q̇
  VecX integrate(const VecX& q, const VecX& v, double h) const;
};

// f(joint) with body i's joint kind (one of JointModel's types): the one dispatch per body each
// sweep makes, so the step for that kind runs with its constants known at compile time.  A switch
// on the kind's index rather than std::visit: every case is a direct call the compiler inlines
// into the sweep (std::visit's table of function pointers costs an indirect call per body, about
// a quarter of a chain's bias).  A kind added to JointModel fails the static_assert until it has
// its case here.
template <class F>
inline void visit_joint(const Model& model, int i, F&& f) {
  const JointModel& j = model.joint_model[i];
  static_assert(std::variant_size_v<JointModel> == 15, "one case per joint kind");
  switch (j.index()) {
    case 0: return f(*std::get_if<0>(&j));
    case 1: return f(*std::get_if<1>(&j));
    case 2: return f(*std::get_if<2>(&j));
    case 3: return f(*std::get_if<3>(&j));
    case 4: return f(*std::get_if<4>(&j));
    case 5: return f(*std::get_if<5>(&j));
    case 6: return f(*std::get_if<6>(&j));
    case 7: return f(*std::get_if<7>(&j));
    case 8: return f(*std::get_if<8>(&j));
    case 9: return f(*std::get_if<9>(&j));
    case 10: return f(*std::get_if<10>(&j));
    case 11: return f(*std::get_if<11>(&j));
    case 12: return f(*std::get_if<12>(&j));
    case 13: return f(*std::get_if<13>(&j));
    case 14: return f(*std::get_if<14>(&j));
  }
  throw Error("visit_joint: body " + std::to_string(i) + " has no joint kind");  // valueless: never built so
}

}  // namespace soadyn
