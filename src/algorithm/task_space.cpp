// Operational-space inertia and the Coriolis matrix (frames.hpp).
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/frames.hpp"
#include "soadyn/algorithm/kinematics.hpp"

#include <Eigen/Eigenvalues>

#include <cstdio>

namespace soadyn {

void operational_space_inertia(const Model& model, Data& data, const MatX& J, MatX& Lambda) {
  if (J.cols() != model.nv || J.rows() < 1 || J.rows() > 6 * model.nbodies + 6)
    throw Error("operational_space_inertia: J: expected k×" + std::to_string(model.nv) + " (k >= 1), got " +
                std::to_string(J.rows()) + "×" + std::to_string(J.cols()));
  // 𝓜 = L Lᵀ; Y = L⁻¹ Jᵀ; J 𝓜⁻¹ Jᵀ = Yᵀ Y.  𝓜 is formed in data.M, then data.M gets back what
  // mass_matrix left there (each result its own function's: data.hpp)
  const MatX kept = data.M;
  mass_matrix(model, data);
  data.work.factor.llt.compute(data.M);
  data.M = kept;
  if (data.work.factor.llt.info() != Eigen::Success) throw Error("operational_space_inertia: the mass matrix is not positive definite");
  MatX Y = J.transpose();
  data.work.factor.llt.matrixL().solveInPlace(Y);
  const MatX W = Y.transpose() * Y;
  // Λ = W⁻¹ from W's eigenvalues, refused when one is (relatively) zero
  const Eigen::SelfAdjointEigenSolver<MatX> es(W);
  const VecX l = es.eigenvalues();  // ascending
  const double largest = l(l.size() - 1);
  if (!(l(0) > 1e-10 * largest)) {
    int rank = 0;
    for (Eigen::Index k = 0; k < l.size(); ++k) rank += l(k) > 1e-10 * largest;
    char msg[400];
    std::snprintf(msg, sizeof msg,
                  "operational_space_inertia: J M^-1 J^T is singular: rank %d of %d (smallest eigenvalue %.3g, largest "
                  "%.3g): the task asks for more independent motions than the joints give at this configuration; use "
                  "fewer rows (e.g. the 3 linear ones) or move away from the singular pose",
                  rank, int(l.size()), l(0), largest);
    throw Error(msg);
  }
  Lambda = es.eigenvectors() * l.cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
}

namespace {

// Ġ_k = Ω × G_k on both halves: G_j is fixed in the parent's frame (Ω = ω_parent), except where
// it turns with the child (Ω = ω_j: the ball's; joint.hpp)
bool subspace_turns_with_child(const Model& model, int j) {
  bool turns = false;
  visit_joint(model, j, [&](const auto& joint) { turns = joints::turns_with_child<std::decay_t<decltype(joint)>>; });
  return turns;
}

}  // namespace

void coriolis_matrix(const Model& model, const Data& data, MatX& C) {
  C.setZero(model.nv, model.nv);
  MatX Ji(6, model.nv), Jd(6, model.nv), T(6, model.nv);
  for (int i = 0; i < model.nbodies; ++i) {
    // J_i, J̇_i: body i's cm rows of J = S Ψ_D G, column k of DOF k on body j ≤ i
    //   c = [g; u + g × (r_i − η_j)],  ċ = [ġ; u̇ + ġ × (r_i − η_j) + g × (ṙ_i − η̇_j)],  ġ = Ω × g, u̇ = Ω × u
    Ji.setZero(), Jd.setZero();
    const Vec3 r = data.r.col(i), rd = data.Vbar.col(i).tail<3>();
    for (int j = i; j >= 0; j = model.parent[j]) {
      const int p = model.parent[j];
      const Vec3 W = subspace_turns_with_child(model, j) ? Vec3(data.V.col(j).head<3>())
                     : p >= 0                                          ? Vec3(data.V.col(p).head<3>())
                                                                       : Vec3::Zero();
      const Vec3 arm = r - data.eta.col(j), arm_d = rd - data.V.col(j).tail<3>();
      for (int k = model.idx_v[j]; k < model.idx_v[j] + model.nv_i[j]; ++k) {
        const Vec3 g = data.G.col(k).head<3>(), u = data.G.col(k).tail<3>();
        const Vec3 gd = W.cross(g);
        Ji.col(k) << g, u + g.cross(arm);
        Jd.col(k) << gd, W.cross(u) + gd.cross(arm) + g.cross(arm_d);
      }
    }
    // C += J_iᵀ (M̄_i J̇_i + [ω̃_i I_i 0; 0 0] J_i)
    const Mat3 I = inertia_cm(data, i);
    const Vec3 w = data.V.col(i).head<3>();
    T.topRows<3>().noalias() = I * Jd.topRows<3>() + (skew(w) * I) * Ji.topRows<3>();
    T.bottomRows<3>() = model.mass[i] * Jd.bottomRows<3>();
    C.noalias() += Ji.transpose() * T;
  }
}

}  // namespace soadyn
