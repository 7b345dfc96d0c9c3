// Prescribed motion in a run (system.hpp, hybrid.hpp): on seeded random trees with some 1-DOF
// joints following given motions, every logged q̈ and prescribed torque satisfies inverse dynamics
// of the whole model; the energy balance E − E₀ = W + W_p − D holds; a run of the whole model
// driven by the logged prescribed torques retraces the motion; every method steps the free joints'
// state; the analytic ∂f/∂y matches differences; a free-floating base keeps its momentum; the
// quintic slew has its closed form.
#include "soadyn/algorithm/hybrid.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/algorithm/table.hpp"
#include "soadyn/sim/integrators.hpp"
#include "soadyn/sim/simulate.hpp"
#include "soadyn/sim/system.hpp"
#include "soadyn/sim/trajectory.hpp"

#include "test_util.hpp"

#include <numbers>

using namespace soadyn;
using namespace soadyn::test;

namespace {

// a scene on a random tree: springs and dampers, a torque, and `share` of the 1-DOF joints
// (never the free root) following sines
Scenario random_scene(std::uint64_t seed, const TreeOptions& o, double share, bool dampers = true) {
  Rng rng(seed);
  Scenario sc;
  sc.model = random_model(rng, o);
  const Model& m = sc.model;
  sc.q0 = random_q(rng, m);
  sc.v0 = random_v(rng, m, 0.5);
  for (int i = 0; i < m.nbodies; ++i) {
    if (m.nv_i[i] != 1 || m.nq_i[i] != 1) continue;
    const int k = m.idx_v[i];
    if (rng.uniform(0, 1) < share) {
      PrescribedInput p;
      p.joint = m.joint_names[size_t(i)], p.body = i, p.dof = k, p.coord = m.idx_q[i];
      p.target.constant = rng.uniform(-0.5, 0.5);
      p.target.amplitude = rng.uniform(0.1, 0.6);
      p.target.frequency = rng.uniform(0.3, 1.2);
      p.target.phase = rng.uniform(0, 3);
      sc.inputs.prescribed.push_back(p);
    } else if (k % 3 == 0) {
      sc.inputs.springs.push_back({m.joint_names[size_t(i)], k, m.idx_q[i], 3.0, 0.2});
    } else if (dampers && k % 3 == 1) {
      sc.inputs.dampers.push_back({m.joint_names[size_t(i)], k, 0.4});
    } else {
      sc.inputs.torques.push_back({m.joint_names[size_t(i)], k, 0.3, 0.5, 1.3, 0.2});
    }
  }
  sc.simulation.t_end = 1.0;
  sc.simulation.output_dt = 0.05;
  sc.simulation.rtol = 1e-10;
  sc.simulation.atol = 1e-10;
  return sc;
}

const TreeCase kCases[] = {
    {"chain8", {.n = 8, .branching = 0.0, .prismatic = 0.3}},
    {"tree16", {.n = 16, .branching = 0.6, .prismatic = 0.2, .ball = 0.15, .helical = 0.1}},
    {"free_tree12", {.n = 12, .branching = 0.5, .prismatic = 0.2, .ball = 0.1, .free_root = true}},
};

class Prescribed : public ::testing::TestWithParam<TreeCase> {};

TEST_P(Prescribed, LoggedMotionSatisfiesInverseDynamicsAndTheBooksBalance) {
  const TreeCase& c = GetParam();
  for (const Method method : {Method::CvodeAdams, Method::CvodeBdf}) {
    Scenario sc = random_scene(c.options.n * 7 + int(method), c.options, 0.4);
    ASSERT_FALSE(sc.inputs.prescribed.empty());
    sc.simulation.method = method;
    std::vector<Sample> samples;
    const RunSummary r = simulate(sc, sc.simulation, nullptr, &samples);
    ASSERT_TRUE(r.completed) << r.status;
    const Model& m = sc.model;
    Data data(m);
    for (const Sample& s : samples) {
      // τ = the inputs' on every joint, plus the prescribed joints' holding torques
      VecX tau(m.nv);
      sc.inputs.evaluate(s.t, s.q, s.qd, tau);
      for (size_t j = 0; j < sc.inputs.prescribed.size(); ++j) {
        const PrescribedInput& p = sc.inputs.prescribed[j];
        tau(p.dof) += s.prescribed_torque(Eigen::Index(j));
        EXPECT_NEAR(s.q(p.coord), p.target.value(s.t), 1e-14);
        EXPECT_NEAR(s.qd(p.dof), p.target.rate(s.t), 1e-14);
        EXPECT_NEAR(s.qdd(p.dof), p.target.acceleration(s.t), 1e-14);
      }
      const VecX id = inverse_dynamics(m, data, s.q, s.qd, s.qdd);
      EXPECT_TRUE(near_rel(id, tau, 1e-9)) << c.name << " t = " << s.t;
    }
    EXPECT_LE(r.max_energy_balance_error, 1e-8) << c.name << " " << to_string(method);
    // the prescribed joints do work: the balance needs W_p
    EXPECT_GT(std::abs(samples.back().work_prescribed), 1e-4);
  }
}

TEST_P(Prescribed, TheLoggedTorquesDriveTheWholeModelAlongTheSameMotion) {
  const TreeCase& c = GetParam();
  Scenario sc = random_scene(c.options.n * 11, c.options, 0.35);
  sc.simulation.output_dt = 0.002;
  std::vector<Sample> samples;
  ASSERT_TRUE(simulate(sc, sc.simulation, nullptr, &samples).completed);
  // the prescribed torques as splines through the log, added on a model whose every joint is free
  const auto T = Eigen::Index(samples.size());
  VecX t(T);
  std::vector<std::shared_ptr<CubicSpline>> spline;
  for (Eigen::Index k = 0; k < T; ++k) t(k) = samples[size_t(k)].t;
  for (size_t j = 0; j < sc.inputs.prescribed.size(); ++j) {
    VecX y(T);
    for (Eigen::Index k = 0; k < T; ++k) y(k) = samples[size_t(k)].prescribed_torque(Eigen::Index(j));
    spline.push_back(std::make_shared<CubicSpline>(t, y));
  }
  Scenario free = sc;
  free.inputs.prescribed.clear();
  free.q0 = samples.front().q, free.v0 = samples.front().qd;
  ControlFunction drive = [&](double time, const VecX&, const VecX&, Eigen::Ref<VecX> tau) {
    for (size_t j = 0; j < sc.inputs.prescribed.size(); ++j) tau(sc.inputs.prescribed[j].dof) += spline[j]->value(time);
  };
  std::vector<Sample> replay;
  ASSERT_TRUE(simulate(free, free.simulation, nullptr, &replay, nullptr, {}, drive).completed);
  ASSERT_EQ(replay.size(), samples.size());
  double worst = 0;
  for (size_t k = 0; k < samples.size(); ++k) worst = std::max(worst, (replay[k].q - samples[k].q).cwiseAbs().maxCoeff());
  // the splines through samples 2 ms apart and the two runs' tolerances (chain8: 1.2e-6)
  EXPECT_LT(worst, 5e-6) << c.name;
}

INSTANTIATE_TEST_SUITE_P(RandomTrees, Prescribed, ::testing::ValuesIn(kCases),
                         [](const auto& info) { return std::string(info.param.name); });

// every method steps the free joints' state: each agrees with a tight CVODE run
TEST(PrescribedMethods, EveryMethodFollowsTheReference) {
  Scenario sc = random_scene(42, {.n = 7, .branching = 0.3, .prismatic = 0.3, .ball = 0.15}, 0.4);
  sc.simulation.t_end = 0.5;
  sc.simulation.output_dt = 0.1;
  std::vector<Sample> ref;
  ASSERT_TRUE(simulate(sc, sc.simulation, nullptr, &ref).completed);
  const std::pair<Method, double> methods[] = {{Method::Rk4, 1e-6},
                                               {Method::ImplicitMidpoint, 1e-3},
                                               {Method::SemiImplicitEuler, 2e-2},
                                               {Method::Euler, 5e-2},
                                               {Method::CvodeBdf, 1e-6}};
  for (const auto& [method, tol] : methods) {
    SimulationSettings s = sc.simulation;
    s.method = method;
    s.dt = 1e-3;
    s.rtol = 1e-9, s.atol = 1e-9;
    std::vector<Sample> out;
    const RunSummary r = simulate(sc, s, nullptr, &out);
    ASSERT_TRUE(r.completed) << to_string(method) << ": " << r.status;
    ASSERT_EQ(out.size(), ref.size());
    EXPECT_LT((out.back().q - ref.back().q).cwiseAbs().maxCoeff(), tol) << to_string(method);
  }
}

// symplectic-euler on a chain without quaternions: order 1 against the reference, its energy
// books (W_p from the holding impulses) closing as h → 0
TEST(PrescribedMethods, SymplecticEulerConvergesAtOrderOne) {
  Scenario sc = random_scene(43, {.n = 5, .branching = 0.0, .prismatic = 0.3}, 0.5);
  ASSERT_FALSE(sc.inputs.prescribed.empty());
  sc.simulation.t_end = 0.5;
  sc.simulation.output_dt = 0.1;
  std::vector<Sample> ref;
  ASSERT_TRUE(simulate(sc, sc.simulation, nullptr, &ref).completed);
  double error[2], books[2];
  for (int k = 0; k < 2; ++k) {
    SimulationSettings s = sc.simulation;
    s.method = Method::SymplecticEuler;
    s.dt = k == 0 ? 2e-3 : 1e-3;
    std::vector<Sample> out;
    const RunSummary r = simulate(sc, s, nullptr, &out);
    ASSERT_TRUE(r.completed) << r.status;
    error[k] = (out.back().q - ref.back().q).cwiseAbs().maxCoeff();
    books[k] = r.max_energy_balance_error;
  }
  EXPECT_NEAR(std::log2(error[0] / error[1]), 1.0, 0.3) << error[0] << " " << error[1];
  EXPECT_NEAR(std::log2(books[0] / books[1]), 1.0, 0.4) << books[0] << " " << books[1];
}

// (q_f, p_f) at t0 ↦ (q_f, p_f) at t0 + h by one step of `method`, p_f = (𝓜(q) v)_f with the
// prescribed joints at their motion
VecX canonical_step(const Scenario& sc, Method method, double t0, double h, const VecX& x) {
  const Model& m = sc.model;
  System sys(m, sc.inputs, FdMethod::Sparse);
  const int n = sys.nv_state();
  const std::vector<int>& fv = sys.v_index();
  Data d(m);
  // v_f from p_f: 𝓜_ff v_f = p_f − 𝓜_fp q̇*
  VecX y = VecX::Zero(sys.size());
  y.head(n) = x.head(n);
  sys.expand(t0, y.data());
  update_kinematics(m, d, sys.q);
  mass_matrix(m, d);
  const VecX given = sys.v;  // the free entries are zero
  y.segment(n, n) = d.M(fv, fv).ldlt().solve(x.tail(n) - (d.M * given)(fv));
  SimulationSettings s;
  s.method = method;
  s.dt = h;
  double t = t0;
  make_integrator(s.method, sys, s, t, y)->advance(t0 + h, t, y);
  sys.expand(t0 + h, y.data());
  update_kinematics(m, d, sys.q);
  mass_matrix(m, d);
  VecX out(2 * n);
  out << y.head(n), (d.M * sys.v)(fv);
  return out;
}

// with given motion the free coordinates' flow is that of a time-dependent Hamiltonian, and
// symplectic-euler's step map keeps Dφᵀ Ω Dφ = Ω in (q_f, p_f) (central differences); the update in
// velocities misses it by O(h)
TEST(PrescribedMethods, SymplecticEulerKeepsTheSymplecticFormOfTheFreeCoordinates) {
  int tried = 0;
  for (int seed = 0; tried < 3; ++seed) {
    ASSERT_LT(seed, 50);
    Scenario sc = random_scene(500 + seed, {.n = 5, .branching = 0.4, .prismatic = 0.3}, 0.4, false);
    if (sc.inputs.prescribed.empty() || int(sc.inputs.prescribed.size()) == sc.model.nv) continue;  // both kinds wanted
    ++tried;
    System sys(sc.model, sc.inputs, FdMethod::Sparse);
    const int n = sys.nv_state();
    Rng rng(seed);
    VecX x(2 * n);
    for (int k = 0; k < 2 * n; ++k) x(k) = rng.uniform(-0.5, 0.5);
    const auto defect = [&](Method method) {
      MatX D(2 * n, 2 * n);
      for (int c = 0; c < 2 * n; ++c) {
        VecX a = x, b = x;
        a(c) += 1e-5, b(c) -= 1e-5;
        D.col(c) = (canonical_step(sc, method, 0.3, 0.02, a) - canonical_step(sc, method, 0.3, 0.02, b)) / 2e-5;
      }
      MatX omega = MatX::Zero(2 * n, 2 * n);
      omega.topRightCorner(n, n).setIdentity();
      omega.bottomLeftCorner(n, n) = -MatX::Identity(n, n);
      return (D.transpose() * omega * D - omega).cwiseAbs().maxCoeff();
    };
    EXPECT_LE(defect(Method::SymplecticEuler), 1e-7) << "seed " << seed;
    EXPECT_GE(defect(Method::SemiImplicitEuler), 1e-4) << "seed " << seed;
  }
}

// ∂f/∂y of the free joints' state, analytic against forward differences of rhs
TEST(PrescribedSystem, AnalyticJacobianMatchesDifferences) {
  for (int seed = 0; seed < 3; ++seed) {
    const Scenario sc = random_scene(300 + seed, {.n = 9, .branching = 0.5, .prismatic = 0.3, .ball = 0.2, .free_root = seed == 2}, 0.4);
    System sys(sc.model, sc.inputs, FdMethod::ArticulatedBody);
    ASSERT_TRUE(sys.has_prescribed());
    EXPECT_EQ(sys.nv_state(), sc.model.nv - int(sc.inputs.prescribed.size()));
    const VecX y = sys.state(sc.q0, sc.v0);
    MatX A(sys.size(), sys.size()), D(sys.size(), sys.size());
    sys.jacobian(0.3, y.data(), A);
    sys.jacobian_dq(0.3, y.data(), D);
    // the q̇ and q̈ rows (W_p's row is left out of the analytic one)
    const int n = sys.nq_state() + sys.nv_state();
    EXPECT_TRUE(near_rel(A.topLeftCorner(n, n), D.topLeftCorner(n, n), 2e-5)) << "seed " << seed;
  }
}

// a free-floating base with an appendage slewed by a prescribed joint: no external force or
// torque, so its linear and angular momentum stay as they started
TEST(PrescribedSystem, AFreeBaseKeepsItsMomentumAcrossASlew) {
  Rng rng(5);
  Scenario sc;
  sc.model = random_model(rng, {.n = 5, .branching = 0.0, .free_root = true, .gravity = Vec3::Zero()});
  sc.q0 = sc.model.neutral_configuration();
  sc.v0 = VecX::Zero(sc.model.nv);
  sc.v0.head(6) << 0.01, -0.02, 0.015, 0.0, 0.0, 0.0;
  PrescribedInput p;
  p.body = 2, p.joint = sc.model.joint_names[2], p.dof = sc.model.idx_v[2], p.coord = sc.model.idx_q[2];
  p.target.slew = std::make_shared<JointSlew>(JointSlew{0.0, std::numbers::pi / 2, 0.5, 2.0});
  sc.inputs.prescribed.push_back(p);
  sc.simulation.t_end = 3.0, sc.simulation.output_dt = 0.1;
  // the invariant is not linear in the state (L = f(q) v): the integrator's error moves it, by less
  // as the tolerance tightens (rtol 1e-8: 2e-5 of L₀, 1e-10: 7e-7, 1e-12: 9e-10)
  sc.simulation.rtol = 1e-12, sc.simulation.atol = 1e-12;
  std::vector<Sample> out;
  ASSERT_TRUE(simulate(sc, sc.simulation, nullptr, &out).completed);
  double worst = 0, scale = std::max(out.front().angular.norm(), 1e-3);
  for (const Sample& s : out) worst = std::max(worst, (s.angular - out.front().angular).norm() / scale);
  EXPECT_LE(worst, 5e-9);
  EXPECT_LE((out.back().linear - out.front().linear).norm(), 1e-9);
  EXPECT_NEAR(out.back().q(p.coord), std::numbers::pi / 2, 1e-15);
  // the base turned in reaction
  EXPECT_GT((out.back().q.segment<4>(3) - out.front().q.segment<4>(3)).norm(), 1e-3);
}

TEST(Slew, ClosedFormAndRestAtBothEnds) {
  JointTarget r;
  r.slew = std::make_shared<JointSlew>(JointSlew{0.2, 1.7, 1.0, 4.0});
  const double D = 1.5, T = 4.0;
  for (const double t : {0.0, 1.0, 1.7, 3.0, 4.2, 5.0, 6.0}) {
    const double s = std::clamp((t - 1.0) / T, 0.0, 1.0);
    EXPECT_NEAR(r.value(t), 0.2 + D * (10 * std::pow(s, 3) - 15 * std::pow(s, 4) + 6 * std::pow(s, 5)), 1e-15);
    const double h = 1e-5;
    if (t > 1.0 && t < 5.0) {
      EXPECT_NEAR(r.rate(t), (r.value(t + h) - r.value(t - h)) / (2 * h), 1e-8);
      EXPECT_NEAR(r.acceleration(t), (r.rate(t + h) - r.rate(t - h)) / (2 * h), 1e-8);
    }
  }
  for (const double t : {1.0, 5.0}) {
    EXPECT_EQ(r.rate(t), 0.0);
    EXPECT_EQ(r.acceleration(t), 0.0);
  }
  EXPECT_EQ(r.value(0.0), 0.2);
  EXPECT_EQ(r.value(9.0), 1.7);
  EXPECT_NEAR(r.rate(3.0), D / T * 30 / 16, 1e-15);  // the peak rate, at the middle: 15/8 Δ/T
}

}  // namespace

namespace {
// a shoulder driven by a sine about z, a passive elbow whose travel is ±0.25 rad, and a wrist:
// the elbow swings into its stops
Scenario elbow_in_its_stops(double restitution) {
  std::vector<BodySpec> b(3);
  const char* names[] = {"upper", "fore", "hand"};
  for (int i = 0; i < 3; ++i) {
    b[size_t(i)].name = names[i];
    b[size_t(i)].parent = i - 1;
    b[size_t(i)].mass = 1.0 - 0.2 * i;
    b[size_t(i)].com = Vec3(0.25, 0, 0);
    b[size_t(i)].inertia = Vec3(0.01, 0.03, 0.03).asDiagonal();
    if (i > 0) b[size_t(i)].placement.p = Vec3(0.5, 0, 0);
  }
  b[1].lower = -0.25, b[1].upper = 0.25;
  b[2].axis = Vec3::UnitY();
  Scenario sc;
  sc.model = Model::build(b, Vec3(0, 0, -9.81));
  sc.q0 = VecX::Zero(3);
  sc.v0 = VecX::Zero(3);
  PrescribedInput p;
  p.joint = "upper", p.body = 0, p.dof = 0, p.coord = 0;
  p.target.amplitude = 0.8, p.target.frequency = 0.7;
  sc.inputs.prescribed.push_back(p);
  sc.v0(0) = p.target.rate(0.0);
  sc.simulation.t_end = 3.0;
  sc.simulation.output_dt = 0.01;
  sc.simulation.rtol = 1e-10, sc.simulation.atol = 1e-12;
  sc.simulation.limits = true;
  sc.simulation.restitution = restitution;
  return sc;
}
}  // namespace

// limits enforced on the free joints while others are prescribed: the elbow stays in its travel,
// hits its stops (its velocity jumps, the shoulder's does not), and the books balance with the
// impacts' loss and the work of the shoulder's impulses in W_p
TEST(PrescribedLimits, TheFreeJointsStopsHoldWhileTheShoulderIsDriven) {
  for (const double e : {0.6, 0.0}) {
    const Scenario sc = elbow_in_its_stops(e);
    check_run(sc, sc.simulation);
    std::vector<Sample> out;
    const RunSummary r = simulate(sc, sc.simulation, nullptr, &out);
    ASSERT_TRUE(r.completed) << r.status;
    ASSERT_GE(r.events.size(), 2u) << "restitution " << e;
    for (const LimitEvent& ev : r.events) EXPECT_EQ(ev.joint, "fore");
    for (const Sample& s : out) {
      EXPECT_LE(std::abs(s.q(1)), 0.25 + 1e-8) << "t = " << s.t;
      EXPECT_NEAR(s.q(0), sc.inputs.prescribed[0].target.value(s.t), 1e-14);
      EXPECT_NEAR(s.qd(0), sc.inputs.prescribed[0].target.rate(s.t), 1e-14);
    }
    EXPECT_GT(out.back().impact_loss, 0.0) << "restitution " << e;
    EXPECT_LE(r.max_energy_balance_error, 1e-8) << "restitution " << e;
    if (e == 0.0) {
      const bool held = std::any_of(r.events.begin(), r.events.end(), [](const LimitEvent& ev) { return ev.kind == "hold"; });
      EXPECT_TRUE(held);
    }
  }
}

// the limits of a prescribed joint, enforced, are refused at its line; a free joint's are taken
TEST(PrescribedLimits, APrescribedJointWithLimitsIsRefused) {
  Scenario sc = elbow_in_its_stops(0.5);
  sc.model = [&] {
    Model m = sc.model;
    m.lower[0] = -1.0, m.upper[0] = 1.0;
    return m;
  }();
  EXPECT_NE(message_of([&] { check_run(sc, sc.simulation); }).find("prescribed: joint 'upper' has limits"), std::string::npos);
  sc.simulation.limits = false;
  EXPECT_EQ(message_of([&] { check_run(sc, sc.simulation); }), "(no error)");
}
