#include "soadyn/algorithms.hpp"
#include "soadyn/kinematics.hpp"
#include "soadyn/operators.hpp"

namespace soadyn {

void mass_matrix_literal(const Model& model, const Data& data, MatX& M_out) {
  const int n6 = 6 * model.nbodies;
  // 1. J(:,k) = Ψ_D G(:,k), one base-to-tip sweep per column   (Alg. for z = Ψ_A x)
  MatX J = MatX::Zero(n6, model.nv);
  for (int k = 0; k < model.nv; ++k) {
    J.block<6, 1>(6 * model.dof_body[k], k) = data.G.col(k);
    auto col = J.col(k);
    psi_base_to_tip(model.parent, DOperator{data.d}, [&](int i) { return col.segment<6>(6 * i); });
  }
  // 2. Q = M J, M = diag{M_i}
  MatX Q(n6, model.nv);
  for (int i = 0; i < model.nbodies; ++i) Q.middleRows<6>(6 * i) = M_matrix(data, i) * J.middleRows<6>(6 * i);
  // 3. 𝓜 = Jᵀ Q
  M_out.noalias() = J.transpose() * Q;
}

void mass_matrix(const Model& model, Data& data) {
  // K_i = M_i + Σ_children D_cᵀ K_c D_c   (tip to base)
  for (int i = 0; i < model.nbodies; ++i) data.K[i] = data.M[i];
  for (int i = model.nbodies - 1; i >= 0; --i)
    if (model.parent[i] >= 0) data.K[model.parent[i]].add_transformed(data.K[i], data.d.col(i));

  // 𝓜_ii = G_iᵀ K_i G_i;  for each ancestor j of i: 𝓜_ji = G_jᵀ (D_{i:j})ᵀ K_i G_i
  for (int i = 0; i < model.nbodies; ++i) {
    const int vi = model.idx_v[i], ni = model.nv_i[i];
    Mat6G F = data.K[i].apply(data.G.middleCols(vi, ni));
    data.Mass.block(vi, vi, ni, ni).noalias() = data.G.middleCols(vi, ni).transpose() * F;
    for (int r = 1; r < ni; ++r)  // a multi-DOF block is symmetric only to rounding: make it exact
      for (int c = 0; c < r; ++c) data.Mass(vi + c, vi + r) = data.Mass(vi + r, vi + c);
    for (int j = i; model.parent[j] >= 0; ) {
      // F ← D_jᵀ F: moment about η_parent(j) = moment about η_j + d_j × force
      for (int c = 0; c < ni; ++c) F.col(c).head<3>() += data.d.col(j).cross(Vec3(F.col(c).tail<3>()));
      j = model.parent[j];
      const int vj = model.idx_v[j], nj = model.nv_i[j];
      data.Mass.block(vj, vi, nj, ni).noalias() = data.G.middleCols(vj, nj).transpose() * F;
      data.Mass.block(vi, vj, ni, nj) = data.Mass.block(vj, vi, nj, ni).transpose();
    }
  }
}

}  // namespace soadyn
