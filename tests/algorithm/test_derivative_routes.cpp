// forward_dynamics_derivatives on big models (𝓜⁻¹ about the origin and its O(N²) products with the
// sweeps' vectors, per path of the tree) against −𝓜⁻¹ ∂τ by a dense LU of 𝓜 and against central
// differences, on seeded random trees numbered depth-first and not, chains of 40 and more bodies and
// free roots; and articulated_solve (the articulated-body factor, many right-hand sides) against 𝓜.
#include "soadyn/algorithm/derivatives.hpp"

#include "test_util.hpp"

using namespace soadyn;
using namespace soadyn::test;

namespace {

const TreeCase kCases[] = {
    {"chain48", {.n = 48, .branching = 0.0}},
    {"chain40_prismatic", {.n = 40, .branching = 0.0, .prismatic = 0.3}},
    {"tree44_mixed", {.n = 44, .branching = 0.5, .prismatic = 0.2, .ball = 0.2, .planar = 0.1}},
    {"free_chain42", {.n = 42, .branching = 0.0, .ball = 0.1, .free_root = true}},
    {"free_tree50_mixed", {.n = 50, .branching = 0.4, .prismatic = 0.2, .ball = 0.2, .planar = 0.1, .free_root = true}},
    {"free_alone", {.n = 1, .free_root = true}},
    {"chain3", {.n = 3, .branching = 0.0}},
    {"tree40_helical", {.n = 40, .branching = 0.5, .prismatic = 0.1, .ball = 0.1, .helical = 0.5, .free_root = true}},
};

// q̈ by the O(N) route at (q ⊕ δ, v)
VecX qdd_at(const Model& m, Data& d, const VecX& q, const VecX& v, const VecX& tau) {
  update_kinematics(m, d, q);
  update_velocities(m, d, v);
  forward_dynamics(m, d, tau, FdMethod::ArticulatedBody);
  return d.qdd;
}

class DerivativeRoutes : public ::testing::TestWithParam<TreeCase> {};

// 𝓜 X = B for numbers of right-hand sides that are and are not multiples of those solved at once:
// one (a one-row pass), 3 and 10 (four and twelve rows, padded), 16, and 29 (16, then 16 padded)
TEST_P(DerivativeRoutes, ArticulatedSolveInvertsTheMassMatrix) {
  const TreeCase& c = GetParam();
  Rng rng(17 + c.options.n);
  const Model model = random_model(rng, c.options);
  Data data(model);
  update_kinematics(model, data, random_q(rng, model));
  update_velocities(model, data, random_v(rng, model));
  forward_dynamics(model, data, random_v(rng, model), FdMethod::ArticulatedBody);  // the factor
  mass_matrix(model, data);
  MatX work = articulated_solve_work(model);
  for (const int rows : {1, 3, 8, 10, 16, 29}) {
    MatX B(model.nv, rows);
    for (auto& b : B.reshaped()) b = rng.uniform();
    MatX X = B;
    articulated_solve(model, data, X, work);
    EXPECT_TRUE(near_rel(data.M * X, B, 1e-10)) << c.name << ", " << rows << " right-hand sides";
  }
}

TEST_P(DerivativeRoutes, ForwardDerivativesEqualDenseSolveAndCentralDifferences) {
  const TreeCase& c = GetParam();
  for (int seed = 0; seed < 2; ++seed) {
    Rng rng(307 * seed + c.options.n);
    const Model model = random_model(rng, c.options);
    Data data(model), work(model);
    DerivativeData dd(model), id(model);
    const VecX q = random_q(rng, model), v = random_v(rng, model, 2.0), tau = random_v(rng, model, 3.0);
    update_kinematics(model, data, q);
    update_velocities(model, data, v);
    forward_dynamics_derivatives(model, data, v, tau, dd);
    EXPECT_TRUE(near_rel(data.qdd, qdd_at(model, work, q, v, tau), 1e-12)) << c.name;
    // −𝓜⁻¹ ∂τ with 𝓜 by the composite route and a dense LU, ∂τ filled pair by pair
    update_kinematics(model, work, q);
    update_velocities(model, work, v);
    mass_matrix(model, work);
    const Eigen::PartialPivLU<MatX> lu(work.M);
    inverse_dynamics_derivatives(model, work, v, data.qdd, id);
    EXPECT_TRUE(near_rel(dd.dqdd_dq, -lu.solve(id.dtau_dq), 1e-9)) << c.name << " seed " << seed << ": ∂q̈/∂q";
    EXPECT_TRUE(near_rel(dd.dqdd_dv, -lu.solve(id.dtau_dv), 1e-9)) << c.name << " seed " << seed << ": ∂q̈/∂v";
    EXPECT_TRUE(near_rel(dd.Minv, lu.inverse(), 1e-9)) << c.name << " seed " << seed << ": 𝓜⁻¹";
    // central differences along the tangent of q and along v
    const double h = 1e-5;
    MatX dq(model.nv, model.nv), dv(model.nv, model.nv);
    for (int k = 0; k < model.nv; ++k) {
      VecX e = VecX::Zero(model.nv);
      e(k) = h;
      dq.col(k) = (qdd_at(model, work, model.integrate(q, e, 1.0), v, tau) -
                   qdd_at(model, work, model.integrate(q, -e, 1.0), v, tau)) / (2 * h);
      dv.col(k) = (qdd_at(model, work, q, v + e, tau) - qdd_at(model, work, q, v - e, tau)) / (2 * h);
    }
    EXPECT_TRUE(near_rel(dd.dqdd_dq, dq, 1e-6)) << c.name << " seed " << seed << ": ∂q̈/∂q by differences";
    EXPECT_TRUE(near_rel(dd.dqdd_dv, dv, 1e-6)) << c.name << " seed " << seed << ": ∂q̈/∂v by differences";
    EXPECT_GT(dq.cwiseAbs().maxCoeff(), 1e-2);  // the comparison means something
  }
}

INSTANTIATE_TEST_SUITE_P(RandomTrees, DerivativeRoutes, ::testing::ValuesIn(kCases),
                         [](const auto& info) { return std::string(info.param.name); });

// The cases cover both numberings minverse and the products handle: depth-first (a subtree's DOFs one
// run) and not, and trees of several paths
TEST(DerivativeRoutesCases, NumberedDepthFirstAndNot) {
  int depth_first = 0, other = 0, branched = 0;
  for (const TreeCase& c : kCases)
    for (int seed = 0; seed < 2; ++seed) {
      Rng rng(307 * seed + c.options.n);
      const Model model = random_model(rng, c.options);
      bool dfs = true;
      for (int x = 0; x < model.nv; ++x) dfs = dfs && model.dfs_dof[size_t(x)] == x;
      ++(dfs ? depth_first : other);
      branched += model.npaths > 1;
    }
  EXPECT_GT(depth_first, 0);
  EXPECT_GT(other, 0);
  EXPECT_GT(branched, 0);
}

}  // namespace
