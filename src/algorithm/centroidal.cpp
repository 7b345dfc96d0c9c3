// Centre of mass and centroidal momentum (frames.hpp): the composite inertias K_j of the note's
// 𝓜 sweep, one tip-to-base pass, and each DOF's K_j G_k moved to the centre of mass.
#include "soadyn/algorithm/frames.hpp"
#include "soadyn/algorithm/kinematics.hpp"

namespace soadyn {

namespace {

double moving_mass(const Model& model) {
  double m = 0.0;
  for (int i = 0; i < model.nbodies; ++i) m += model.mass[i];
  return m;
}

// K_i = M_i + Σ_children D_cᵀ K_c D_c, about η_i (tip to base), as mass_matrix forms them
void composite_inertias(const Model& model, Data& data) {
  for (int i = 0; i < model.nbodies; ++i) data.work.composite.K[i] = data.inertia[i];
  for (int i = model.nbodies - 1; i >= 0; --i)
    if (model.parent[i] >= 0) data.work.composite.K[model.parent[i]].add_transformed(data.work.composite.K[i], data.d.col(i));
}

// J_c from each body's K_j = (m_j, h_j, ·), only its mass and first moment read:
// Σ_{i ≥ j} m_i (u + g × (r_i − η_j)) = m_j u − h_j × g for G_k = [g; u], f of K_j G_k, over m
void com_columns(const Model& model, const Data& data, MatX& J) {
  J.resize(3, model.nv);
  const double m = moving_mass(model);
  for (int i = 0; i < model.nbodies; ++i)
    for (int k = model.idx_v[i]; k < model.idx_v[i] + model.nv_i[i]; ++k)
      J.col(k) = (data.work.composite.K[i].m * data.G.col(k).tail<3>() - data.work.composite.K[i].h.cross(Vec3(data.G.col(k).head<3>()))) / m;
}

}  // namespace

Vec3 com(const Model& model, const Data& data) {
  Vec3 c = Vec3::Zero();
  for (int i = 0; i < model.nbodies; ++i) c += model.mass[i] * data.r.col(i);
  return c / moving_mass(model);
}

Vec3 com_velocity(const Model& model, const Data& data) {
  Vec3 cd = Vec3::Zero();
  for (int i = 0; i < model.nbodies; ++i) cd += model.mass[i] * data.Vbar.col(i).tail<3>();
  return cd / moving_mass(model);
}

void com_jacobian(const Model& model, Data& data, MatX& J) {
  composite_inertias(model, data);
  com_columns(model, data, J);
}

void com_jacobian(const Model& model, Data& data, const VecX& q, MatX& J) {
  update_frames(model, data, q);
  // tip to base, the subtree's mass m_j and first moment h_j about η_j alone (K_j without its
  // rotational inertia, which J_c does not need): h_i = m_i C_i com_i, then h_p += h_i + m_i d_i
  for (int i = 0; i < model.nbodies; ++i) {
    data.work.composite.K[i].m = model.mass[i];
    data.work.composite.K[i].h.noalias() = model.mass[i] * (data.R[i] * model.com[i]);
  }
  for (int i = model.nbodies - 1; i >= 0; --i) {
    const int p = model.parent[i];
    if (p < 0) continue;
    data.work.composite.K[p].m += data.work.composite.K[i].m;
    data.work.composite.K[p].h += data.work.composite.K[i].h + data.work.composite.K[i].m * data.d.col(i);
  }
  com_columns(model, data, J);
}

void centroidal_momentum_matrix(const Model& model, Data& data, MatX& AG) {
  composite_inertias(model, data);
  const Vec3 c = com(model, data);
  AG.resize(6, model.nv);
  for (int i = 0; i < model.nbodies; ++i) {
    const Vec3 arm = data.eta.col(i) - c;
    for (int k = model.idx_v[i]; k < model.idx_v[i] + model.nv_i[i]; ++k) {
      // K_i G_k = [n; f] about η_i, moved to c: [n + (η_i − c) × f; f]
      const Vec6 F = data.work.composite.K[i] * data.G.col(k);
      AG.col(k) << F.head<3>() + arm.cross(F.tail<3>()), F.tail<3>();
    }
  }
}

Vec6 centroidal_momentum(const Model& model, const Data& data) {
  const Vec3 c = com(model, data);
  Vec6 h = Vec6::Zero();
  for (int i = 0; i < model.nbodies; ++i) {
    // [I_i ω_i + (r_i − c) × m_i ṙ_i; m_i ṙ_i]
    const Vec3 p = model.mass[i] * data.Vbar.col(i).tail<3>();
    h.head<3>() += inertia_cm(data, i) * data.Vbar.col(i).head<3>() + (data.r.col(i) - c).cross(p);
    h.tail<3>() += p;
  }
  return h;
}

Vec6 centroidal_momentum_matrix_dot_times_v(const Model& model, Data& data) {
  const Vec3 c = com(model, data);
  Vec6 hd = Vec6::Zero();
  for (int i = 0; i < model.nbodies; ++i) {
    // a = Ψ_D 𝔞 at q̈ = 0 (a root's 𝔞 is gravity's −g, left out): a_i = D_i a_p + 𝔞_i
    const int p = model.parent[i];
    if (p < 0) {
      data.A.col(i).setZero();
    } else {
      const Vec3 wp = data.A.col(p).head<3>();
      data.A.col(i).head<3>() = wp + data.coriolis.col(i).head<3>();
      data.A.col(i).tail<3>() = data.A.col(p).tail<3>() + wp.cross(Vec3(data.d.col(i))) + data.coriolis.col(i).tail<3>();
    }
    // the body's rate of momentum, the force pair M_i a_i + 𝔟_i about η_i, moved to c
    const Vec6 F = data.inertia[i] * data.A.col(i) + data.gyroscopic.col(i);
    hd.head<3>() += F.head<3>() + (data.eta.col(i) - c).cross(F.tail<3>());
    hd.tail<3>() += F.tail<3>();
  }
  return hd;
}

SpatialInertia centroidal_inertia(const Model& model, Data& data) {
  composite_inertias(model, data);
  const Vec3 c = com(model, data);
  SpatialInertia KG;
  // each root's composite, moved from η_root to c (D with d = η_root − c)
  for (int i = 0; i < model.nbodies; ++i)
    if (model.parent[i] < 0) KG.add_transformed(data.work.composite.K[i], data.eta.col(i) - c);
  return KG;
}

}  // namespace soadyn
