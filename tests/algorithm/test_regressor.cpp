// The joint-torque regressor and the inertial parameters: Y π against inverse dynamics on seeded
// random trees of every joint type, τ linear in π (Y of a model with other parameters unchanged),
// Yᵀ μ by the O(N) sweep against the formed Y, the round trip parameters → with_parameters, ∂q̈/∂π against central differences of forward
// dynamics, and the refusal of physically inconsistent parameters.
#include "soadyn/algorithm/regressor.hpp"

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "test_util.hpp"

using namespace soadyn;
using namespace soadyn::test;
using ::testing::HasSubstr;

namespace {

const TreeCase kCases[] = {
    {"chain_revolute", {.n = 6, .branching = 0.0}},
    {"tree_mixed", {.n = 9, .branching = 0.6, .prismatic = 0.3, .ball = 0.2, .planar = 0.1, .fixed = 2}},
    {"free_root", {.n = 7, .branching = 0.5, .prismatic = 0.2, .ball = 0.2, .free_root = true}},
    {"helical", {.n = 7, .branching = 0.5, .prismatic = 0.1, .helical = 0.5}},
};

class Regressor : public ::testing::TestWithParam<TreeCase> {};

// a random tree of the case's kind at a random (q, v, q̈), with [kin] and [vel] there
struct State {
  Model model;
  Data data;
  VecX q, v, qdd;
  State(Rng& rng, const TreeOptions& o) : model(random_model(rng, o)), data(model) {
    q = random_q(rng, model), v = random_v(rng, model, 2.0), qdd = random_v(rng, model, 3.0);
    update_kinematics(model, data, q);
    update_velocities(model, data, v);
  }
};

// τ of another model (other parameters, the same joints) at the same (q, v, q̈)
VecX inverse_dynamics_of(const Model& other, const State& x) {
  Data d(other);
  update_kinematics(other, d, x.q);
  update_velocities(other, d, x.v);
  inverse_dynamics(other, d, x.qdd);
  return d.tau;
}

TEST_P(Regressor, TimesParametersIsInverseDynamics) {
  Rng rng(41);
  for (int trial = 0; trial < 5; ++trial) {
    State x(rng, GetParam().options);
    const Model& model = x.model;
    MatX Y;
    regressor(model, x.data, x.qdd, Y);
    ASSERT_EQ(Y.rows(), model.nv);
    ASSERT_EQ(Y.cols(), 10 * model.nbodies);
    inverse_dynamics(model, x.data, x.qdd);
    EXPECT_TRUE(near_rel(Y * parameters(model), x.data.tau, 1e-12)) << trial;
    // linear in π: the same Y times another model's parameters is that model's inverse dynamics
    VecX pi2 = parameters(model);
    for (int i = 0; i < model.nbodies; ++i) pi2(10 * i) *= 1.5, pi2.segment<3>(10 * i + 1) *= 1.5;  // heavier, same c
    for (int i = 0; i < model.nbodies; ++i) pi2.segment<6>(10 * i + 4) *= 1.5;
    EXPECT_TRUE(near_rel(Y * pi2, inverse_dynamics_of(with_parameters(model, pi2), x), 1e-12)) << trial;
  }
}

// the listed bodies' columns alone (any order) against inverse dynamics: making body b 1.5 times
// heavier (same centre of mass) changes τ by its ten columns times the change of its π; and each
// body listed alone gives the same columns by the other route to its acceleration
TEST_P(Regressor, ListedBodiesColumnsGiveEachBodysShareOfInverseDynamics) {
  Rng rng(47);
  for (int trial = 0; trial < 5; ++trial) {
    State x(rng, GetParam().options);
    const Model& model = x.model;
    std::vector<int> bodies;
    for (int b = model.nbodies - 1; b >= 0; b -= 2) bodies.push_back(b);  // tip first: not the model's order
    MatX Y;
    regressor(model, x.data, x.qdd, bodies, Y);
    ASSERT_EQ(Y.rows(), model.nv);
    ASSERT_EQ(Y.cols(), 10 * Eigen::Index(bodies.size()));
    const VecX tau = inverse_dynamics_of(model, x);
    for (size_t k = 0; k < bodies.size(); ++k) {
      const int b = bodies[k];
      VecX pi = parameters(model);
      const VecX before = pi.segment<10>(10 * b);
      pi.segment<10>(10 * b) *= 1.5;
      EXPECT_TRUE(near_rel(Y.middleCols<10>(10 * Eigen::Index(k)) * (0.5 * before),
                           inverse_dynamics_of(with_parameters(model, pi), x) - tau, 1e-11))
          << trial << " body " << b;
      // the body alone: its acceleration along its own chain, where the list above (chains longer
      // than the tree) took the whole tree's inverse dynamics
      MatX Yb;
      regressor(model, x.data, x.qdd, std::vector<int>{b}, Yb);
      EXPECT_TRUE(near_rel(Yb, Y.middleCols<10>(10 * Eigen::Index(k)), 1e-12)) << trial << " body " << b << " alone";
    }
  }
  Model model = random_model(rng, GetParam().options);
  Data data(model);
  MatX Y;
  EXPECT_THROW(regressor(model, data, VecX::Zero(model.nv), std::vector<int>{model.nbodies}, Y), Error);
}

// the O(N) sweep against the formed regressor (two independent routes: carried down as velocities,
// up as forces)
TEST_P(Regressor, TransposeTimesVectorEqualsTheFormedRegressors) {
  Rng rng(43);
  for (int trial = 0; trial < 5; ++trial) {
    State x(rng, GetParam().options);
    const Model& model = x.model;
    const VecX mu = random_v(rng, model);
    MatX Y;
    regressor(model, x.data, x.qdd, Y);
    VecX got(10 * model.nbodies);
    regressor_transpose_times(model, x.data, x.qdd, mu, got);
    EXPECT_TRUE(near_rel(got, Y.transpose() * mu, 1e-12)) << trial;
  }
}

TEST_P(Regressor, ParameterDerivativeOfForwardDynamicsAgainstCentralDifferences) {
  Rng rng(5);
  const Model model = random_model(rng, GetParam().options);
  Data data(model);
  const VecX q = random_q(rng, model), v = random_v(rng, model), tau = random_v(rng, model, 2.0);
  update_kinematics(model, data, q);
  update_velocities(model, data, v);
  MatX dqdd;
  forward_dynamics_parameter_derivative(model, data, tau, dqdd);
  const VecX pi = parameters(model);
  auto qdd_at = [&](const VecX& p) {
    const Model m2 = with_parameters(model, p);
    Data d2(m2);
    update_kinematics(m2, d2, q);
    update_velocities(m2, d2, v);
    forward_dynamics(m2, d2, tau, FdMethod::Dense);
    return VecX(d2.qdd);
  };
  MatX fd(model.nv, pi.size());
  for (Eigen::Index j = 0; j < pi.size(); ++j) {
    // a small step that keeps every perturbed body physical: the masses' and the moments' own scale
    const double h = 1e-6 * std::max(std::abs(pi(j)), 1e-3);
    VecX p = pi, m = pi;
    p(j) += h;
    m(j) -= h;
    fd.col(j) = (qdd_at(p) - qdd_at(m)) / (2 * h);
  }
  EXPECT_TRUE(near_rel(dqdd, fd, 1e-6));
}

INSTANTIATE_TEST_SUITE_P(Trees, Regressor, ::testing::ValuesIn(kCases),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(Parameters, RoundTripGivesTheSameModel) {
  Rng rng(3);
  const Model model = random_model(rng, {.n = 8, .branching = 0.5, .ball = 0.2, .fixed = 2});
  const Model again = with_parameters(model, parameters(model));
  Data a(model), b(again);
  const VecX q = random_q(rng, model);
  update_kinematics(model, a, q);
  update_kinematics(again, b, q);
  mass_matrix(model, a);
  mass_matrix(again, b);
  EXPECT_TRUE(near_rel(a.M, b.M, 1e-13));
  for (int i = 0; i < model.nbodies; ++i) EXPECT_TRUE(near_rel(model.com[i], again.com[i], 1e-14));
}

TEST(Parameters, PhysicallyInconsistentParametersAreRefusedNamingTheBody) {
  Rng rng(9);
  const Model model = random_model(rng, {.n = 3, .branching = 0.0});
  auto refusal = [&](VecX pi) {
    try {
      with_parameters(model, pi);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  VecX pi = parameters(model);
  pi(10) = -1.0;  // body 1's mass
  EXPECT_THAT(refusal(pi), HasSubstr("body '" + model.body_names[1] + "': mass: expected > 0"));
  pi = parameters(model);
  pi.segment<6>(24) << 1e-3, 0, 1e-3, 0, 0, 10.0;  // body 2: I_zz far past I_xx + I_yy
  EXPECT_THAT(refusal(pi), HasSubstr("body '" + model.body_names[2] + "'"));
  pi = parameters(model);
  pi(4) = -5.0;  // body 0: negative moment
  EXPECT_THAT(refusal(pi), HasSubstr("positive semidefinite"));
  EXPECT_THAT(refusal(VecX::Zero(5)), HasSubstr("expected 30 numbers"));
}

}  // namespace
