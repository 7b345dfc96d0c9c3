// The two ways forward_dynamics_derivatives applies 𝓜⁻¹ (DerivativeData::route): the articulated-body
// factor (articulated_solve) against 𝓜 and against the LᵀDL route, and against central differences,
// on seeded random trees, chains of 40 and more bodies and free roots, so that the route
// derivative_route picks for big models is the one exercised.
#include "soadyn/derivatives.hpp"

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
};

// q̈ by the O(N) route at (q ⊕ δ, v)
VecX qdd_at(const Model& m, Data& d, const VecX& q, const VecX& v, const VecX& tau) {
  update_kinematics(m, d, q);
  update_velocities(m, d, v);
  forward_dynamics(m, d, tau, FdMethod::ArticulatedBody);
  return d.qdd;
}

class DerivativeRoutes : public ::testing::TestWithParam<TreeCase> {};

// 𝓜 X = B for numbers of right-hand sides that are and are not multiples of those solved at once
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
  for (const int rows : {1, 8, 16, 29}) {
    MatX B(model.nv, rows);
    for (auto& b : B.reshaped()) b = rng.uniform();
    MatX X = B;
    articulated_solve(model, data, X, work);
    EXPECT_TRUE(near_rel(data.M * X, B, 1e-10)) << c.name << ", " << rows << " right-hand sides";
  }
}

TEST_P(DerivativeRoutes, ArticulatedBodyRouteEqualsLtdlAndCentralDifferences) {
  const TreeCase& c = GetParam();
  for (int seed = 0; seed < 2; ++seed) {
    Rng rng(307 * seed + c.options.n);
    const Model model = random_model(rng, c.options);
    Data data(model), work(model);
    DerivativeData aba(model), ltdl(model);
    aba.route = FdMethod::ArticulatedBody;
    ltdl.route = FdMethod::Sparse;
    const VecX q = random_q(rng, model), v = random_v(rng, model, 2.0), tau = random_v(rng, model, 3.0);
    update_kinematics(model, data, q);
    update_velocities(model, data, v);
    forward_dynamics_derivatives(model, data, v, tau, ltdl, nullptr, true);
    forward_dynamics_derivatives(model, data, v, tau, aba, nullptr, true);
    EXPECT_TRUE(near_rel(aba.dqdd_dq, ltdl.dqdd_dq, 1e-9)) << c.name << " seed " << seed << ": ∂q̈/∂q";
    EXPECT_TRUE(near_rel(aba.dqdd_dv, ltdl.dqdd_dv, 1e-9)) << c.name << " seed " << seed << ": ∂q̈/∂v";
    EXPECT_TRUE(near_rel(aba.Minv, ltdl.Minv, 1e-9)) << c.name << " seed " << seed << ": 𝓜⁻¹";
    EXPECT_TRUE(near_rel(data.qdd, qdd_at(model, work, q, v, tau), 1e-12)) << c.name;
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
    EXPECT_TRUE(near_rel(aba.dqdd_dq, dq, 1e-6)) << c.name << " seed " << seed << ": ∂q̈/∂q by differences";
    EXPECT_TRUE(near_rel(aba.dqdd_dv, dv, 1e-6)) << c.name << " seed " << seed << ": ∂q̈/∂v by differences";
    EXPECT_GT(dq.cwiseAbs().maxCoeff(), 1e-2);  // the comparison means something
  }
}

INSTANTIATE_TEST_SUITE_P(RandomTrees, DerivativeRoutes, ::testing::ValuesIn(kCases),
                         [](const auto& info) { return std::string(info.param.name); });

// derivative_route picks the articulated-body factor for long chains, LᵀDL for short chains and
// shallow trees; a Dense route is refused
TEST(DerivativeRoutesChoice, LongChainsTakeTheArticulatedBodyFactor) {
  Rng rng(3);
  const Model big = random_model(rng, {.n = 64, .branching = 0.0});
  EXPECT_EQ(derivative_route(big), FdMethod::ArticulatedBody);
  EXPECT_EQ(derivative_route(random_model(rng, {.n = 8, .branching = 0.0})), FdMethod::Sparse);
  EXPECT_EQ(derivative_route(random_model(rng, {.n = 64, .branching = 1.0})), FdMethod::Sparse);
  Data data(big);
  DerivativeData dd(big);
  dd.route = FdMethod::Dense;
  update_kinematics(big, data, random_q(rng, big));
  update_velocities(big, data, VecX::Zero(big.nv));
  EXPECT_THROW(forward_dynamics_derivatives(big, data, VecX::Zero(big.nv), VecX::Zero(big.nv), dd), Error);
}

}  // namespace
