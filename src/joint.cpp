#include "soadyn/joint.hpp"

#include <cmath>

namespace soadyn {

std::string_view to_string(JointType t) {
  switch (t) {
    case JointType::Revolute: return "revolute";
    case JointType::Prismatic: return "prismatic";
    case JointType::Free: return "free";
    case JointType::Fixed: return "fixed";
  }
  return "?";
}

int joint_nq(JointType t) {
  switch (t) {
    case JointType::Revolute:
    case JointType::Prismatic: return 1;
    case JointType::Free: return 7;
    case JointType::Fixed: return 0;
  }
  return 0;
}

int joint_nv(JointType t) {
  switch (t) {
    case JointType::Revolute:
    case JointType::Prismatic: return 1;
    case JointType::Free: return 6;
    case JointType::Fixed: return 0;
  }
  return 0;
}

namespace {
Eigen::Quaterniond free_quat(const double* q) {
  // stored w, x, y, z; Eigen's constructor takes (w, x, y, z) too
  return Eigen::Quaterniond(q[3], q[4], q[5], q[6]);
}
}  // namespace

void joint_motion(JointType t, const Vec3& axis, const double* q, Mat3& R, Vec3& p) {
  switch (t) {
    case JointType::Revolute:
      R = Eigen::AngleAxisd(q[0], axis).toRotationMatrix();
      p.setZero();
      return;
    case JointType::Prismatic:
      R.setIdentity();
      p = q[0] * axis;
      return;
    case JointType::Free:
      R = free_quat(q).normalized().toRotationMatrix();
      p = Vec3(q[0], q[1], q[2]);
      return;
    case JointType::Fixed:
      R.setIdentity();
      p.setZero();
      return;
  }
}

void joint_subspace(JointType t, const Vec3& axis, const Mat3& Rj, Eigen::Ref<Mat6X> G) {
  G.setZero();
  switch (t) {
    case JointType::Revolute: G.col(0).head<3>() = Rj * axis; return;   // G_i = [g_i; 0]
    case JointType::Prismatic: G.col(0).tail<3>() = Rj * axis; return;  // G_i = [0; g_i]
    case JointType::Free: G.setIdentity(); return;                      // G_i = e
    case JointType::Fixed: return;
  }
}

void joint_qdot(JointType t, const double* q, const double* v, double* qdot) {
  switch (t) {
    case JointType::Revolute:
    case JointType::Prismatic: qdot[0] = v[0]; return;
    case JointType::Free: {
      // ṗ = η̇;  quaternion: ½ [0; ω] ⊗ quat  (ω inertial)
      const double w = q[3], x = q[4], y = q[5], z = q[6];
      const double ox = v[0], oy = v[1], oz = v[2];
      qdot[0] = v[3];
      qdot[1] = v[4];
      qdot[2] = v[5];
      qdot[3] = 0.5 * (-ox * x - oy * y - oz * z);
      qdot[4] = 0.5 * (ox * w + oy * z - oz * y);
      qdot[5] = 0.5 * (-ox * z + oy * w + oz * x);
      qdot[6] = 0.5 * (ox * y - oy * x + oz * w);
      return;
    }
    case JointType::Fixed: return;
  }
}

void joint_velocity(JointType t, const double* q, const double* qdot, double* v) {
  switch (t) {
    case JointType::Revolute:
    case JointType::Prismatic: v[0] = qdot[0]; return;
    case JointType::Free: {
      // [0; ω] = 2 quaṫ ⊗ quat* / |quat|²
      const Eigen::Quaterniond quat = free_quat(q);
      const Eigen::Quaterniond rate(qdot[3], qdot[4], qdot[5], qdot[6]);
      const Eigen::Quaterniond w = rate * quat.conjugate();
      const double n2 = quat.squaredNorm();
      v[0] = 2.0 * w.x() / n2;
      v[1] = 2.0 * w.y() / n2;
      v[2] = 2.0 * w.z() / n2;
      for (int k = 0; k < 3; ++k) v[3 + k] = qdot[k];
      return;
    }
    case JointType::Fixed: return;
  }
}

void joint_integrate(JointType t, const double* q, const double* v, double h, double* q_out) {
  switch (t) {
    case JointType::Revolute:
    case JointType::Prismatic: q_out[0] = q[0] + h * v[0]; return;
    case JointType::Free: {
      const Vec3 w(v[0], v[1], v[2]);
      const double wn = w.norm();
      const Eigen::Quaterniond dq = wn > 0 ? Eigen::Quaterniond(Eigen::AngleAxisd(h * wn, w / wn))
                                           : Eigen::Quaterniond::Identity();
      const Eigen::Quaterniond qn = (dq * free_quat(q)).normalized();
      for (int k = 0; k < 3; ++k) q_out[k] = q[k] + h * v[3 + k];
      q_out[3] = qn.w();
      q_out[4] = qn.x();
      q_out[5] = qn.y();
      q_out[6] = qn.z();
      return;
    }
    case JointType::Fixed: return;
  }
}

void joint_neutral(JointType t, double* q) {
  for (int k = 0; k < joint_nq(t); ++k) q[k] = 0.0;
  if (t == JointType::Free) q[3] = 1.0;
}

}  // namespace soadyn
