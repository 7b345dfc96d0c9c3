// The stiffness hint (RunSummary::stiffness_index, stiffness_hint): the spectral radius against a
// closed form, and the hint on a stiff scene run by cvode-adams, absent for cvode-bdf and for a
// scene that is not stiff.
#include "../../src/sim/stiffness.hpp"
#include "soadyn/io/run.hpp"
#include "soadyn/io/scenario_file.hpp"

#include "test_util.hpp"

#include <cmath>

using namespace soadyn;

namespace {

const std::string kDir = SOADYN_SOURCE_DIR "/scenarios/";

// a slider of mass m on a spring k and damper c along x: ẍ = −(k x + c ẋ)/m, no gravity along it
std::string slider(double m, double k, double c) {
  return "name: slider\ngravity: [0, 0, -9.81]\nbodies:\n"
         "  - name: block\n    joint: {type: prismatic, name: x, axis: [1, 0, 0]}\n"
         "    mass: " + std::to_string(m) + "\n    com: [0, 0, 0]\n    inertia: [0.1, 0.1, 0.1]\n"
         "initial:\n  q: {x: 0.01}\n"
         "inputs:\n  springs:\n    - {joint: x, stiffness: " + std::to_string(k) + ", rest: 0.0}\n"
         "  dampers:\n    - {joint: x, damping: " + std::to_string(c) + "}\n"
         "simulation:\n  t_end: 1.0\n  method: cvode-adams\n  rtol: 1.0e-6\n";
}

}  // namespace

// ρ of [0 1; −k/m −c/m] (with W's and D's zero rows): √(k/m) underdamped (|λ|² = k/m), the
// larger real root (c + √(c² − 4 k m)) / 2m overdamped
TEST(Stiffness, SpectralRadiusIsTheClosedForm) {
  for (const auto& [m, k, c] : {std::tuple{2.0, 800.0, 4.0}, std::tuple{0.5, 2.0e4, 10.0}, std::tuple{1.0, 100.0, 50.0}}) {
    const Scenario sc = parse_scenario(slider(m, k, c), "<slider>");
    System sys(sc.model, sc.inputs, FdMethod::ArticulatedBody);
    const VecX y = sys.state(sc.q0, sc.v0);
    const double disc = c * c - 4 * k * m;
    const double expected = disc < 0 ? std::sqrt(k / m) : (c + std::sqrt(disc)) / (2 * m);
    EXPECT_NEAR(detail::spectral_radius(sys, 0.0, y), expected, 1e-5 * expected) << "m " << m << " k " << k << " c " << c;
  }
}

// The stiff arm under cvode-adams: its steps held by stability (h̄ ρ ≥ 0.2), said once with
// cvode-bdf named; the same scene under cvode-bdf, and the soft three-link arm under cvode-adams
// (h̄ ρ estimated, well below): no hint.
TEST(Stiffness, HintOnAStiffAdamsRunOnly) {
  const Scenario stiff = load_scenario(kDir + "stiff_arm.yaml");
  SimulateOptions o;
  o.keep_samples = false;
  o.settings = stiff.simulation;
  o.settings->t_end = 0.5;
  o.settings->method = Method::CvodeAdams;
  const RunSummary adams = simulate(stiff, o).summary;
  ASSERT_TRUE(adams.completed) << adams.status;
  EXPECT_GE(adams.stats.steps, detail::kStiffSteps);
  EXPECT_GE(adams.stiffness_index, 0.5);
  EXPECT_LT(adams.stiffness_index, 5.0);  // at the stability edge, not past it
  EXPECT_NE(adams.stiffness_hint.find("cvode-bdf"), std::string::npos) << adams.stiffness_hint;
  EXPECT_NE(adams.stiffness_hint.find(std::to_string(adams.stats.steps)), std::string::npos) << adams.stiffness_hint;

  o.settings->method = Method::CvodeBdf;
  const RunSummary bdf = simulate(stiff, o).summary;
  ASSERT_TRUE(bdf.completed) << bdf.status;
  EXPECT_LT(20 * bdf.stats.steps, adams.stats.steps);  // the hint's promise, measured
  EXPECT_TRUE(bdf.stiffness_hint.empty());
  EXPECT_EQ(bdf.stiffness_index, 0.0);

  const Scenario soft = load_scenario(kDir + "three_link_arm.yaml");
  o.settings = soft.simulation;
  o.settings->method = Method::CvodeAdams;
  o.settings->rtol = 1e-9;
  o.settings->atol = 1e-11;
  const RunSummary calm = simulate(soft, o).summary;
  ASSERT_TRUE(calm.completed) << calm.status;
  ASSERT_GE(calm.stats.steps, detail::kStiffSteps);
  EXPECT_GT(calm.stiffness_index, 0.0);
  EXPECT_LT(calm.stiffness_index, 0.1);
  EXPECT_TRUE(calm.stiffness_hint.empty()) << calm.stiffness_hint;
}
