#include "soadyn/multibody/joint.hpp"

#include <cmath>

namespace soadyn {

const std::vector<JointTraits>& joint_traits_table() {
  static const std::vector<JointTraits> table = {
      {JointType::Revolute, "revolute", 1, 1, -1, true, false, {""}, {""}, {"rad"}, {"rad/s"}},
      {JointType::Prismatic, "prismatic", 1, 1, -1, true, false, {""}, {""}, {"m"}, {"m/s"}},
      {JointType::Ball, "ball", 4, 3, 0, false, false, {"qw", "qx", "qy", "qz"}, {"wx", "wy", "wz"}, {"1", "1", "1", "1"},
       {"rad/s", "rad/s", "rad/s"}},
      {JointType::Planar, "planar", 3, 3, -1, true, false, {"x", "y", "theta"}, {"x", "y", "theta"}, {"m", "m", "rad"},
       {"m/s", "m/s", "rad/s"}},
      {JointType::Free, "free", 7, 6, 3, false, true, {"x", "y", "z", "qw", "qx", "qy", "qz"},
       {"wx", "wy", "wz", "vx", "vy", "vz"}, {"m", "m", "m", "1", "1", "1", "1"},
       {"rad/s", "rad/s", "rad/s", "m/s", "m/s", "m/s"}},
      {JointType::Fixed, "fixed", 0, 0, -1, false, false, {}, {}, {}, {}},
  };
  return table;
}

const JointTraits& joint_traits(JointType t) { return joint_traits_table()[static_cast<int>(t)]; }

std::string_view to_string(JointType t) { return joint_traits(t).name; }

namespace {

// stored w, x, y, z; Eigen's constructor takes (w, x, y, z) too
Eigen::Quaterniond quat_at(const double* q) { return Eigen::Quaterniond(q[0], q[1], q[2], q[3]); }

void store(const Eigen::Quaterniond& u, double* q) {
  q[0] = u.w();
  q[1] = u.x();
  q[2] = u.y();
  q[3] = u.z();
}

// exp(h ω) as a unit quaternion
Eigen::Quaterniond rotation_by(const Vec3& w, double h) {
  const double wn = w.norm();
  return wn > 0 ? Eigen::Quaterniond(Eigen::AngleAxisd(h * wn, w / wn)) : Eigen::Quaterniond::Identity();
}

}  // namespace

void plane_basis(const Vec3& n, Vec3& e1, Vec3& e2) {
  Eigen::Index k = 0;
  n.cwiseAbs().minCoeff(&k);  // the coordinate axis least aligned with n
  e1 = Vec3::Unit(k) - n * n(k);
  e1.normalize();
  e2 = n.cross(e1);
}

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
    case JointType::Ball:
      R = quat_at(q).normalized().toRotationMatrix();
      p.setZero();
      return;
    case JointType::Planar: {
      Vec3 e1, e2;
      plane_basis(axis, e1, e2);
      R = Eigen::AngleAxisd(q[2], axis).toRotationMatrix();
      p = q[0] * e1 + q[1] * e2;
      return;
    }
    case JointType::Free:
      R = quat_at(q + 3).normalized().toRotationMatrix();
      p = Vec3(q[0], q[1], q[2]);
      return;
    case JointType::Fixed:
      R.setIdentity();
      p.setZero();
      return;
  }
}

void joint_subspace(JointType t, const Vec3& axis, const Mat3& Rj, const Mat3& Rb, Eigen::Ref<Mat6X> G) {
  G.setZero();
  switch (t) {
    case JointType::Revolute: G.col(0).head<3>() = Rj * axis; return;   // G_i = [g_i; 0]
    case JointType::Prismatic: G.col(0).tail<3>() = Rj * axis; return;  // G_i = [0; g_i]
    case JointType::Ball: G.topRows<3>() = Rb; return;                  // G_i = [C_i; 0]
    case JointType::Planar: {                                           // G_i = [0 0 n; e1 e2 0]
      Vec3 e1, e2;
      plane_basis(axis, e1, e2);
      G.col(0).tail<3>() = Rj * e1;
      G.col(1).tail<3>() = Rj * e2;
      G.col(2).head<3>() = Rj * axis;
      return;
    }
    case JointType::Free: G.setIdentity(); return;  // G_i = e
    case JointType::Fixed: return;
  }
}

void joint_qdot(JointType t, const double* q, const double* v, double* qdot) {
  switch (t) {
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
    case JointType::Ball: {
      // quaṫ = ½ quat ⊗ [0; ω]  (ω in the child's frame)
      const double w = q[0], x = q[1], y = q[2], z = q[3];
      const double a = v[0], b = v[1], c = v[2];
      qdot[0] = 0.5 * (-x * a - y * b - z * c);
      qdot[1] = 0.5 * (w * a + y * c - z * b);
      qdot[2] = 0.5 * (w * b + z * a - x * c);
      qdot[3] = 0.5 * (w * c + x * b - y * a);
      return;
    }
    case JointType::Revolute:
    case JointType::Prismatic:
    case JointType::Planar:
    case JointType::Fixed:
      for (int k = 0; k < joint_nv(t); ++k) qdot[k] = v[k];
      return;
  }
}

void joint_velocity(JointType t, const double* q, const double* qdot, double* v) {
  switch (t) {
    case JointType::Free: {
      // [0; ω] = 2 quaṫ ⊗ quat* / |quat|²
      const Eigen::Quaterniond quat = quat_at(q + 3);
      const Eigen::Quaterniond w = quat_at(qdot + 3) * quat.conjugate();
      const double n2 = quat.squaredNorm();
      v[0] = 2.0 * w.x() / n2;
      v[1] = 2.0 * w.y() / n2;
      v[2] = 2.0 * w.z() / n2;
      for (int k = 0; k < 3; ++k) v[3 + k] = qdot[k];
      return;
    }
    case JointType::Ball: {
      // [0; ω] = 2 quat* ⊗ quaṫ / |quat|²
      const Eigen::Quaterniond quat = quat_at(q);
      const Eigen::Quaterniond w = quat.conjugate() * quat_at(qdot);
      const double n2 = quat.squaredNorm();
      v[0] = 2.0 * w.x() / n2;
      v[1] = 2.0 * w.y() / n2;
      v[2] = 2.0 * w.z() / n2;
      return;
    }
    case JointType::Revolute:
    case JointType::Prismatic:
    case JointType::Planar:
    case JointType::Fixed:
      for (int k = 0; k < joint_nv(t); ++k) v[k] = qdot[k];
      return;
  }
}

void joint_integrate(JointType t, const double* q, const double* v, double h, double* q_out) {
  switch (t) {
    case JointType::Free: {
      // position + h η̇; attitude turned by exp(h ω) about inertial axes: quat⁺ = exp(h ω) ⊗ quat
      for (int k = 0; k < 3; ++k) q_out[k] = q[k] + h * v[3 + k];
      store((rotation_by(Vec3(v[0], v[1], v[2]), h) * quat_at(q + 3)).normalized(), q_out + 3);
      return;
    }
    case JointType::Ball:
      // about the child's axes: quat⁺ = quat ⊗ exp(h ω)
      store((quat_at(q) * rotation_by(Vec3(v[0], v[1], v[2]), h)).normalized(), q_out);
      return;
    case JointType::Revolute:
    case JointType::Prismatic:
    case JointType::Planar:
    case JointType::Fixed:
      for (int k = 0; k < joint_nq(t); ++k) q_out[k] = q[k] + h * v[k];
      return;
  }
}

void joint_neutral(JointType t, double* q) {
  const JointTraits& tr = joint_traits(t);
  for (int k = 0; k < tr.nq; ++k) q[k] = 0.0;
  if (tr.quaternion >= 0) q[tr.quaternion] = 1.0;
}

}  // namespace soadyn

namespace soadyn {

bool joint_carries(JointType t, int k, int m) {
  switch (t) {
    case JointType::Ball: return true;                   // all three turn with the child
    case JointType::Planar: return k < 2 && m == 2;      // x, y carry the axis of θ
    case JointType::Free: return k >= 3 && m < 3;        // η̇ carries the rotations' moment arm
    case JointType::Revolute:
    case JointType::Prismatic:
    case JointType::Fixed: return false;                 // G × G = 0
  }
  throw Error("joint_carries: unknown joint type " + std::to_string(static_cast<int>(t)));
}

void joint_tangent_map(JointType t, const double* q, Eigen::Ref<MatX> T) {
  T.setZero();
  // rows of 2 vec(Q* ⊗ dQ) (ball) or 2 vec(dQ ⊗ Q*) (free), divided by |Q|²
  auto quaternion = [](const double* Q, bool right, auto&& block) {
    const double w = Q[0], x = Q[1], y = Q[2], z = Q[3];
    const double s = 2.0 / (w * w + x * x + y * y + z * z);
    if (right)
      block << -x, w, -z, y, -y, z, w, -x, -z, -y, x, w;
    else
      block << -x, w, z, -y, -y, -z, w, x, -z, y, -x, w;
    block *= s;
  };
  switch (t) {
    case JointType::Ball: {
      auto b = T.block<3, 4>(0, 0);
      quaternion(q, false, b);
      return;
    }
    case JointType::Free: {
      auto b = T.block<3, 4>(0, 3);
      quaternion(q + 3, true, b);
      T.block<3, 3>(3, 0).setIdentity();
      return;
    }
    case JointType::Revolute:
    case JointType::Prismatic:
    case JointType::Planar:
    case JointType::Fixed: T.setIdentity(); return;
  }
}

void joint_qdot_jacobian(JointType t, const double* q, const double* v, Eigen::Ref<MatX> dq, Eigen::Ref<MatX> dv) {
  dq.setZero();
  dv.setZero();
  switch (t) {
    case JointType::Ball: {
      // quaṫ = ½ Q ⊗ [0; ω]: linear in Q and in ω
      const double w = q[0], x = q[1], y = q[2], z = q[3], a = v[0], b = v[1], c = v[2];
      dq.block<4, 4>(0, 0) << 0, -a, -b, -c, a, 0, c, -b, b, -c, 0, a, c, b, -a, 0;
      dv.block<4, 3>(0, 0) << -x, -y, -z, w, -z, y, z, w, -x, -y, x, w;
      break;
    }
    case JointType::Free: {
      // ṗ = η̇;  quaṫ = ½ [0; ω] ⊗ Q
      const double w = q[3], x = q[4], y = q[5], z = q[6], a = v[0], b = v[1], c = v[2];
      dq.block<4, 4>(3, 3) << 0, -a, -b, -c, a, 0, -c, b, b, c, 0, -a, c, -b, a, 0;
      dv.block<4, 3>(3, 0) << -x, -y, -z, w, z, -y, -z, w, x, y, -x, w;
      dq *= 0.5;
      dv *= 0.5;
      dv.block<3, 3>(0, 3).setIdentity();
      return;
    }
    case JointType::Revolute:
    case JointType::Prismatic:
    case JointType::Planar:
    case JointType::Fixed: dv.setIdentity(); return;
  }
  dq *= 0.5;
  dv *= 0.5;
}

}  // namespace soadyn
