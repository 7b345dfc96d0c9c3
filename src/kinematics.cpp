#include "soadyn/kinematics.hpp"

#include "soadyn/operators.hpp"

namespace soadyn {

void update_kinematics(const Model& model, Data& data, const VecX& q) {
  data.check(model, "update_kinematics", "q", q.size(), model.nq);
  for (int i = 0; i < model.nbodies; ++i) {
    const int p = model.parent[i];
    const Mat3 Rp = p < 0 ? Mat3::Identity() : data.R[p];
    const Vec3 eta_p = p < 0 ? Vec3::Zero() : Vec3(data.eta.col(p));
    // body frame = parent frame · placement · joint motion(q)
    const Mat3 Rj = Rp * model.placement[i].R;
    Mat3 Rm;
    Vec3 pm;
    joint_motion(model.joint_type[i], model.axis[i], q.data() + model.idx_q[i], Rm, pm);
    data.R[i].noalias() = Rj * Rm;
    data.eta.col(i) = eta_p + Rp * model.placement[i].p + Rj * pm;
    // d_i = η_i − η_p;  s_i = C_i com_i;  r_i = η_i + s_i
    data.d.col(i) = data.eta.col(i) - eta_p;
    data.s.col(i) = data.R[i] * model.com[i];
    data.r.col(i) = data.eta.col(i) + data.s.col(i);
    joint_subspace(model.joint_type[i], model.axis[i], Rj, data.R[i], data.G.middleCols(model.idx_v[i], model.nv_i[i]));
    // M_i = [I_i − m s̃ s̃, m s̃; −m s̃, m e] (eq. 12); its upper-left block, the inertia about η_i,
    // is the body-frame one turned: C_i I_η C_iᵀ
    data.M[i].m = model.mass[i];
    data.M[i].h = model.mass[i] * data.s.col(i);
    data.M[i].I.noalias() = data.R[i] * model.inertia_origin[i] * data.R[i].transpose();
  }
}

void update_velocities(const Model& model, Data& data, const VecX& v) {
  data.check(model, "update_velocities", "v", v.size(), model.nv);
  // (3)-(4) v = Φ_D v + G q̇  ⇒  v = Ψ_D G q̇
  for (int i = 0; i < model.nbodies; ++i)
    data.V.col(i).noalias() = data.G.middleCols(model.idx_v[i], model.nv_i[i]) *
                              v.segment(model.idx_v[i], model.nv_i[i]);
  data.coriolis = data.V;  // keep G_i q̇_i for the velocity-product terms below
  psi_base_to_tip(model.parent, DOperator{data.d}, [&](int i) { return data.V.col(i); });

  for (int i = 0; i < model.nbodies; ++i) {
    const int p = model.parent[i];
    const Vec3 w = data.V.col(i).head<3>();
    const Vec3 s = data.s.col(i);
    // (5) v̄_i = S_i v_i: ṙ_i = η̇_i + ω_i × s_i
    data.Vbar.col(i) << w, data.V.col(i).tail<3>() + w.cross(s);
    // 𝔞_i = Ḋ_i v_p + Ġ_i q̇_i with Ḋ_i v_p = [0; ω_p × ḋ_i], ḋ_i = η̇_i − η̇_p, and
    //   Ġ_i q̇_i = ω_p × (G_i q̇_i) (joint.hpp); gravity enters as a base acceleration −g
    if (p < 0) {
      data.coriolis.col(i) << Vec3::Zero(), -model.gravity;
    } else {
      const Vec3 wp = data.V.col(p).head<3>();
      const Vec3 ddot = data.V.col(i).tail<3>() - data.V.col(p).tail<3>();
      const Vec6 Gv = data.coriolis.col(i);
      data.coriolis.col(i) = joint_velocity_product(wp, Gv);
      data.coriolis.col(i).tail<3>() += wp.cross(ddot);
    }
    // gyroscopic force about η_i: f = m ω × (ω × s), n = ω × I ω + s × f = ω × (I − m s̃ s̃) ω
    const Vec3& h = data.M[i].h;
    data.gyroscopic.col(i) << w.cross(data.M[i].I * w), w.cross(w.cross(h));
  }
}

Mat6 D_matrix(const Data& data, int i) {
  Mat6 D = Mat6::Identity();
  D.bottomLeftCorner<3, 3>() = -skew(data.d.col(i));
  return D;
}

Mat6 S_matrix(const Data& data, int i) {
  Mat6 S = Mat6::Identity();
  S.bottomLeftCorner<3, 3>() = -skew(data.s.col(i));
  return S;
}

Mat6 M_matrix(const Data& data, int i) { return data.M[i].matrix(); }

Mat3 inertia_cm(const Data& data, int i) {
  const Vec3 s = data.s.col(i);
  return data.M[i].I - parallel_axis(data.M[i].m, s);
}

Mat6G G_matrix(const Model& model, const Data& data, int i) {
  return data.G.middleCols(model.idx_v[i], model.nv_i[i]);
}

void jacobian(const Model& model, const Data& data, MatX& J) {
  // (7) J = S Ψ_D G: all columns at once, one base-to-tip sweep over 6×nv blocks
  J.setZero(6 * model.nbodies, model.nv);
  for (int i = 0; i < model.nbodies; ++i)
    J.block(6 * i, model.idx_v[i], 6, model.nv_i[i]) = G_matrix(model, data, i);
  psi_base_to_tip(model.parent, DOperator{data.d}, [&](int i) { return J.middleRows<6>(6 * i); });
  for (int i = 0; i < model.nbodies; ++i) {
    auto Ji = J.middleRows<6>(6 * i);
    Ji.bottomRows<3>() -= skew(data.s.col(i)) * Ji.topRows<3>();  // S_i = [e 0; −s̃_i e]
  }
}

Eigen::Vector4d attitude_quaternion(const Mat3& R) {
  Eigen::Quaterniond u(R);
  if (u.w() < 0) u.coeffs() = -u.coeffs();
  return {u.w(), u.x(), u.y(), u.z()};
}

}  // namespace soadyn
