// The note's sweeps z = Ψ_A x and z = Ψ_Aᵀ x against dense (e − Φ_A)⁻¹ and the truncated series.
#include "soadyn/algorithm/operators.hpp"

#include "test_util.hpp"

#include <Eigen/LU>

using namespace soadyn;
using namespace soadyn::test;

namespace {

// Def. 1: [Φ_A]_{i,j} = A_i if b_j = parent of b_i
MatX dense_phi(const std::vector<int>& parent, const std::vector<MatX>& A, int k) {
  const int n = int(parent.size());
  MatX Phi = MatX::Zero(k * n, k * n);
  for (int i = 0; i < n; ++i)
    if (parent[i] >= 0) Phi.block(k * i, k * parent[i], k, k) = A[i];
  return Phi;
}

int chain_depth(const std::vector<int>& parent) {
  std::vector<int> level(parent.size());
  int m = 0;
  for (size_t i = 0; i < parent.size(); ++i) {
    level[i] = parent[i] < 0 ? 1 : level[parent[i]] + 1;
    m = std::max(m, level[i]);
  }
  return m;
}

class Sweeps : public ::testing::TestWithParam<int> {};

TEST_P(Sweeps, MatchDenseInverseAndTruncatedSeries) {
  Rng rng(1000 + GetParam());
  const int n = rng.integer(1, 40), k = 6;
  std::vector<int> parent(n);
  for (int i = 0; i < n; ++i) parent[i] = i == 0 ? -1 : (rng.uniform(0, 1) < 0.3 ? -1 : rng.integer(0, i - 1));
  parent[0] = -1;
  std::vector<MatX> A(n);
  for (auto& Ai : A) Ai = MatX::Random(k, k) * 0.7;

  const MatX Phi = dense_phi(parent, A, k);
  const MatX E = MatX::Identity(k * n, k * n);
  const MatX Psi = (E - Phi).partialPivLu().solve(E);

  // nilpotency: Φ^m = 0 with m the longest chain, Φ^{m−1} ≠ 0; Ψ = e + Φ + … + Φ^{m−1}
  const int m = chain_depth(parent);
  MatX series = E, power = E;
  for (int p = 1; p < m; ++p) {
    power = power * Phi;
    series += power;
  }
  EXPECT_GT(power.cwiseAbs().maxCoeff(), 0.0) << "Φ^(m−1) should not vanish, m = " << m;
  EXPECT_TRUE(near_rel(power * Phi, MatX::Zero(k * n, k * n), 0.0)) << "Φ^m must vanish, m = " << m;
  EXPECT_TRUE(near_rel(series, Psi, 1e-12));

  // 6-vectors and 6×3 blocks
  for (int cols : {1, 3}) {
    const MatX x = MatX::Random(k * n, cols);
    MatX z = x;
    psi_base_to_tip(parent, BlockOperator{A}, [&](int i) { return z.middleRows<6>(6 * i); });
    EXPECT_TRUE(near_rel(z, Psi * x, 1e-12));
    MatX zt = x;
    psi_tip_to_base(parent, BlockOperator{A}, [&](int i) { return zt.middleRows<6>(6 * i); });
    EXPECT_TRUE(near_rel(zt, Psi.transpose() * x, 1e-12));
  }
}

INSTANTIATE_TEST_SUITE_P(RandomTrees, Sweeps, ::testing::Range(0, 12));

TEST(Sweeps, DOperatorEqualsItsMatrix) {
  Rng rng(7);
  const Model model = random_model(rng, {.n = 25, .branching = 0.5, .prismatic = 0.3});
  Data data(model);
  update_kinematics(model, data, random_q(rng, model));
  std::vector<MatX> Dblocks(model.nbodies);
  for (int i = 0; i < model.nbodies; ++i) Dblocks[i] = D_matrix(data, i);
  const Mat6X x = Mat6X::Random(6, model.nbodies);
  Mat6X z1 = x, z2 = x;
  psi_base_to_tip(model.parent, DOperator{data.d}, [&](int i) { return z1.col(i); });
  psi_base_to_tip(model.parent, BlockOperator{Dblocks}, [&](int i) { return z2.col(i); });
  EXPECT_TRUE(near_rel(z1, z2, 1e-14));
  z1 = x;
  z2 = x;
  psi_tip_to_base(model.parent, DOperator{data.d}, [&](int i) { return z1.col(i); });
  psi_tip_to_base(model.parent, BlockOperator{Dblocks}, [&](int i) { return z2.col(i); });
  EXPECT_TRUE(near_rel(z1, z2, 1e-14));
}

}  // namespace
