// Forward sensitivities with prescribed motion (sensitivity.hpp, system.hpp): the free joints' x(t)
// against x₀ and the bodies' parameters π, by CVODES with the hybrid dynamics' products, against
// fourth-order central differences of whole runs (x₀ moved along the tangent on the free DOFs only,
// π by with_parameters), on a random chain with springs, a damper and a torque, and on a random
// tree on a free root whose appendage is slewed; the plan names the free DOFs alone; the adjoint's
// refusal.
#include "soadyn/sim/adjoint.hpp"
#include "soadyn/sim/sensitivity.hpp"
#include "soadyn/sim/simulate.hpp"
#include "soadyn/sim/system.hpp"

#include "test_util.hpp"
#include "whole_run_util.hpp"

#include <cstdio>
#include <numbers>

using namespace soadyn;
using namespace soadyn::test;

namespace {

std::vector<Sample> run(const Scenario& sc, const SimulationSettings& s) {
  std::vector<Sample> out;
  const RunSummary r = simulate(sc, s, nullptr, &out);
  EXPECT_TRUE(r.completed) << r.status;
  return out;
}

// the free DOFs' x(t) − x'(t) along the tangent, to first order: T(q) (q − q') for the coordinates,
// v − v' (rows: the state's v indices, then the same for v)
VecX free_difference(const Model& m, const std::vector<int>& free, const Sample& a, const Sample& b) {
  VecX full(2 * m.nv);
  full.tail(m.nv) = a.qd - b.qd;
  for (int i = 0; i < m.nbodies; ++i) {
    const int iq = m.idx_q[i], iv = m.idx_v[i], mi = m.nq_i[i], ni = m.nv_i[i];
    MatX T(ni, mi);
    joint_tangent_map(m.joint_type[i], a.q.data() + iq, T);
    full.segment(iv, ni) = T * (a.q - b.q).segment(iq, mi);
  }
  const int n = int(free.size());
  VecX d(2 * n);
  for (int k = 0; k < n; ++k) d(k) = full(free[size_t(k)]), d(n + k) = full(m.nv + free[size_t(k)]);
  return d;
}

// (8 (x(h) − x(−h)) − (x(2h) − x(−2h))) / 12h of whole runs at every output
template <class Run>
std::vector<VecX> central_difference(const Model& m, const std::vector<int>& free, double h, Run&& run_at) {
  const std::vector<Sample> p1 = run_at(h), m1 = run_at(-h), p2 = run_at(2 * h), m2 = run_at(-2 * h);
  std::vector<VecX> out;
  for (size_t r = 0; r < p1.size(); ++r)
    out.push_back((8 * free_difference(m, free, p1[r], m1[r]) - free_difference(m, free, p2[r], m2[r])) / (12 * h));
  return out;
}

// the largest |a − b| / max(1, |b|) over the outputs
double worst(const std::vector<MatX>& got, const std::vector<MatX>& want) {
  double e = 0;
  for (size_t r = 0; r < want.size(); ++r)
    e = std::max(e, (got[r] - want[r]).cwiseAbs().maxCoeff() / std::max(1.0, want[r].cwiseAbs().maxCoeff()));
  return e;
}

void check_against_differences(const Scenario& sc, SimulationSettings s, double tol) {
  const Model& m = sc.model;
  const std::vector<Sample> got = run(sc, s);
  const SensitivityPlan plan = plan_sensitivities(m, s.sensitivities, sc.inputs.prescribed);
  const System sys(m, sc.inputs, FdMethod::ArticulatedBody);
  const std::vector<int>& free = sys.v_index();
  const int n = int(free.size());
  ASSERT_EQ(plan.nx, 2 * n);
  ASSERT_EQ(got.back().sensitivity_initial_state.rows(), 2 * n);
  ASSERT_EQ(got.back().sensitivity_initial_state.cols(), 2 * n);
  SimulationSettings plain = s;
  plain.sensitivities = {};
  const double h = 1e-3;
  // x₀: q₀ ⊕ a e_k or v₀ + a e_k on the free DOFs
  std::vector<MatX> d0(got.size(), MatX::Zero(2 * n, 2 * n)), g0, dp(got.size(), MatX::Zero(2 * n, plan.np())), gp;
  for (int c = 0; c < 2 * n; ++c) {
    const int k = free[size_t(c % n)];
    const std::vector<VecX> d = central_difference(m, free, h, [&](double a) {
      Scenario moved = sc;
      if (c < n) moved.q0 = m.integrate(sc.q0, VecX::Unit(m.nv, k), a);
      else moved.v0(k) += a;
      return run(moved, plain);
    });
    for (size_t r = 0; r < d.size(); ++r) d0[r].col(c) = d[r];
  }
  // π_j moved by a times its scale
  const VecX pi = parameters(m);
  for (int c = 0; c < plan.np(); ++c) {
    const int j = kParametersPerBody * plan.bodies[size_t(c / kParametersPerBody)] + c % kParametersPerBody;
    const double scale = std::max(std::abs(pi(j)), 0.1 * std::abs(pi(j - j % kParametersPerBody)));
    const std::vector<VecX> d = central_difference(m, free, h, [&](double a) {
      Scenario moved = sc;
      VecX p = pi;
      p(j) += a * scale;
      moved.model = with_parameters(m, p);
      return run(moved, plain);
    });
    for (size_t r = 0; r < d.size(); ++r) dp[r].col(c) = d[r] / scale;
  }
  for (const Sample& x : got) g0.push_back(x.sensitivity_initial_state), gp.push_back(x.sensitivity_parameters);
  const double e0 = worst(g0, d0), ep = worst(gp, dp);
  std::printf("  %s, %s: largest relative difference from central differences: x0 %.1e, pi %.1e\n", sc.path.c_str(),
              std::string(to_string(s.method)).c_str(), e0, ep);
  EXPECT_LT(e0, tol);
  EXPECT_LT(ep, tol);
  // the motion is felt: the sensitivities are not those of the free joints alone
  EXPECT_GT(got.back().sensitivity_initial_state.cwiseAbs().maxCoeff(), 1e-2);
}

PrescribedInput sine(const Model& m, int body, double amplitude, double frequency) {
  PrescribedInput p;
  p.body = body, p.joint = m.joint_names[size_t(body)], p.dof = m.idx_v[body], p.coord = m.idx_q[body];
  p.target.constant = 0.2;
  p.target.amplitude = amplitude;
  p.target.frequency = frequency;
  p.target.phase = 0.3;
  return p;
}

// the chain of test_sensitivity with its second joint following a sine
Scenario chain_with_a_driven_joint() {
  Scenario sc = random_chain_with_inputs();
  sc.path = "random chain, b1 driven";
  sc.inputs.prescribed.push_back(sine(sc.model, 1, 0.4, 0.8));
  sc.q0(sc.model.idx_q[1]) = 0.2 + 0.4 * std::sin(0.3);
  sc.v0(sc.model.idx_v[1]) = 0.4 * 2 * std::numbers::pi * 0.8 * std::cos(0.3);
  return sc;
}

}  // namespace

TEST(PrescribedSensitivity, ChainMatchesCentralDifferencesAdams) {
  const Scenario sc = chain_with_a_driven_joint();
  SimulationSettings s = tight("cvode-adams", 0.8);
  s.sensitivities = {true, {"b0", "b3"}};
  check_against_differences(sc, s, 1e-6);
}

TEST(PrescribedSensitivity, ChainMatchesCentralDifferencesBdf) {
  const Scenario sc = chain_with_a_driven_joint();
  SimulationSettings s = tight("cvode-bdf", 0.8);
  s.sensitivities = {true, {"b2"}};
  check_against_differences(sc, s, 1e-6);
}

// a free root (its quaternion along the tangent) whose 1-DOF appendage is slewed
TEST(PrescribedSensitivity, FreeRootWithASlewedAppendageMatchesCentralDifferences) {
  Rng rng(17);
  Scenario sc;
  sc.path = "free tree, slewed";
  sc.model = random_model(rng, {.n = 4, .branching = 0.0, .free_root = true});
  sc.q0 = random_q(rng, sc.model);
  sc.v0 = random_v(rng, sc.model);
  PrescribedInput p = sine(sc.model, 2, 0.0, 0.0);
  p.target.slew = std::make_shared<JointSlew>(JointSlew{0.1, 1.2, 0.1, 0.4});
  sc.inputs.prescribed.push_back(p);
  sc.q0(p.coord) = 0.1, sc.v0(p.dof) = 0.0;
  SimulationSettings s = tight("cvode-bdf", 0.6);
  s.sensitivities = {true, {"b0", "b3"}};
  check_against_differences(sc, s, 1e-6);
}

TEST(PrescribedSensitivity, ThePlanNamesTheFreeDofsAlone) {
  const Scenario sc = chain_with_a_driven_joint();
  const SensitivityPlan plan = plan_sensitivities(sc.model, {true, {}}, sc.inputs.prescribed);
  const std::string driven = sc.model.v_names()[size_t(sc.model.idx_v[1])];
  EXPECT_EQ(plan.nx, 2 * (sc.model.nv - 1));
  ASSERT_EQ(int(plan.state_names.size()), plan.nx);
  for (const std::string& name : plan.state_names) EXPECT_EQ(name.find(driven), std::string::npos) << name;
}

TEST(PrescribedSensitivity, TheAdjointRefusesInOneLine) {
  const Scenario sc = chain_with_a_driven_joint();
  Cost cost;
  cost.terminal = [](const VecX& q, const VecX&, Eigen::Ref<VecX> dq, Eigen::Ref<VecX> dv) {
    dq.setZero(), dv.setZero();
    dq(0) = 1;
    return q(0);
  };
  const std::string why = message_of([&] { gradient(sc, tight("cvode-bdf", 0.2), cost, {true, {}}); });
  EXPECT_NE(why.find("the adjoint does not take prescribed motion"), std::string::npos) << why;
  EXPECT_EQ(why.find('\n'), std::string::npos);
}
