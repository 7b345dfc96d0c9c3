// The joint interface per JointType, answered by the kind each type names (with_kind): the
// formulas are the kinds' (joint_model.hpp) and their configuration spaces' (joint_space.hpp).
#include "soadyn/multibody/joint.hpp"

#include "soadyn/multibody/joint_model.hpp"

namespace soadyn {

namespace {

// a row of the table, its sizes and quaternion offset taken from the kind the type names
JointTraits traits(JointType t, std::string_view name, bool has_axis, bool root_only, std::vector<std::string_view> ql,
                   std::vector<std::string_view> vl, std::vector<std::string_view> qu, std::vector<std::string_view> vu) {
  JointTraits tr{t, name, 0, 0, -1, has_axis, root_only, std::move(ql), std::move(vl), std::move(qu), std::move(vu)};
  with_kind(t, Vec3::UnitZ(), 0.0, [&](const auto& j) {
    using J = std::decay_t<decltype(j)>;
    tr.nq = J::nq, tr.nv = J::nv, tr.quaternion = J::quaternion;
  });
  return tr;
}

}  // namespace

const std::vector<JointTraits>& joint_traits_table() {
  static const std::vector<JointTraits> table = {
      traits(JointType::Revolute, "revolute", true, false, {""}, {""}, {"rad"}, {"rad/s"}),
      traits(JointType::Prismatic, "prismatic", true, false, {""}, {""}, {"m"}, {"m/s"}),
      traits(JointType::Ball, "ball", false, false, {"qw", "qx", "qy", "qz"}, {"wx", "wy", "wz"}, {"1", "1", "1", "1"},
             {"rad/s", "rad/s", "rad/s"}),
      traits(JointType::Planar, "planar", true, false, {"x", "y", "theta"}, {"x", "y", "theta"}, {"m", "m", "rad"},
             {"m/s", "m/s", "rad/s"}),
      traits(JointType::Free, "free", false, true, {"x", "y", "z", "qw", "qx", "qy", "qz"},
             {"wx", "wy", "wz", "vx", "vy", "vz"}, {"m", "m", "m", "1", "1", "1", "1"},
             {"rad/s", "rad/s", "rad/s", "m/s", "m/s", "m/s"}),
      traits(JointType::Helical, "helical", true, false, {""}, {""}, {"rad"}, {"rad/s"}),
      traits(JointType::Fixed, "fixed", false, false, {}, {}, {}, {}),
  };
  return table;
}

const JointTraits& joint_traits(JointType t) { return joint_traits_table()[static_cast<int>(t)]; }

std::string_view to_string(JointType t) { return joint_traits(t).name; }

void plane_basis(const Vec3& n, Vec3& e1, Vec3& e2) {
  Eigen::Index k = 0;
  n.cwiseAbs().minCoeff(&k);  // the coordinate axis least aligned with n
  e1 = Vec3::Unit(k) - n * n(k);
  e1.normalize();
  e2 = n.cross(e1);
}

// body frame = joint frame · (R, p)(q)  (a fixed joint: the identity)
void joint_motion(JointType t, const Vec3& axis, const double* q, Mat3& R, Vec3& p, double pitch) {
  R.setIdentity(), p.setZero();
  with_kind(t, axis, pitch, [&](const auto& j) { j.motion(q, R, p); });
}

void joint_subspace(JointType t, const Vec3& axis, const Mat3& Rj, const Mat3& Rb, Eigen::Ref<Mat6X> G, double pitch) {
  G.setZero();
  with_kind(t, axis, pitch, [&](const auto& j) { j.subspace(Rj, Rb, G); });
}

// q̇ = T̄(q) v
void joint_qdot(JointType t, const double* q, const double* v, double* qdot) {
  with_kind(t, Vec3::UnitZ(), 0.0, [&](const auto& j) { j.qdot(q, v, qdot); });
}

void joint_velocity(JointType t, const double* q, const double* qdot, double* v) {
  with_kind(t, Vec3::UnitZ(), 0.0, [&](const auto& j) { j.velocity(q, qdot, v); });
}

// q_out = q ⊕ h v
void joint_integrate(JointType t, const double* q, const double* v, double h, double* q_out) {
  with_kind(t, Vec3::UnitZ(), 0.0, [&](const auto& j) { j.integrate(q, v, h, q_out); });
}

// v = q1 ⊖ q0
void joint_difference(JointType t, const double* q0, const double* q1, double* v) {
  with_kind(t, Vec3::UnitZ(), 0.0, [&](const auto& j) { j.difference(q0, q1, v); });
}

void joint_neutral(JointType t, double* q) {
  with_kind(t, Vec3::UnitZ(), 0.0, [&](const auto& j) { j.neutral(q); });
}

// ∂G_m/∂δ_k = G_k × G_m, or 0
bool joint_carries(JointType t, int k, int m) {
  bool carries = false;
  with_kind(t, Vec3::UnitZ(), 0.0, [&](const auto& j) { carries = j.carries(k, m); });
  return carries;
}

// dδ = T dq
void joint_tangent_map(JointType t, const double* q, Eigen::Ref<MatX> T) {
  T.setZero();
  with_kind(t, Vec3::UnitZ(), 0.0, [&](const auto& j) { T = j.tangent(q); });
}

// ∂q̇/∂q, ∂q̇/∂v
void joint_qdot_jacobian(JointType t, const double* q, const double* v, Eigen::Ref<MatX> dq, Eigen::Ref<MatX> dv) {
  dq.setZero(), dv.setZero();
  with_kind(t, Vec3::UnitZ(), 0.0, [&](const auto& j) {
    using J = std::decay_t<decltype(j)>;
    Eigen::Matrix<double, J::nq, J::nq> a;
    Eigen::Matrix<double, J::nq, J::nv> b;
    j.qdot_jacobian(q, v, a, b);
    dq = a, dv = b;
  });
}

}  // namespace soadyn
