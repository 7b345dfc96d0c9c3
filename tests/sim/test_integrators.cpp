// The fixed-step methods (integrators.cpp) do what they say: steps of exactly dt, counted as
// integers; the order each one claims (IntegratorInfo::order), measured; for each method called
// symplectic, a symplectic one-step map and no secular energy growth over 10⁵ steps.
#include "soadyn/sim/simulate.hpp"
#include "soadyn/io/scenario_file.hpp"

#include "test_util.hpp"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <memory>

using namespace soadyn;
using namespace soadyn::test;

namespace {

const std::string kDir = SOADYN_SOURCE_DIR "/scenarios/";

std::vector<std::string> fixed_step_methods() {
  std::vector<std::string> names;
  for (const auto& info : integrators())
    if (info.fixed_step) names.emplace_back(info.name);
  return names;
}

// Counts the samples and checks each one's time against the grid t = (k·stride)·dt (to rounding),
// the last at t_end
class GridCheck : public RunObserver {
 public:
  GridCheck(double dt, double stride, double t_end) : dt_(dt), stride_(stride), t_end_(t_end) {}
  void on_sample(const Sample& s) override {
    const double expected = double(samples_) * stride_ * dt_;
    if (std::abs(s.t - expected) > 1e-12 * std::max(1.0, expected) && s.t != t_end_) ++off_grid_;
    last_ = s.t;
    ++samples_;
  }
  void on_finish(const RunSummary&) override {}
  long samples_ = 0, off_grid_ = 0;
  double last_ = 0.0;

 private:
  double dt_, stride_, t_end_;
};

SimulationSettings fixed(const Scenario& sc, const std::string& method, double dt, double t_end, double output_dt) {
  SimulationSettings s = sc.simulation;
  s.method = parse_method(method);
  s.dt = dt;
  s.t_end = t_end;
  s.output_dt = output_dt;
  return s;
}

// ---- exact steps ---------------------------------------------------------------------------

TEST(StepCount, WholeSpansAreRoundTOverDt) {
  EXPECT_EQ(count_steps(200.0, 1e-3).whole, 200000.0);
  EXPECT_FALSE(count_steps(200.0, 1e-3).partial);
  EXPECT_EQ(count_steps(0.3, 0.1).whole, 3.0);  // 0.3 / 0.1 = 2.9999999999999996
  EXPECT_FALSE(count_steps(0.3, 0.1).partial);
  EXPECT_EQ(count_steps(1.0, 1e-4).whole, 10000.0);
  EXPECT_FALSE(count_steps(1.0, 1e-4).partial);
  // not a whole number: floor(T/dt) steps and a shorter one
  EXPECT_EQ(count_steps(1.0, 0.3).whole, 3.0);
  EXPECT_TRUE(count_steps(1.0, 0.3).partial);
  EXPECT_EQ(count_steps(0.05, 0.1).whole, 0.0);
  EXPECT_TRUE(count_steps(0.05, 0.1).partial);
}

class ExactSteps : public ::testing::TestWithParam<std::string> {};

// t_end 200, dt 1e-3: exactly 200 000 steps at every output step (the bug split an interval in two
// half steps once rounding in t_out − t passed 1e-12 of dt: 325 888 steps at output_dt 0.001,
// 202 304 at 0.01); every sample on the grid k·dt, the last at t_end
TEST_P(ExactSteps, TwoHundredSecondsAtOneMillisecondAre200000Steps) {
  const Scenario sc = load_scenario(kDir + "pendulum_on_cart.yaml");
  for (double output_dt : {0.001, 0.01}) {
    const SimulationSettings s = fixed(sc, GetParam(), 1e-3, 200.0, output_dt);
    GridCheck grid(s.dt, output_stride(s), s.t_end);
    const RunSummary r = simulate(sc, s, &grid);
    ASSERT_TRUE(r.completed) << GetParam() << ": " << r.status;
    EXPECT_EQ(r.stats.steps, 200000) << GetParam() << " output_dt " << output_dt;
    EXPECT_EQ(r.t_reached, 200.0);
    EXPECT_EQ(grid.samples_, long(output_rows(s))) << GetParam() << " output_dt " << output_dt;
    EXPECT_EQ(grid.samples_, 1 + long(std::llround(200.0 / output_dt)));
    EXPECT_EQ(grid.off_grid_, 0) << GetParam() << " output_dt " << output_dt;
    EXPECT_EQ(grid.last_, 200.0);
  }
}

// awkward values: T/dt a whole number only within rounding, a span that is not one, an output_dt
// that is not a multiple of dt (taken as the nearest: every 2 steps for 1.5 dt), and below dt
TEST_P(ExactSteps, AwkwardSpans) {
  const Scenario sc = load_scenario(kDir + "double_pendulum.yaml");
  struct Case {
    double dt, t_end, output_dt;
    long steps, rows;
  };
  for (const Case& c : {Case{0.1, 0.3, 0.01, 3, 4}, Case{1e-4, 1.0, 0.01, 10000, 101}, Case{1e-4, 1.0, 1e-4, 10000, 10001},
                        Case{0.03, 0.1, 0.01, 4, 5}, Case{1e-3, 0.1, 0.0015, 100, 51}, Case{0.01, 0.1, 1e-3, 10, 11}}) {
    const SimulationSettings s = fixed(sc, GetParam(), c.dt, c.t_end, c.output_dt);
    GridCheck grid(s.dt, output_stride(s), s.t_end);
    const RunSummary r = simulate(sc, s, &grid);
    const std::string what = GetParam() + " dt " + std::to_string(c.dt) + " t_end " + std::to_string(c.t_end);
    ASSERT_TRUE(r.completed) << what << ": " << r.status;
    EXPECT_EQ(r.stats.steps, c.steps) << what;
    EXPECT_EQ(grid.samples_, c.rows) << what;
    EXPECT_EQ(long(output_rows(s)), c.rows) << what;
    EXPECT_EQ(grid.off_grid_, 0) << what;
    EXPECT_EQ(r.t_reached, c.t_end) << what;
  }
}

INSTANTIATE_TEST_SUITE_P(FixedStepMethods, ExactSteps, ::testing::ValuesIn(fixed_step_methods()),
                         [](const auto& info) {
                           std::string n = info.param;
                           for (char& ch : n)
                             if (ch == '-') ch = '_';
                           return n;
                         });

// output times accumulated by a caller (t_out += 1 ms, whose rounding drifts from k·dt) still give
// one step per millisecond; a step's time comes from its index
TEST(ExactStepsAdvance, AccumulatedOutputTimesTakeOneStepEach) {
  const Scenario sc = load_scenario(kDir + "double_pendulum.yaml");
  const SimulationSettings s = fixed(sc, "rk4", 1e-3, 10.0, 1e-3);
  System sys(sc.model, sc.inputs, s.dynamics);
  VecX y = sys.state(sc.q0, sc.v0);
  double t = 0.0, t_out = 0.0;
  auto integrator = make_integrator(s.method, sys, s, t, y);
  for (int k = 1; k <= 10000; ++k) {
    t_out += 1e-3;
    integrator->advance(t_out, t, y);
    ASSERT_EQ(integrator->stats().steps, k) << "t_out " << t_out;
  }
  EXPECT_NEAR(t, 10.0, 1e-12);
}

// the command line, as the issue ran it
TEST(ExactStepsCli, RunReports200000Steps) {
  const std::string dir = (std::filesystem::temp_directory_path() / ("soadyn_steps_" + std::to_string(getpid()))).string();
  std::filesystem::create_directories(dir);
  const std::string cmd = std::string(SOADYN_CLI) + " run " + kDir +
                          "pendulum_on_cart.yaml --method euler --dt 1e-3 --t-end 200 --output-dt 0.001 --log energy -o " +
                          dir + "/run.h5";
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(cmd.c_str(), "r"), pclose);
  ASSERT_TRUE(pipe);
  std::string out;
  char buf[256];
  while (std::fgets(buf, sizeof buf, pipe.get())) out += buf;
  std::filesystem::remove_all(dir);
  EXPECT_THAT(out, ::testing::ContainsRegex("steps +200000\n")) << out;
  EXPECT_THAT(out, ::testing::ContainsRegex("t reached +200 s\n")) << out;
}

// ---- claimed properties --------------------------------------------------------------------

// error at t = 1 against CVODE at rtol 1e-13 for dt, dt/2, dt/4: the mean log2 slope
double observed_order(const Scenario& sc, const std::string& method, double dt, double T) {
  SimulationSettings ref = sc.simulation;
  ref.method = Method::CvodeAdams;
  ref.rtol = 1e-13;
  ref.atol = 1e-15;
  ref.t_end = T;
  ref.output_dt = T;
  std::vector<Sample> r;
  EXPECT_TRUE(simulate(sc, ref, nullptr, &r).completed);
  std::vector<double> err;
  for (double h : {dt, dt / 2, dt / 4}) {
    std::vector<Sample> x;
    const RunSummary sum = simulate(sc, fixed(sc, method, h, T, T), nullptr, &x);
    EXPECT_TRUE(sum.completed) << method << ": " << sum.status;
    VecX e(2 * sc.model.nv);
    e << x.back().q - r.back().q, x.back().qd - r.back().qd;
    err.push_back(e.norm());
  }
  return 0.5 * (std::log2(err[0] / err[1]) + std::log2(err[1] / err[2]));
}

class ClaimedOrder : public ::testing::TestWithParam<std::string> {};

// every fixed-step method's order as the registry (and the README) states it, within ±0.3, on both
// scenes; the base step puts the errors between the reference's accuracy and the asymptotic range
TEST_P(ClaimedOrder, MeasuredOnTheDoublePendulumAndThePendulumOnTheCart) {
  const IntegratorInfo* info = find_integrator(GetParam());
  ASSERT_TRUE(info);
  const double dt = info->order == 1 ? 1e-3 : 1e-2;
  for (const char* scene : {"double_pendulum", "pendulum_on_cart"}) {
    const Scenario sc = load_scenario(kDir + scene + ".yaml");
    const double p = observed_order(sc, GetParam(), dt, 1.0);
    EXPECT_NEAR(p, info->order, 0.3) << GetParam() << " on " << scene;
    std::printf("[ order ] %-20s %-18s %.3f (claimed %d)\n", GetParam().c_str(), scene, p, info->order);
  }
}

INSTANTIATE_TEST_SUITE_P(FixedStepMethods, ClaimedOrder, ::testing::ValuesIn(fixed_step_methods()),
                         [](const auto& info) {
                           std::string n = info.param;
                           for (char& ch : n)
                             if (ch == '-') ch = '_';
                           return n;
                         });

// the largest |E(t) − E(0)| in each 20 s window of a run at dt 1e-3
std::vector<double> energy_windows(const std::string& scene, const std::string& method, double t_end) {
  const Scenario sc = load_scenario(kDir + scene + ".yaml");
  std::vector<Sample> x;
  const RunSummary r = simulate(sc, fixed(sc, method, 1e-3, t_end, 0.01), nullptr, &x);
  EXPECT_TRUE(r.completed) << r.status;
  std::vector<double> w(size_t(std::llround(t_end / 20.0)), 0.0);
  for (const Sample& s : x) {
    const size_t k = std::min(w.size() - 1, size_t(s.t / 20.0));
    w[k] = std::max(w[k], std::abs(s.total - x.front().total));
  }
  std::printf("[ energy ] %-18s %-20s", scene.c_str(), method.c_str());
  for (double e : w) std::printf(" %.3g", e);
  std::printf("\n");
  return w;
}

// 10⁵ steps on the two scenes where 𝓜 depends on q: a method called symplectic shows no secular
// growth (the last 20 s window's largest energy error at most 1.5× the first's).  Before the
// method was symplectic (the update in v, as semi-implicit-euler still is) the windows grew
// 0.40 → 2.33 (double pendulum) and 0.077 → 0.35 (pendulum on the cart) over these 100 s.
TEST(ClaimedSymplectic, NoSecularEnergyGrowthOver1e5Steps) {
  int symplectic = 0;
  for (const auto& info : integrators()) {
    if (!info.symplectic) continue;
    ++symplectic;
    for (const char* scene : {"double_pendulum", "pendulum_on_cart"}) {
      const std::vector<double> w = energy_windows(scene, std::string(info.name), 100.0);
      EXPECT_GT(w.front(), 0.0) << info.name << " " << scene;
      EXPECT_LE(w.back(), 1.5 * w.front()) << info.name << " on " << scene << ": first window " << w.front()
                                            << ", last " << w.back();
    }
  }
  EXPECT_GE(symplectic, 1) << "the registry claims no symplectic method: the README must not either";
}

// the README's contrast: the update in velocities is not symplectic with 𝓜(q), and its energy error
// grows; the symmetric implicit midpoint rule in (q, v) is not symplectic either, but on these two
// (reversible) scenes its energy error stays level, as the README says it measured
TEST(ClaimedSymplectic, SemiImplicitEulerDriftsAndTheMidpointRuleStaysLevel) {
  for (const char* scene : {"double_pendulum", "pendulum_on_cart"}) {
    const std::vector<double> se = energy_windows(scene, "semi-implicit-euler", 100.0);
    EXPECT_GT(se.back(), 2.0 * se.front()) << scene;
    const std::vector<double> mid = energy_windows(scene, "implicit-midpoint", 100.0);
    EXPECT_LE(mid.back(), 1.5 * mid.front()) << scene;
  }
}

// (q, p) ↦ (q⁺, p⁺) of one step, p = 𝓜(q) v
VecX canonical_step(const Scenario& sc, const std::string& method, double h, const VecX& x) {
  const Model& m = sc.model;
  Data d(m);
  const int n = m.nv;
  update_kinematics(m, d, x.head(n));
  mass_matrix(m, d);
  System sys(m, sc.inputs, FdMethod::Sparse);
  VecX y = sys.state(x.head(n), d.M.ldlt().solve(x.tail(n)));
  SimulationSettings s;
  s.method = parse_method(method);
  s.dt = h;
  double t = 0.0;
  make_integrator(s.method, sys, s, t, y)->advance(h, t, y);
  update_kinematics(m, d, y.head(n));
  mass_matrix(m, d);
  VecX out(2 * n);
  out << y.head(n), d.M * y.segment(n, n);
  return out;
}

// ‖Dφᵀ Ω Dφ − Ω‖ for the one-step map φ at x, by central differences
double symplecticity_defect(const Scenario& sc, const std::string& method, double h, const VecX& x) {
  const int n2 = int(x.size()), n = n2 / 2;
  MatX D(n2, n2);
  for (int c = 0; c < n2; ++c) {
    VecX a = x, b = x;
    const double e = 1e-5;
    a(c) += e;
    b(c) -= e;
    D.col(c) = (canonical_step(sc, method, h, a) - canonical_step(sc, method, h, b)) / (2 * e);
  }
  MatX Omega = MatX::Zero(n2, n2);
  Omega.topRightCorner(n, n).setIdentity();
  Omega.bottomLeftCorner(n, n) = -MatX::Identity(n, n);
  return (D.transpose() * Omega * D - Omega).cwiseAbs().maxCoeff();
}

// symplectic by the definition: the one-step map's Jacobian J in (q, p) keeps Jᵀ Ω J = Ω, on the
// double pendulum and on random chains of revolute, prismatic and planar joints with springs
// (conservative inputs); the update in velocities misses it by O(h)
TEST(ClaimedSymplectic, OneStepMapPreservesTheSymplecticForm) {
  std::vector<Scenario> scenes;
  scenes.push_back(load_scenario(kDir + "double_pendulum.yaml"));
  Rng rng(11);
  for (int k = 0; k < 3; ++k) {
    TreeOptions o;
    o.n = 4;
    o.prismatic = 0.25;
    o.planar = 0.25;
    Scenario sc;
    sc.path = "random";
    sc.model = random_model(rng, o);
    sc.inputs.springs.push_back({"", 0, 0, 3.0, 0.2});  // joint 0 is 1-DOF or planar: its first coordinate
    scenes.push_back(sc);
  }
  for (const Scenario& sc : scenes) {
    for (const auto& info : integrators()) {
      if (!info.symplectic) continue;
      VecX x(2 * sc.model.nv);
      x << random_q(rng, sc.model), random_v(rng, sc.model);
      const double h = 0.02;
      EXPECT_LE(symplecticity_defect(sc, std::string(info.name), h, x), 1e-7) << info.name << " on " << sc.path;
      EXPECT_GE(symplecticity_defect(sc, "semi-implicit-euler", h, x), 1e-4) << sc.path;
    }
  }
}

// where 𝓜 is constant and bias has no velocity term (one hinge), the canonical update is the
// velocity update: the two methods agree to rounding, torque and spring included
TEST(ClaimedSymplectic, EqualsTheVelocityUpdateWhereTheMassMatrixIsConstant) {
  const Scenario sc = parse_scenario(R"(gravity: [0, 0, -9.81]
bodies:
  - name: bob
    joint: {type: revolute, axis: [1, 0, 0]}
    mass: 1.0
    com: [0, 0, -1.0]
    inertia: [0.01, 0.01, 0.001]
initial:
  q: {bob: 1.0}
inputs:
  torques:
    - {joint: bob, constant: 0.2, amplitude: 1.0, frequency: 0.5}
  springs:
    - {joint: bob, stiffness: 2.0, rest: 0.1}
)",
                                     "hinge.yaml");
  std::vector<Sample> a, b;
  ASSERT_TRUE(simulate(sc, fixed(sc, "symplectic-euler", 1e-3, 5.0, 0.1), nullptr, &a).completed);
  ASSERT_TRUE(simulate(sc, fixed(sc, "semi-implicit-euler", 1e-3, 5.0, 0.1), nullptr, &b).completed);
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_NEAR(a[k].q(0), b[k].q(0), 1e-10) << "t = " << a[k].t;
    EXPECT_NEAR(a[k].qd(0), b[k].qd(0), 1e-10) << "t = " << a[k].t;
  }
  EXPECT_GT(std::abs(a.back().q(0) - a.front().q(0)), 0.1) << "it moved";
}

// a quaternion (free or ball joint) makes (q, 𝓜 v) non-canonical: refused before anything runs,
// naming the structure-preserving method that takes them
TEST(ClaimedSymplectic, RefusesModelsWithQuaternions) {
  for (const char* scene : {"satellite_two_arrays", "spherical_pendulum"}) {
    const Scenario sc = load_scenario(kDir + scene + ".yaml");
    const SimulationSettings s = fixed(sc, "symplectic-euler", 1e-3, 0.1, 0.01);
    try {
      check_run(sc, s);
      ADD_FAILURE() << scene << ": not refused";
    } catch (const Error& e) {
      EXPECT_THAT(e.what(), ::testing::HasSubstr("free or ball joint")) << e.what();
      EXPECT_THAT(e.what(), ::testing::HasSubstr("use variational (symplectic on the group")) << e.what();
    }
    EXPECT_THROW(simulate(sc, s), Error);
    EXPECT_TRUE(simulate(sc, fixed(sc, "variational", 1e-3, 0.1, 0.01)).completed);
  }
}

}  // namespace
