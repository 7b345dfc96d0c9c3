// Forward sensitivities by CVODES (sensitivity.hpp) against independent routes: central differences
// of whole runs (fourth order; x₀ moved along the tangent, π by with_parameters, each rerun at rtol 1e-11)
// on the note's double pendulum, a seeded random chain with springs, dampers and torques, and a
// random tree on a free root; closed forms (a pendulum at rest at the bottom: the linear oscillator's
// cos ωt, sin ωt / ω; a free-falling ball: I, T·I, and no dependence on its parameters); the
// scenario key, its refusals and its HDF5 datasets.
#include "soadyn/sim/sensitivity.hpp"
#include "soadyn/io/scenario_file.hpp"

#include "soadyn/io/h5log.hpp"
#include "soadyn/io/run_file.hpp"
#include "soadyn/sim/simulate.hpp"
#include "test_util.hpp"
#include "whole_run_util.hpp"


#include <cmath>
#include <cstdio>
#include <filesystem>

using namespace soadyn;
using namespace soadyn::test;
using ::testing::HasSubstr;

namespace {

std::vector<Sample> run(const Scenario& sc, const SimulationSettings& s) {
  std::vector<Sample> out;
  const RunSummary r = simulate(sc, s, nullptr, &out);
  EXPECT_TRUE(r.completed) << r.status;
  return out;
}

// x(t) − x'(t) along the tangent, to first order: T(q) (q − q') for the coordinates, v − v'
VecX tangent_difference(const Model& m, const Sample& a, const Sample& b) {
  VecX d(2 * m.nv);
  d.tail(m.nv) = a.qd - b.qd;
  for (int i = 0; i < m.nbodies; ++i) {
    const int iq = m.idx_q[i], iv = m.idx_v[i], mi = m.nq_i[i], ni = m.nv_i[i];
    MatX T(ni, mi);
    joint_tangent_map(m.joint_type[i], a.q.data() + iq, T);
    d.segment(iv, ni) = T * (a.q - b.q).segment(iq, mi);
  }
  return d;
}

// the fourth-order central difference (8 (x(h) − x(−h)) − (x(2h) − x(−2h))) / 12h of whole runs, at
// every output: run(a) is the run with the input moved by a (truncation O(h⁴), so the runs'
// own error, ~rtol / h, is what is left)
template <class Run>
std::vector<VecX> central_difference(const Model& m, double h, Run&& run_at) {
  const std::vector<Sample> p1 = run_at(h), m1 = run_at(-h), p2 = run_at(2 * h), m2 = run_at(-2 * h);
  std::vector<VecX> out;
  for (size_t r = 0; r < p1.size(); ++r)
    out.push_back((8 * tangent_difference(m, p1[r], m1[r]) - tangent_difference(m, p2[r], m2[r])) / (12 * h));
  return out;
}

// ∂x(t)/∂x₀, x₀ moved along the tangent: q₀ ⊕ a e_k, or v₀ + a e_k
std::vector<MatX> differences_initial(const Scenario& sc, const SimulationSettings& s, double h) {
  const Model& m = sc.model;
  SimulationSettings plain = s;
  plain.sensitivities = {};
  std::vector<MatX> out;
  for (int k = 0; k < 2 * m.nv; ++k) {
    const std::vector<VecX> d = central_difference(m, h, [&](double a) {
      Scenario moved = sc;
      if (k < m.nv) moved.q0 = m.integrate(sc.q0, VecX::Unit(m.nv, k), a);
      else moved.v0(k - m.nv) += a;
      return run(moved, plain);
    });
    if (out.empty()) out.assign(d.size(), MatX::Zero(2 * m.nv, 2 * m.nv));
    for (size_t r = 0; r < d.size(); ++r) out[r].col(k) = d[r];
  }
  return out;
}

// ∂x(t)/∂π for the bodies of `plan`, π_j moved by a times its scale (with_parameters)
std::vector<MatX> differences_parameters(const Scenario& sc, const SimulationSettings& s, const SensitivityPlan& plan,
                                         double h) {
  const Model& m = sc.model;
  SimulationSettings plain = s;
  plain.sensitivities = {};
  const VecX pi = parameters(m);
  std::vector<MatX> out;
  for (int c = 0; c < plan.np(); ++c) {
    const int j = kParametersPerBody * plan.bodies[size_t(c / kParametersPerBody)] + c % kParametersPerBody;
    const double scale = std::max(std::abs(pi(j)), 0.1 * std::abs(pi(j - j % kParametersPerBody)));
    const std::vector<VecX> d = central_difference(m, h, [&](double a) {
      Scenario moved = sc;
      VecX p = pi;
      p(j) += a * scale;
      moved.model = with_parameters(m, p);
      return run(moved, plain);
    });
    if (out.empty()) out.assign(d.size(), MatX::Zero(2 * m.nv, plan.np()));
    for (size_t r = 0; r < d.size(); ++r) out[r].col(c) = d[r] / scale;
  }
  return out;
}

// the largest |a − b| over max(1, the largest |b|), over every output
double worst(const std::vector<Sample>& got, const std::vector<MatX>& want, bool initial) {
  double e = 0;
  for (size_t r = 0; r < want.size(); ++r) {
    const MatX& a = initial ? got[r].sensitivity_initial_state : got[r].sensitivity_parameters;
    e = std::max(e, (a - want[r]).cwiseAbs().maxCoeff() / std::max(1.0, want[r].cwiseAbs().maxCoeff()));
  }
  return e;
}

void check_against_differences(const Scenario& sc, SimulationSettings s, double tol) {
  const std::vector<Sample> got = run(sc, s);
  const SensitivityPlan plan = plan_sensitivities(sc.model, s.sensitivities);
  ASSERT_EQ(got.back().sensitivity_initial_state.rows(), 2 * sc.model.nv);
  ASSERT_EQ(got.back().sensitivity_parameters.cols(), plan.np());
  const double h = 1e-3;  // with the fourth-order stencil: truncation ~h⁴, the reruns' error ~1e-11 / h
  const double e0 = worst(got, differences_initial(sc, s, h), true);
  const double ep = worst(got, differences_parameters(sc, s, plan, h), false);
  std::printf("  %s: largest relative difference from central differences: x0 %.1e, pi %.1e\n", std::string(to_string(s.method)).c_str(), e0, ep);
  EXPECT_LT(e0, tol);
  EXPECT_LT(ep, tol);
}

Scenario double_pendulum() {
  Scenario sc = load_scenario(SOADYN_SOURCE_DIR "/scenarios/double_pendulum.yaml");
  return sc;
}

TEST(Sensitivity, DoublePendulumMatchesCentralDifferencesAdams) {
  Scenario sc = double_pendulum();
  SimulationSettings s = tight("cvode-adams", 1.0);
  s.sensitivities = {true, {"all"}};
  check_against_differences(sc, s, 1e-6);
}

// with the LᵀDL route the System's rhs leaves no articulated-body factor, so each linearization makes
// its own (System::linearize) instead of starting from the evaluation CVODES has just made
TEST(Sensitivity, DoublePendulumMatchesCentralDifferencesOnTheSparseRoute) {
  Scenario sc = double_pendulum();
  SimulationSettings s = tight("cvode-adams", 1.0);
  s.dynamics = FdMethod::Sparse;
  s.sensitivities = {true, {"all"}};
  check_against_differences(sc, s, 1e-6);
}

TEST(Sensitivity, DoublePendulumMatchesCentralDifferencesBdf) {
  Scenario sc = double_pendulum();
  SimulationSettings s = tight("cvode-bdf", 1.0);
  s.sensitivities = {true, {"lower"}};
  check_against_differences(sc, s, 1e-6);
}

TEST(Sensitivity, RandomChainWithInputsMatchesCentralDifferences) {
  const Scenario sc = random_chain_with_inputs();
  SimulationSettings s = tight("cvode-adams", 0.8);
  s.sensitivities = {true, {"b1", "b3"}};
  check_against_differences(sc, s, 1e-6);
}

TEST(Sensitivity, FreeRootMatchesCentralDifferencesAlongTheTangent) {
  const Scenario sc = random_free_tree();
  SimulationSettings s = tight("cvode-bdf", 0.6);
  s.sensitivities = {true, {"b0", "b2"}};
  check_against_differences(sc, s, 1e-6);
}

// one hinge about x, the centre of mass c below it: at rest at the bottom the variational equation
// is the linear oscillator's, s̈ = −ω² s, ω² = m g c / (J + m c²)
TEST(Sensitivity, PendulumAtRestIsTheLinearOscillator) {
  const double m = 1.3, c = 0.4, J = 0.02, g = 9.81;
  BodySpec b;
  b.name = "bob";
  b.axis = Vec3::UnitX();
  b.mass = m;
  b.com = Vec3(0, 0, -c);
  b.inertia = Vec3(J, J, 0.01).asDiagonal();
  Scenario sc;
  sc.path = "pendulum";
  sc.model = Model::build({b}, Vec3(0, 0, -g));
  sc.q0 = VecX::Zero(1);
  sc.v0 = VecX::Zero(1);
  SimulationSettings s = tight("cvode-adams", 2.0);
  s.output_dt = 0.1;
  s.sensitivities = {true, {"bob"}};
  const double w = std::sqrt(m * g * c / (J + m * c * c));
  for (const Sample& x : run(sc, s)) {
    const double t = x.t;
    Eigen::Matrix2d want;
    want << std::cos(w * t), std::sin(w * t) / w, -w * std::sin(w * t), std::cos(w * t);
    EXPECT_TRUE(near_rel(x.sensitivity_initial_state, want, 1e-8)) << "t = " << t;
    // m c_y moves the centre of mass sideways: a constant gravity torque −g δ(m c_y) on an
    // oscillator of inertia J + m c², s = b / ω² (1 − cos ωt) with b = −g / (J + m c²)
    const double b_y = -g / (J + m * c * c);
    EXPECT_NEAR(x.sensitivity_parameters(0, 2), b_y / (w * w) * (1 - std::cos(w * t)), 1e-8) << "t = " << t;
    EXPECT_NEAR(x.sensitivity_parameters(0, 0), 0.0, 1e-10) << "mass, t = " << t;  // at rest: nothing moves
  }
}

// a ball on a free joint, its centre of mass at the frame's origin, no spin: δp(T) = δp₀ + T δv₀,
// δθ(T) = δθ₀ + T δω₀, and gravity accelerates it the same whatever its mass and inertia
TEST(Sensitivity, FreeFallingBallInClosedForm) {
  const Scenario sc = falling_ball();
  SimulationSettings s = tight("cvode-bdf", 1.5);
  s.sensitivities = {true, {"all"}};
  for (const Sample& x : run(sc, s)) {
    MatX want = MatX::Identity(12, 12);
    want.topRightCorner(6, 6) = x.t * MatX::Identity(6, 6);
    EXPECT_TRUE(near_rel(x.sensitivity_initial_state, want, 1e-8)) << "t = " << x.t;
    EXPECT_LT(x.sensitivity_parameters.cwiseAbs().maxCoeff(), 1e-8) << "t = " << x.t;
  }
}

TEST(Sensitivity, RefusesWhatItDoesNotDifferentiate) {
  Scenario sc = double_pendulum();
  SimulationSettings s = tight("rk4", 0.1);
  s.sensitivities = {true, {}};
  EXPECT_THAT([&] { simulate(sc, s); }, testing::ThrowsMessage<Error>(HasSubstr("need a CVODE method")));
  s.method = Method::CvodeAdams;
  EXPECT_THAT([&] { simulate(sc, s, nullptr, nullptr, nullptr, {}, [](double, const VecX&, const VecX&, Eigen::Ref<VecX>) {}); },
              testing::ThrowsMessage<Error>(HasSubstr("controller")));
  s.sensitivities = {false, {"lowr"}};
  EXPECT_THAT([&] { simulate(sc, s); }, testing::ThrowsMessage<Error>(HasSubstr("did you mean 'lower'")));
}

TEST(Sensitivity, ScenarioKeyAndItsErrors) {
  const std::string head = R"(
bodies:
  - name: link1
    joint: {type: revolute, axis: [1, 0, 0]}
    mass: 1.0
    com: [0, 0, -0.3]
    inertia: [0.01, 0.01, 0.01]
  - name: link2
    parent: link1
    joint: {type: revolute, axis: [1, 0, 0]}
    origin: {xyz: [0, 0, -0.6]}
    mass: 1.0
    com: [0, 0, -0.3]
    inertia: [0.01, 0.01, 0.01]
simulation:
)";
  Scenario sc = parse_scenario(head + "  sensitivities: {initial_state: true, parameters: [link2]}\n", "s.yaml");
  EXPECT_TRUE(sc.simulation.sensitivities.initial_state);
  EXPECT_EQ(sc.simulation.sensitivities.parameters, std::vector<std::string>{"link2"});
  sc = parse_scenario(head + "  sensitivities: {parameters: all}\n", "s.yaml");
  EXPECT_EQ(sc.simulation.sensitivities.parameters, std::vector<std::string>{"all"});
  EXPECT_THAT([&] { parse_scenario(head + "  sensitivities: {parameters: [lnk2]}\n", "s.yaml"); },
              testing::ThrowsMessage<Error>(HasSubstr("did you mean 'link2'")));
  EXPECT_THAT([&] { parse_scenario(head + "  sensitivities: {initial_stat: true}\n", "s.yaml"); },
              testing::ThrowsMessage<Error>(HasSubstr("initial_state")));
  EXPECT_THAT([&] { parse_scenario(head + "  sensitivity: {initial_state: true}\n", "s.yaml"); },
              testing::ThrowsMessage<Error>(HasSubstr("sensitivities")));
}

// the run file: /sensitivities/initial_state T×nx×nx and /sensitivities/parameters T×nx×np, the
// last rows the run's own numbers, names on the group
TEST(Sensitivity, LoggedToTheRunFile) {
  Scenario sc = double_pendulum();
  SimulationSettings s = tight("cvode-adams", 0.5);
  s.sensitivities = {true, {"upper"}};
  const std::string path = (std::filesystem::temp_directory_path() / ("soadyn_sens_" + std::to_string(::getpid()) + ".h5")).string();
  std::vector<Sample> samples;
  {
    H5Log log(path, sc, s, "test");
    simulate(sc, s, &log, &samples);
  }
  const RunContents file = read_run_file(path);
  for (const auto& [name, cols] : {std::pair{"/sensitivities/initial_state", 4}, std::pair{"/sensitivities/parameters", 10}}) {
    const RunSeries* d = file.find(name);
    ASSERT_NE(d, nullptr) << name;
    EXPECT_EQ(d->values.rows(), Eigen::Index(samples.size()));
    EXPECT_EQ(d->shape, (std::vector<Eigen::Index>{4, cols}));
    // row-major (i, j) in the last row; stored doubles come back bit for bit
    const MatX& want = cols == 4 ? samples.back().sensitivity_initial_state : samples.back().sensitivity_parameters;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < cols; ++j) EXPECT_EQ(d->values(d->values.rows() - 1, i * cols + j), want(i, j)) << name << " " << i << "," << j;
  }
  EXPECT_EQ(file.parameter_names.size(), 10u);
  EXPECT_EQ(file.state_units.size(), 4u);
  std::filesystem::remove(path);
}

}  // namespace
