#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/algorithm/operators.hpp"

#include "joint_inertial.hpp"
#include "mass_matrix_entries.hpp"

namespace soadyn {

void mass_matrix_literal(const Model& model, const Data& data, MatX& M_out) {
  data.require("mass_matrix_literal", false);
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
  data.require("mass_matrix", false);
  // K_i = M_i + Σ_children D_cᵀ K_c D_c   (tip to base); K_i is complete when the sweep reaches i.
  //
  // 𝓜_jk = G_jᵀ D_{i:j}ᵀ K_i G_k for DOF j on the chain of DOF k (body i), and the note's
  // D_{i:j} = D_i ⋯ = [e 0; −(η_i − η_j)~ e] telescopes: with every column moved once to the
  // inertial origin, F0_k = [n + η_i × f; f] for K_i G_k = [n; f] and S0_j = [a; b + η × a] for
  // G_j = [a; b], each entry is one dot product 𝓜_jk = S0_jᵀ F0_k.
  for (int i = 0; i < model.nbodies; ++i) data.work.composite.K[i] = data.inertia[i];
  for (int i = model.nbodies - 1; i >= 0; --i) {
    const SpatialInertia& K = data.work.composite.K[i];
    const Vec3 eta = data.eta.col(i);
    visit_joint(model, i, [&](const auto& j) {
      using J = std::decay_t<decltype(j)>;
      for (int k = model.idx_v[i]; k < model.idx_v[i] + J::nv; ++k) {
        const Vec3 a = data.G.col(k).head<3>(), b = data.G.col(k).tail<3>();
        Vec3 n, f;  // K_i G_k = [n; f]: [I a; a × h] for [a; 0], [h × b; m b] for [0; b]
        if constexpr (inertial::angular<J>) n.noalias() = K.I * a, f = a.cross(K.h);
        else if constexpr (inertial::linear<J>) n = K.h.cross(b), f = K.m * b;
        else n.noalias() = K.I * a + K.h.cross(b), f = K.m * b - K.h.cross(a);
        data.work.composite.F0.col(k) << n + eta.cross(f), f;
        data.work.composite.S0.col(k) << a, b + eta.cross(a);
      }
    });
    if (model.parent[i] >= 0) data.work.composite.K[model.parent[i]].add_transformed(K, data.d.col(i));
  }
  mass_matrix_entries(model, data);
}

void mass_matrix_entries(const Model& model, Data& data) {
  if (model.chain && model.nv >= 32) {
    // every DOF is an ancestor of the later ones: 𝓜_jk = F0_jᵀ S0_k on and below the diagonal,
    // column k's part one matrix–vector product F0ᵀ[k:, :] S0_k (six vectorized column updates),
    // then mirrored.  It fills no more than the triangle, where a matrix product would first zero
    // and fill the whole (6×N by 6×N, one run, CPU time: N = 64 1.58 against 2.04 µs for the
    // whole product and mirror, 100 3.9 against 6.0; N = 128 7.4 against 11.0 µs for two
    // products and no mirror, 256 38.5 against 40.4)
    const Eigen::Index n = model.nv;
    data.work.composite.F0t = data.work.composite.F0.transpose();
    for (Eigen::Index k = 0; k < n; ++k)
      data.M.col(k).tail(n - k).noalias() = data.work.composite.F0t.bottomRows(n - k) * data.work.composite.S0.col(k);
    data.M.triangularView<Eigen::StrictlyUpper>() = data.M.transpose();
  } else {
    double* M = data.M.data();
    const Eigen::Index n = data.M.rows();
    for (int k = 0; k < model.nv; ++k) {
      const Vec6 F0 = data.work.composite.F0.col(k);
      for (int j = k; j >= 0; j = model.dof_parent[j]) M[j + k * n] = M[k + j * n] = data.work.composite.S0.col(j).dot(F0);
    }
  }
}

}  // namespace soadyn
