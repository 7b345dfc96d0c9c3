// Where methods fail, pinned with generous margins: explicit Euler gains energy on an undamped
// pendulum, symplectic Euler keeps it bounded over 10⁵ steps (here 𝓜 is constant; the scenes where
// it is not are in test_integrators), BDF beats Adams on the stiff arm.
// (RK4 beyond its limit is in test_simulation: Instability.)
#include "soadyn/sim/simulate.hpp"
#include "soadyn/io/scenario_file.hpp"

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
  s.method = parse_method(method);
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
  s.method = Method::CvodeBdf;
  const RunSummary bdf = simulate(sc, s);
  s.method = Method::CvodeAdams;
  const RunSummary adams = simulate(sc, s);
  ASSERT_TRUE(bdf.completed) << bdf.status;
  ASSERT_TRUE(adams.completed) << adams.status;
  EXPECT_GE(double(adams.stats.rhs_evals), 10.0 * double(bdf.stats.rhs_evals))
      << "Adams " << adams.stats.rhs_evals << ", BDF " << bdf.stats.rhs_evals;
  // and the explicit methods need a step ~1000x below the motion's: RK4 at 1 ms blows up
  s.method = Method::Rk4;
  s.dt = 1e-3;
  EXPECT_FALSE(simulate(sc, s).completed);
}

// BDF at the scene's own tolerance (rtol 1e-6) lands where a tight run lands: the reference is
// the implicit midpoint rule (another method: A-stable, order 2) at 0.1 ms, itself checked
// against BDF at rtol 1e-11.  Final state and every sample along the way.
TEST(Stability, BdfOnTheStiffArmIsAccurate) {
  const Scenario sc = load_scenario(SOADYN_SOURCE_DIR "/scenarios/stiff_arm.yaml");
  SimulationSettings s = sc.simulation;
  s.t_end = 2.0;
  s.output_dt = 0.1;
  std::vector<Sample> bdf, tight, ref;
  ASSERT_TRUE(simulate(sc, s, nullptr, &bdf).completed);
  SimulationSettings t = s;
  t.rtol = 1e-11;
  t.atol = 1e-13;
  ASSERT_TRUE(simulate(sc, t, nullptr, &tight).completed);
  SimulationSettings m = s;
  m.method = Method::ImplicitMidpoint;
  m.dt = 1e-4;
  ASSERT_TRUE(simulate(sc, m, nullptr, &ref).completed);
  ASSERT_EQ(bdf.size(), ref.size());
  ASSERT_EQ(tight.size(), ref.size());
  auto state = [](const Sample& x) {
    VecX y(x.q.size() + x.qd.size());
    y << x.q, x.qd;
    return y;
  };
  double worst_bdf = 0, worst_tight = 0;
  for (size_t k = 0; k < ref.size(); ++k) {
    ASSERT_NEAR(bdf[k].t, ref[k].t, 1e-12);
    const VecX r = state(ref[k]);
    worst_bdf = std::max(worst_bdf, (state(bdf[k]) - r).cwiseAbs().maxCoeff());
    worst_tight = std::max(worst_tight, (state(tight[k]) - r).cwiseAbs().maxCoeff());
  }
  EXPECT_LE(worst_tight, 1e-6) << "the two references disagree";
  EXPECT_LE(worst_bdf, 4e-5) << "BDF at rtol 1e-6";
  // the arm really moved: comparing the states is not vacuous
  EXPECT_GT((state(ref.back()) - state(ref.front())).cwiseAbs().maxCoeff(), 0.5);
}

}  // namespace
