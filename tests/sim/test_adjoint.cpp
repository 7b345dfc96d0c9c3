// Adjoint gradients of a run's cost (adjoint.hpp) against independent routes: the forward
// sensitivities of the same run (CVODES' other mode: ∂Φ/∂x(T) times ∂x(T)/∂x₀, ∂x(T)/∂π) on the
// note's double pendulum, a seeded random chain with springs, dampers and torques, a random tree on
// a free root and a 7-DOF arm; central differences of the cost of whole runs for a running
// (tracking) cost; a free-falling ball in closed form; the same gradient whatever the checkpoint
// spacing; the refusals.
#include "soadyn/sim/adjoint.hpp"
#include "soadyn/io/scenario_file.hpp"

#include "soadyn/sim/sensitivity.hpp"
#include "soadyn/sim/simulate.hpp"
#include "test_util.hpp"
#include "whole_run_util.hpp"

#include <cmath>
#include <cstdio>

using namespace soadyn;
using namespace soadyn::test;
using ::testing::HasSubstr;

namespace {

// Φ = ½ Σ w_k (y_k − c_k)² + aᵀ y on the coordinates at T, seeded weights and centres
Cost seeded_terminal(Rng& rng, const Model& m) {
  const int n = m.nq + m.nv;
  VecX w(n), c(n), a(n);
  for (int k = 0; k < n; ++k) w(k) = rng.uniform(0.5, 2.0), c(k) = rng.uniform(-1, 1), a(k) = rng.uniform(-1, 1);
  Cost cost;
  cost.terminal = [w, c, a, m](const VecX& q, const VecX& v, Eigen::Ref<VecX> dq, Eigen::Ref<VecX> dv) {
    VecX y(q.size() + v.size());
    y << q, v;
    const VecX e = y - c;
    const VecX g = w.cwiseProduct(e) + a;
    dq = g.head(m.nq);
    dv = g.tail(m.nv);
    return 0.5 * e.dot(w.cwiseProduct(e)) + a.dot(y);
  };
  return cost;
}

// the gradient of Φ(y(T)) by the forward sensitivities: ∂Φ/∂x(T) = [∂Φ/∂q P(q(T)); ∂Φ/∂v], times
// ∂x(T)/∂x₀ and ∂x(T)/∂π
std::pair<VecX, VecX> forward_gradient(const Scenario& sc, SimulationSettings s, const Cost& cost,
                                       const SensitivitySettings& wrt) {
  const Model& m = sc.model;
  s.sensitivities = wrt;
  std::vector<Sample> samples;
  const RunSummary r = simulate(sc, s, nullptr, &samples);
  EXPECT_TRUE(r.completed) << r.status;
  const Sample& last = samples.back();
  VecX dq = VecX::Zero(m.nq), dv = VecX::Zero(m.nv);
  cost.terminal(last.q, last.qd, dq, dv);
  VecX dx(2 * m.nv);
  dx << tangent_to_coordinates(m, last.q).transpose() * dq, dv;
  VecX g0, gp;
  if (wrt.initial_state) g0 = last.sensitivity_initial_state.transpose() * dx;
  if (!wrt.parameters.empty()) gp = last.sensitivity_parameters.transpose() * dx;
  return {g0, gp};
}

double relative(const VecX& a, const VecX& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(1.0, b.cwiseAbs().maxCoeff());
}

void check_against_forward(const Scenario& sc, const SimulationSettings& s, const SensitivitySettings& wrt, uint64_t seed,
                           double tol = 1e-6) {
  Rng rng(seed);
  const Cost cost = seeded_terminal(rng, sc.model);
  const CostGradient adj = gradient(sc, s, cost, wrt);
  const auto [g0, gp] = forward_gradient(sc, s, cost, wrt);
  ASSERT_EQ(adj.d_initial_state.size(), g0.size());
  ASSERT_EQ(adj.d_parameters.size(), gp.size());
  const double e0 = g0.size() ? relative(adj.d_initial_state, g0) : 0.0;
  const double ep = gp.size() ? relative(adj.d_parameters, gp) : 0.0;
  std::printf("  %s: adjoint against forward sensitivities: x0 %.1e, pi %.1e (forward %ld steps, backward %ld, %ld checkpoints)\n",
              std::string(to_string(s.method)).c_str(), e0, ep, adj.forward_steps, adj.backward_steps, adj.checkpoints);
  EXPECT_LT(e0, tol);
  EXPECT_LT(ep, tol);
  EXPECT_GT(adj.backward_steps, 0);
}

Scenario double_pendulum() { return load_scenario(SOADYN_SOURCE_DIR "/scenarios/double_pendulum.yaml"); }

TEST(Adjoint, DoublePendulumMatchesForwardSensitivitiesAdams) {
  check_against_forward(double_pendulum(), tight("cvode-adams", 1.0), {true, {"all"}}, 1);
}

TEST(Adjoint, DoublePendulumMatchesForwardSensitivitiesBdf) {
  check_against_forward(double_pendulum(), tight("cvode-bdf", 1.0), {true, {"lower"}}, 2);
}

TEST(Adjoint, RandomChainWithInputsMatchesForwardSensitivities) {
  check_against_forward(random_chain_with_inputs(), tight("cvode-adams", 0.8), {true, {"b1", "b3"}}, 3);
}

TEST(Adjoint, FreeRootTreeMatchesForwardSensitivitiesAlongTheTangent) {
  check_against_forward(random_free_tree(), tight("cvode-bdf", 0.6), {true, {"b0", "b2"}}, 4);
}

TEST(Adjoint, SevenDofArmMatchesForwardSensitivities) {
  Scenario sc = load_scenario(SOADYN_SOURCE_DIR "/tests/data/arm7.urdf");
  Rng rng(5);
  sc.q0 = random_q(rng, sc.model);
  sc.v0 = random_v(rng, sc.model);
  check_against_forward(sc, tight("cvode-adams", 0.5), {true, {"all"}}, 5);
}

// a running cost: tracking a run of the same pendulum with other masses, against fourth-order
// central differences of the cost of whole runs (each its own forward quadrature)
TEST(Adjoint, TrackingCostMatchesCentralDifferencesOfWholeRuns) {
  Scenario sc = double_pendulum();
  SimulationSettings s = tight("cvode-adams", 1.0);
  Scenario other = sc;
  VecX pi = parameters(sc.model);
  pi(0) *= 1.1;
  pi(kParametersPerBody) *= 0.8;
  other.model = with_parameters(sc.model, pi);
  SimulationSettings logged = s;
  logged.output_dt = 0.01;
  std::vector<Sample> ref;
  simulate(other, logged, nullptr, &ref);
  const Eigen::Index n = Eigen::Index(ref.size());
  VecX t(n);
  MatX q(n, sc.model.nq), v(n, sc.model.nv);
  for (Eigen::Index r = 0; r < n; ++r) t(r) = ref[size_t(r)].t, q.row(r) = ref[size_t(r)].q, v.row(r) = ref[size_t(r)].qd;
  TrackingWeights w;
  w.q = VecX::Constant(sc.model.nq, 2.0);
  w.v = VecX::Constant(sc.model.nv, 0.5);
  w.q_final = VecX::Constant(sc.model.nq, 1.0);
  const Cost cost = tracking_cost(sc.model, t, q, v, w);
  const SensitivitySettings wrt{true, {"all"}};
  const CostGradient adj = gradient(sc, s, cost, wrt);
  EXPECT_GT(adj.cost, 0.0);
  // G at a moved scene, by the forward quadrature alone (the gradient's other half unused)
  const auto G = [&](const Scenario& moved) { return gradient(moved, s, cost, {true, {}}).cost; };
  const auto central = [&](auto&& at, double h) { return (8 * (at(h) - at(-h)) - (at(2 * h) - at(-2 * h))) / (12 * h); };
  const Model& m = sc.model;
  VecX fd0(2 * m.nv), fdp(pi.size());
  for (int k = 0; k < 2 * m.nv; ++k)
    fd0(k) = central([&](double a) {
      Scenario moved = sc;
      if (k < m.nv) moved.q0 = m.integrate(sc.q0, VecX::Unit(m.nv, k), a);
      else moved.v0(k - m.nv) += a;
      return G(moved);
    }, 1e-3);
  const VecX pi0 = parameters(m);
  for (int j = 0; j < pi0.size(); ++j) {
    const double scale = std::max(std::abs(pi0(j)), 0.1 * std::abs(pi0(j - j % kParametersPerBody)));
    fdp(j) = central([&](double a) {
      Scenario moved = sc;
      VecX p = pi0;
      p(j) += a * scale;
      moved.model = with_parameters(m, p);
      return G(moved);
    }, 1e-3) / scale;
  }
  const double e0 = relative(adj.d_initial_state, fd0), ep = relative(adj.d_parameters, fdp);
  std::printf("  tracking cost G = %.6g: adjoint against central differences: x0 %.1e, pi %.1e\n", adj.cost, e0, ep);
  EXPECT_LT(e0, 1e-6);
  EXPECT_LT(ep, 1e-6);
}

// a ball falling freely, no spin: G = ∫₀ᵀ z dt + z(T) + v_z(T), so ∂G/∂z₀ = T + 1, ∂G/∂v_z0 = T²/2 + T + 1,
// nothing else (gravity accelerates every mass alike)
TEST(Adjoint, FreeFallingBallInClosedForm) {
  const Scenario sc = falling_ball();
  const double T = 1.5;
  Cost cost;
  cost.running = [](double, const VecX& q, const VecX&, Eigen::Ref<VecX> dq, Eigen::Ref<VecX>) {
    dq(2) = 1.0;
    return q(2);
  };
  cost.terminal = [](const VecX& q, const VecX& v, Eigen::Ref<VecX> dq, Eigen::Ref<VecX> dv) {
    dq(2) = 1.0;
    dv(5) = 1.0;
    return q(2) + v(5);
  };
  for (const char* method : {"cvode-adams", "cvode-bdf"}) {
    const CostGradient g = gradient(sc, tight(method, T), cost, {true, {"all"}});
    VecX want = VecX::Zero(12);
    want(5) = T + 1;                  // δp_z
    want(11) = T * T / 2 + T + 1;     // δv_z
    EXPECT_TRUE(near_rel(g.d_initial_state, want, 1e-8)) << method << "\n" << g.d_initial_state.transpose();
    EXPECT_LT(g.d_parameters.cwiseAbs().maxCoeff(), 1e-8) << method;
    // G = ∫ (z₀ + v t − g t²/2) dt + z(T) + v(T)
    const double z0 = 3.0, vz = 2.0, gz = 9.81;
    const double G = z0 * T + vz * T * T / 2 - gz * T * T * T / 6 + (z0 + vz * T - gz * T * T / 2) + (vz - gz * T);
    EXPECT_NEAR(g.cost, G, 1e-8 * std::abs(G)) << method;
    EXPECT_EQ(g.state_names.size(), 12u);
    EXPECT_EQ(g.parameter_names.front(), "ball.m");
  }
}

// CVODES re-runs the forward problem from checkpoints: the gradient does not depend on their spacing
TEST(Adjoint, CheckpointSpacingChangesMemoryNotTheGradient) {
  Scenario sc = double_pendulum();
  Rng rng(9);
  const Cost cost = seeded_terminal(rng, sc.model);
  const SimulationSettings s = tight("cvode-adams", 1.0);
  const CostGradient few = gradient(sc, s, cost, {true, {"all"}}, 100000);
  const CostGradient many = gradient(sc, s, cost, {true, {"all"}}, 5);
  EXPECT_LE(few.checkpoints, 2);
  EXPECT_GE(many.checkpoints, few.forward_steps / 5 - 1);
  EXPECT_LT(relative(many.d_initial_state, few.d_initial_state), 1e-8);
  EXPECT_LT(relative(many.d_parameters, few.d_parameters), 1e-8);
  // 0: the spacing from the state's size (double pendulum: 4 entries, the floor of 500 steps), the
  // same gradient; a negative spacing is refused
  EXPECT_EQ(automatic_steps_per_checkpoint(4), 500);
  EXPECT_EQ(automatic_steps_per_checkpoint(14), 700);
  EXPECT_EQ(automatic_steps_per_checkpoint(1000), 10000);
  const CostGradient automatic = gradient(sc, s, cost, {true, {"all"}});
  EXPECT_EQ(automatic.checkpoints, few.forward_steps > 500 ? few.forward_steps / 500 : 0);
  EXPECT_LT(relative(automatic.d_initial_state, few.d_initial_state), 1e-8);
  EXPECT_THAT([&] { gradient(sc, s, cost, {true, {}}, -1); },
              testing::ThrowsMessage<Error>(HasSubstr("steps_per_checkpoint: expected a number of steps")));
}

TEST(Adjoint, RefusesWhatItDoesNotDifferentiate) {
  Scenario sc = double_pendulum();
  Rng rng(1);
  const Cost cost = seeded_terminal(rng, sc.model);
  EXPECT_THAT([&] { gradient(sc, tight("rk4", 0.1), cost, {true, {}}); },
              testing::ThrowsMessage<Error>(HasSubstr("need a CVODE method")));
  EXPECT_THAT([&] { gradient(sc, tight("cvode-adams", 0.1), cost, {false, {}}); },
              testing::ThrowsMessage<Error>(HasSubstr("nothing to differentiate")));
  EXPECT_THAT([&] { gradient(sc, tight("cvode-adams", 0.1), Cost{}, {true, {}}); },
              testing::ThrowsMessage<Error>(HasSubstr("neither a running nor a terminal part")));
  EXPECT_THAT([&] { gradient(sc, tight("cvode-adams", 0.1), cost, {false, {"lowr"}}); },
              testing::ThrowsMessage<Error>(HasSubstr("did you mean 'lower'")));
  const VecX t = VecX::LinSpaced(3, 0, 1);
  EXPECT_THAT([&] { tracking_cost(sc.model, t, MatX::Zero(3, 3), MatX::Zero(3, 2), {}); },
              testing::ThrowsMessage<Error>(HasSubstr("q has shape (3, 3), expected (3, 2)")));
  EXPECT_THAT([&] { tracking_cost(sc.model, VecX::Zero(3), MatX::Zero(3, 2), MatX::Zero(3, 2), {}); },
              testing::ThrowsMessage<Error>(HasSubstr("times must increase")));
  TrackingWeights w;
  w.q = VecX::Constant(2, -1.0);
  EXPECT_THAT([&] { tracking_cost(sc.model, t, MatX::Zero(3, 2), MatX::Zero(3, 2), w); },
              testing::ThrowsMessage<Error>(HasSubstr("≥ 0")));
}

}  // namespace
