// Inertial-parameter identification (identify.hpp) on the note's three-link arm driven by three
// sine torques (a run made with known parameters): the scene perturbed by ±30 % and fitted back by
// least squares and by Gauss–Newton; the unidentifiable directions against the regressor at other
// states (structural: Y n = 0 for every motion) and the turret's closed form (it turns about z
// alone, so of its ten parameters only Izz acts); seeded Gaussian noise on the torques against
// the reported standard errors; the fitted scene's text loaded back; the refusals.
#include "soadyn/sim/identify.hpp"
#include "soadyn/io/scenario_file.hpp"

#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/io/output_file.hpp"
#include "soadyn/algorithm/regressor.hpp"
#include "soadyn/sim/simulate.hpp"
#include "test_util.hpp"

#include <cmath>
#include <random>

using namespace soadyn;
using namespace soadyn::test;
using ::testing::HasSubstr;

namespace {

const char* kArm = R"(name: driven_three_link_arm
gravity: [0, 0, -9.81]
bodies:
  - name: turret
    joint: {type: revolute, name: theta1, axis: [0, 0, 1]}
    mass: 5.0
    com: [0.02, -0.01, 0.1]
    inertia: [0.05, 0.05, 0.04]
  - name: upper_arm
    parent: turret
    joint: {type: revolute, name: theta2, axis: [1, 0, 0]}
    origin: {xyz: [0, 0, 0.2]}
    mass: 2.0
    com: [0.01, 0.02, 0.4]
    inertia: {ixx: 0.107, iyy: 0.105, izz: 0.006, ixy: 0.001, ixz: 0.002, iyz: -0.001}
  - name: forearm
    parent: upper_arm
    joint: {type: revolute, name: theta3, axis: [1, 0, 0]}
    origin: {xyz: [0, 0, 0.8]}
    mass: 1.0
    com: [0.015, -0.01, 0.35]
    inertia: {ixx: 0.041, iyy: 0.040, izz: 0.006, ixy: 0.0005, ixz: -0.001, iyz: 0.0008}
initial:
  q: {theta1: 0.3, theta2: 0.5, theta3: -0.4}
  qd: {theta1: 1.0}
inputs:
  torques:
    - {joint: theta1, amplitude: 3.0, frequency: 0.31, phase: 0.2}
    - {joint: theta1, amplitude: 1.0, frequency: 1.13}
    - {joint: theta2, constant: 10.0, amplitude: 12.0, frequency: 0.47, phase: 1.0}
    - {joint: theta3, constant: 2.0, amplitude: 4.0, frequency: 0.83}
simulation:
  t_end: 4.0
  output_dt: 0.01
  method: cvode-adams
  rtol: 1.0e-11
  atol: 1.0e-13
)";

Scenario arm() { return parse_scenario(kArm, "driven_three_link_arm.yaml"); }

// the run's samples as measurements (q̈ dropped for Gauss–Newton)
Measurements measure(const Scenario& sc, bool with_qdd, double t_end = 4.0) {
  SimulationSettings s = sc.simulation;
  s.t_end = t_end;
  std::vector<Sample> samples;
  const RunSummary r = simulate(sc, s, nullptr, &samples);
  EXPECT_TRUE(r.completed) << r.status;
  const Eigen::Index T = Eigen::Index(samples.size());
  Measurements d;
  d.path = "<run>";
  d.t.resize(T);
  d.q.resize(T, sc.model.nq);
  d.v.resize(T, sc.model.nv);
  if (with_qdd) d.qdd.resize(T, sc.model.nv);
  for (Eigen::Index k = 0; k < T; ++k) {
    const Sample& x = samples[size_t(k)];
    d.t(k) = x.t;
    d.q.row(k) = x.q.transpose();
    d.v.row(k) = x.qd.transpose();
    if (with_qdd) d.qdd.row(k) = x.qdd.transpose();
  }
  return d;
}

// the scene with the bodies' masses 30 % up (centres of mass kept) and their inertias about the
// centre of mass 30 % down: still rigid bodies, every parameter off
Scenario perturbed(const Scenario& truth, const std::vector<std::string>& bodies) {
  Scenario sc = truth;
  VecX pi = parameters(truth.model);
  for (const auto& name : bodies) {
    const int i = truth.model.body_index(name);
    const double m = 1.3 * truth.model.mass[i];
    const Vec3 c = truth.model.com[i];
    const Mat3 Io = 0.7 * truth.model.inertia[i] + parallel_axis(m, c);
    pi.segment<10>(10 * i) << m, m * c.x(), m * c.y(), m * c.z(), Io(0, 0), Io(0, 1), Io(1, 1), Io(0, 2), Io(1, 2), Io(2, 2);
  }
  sc.model = with_parameters(truth.model, pi);
  return sc;
}

// π of `bodies` in model order
VecX truth_of(const Model& m, const IdentifyResult& r) {
  const VecX pi = parameters(m);
  VecX out(r.fitted.size());
  for (size_t k = 0; k < r.bodies.size(); ++k) out.segment<10>(10 * Eigen::Index(k)) = pi.segment<10>(10 * r.bodies[k]);
  return out;
}

// parameters with no component along any unidentifiable direction: identifiable one by one
std::vector<int> identifiable_alone(const IdentifyResult& r) {
  std::vector<int> out;
  for (Eigen::Index j = 0; j < r.fitted.size(); ++j)
    if (r.unidentifiable.cols() == 0 || r.unidentifiable.row(j).cwiseAbs().maxCoeff() < 1e-12) out.push_back(int(j));
  return out;
}

// ‖Y_S n‖ / (‖Y_S‖ ‖n‖) of every reported direction at random states: zero for a structural null space
double worst_null_residual(const Model& m, const IdentifyResult& r) {
  Rng rng(17);
  Data data(m);
  MatX Y;
  double worst = 0.0;
  for (int trial = 0; trial < 20; ++trial) {
    const VecX q = random_q(rng, m), v = random_v(rng, m, 2.0), qdd = random_v(rng, m, 3.0);
    update_kinematics(m, data, q);
    update_velocities(m, data, v);
    regressor(m, data, qdd, Y);
    MatX YS(m.nv, r.fitted.size());
    for (size_t k = 0; k < r.bodies.size(); ++k) YS.middleCols(10 * Eigen::Index(k), 10) = Y.middleCols(10 * r.bodies[k], 10);
    for (Eigen::Index c = 0; c < r.unidentifiable.cols(); ++c)
      worst = std::max(worst, (YS * r.unidentifiable.col(c)).norm() / (YS.norm() * r.unidentifiable.col(c).norm()));
  }
  return worst;
}

void expect_recovered(const IdentifyResult& r, const VecX& truth, double tol, const char* what) {
  const std::vector<int> alone = identifiable_alone(r);
  ASSERT_FALSE(alone.empty());
  double worst = 0.0;
  for (int j : alone) worst = std::max(worst, std::abs(r.fitted(j) - truth(j)) / std::max(1e-3, std::abs(truth(j))));
  EXPECT_LE(worst, tol) << what;
  std::printf("%s: %zu of %lld parameters identifiable alone, rank %d, worst relative error %.3g\n", what, alone.size(),
              static_cast<long long>(truth.size()), r.rank, worst);
}

}  // namespace

TEST(Identify, LeastSquaresRecoversThePerturbedForearm) {
  // given the turret and the upper arm, all ten of the forearm's parameters act on the torques
  const Scenario truth = arm();
  const Measurements d = measure(truth, true);
  IdentifyOptions o;
  o.bodies = {"forearm"};
  const IdentifyResult r = identify(perturbed(truth, o.bodies), d, o);
  EXPECT_EQ(r.method, "least-squares");
  EXPECT_EQ(r.rows, 3 * int(d.t.size()));
  EXPECT_EQ(r.rank, 10);
  EXPECT_EQ(r.unidentifiable.cols(), 0);
  expect_recovered(r, truth_of(truth.model, r), 1e-6, "least squares, forearm +-30 %");
  EXPECT_LE(r.rms_fitted, 1e-8);
  EXPECT_GT(r.rms_prior, 0.1);
  // the fitted model's torques along the run are the truth's
  Data a(truth.model), b(r.model);
  for (Eigen::Index k = 0; k < d.t.size(); k += 37) {
    const VecX q = d.q.row(k).transpose(), v = d.v.row(k).transpose(), qdd = d.qdd.row(k).transpose();
    update_kinematics(truth.model, a, q);
    update_velocities(truth.model, a, v);
    update_kinematics(r.model, b, q);
    update_velocities(r.model, b, v);
    inverse_dynamics(truth.model, a, qdd);
    inverse_dynamics(r.model, b, qdd);
    EXPECT_TRUE(near_rel(b.tau, a.tau, 1e-8)) << k;
  }
}

TEST(Identify, TheWholeArmHasFifteenBaseParameters) {
  // all 30: the turret's 9 besides Izz, the upper arm's m and m c_x (its centre of mass moves in
  // the plane through the hinge only with the forearm's hinge point), and three combinations of
  // the two links (the classical regrouping): 15 directions, each Y n = 0 at any state
  const Scenario truth = arm();
  const Measurements d = measure(truth, true);
  IdentifyOptions o;
  o.bodies = {"all"};
  const IdentifyResult r = identify(truth, d, o);
  EXPECT_EQ(r.rank, 15);
  ASSERT_EQ(r.unidentifiable.cols(), 15);
  EXPECT_LE(worst_null_residual(truth.model, r), 1e-12);
  std::vector<std::string> alone;
  for (int k = 0; k < 15; ++k) alone.push_back(describe_direction(r, k));
  EXPECT_THAT(alone, ::testing::Contains("upper_arm.m"));
  EXPECT_THAT(alone, ::testing::Contains("upper_arm.mcx"));
  EXPECT_THAT(alone, ::testing::Contains("turret.Ixx"));
  EXPECT_THAT(alone, ::testing::Not(::testing::Contains("turret.Izz")));
  // nothing to fit at the truth: the fit is the scene to round-off
  EXPECT_TRUE(near_rel(r.fitted, r.prior, 1e-12));
  // the tolerance is far from the spectrum's gap: the smallest kept σ and the largest dropped one
  EXPECT_GT(r.singular_values(14) / r.singular_values(0), 1e-3);
  EXPECT_LT(r.singular_values(15) / r.singular_values(0), 1e-14);
  std::printf("whole arm: rank %d of 30, smallest kept singular value %.3g, largest dropped %.3g (relative)\n", r.rank,
              r.singular_values(14) / r.singular_values(0), r.singular_values(15) / r.singular_values(0));
}

TEST(Identify, TheTurretShowsOnlyItsInertiaAboutZ) {
  // turning about the fixed z axis through its origin, the turret's torque is Izz θ̈₁ whatever its
  // other nine parameters: rank 1, nine directions, each without Izz, held at the scene's values
  const Scenario truth = arm();
  const Measurements d = measure(truth, true, 2.0);
  Scenario start = perturbed(truth, {"turret"});
  IdentifyOptions o;
  o.bodies = {"turret"};
  const IdentifyResult r = identify(start, d, o);
  EXPECT_EQ(r.rank, 1);
  ASSERT_EQ(r.unidentifiable.cols(), 9);
  EXPECT_EQ(r.unidentifiable.row(9).cwiseAbs().maxCoeff(), 0.0);  // Izz in no direction
  for (int j = 0; j < 9; ++j) EXPECT_EQ(describe_direction(r, j), r.names[size_t(j)]);  // each parameter alone
  const VecX pi = truth_of(truth.model, r), prior = truth_of(start.model, r);
  EXPECT_NEAR(r.fitted(9), pi(9), 1e-8 * pi(9));
  EXPECT_TRUE(near_rel(r.fitted.head(9), prior.head(9), 1e-12));  // not fitted to anything
  EXPECT_GT(r.standard_error(9), 0.0);
}

TEST(Identify, NoiseOnTheTorquesStaysWithinThreeStandardErrors) {
  const Scenario truth = arm();
  Measurements d = measure(truth, true);
  const double sigma = 0.05;  // N m
  std::mt19937_64 gen(20261206);
  std::normal_distribution<double> noise(0.0, sigma);
  d.tau.resize(d.t.size(), truth.model.nv);
  for (Eigen::Index k = 0; k < d.t.size(); ++k) {
    VecX tau(truth.model.nv);
    truth.inputs.evaluate(d.t(k), d.q.row(k).transpose(), d.v.row(k).transpose(), tau);
    for (int j = 0; j < truth.model.nv; ++j) d.tau(k, j) = tau(j) + noise(gen);
  }
  IdentifyOptions o;
  o.bodies = {"upper_arm", "forearm"};
  const IdentifyResult r = identify(truth, d, o);
  const VecX pi = truth_of(truth.model, r);
  EXPECT_EQ(r.rank, 15);
  EXPECT_NEAR(std::sqrt(r.sigma2), sigma, 0.1 * sigma);
  double worst = 0.0;
  const std::vector<int> alone = identifiable_alone(r);
  EXPECT_EQ(alone.size(), 9u);
  for (int j : alone) {
    ASSERT_GT(r.standard_error(j), 0.0);
    worst = std::max(worst, std::abs(r.fitted(j) - pi(j)) / r.standard_error(j));
  }
  EXPECT_LE(worst, 3.0);
  std::printf("noise sigma %g: estimated %.4g; %zu parameters identifiable alone, worst |fit - truth| / standard error %.3g\n",
              sigma, std::sqrt(r.sigma2), alone.size(), worst);
}

TEST(Identify, GaussNewtonOnTheTrajectoryRecoversTheForearm) {
  const Scenario truth = arm();
  const Measurements d = measure(truth, false, 2.0);
  IdentifyOptions o;
  o.bodies = {"forearm"};
  const IdentifyResult r = identify(perturbed(truth, o.bodies), d, o);
  EXPECT_EQ(r.method, "gauss-newton");
  EXPECT_GE(r.iterations, 1);
  EXPECT_LE(r.iterations, o.max_iterations);
  expect_recovered(r, truth_of(truth.model, r), 1e-6, "gauss-newton, ±30 %");
  EXPECT_LE(worst_null_residual(truth.model, r), 1e-8);
  EXPECT_LE(r.rms_fitted, 1e-8);
}

TEST(Identify, TheFittedSceneLoadsTheFittedValues) {
  const Scenario truth = arm();
  const Measurements d = measure(truth, true, 2.0);
  IdentifyOptions o;
  o.bodies = {"forearm"};
  const Scenario start = perturbed(truth, o.bodies);
  const IdentifyResult r = identify(start, d, o);
  const std::string text = fitted_scenario_text(start, r, "fitted.yaml");
  EXPECT_EQ(text.rfind(kFittedScenarioHeader, 0), 0u);
  const Scenario back = parse_scenario(text, "fitted.yaml");
  const int i = back.model.body_index("forearm");
  EXPECT_EQ(back.model.mass[i], r.model.mass[i]);
  EXPECT_TRUE(near_rel(parameters(back.model), parameters(r.model), 1e-14));
  EXPECT_EQ(back.q0, start.q0);
  EXPECT_EQ(back.inputs.torques.size(), start.inputs.torques.size());
}

TEST(Identify, Refusals) {
  const Scenario sc = arm();
  const Measurements d = measure(sc, true, 0.5);
  const auto message = [&](const Scenario& s, const Measurements& m, const IdentifyOptions& o) {
    try {
      identify(s, m, o);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  IdentifyOptions o;
  o.bodies = {"forarm"};
  EXPECT_THAT(message(sc, d, o), HasSubstr("no body named 'forarm'; did you mean 'forearm'?"));
  o.bodies = {};
  EXPECT_THAT(message(sc, d, o), HasSubstr("expected the bodies to fit"));
  o.bodies = {"forearm"};
  Measurements short_q = d;
  short_q.q.conservativeResize(Eigen::NoChange, 2);
  EXPECT_THAT(message(sc, short_q, o), HasSubstr("q: expected"));
  Measurements no_qdd = d;
  no_qdd.qdd.resize(0, 0);
  o.method = IdentifyMethod::LeastSquares;
  EXPECT_THAT(message(sc, no_qdd, o), HasSubstr("least squares needs the accelerations (/qdd)"));
  // torques of the other sign: the fit is a negative mass, refused naming the body
  Measurements negative = d;
  negative.tau.resize(d.t.size(), 3);
  for (Eigen::Index k = 0; k < d.t.size(); ++k) {
    VecX tau(3);
    sc.inputs.evaluate(d.t(k), d.q.row(k).transpose(), d.v.row(k).transpose(), tau);
    negative.tau.row(k) = -tau.transpose();
  }
  o.bodies = {"all"};
  EXPECT_THAT(message(sc, negative, o), HasSubstr("the fit is no rigid body: body '"));
  // a controller's torques are not in the data
  std::string with_controller = kArm;
  with_controller.insert(with_controller.find("simulation:"), "  controllers:\n    - {type: gravity_compensation}\n");
  Scenario controlled = parse_scenario(with_controller, "c.yaml");
  EXPECT_THAT(message(controlled, d, o), HasSubstr("controllers"));
  // Gauss–Newton needs a run's output grid
  Measurements jittered = d;
  jittered.t(3) += 1e-4;
  o.method = IdentifyMethod::GaussNewton;
  EXPECT_THAT(message(sc, jittered, o), HasSubstr("expected samples at t_0 + k"));
}

TEST(Identify, TheInertialKeyOverridesABodyAndRefusesWhatIsNoBody) {
  // the forearm's values as the bodies: section would give them, over any body's (here the scene's own)
  const std::string over = "inertial:\n  forearm: {mass: 1.3, com: [0.01, 0.02, 0.3], inertia: {ixx: 0.03, iyy: 0.029, izz: 0.004, ixy: 0.001}}\n";
  const Scenario sc = parse_scenario(std::string(kArm) + over, "over.yaml");
  std::string inline_body = kArm;
  const size_t at = inline_body.find("    mass: 1.0\n    com: [0.015");
  inline_body.replace(at, inline_body.find("initial:") - at,
                      "    mass: 1.3\n    com: [0.01, 0.02, 0.3]\n    inertia: {ixx: 0.03, iyy: 0.029, izz: 0.004, ixy: 0.001}\n");
  const Scenario ref = parse_scenario(inline_body, "inline.yaml");
  const int i = ref.model.body_index("forearm");
  EXPECT_EQ(sc.model.mass[i], ref.model.mass[i]);
  EXPECT_EQ(sc.model.com[i], ref.model.com[i]);
  EXPECT_EQ(sc.model.inertia[i], ref.model.inertia[i]);
  EXPECT_EQ(sc.model.inertia_origin[i], ref.model.inertia_origin[i]);  // the same arithmetic as build's
  const auto refusal = [&](const std::string& entry) {
    try {
      parse_scenario(std::string(kArm) + "inertial:\n  " + entry + "\n", "bad.yaml");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_THAT(refusal("forarm: {mass: 1, com: [0, 0, 0], inertia: [1, 1, 1]}"), HasSubstr("bad.yaml:39:3: inertial: no body named 'forarm'"));
  EXPECT_THAT(refusal("forearm: {mass: -1, com: [0, 0, 0], inertia: [1, 1, 1]}"), HasSubstr("inertial.forearm.mass: expected a positive number"));
  EXPECT_THAT(refusal("forearm: {mass: 1, com: [0, 0, 0], inertia: [1, 1, 3]}"),
              HasSubstr("inertial.forearm: body 'forearm': inertia about the centre of mass: expected principal moments obeying the triangle inequality"));
  EXPECT_THAT(refusal("forearm: {mass: 1, inertia: [1, 1, 1]}"), HasSubstr("inertial.forearm: missing required field 'com'"));
}
