// Inverse dynamics and the bias forces by the recursive Newton–Euler sweeps (algorithms.hpp),
// in the note's inertial operators.
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/algorithm/operators.hpp"

#include "joint_inertial.hpp"

namespace soadyn {

namespace {

// the note's A = Ψ_D (G q̈ + 𝔞), then F = Ψ_Dᵀ (M A + 𝔟), projected: τ = Gᵀ F.  Each Ψ is one
// sweep: base to tip A_i = D_i A_p + G_i q̈_i + 𝔞_i with F_i = M_i A_i + 𝔟_i formed at once; tip
// to base τ_i = G_iᵀ F_i as soon as F_i is complete, then F_p += D_iᵀ F_i.
// Every 6-vector here is read and written as its two 3-vector halves, never whole: a column
// written in halves and read back at once in 16-byte pieces straddles two stores, which the CPU
// cannot forward (each sweep reads what the step before it has just written).
void rnea(const Model& model, Data& data, const VecX* qdd, VecX& out) {
  const DOperator D{data.d};
  for (int i = 0; i < model.nbodies; ++i) {
    const int p = model.parent[i], iv = model.idx_v[i];
    Vec3 w = data.coriolis.col(i).head<3>(), u = data.coriolis.col(i).tail<3>();
    if (qdd) {  // + G_i q̈_i
      Vec3 gw, gu;
      visit_joint(model, i, [&](const auto& j) {
        inertial::motion<std::decay_t<decltype(j)>>(data.G, iv, qdd->data() + iv, gw, gu);
      });
      w += gw;
      u += gu;
    }
    if (p >= 0) {  // D_i A_p = [ω_p; u_p + ω_p × d_i]
      const Vec3 wp = data.A.col(p).head<3>();
      w += wp;
      u += data.A.col(p).tail<3>() + wp.cross(Vec3(data.d.col(i)));
    }
    data.A.col(i).head<3>() = w;
    data.A.col(i).tail<3>() = u;
    // F_i = M_i A_i + 𝔟_i with M_i [ω; u] = [I ω + h × u; m u − h × ω]
    const SpatialInertia& M = data.inertia[i];
    data.F.col(i).head<3>() = M.I * w + M.h.cross(u) + data.gyroscopic.col(i).head<3>();
    data.F.col(i).tail<3>() = M.m * u - M.h.cross(w) + data.gyroscopic.col(i).tail<3>();
  }
  for (int i = model.nbodies - 1; i >= 0; --i) {
    const int p = model.parent[i], iv = model.idx_v[i];
    const Vec3 n = data.F.col(i).head<3>(), f = data.F.col(i).tail<3>();
    visit_joint(model, i, [&](const auto& j) {
      inertial::project<std::decay_t<decltype(j)>>(data.G, iv, n, f, out.data() + iv);
    });
    if (p >= 0) D.add_apply_transpose(i, data.F.col(i), data.F.col(p));  // F_p += D_iᵀ F_i, in halves
  }
}

}  // namespace

void bias_forces(const Model& model, Data& data) {
  data.require("bias_forces", true);
  rnea(model, data, nullptr, data.bias);
}

void inverse_dynamics(const Model& model, Data& data, const VecX& qdd) {
  data.check(model, "inverse_dynamics", "qdd", qdd.size(), model.nv);
  data.require("inverse_dynamics", true);
  rnea(model, data, &qdd, data.tau);
}

const VecX& inverse_dynamics(const Model& model, Data& data, const VecX& q, const VecX& v, const VecX& qdd) {
  data.check(model, "inverse_dynamics", "v", v.size(), model.nv);  // every size before any work
  data.check(model, "inverse_dynamics", "qdd", qdd.size(), model.nv);
  update_kinematics(model, data, q);
  update_velocities(model, data, v);
  inverse_dynamics(model, data, qdd);
  return data.tau;
}

}  // namespace soadyn
