// Where methods fail, pinned with generous margins: explicit Euler gains energy on an undamped
// pendulum, symplectic Euler keeps it bounded over 10⁵ steps, BDF beats Adams on the stiff arm.
// (RK4 beyond its limit is in test_simulation: Instability.)
#include "soadyn/simulate.hpp"

#include "test_util.hpp"

using namespace soadyn;

namespace {

const std::string kPendulum = R"(gravity: [0, 0, -9.81]
bodies:
  - name: bob
    joint: {type: revolute, axis: [1, 0, 0]}
    mass: 1.0
    com: [0, 0, -1.0]
    inertia: [0.01, 0.01, 0.001]
initial:
  q: {bob: 1.0}
)";

std::vector<Sample> run(const Scenario& sc, const std::string& method, double dt, double t_end, RunSummary* out = nullptr) {
  SimulationSettings s = sc.simulation;
  s.method = method;
  s.dt = dt;
  s.t_end = t_end;
  s.output_dt = 0.1;
  std::vector<Sample> samples;
  const RunSummary r = simulate(sc, s, nullptr, &samples);
  EXPECT_TRUE(r.completed) << r.status;
  if (out) *out = r;
  return samples;
}

TEST(Stability, ExplicitEulerGainsEnergyOnAnUndampedPendulum) {
  const Scenario sc = parse_scenario(kPendulum, "pendulum.yaml");
  const auto s = run(sc, "euler", 1e-3, 20.0);
  const double E0 = s.front().total, scale = std::abs(E0);
  EXPECT_GT(s.back().total - E0, 0.05 * scale) << "explicit Euler should pump energy in";
  // and it keeps growing: the energy at each full second exceeds the one before (sampled at 1 s)
  for (size_t k = 20; k < s.size(); k += 10) EXPECT_GT(s[k].total, s[k - 10].total);
}

TEST(Stability, SymplecticEulerKeepsEnergyBoundedOver1e5Steps) {
  const Scenario sc = parse_scenario(kPendulum, "pendulum.yaml");
  const auto s = run(sc, "symplectic-euler", 1e-3, 100.0);  // 10⁵ steps
  const double E0 = s.front().total;
  double first = 0, second = 0;
  for (size_t k = 0; k < s.size(); ++k)
    (k < s.size() / 2 ? first : second) = std::max(k < s.size() / 2 ? first : second, std::abs(s[k].total - E0));
  EXPECT_LT(second, 0.01 * std::abs(E0)) << "bounded";
  EXPECT_LT(second, 2.0 * first + 1e-12) << "no secular drift: the second half no worse than the first";
  EXPECT_GT(first, 0.0);
}

TEST(Stability, BdfSolvesTheStiffArmWithTenTimesFewerRhsEvaluations) {
  const Scenario sc = load_scenario(SOADYN_SOURCE_DIR "/scenarios/stiff_arm.yaml");
  SimulationSettings s = sc.simulation;
  s.t_end = 5.0;
  s.method = "cvode-bdf";
  const RunSummary bdf = simulate(sc, s);
  s.method = "cvode-adams";
  const RunSummary adams = simulate(sc, s);
  ASSERT_TRUE(bdf.completed) << bdf.status;
  ASSERT_TRUE(adams.completed) << adams.status;
  EXPECT_GE(double(adams.stats.rhs_evals), 10.0 * double(bdf.stats.rhs_evals))
      << "Adams " << adams.stats.rhs_evals << ", BDF " << bdf.stats.rhs_evals;
  // and the explicit methods need a step ~1000x below the motion's: RK4 at 1 ms blows up
  s.method = "rk4";
  s.dt = 1e-3;
  EXPECT_FALSE(simulate(sc, s).completed);
}

}  // namespace
