// Simulation: conservation on the four scenarios, convergence orders, HDF5 files (read back with
// the HDF5 API), instability, inputs.  Killed runs: tests/cli/test_data_safety.py.
#include "soadyn/io/h5log.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/io/run_file.hpp"
#include "soadyn/sim/simulate.hpp"

#include "test_util.hpp"

#include <unistd.h>

#include <fstream>
#include <cmath>
#include <filesystem>

using namespace soadyn;
using namespace soadyn::test;

namespace {

const std::string kDir = SOADYN_SOURCE_DIR "/scenarios/";
const char* kScenarios[] = {"pendulum_on_cart", "double_pendulum", "satellite_two_arrays", "three_link_arm", "screw_lift"};

std::string tmp(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("soadyn_test_" + std::to_string(getpid()) + "_" + name)).string();
}

RunSummary run(const Scenario& sc, const std::string& method, double rtol, std::vector<Sample>* samples = nullptr,
               double t_end = 0) {
  SimulationSettings s = sc.simulation;
  s.method = parse_method(method);
  s.rtol = rtol;
  s.atol = rtol * 1e-2;
  if (t_end > 0) s.t_end = t_end;
  return simulate(sc, s, nullptr, samples);
}

class Conservation : public ::testing::TestWithParam<const char*> {};

// CVODE Adams and BDF at rtol 1e-10: |E(t) − E(0)| / max(|E0|, peak T) ≤ 1e-7 over t_end, and the
// drift falls ≥ 100× from rtol 1e-6 to 1e-10
TEST_P(Conservation, EnergyDriftIsSmallAndFallsWithTolerance) {
  const Scenario sc = load_scenario(kDir + GetParam() + ".yaml");
  ASSERT_GE(sc.simulation.t_end, 10.0);
  for (const char* method : {"cvode-adams", "cvode-bdf"}) {
    const RunSummary tight = run(sc, method, 1e-10);
    ASSERT_TRUE(tight.completed) << tight.status;
    EXPECT_LE(tight.max_energy_balance_error, 1e-7) << GetParam() << " " << method;
    const RunSummary loose = run(sc, method, 1e-6);
    ASSERT_TRUE(loose.completed) << loose.status;
    EXPECT_GE(loose.max_energy_balance_error, 100.0 * tight.max_energy_balance_error)
        << GetParam() << " " << method << ": " << loose.max_energy_balance_error << " vs "
        << tight.max_energy_balance_error;
  }
}

INSTANTIATE_TEST_SUITE_P(Scenarios, Conservation, ::testing::ValuesIn(kScenarios));

// the satellite: momentum conserved to 1e-9 by both CVODE methods
TEST(Satellite, MomentumIsConserved) {
  const Scenario sc = load_scenario(kDir + "satellite_two_arrays.yaml");
  for (const char* method : {"cvode-adams", "cvode-bdf"}) {
    std::vector<Sample> samples;
    const RunSummary r = run(sc, method, 1e-12, &samples);
    ASSERT_TRUE(r.completed) << r.status;
    const Sample& s0 = samples.front();
    const double L = s0.linear.norm(), H = s0.angular.norm();
    ASSERT_GT(L, 1.0);
    ASSERT_GT(H, 1.0);
    double worst_l = 0, worst_h = 0;
    for (const Sample& s : samples) {
      worst_l = std::max(worst_l, (s.linear - s0.linear).norm() / L);
      worst_h = std::max(worst_h, (s.angular - s0.angular).norm() / H);
    }
    EXPECT_LE(worst_l, 1e-9) << method;
    EXPECT_LE(worst_h, 1e-9) << method;
    // the bus really turned: the check is not vacuous
    EXPECT_GT((samples.back().q.segment<4>(3) - s0.q.segment<4>(3)).norm(), 0.1);
  }
}

// The unit quaternion, where normalizing the output cannot hide a drift: Adams' own state (the q
// of CVODE's last right-hand-side evaluation; its outputs are normalized), BDF's projected
// outputs (not renormalized), and the orientation both reach, which normalizing cannot fix.
TEST(Satellite, QuaternionStaysUnitInTheIntegratorState) {
  const Scenario sc = load_scenario(kDir + "satellite_two_arrays.yaml");
  const int k = sc.model.idx_q[0] + 3;
  std::vector<Eigen::Vector4d> final_quaternion;
  for (const char* method : {"cvode-adams", "cvode-bdf"}) {
    SimulationSettings s = sc.simulation;
    s.method = parse_method(method);
    s.rtol = 1e-12;
    s.atol = 1e-14;
    System sys(sc.model, sc.inputs, s.dynamics);
    VecX y = sys.state(sc.q0, sc.v0);
    double t = 0;
    auto integrator = make_integrator(s.method, sys, s, t, y);
    const bool projected = integrator->quaternion_handling().find("CVodeSetProjFn") != std::string::npos;
    EXPECT_EQ(projected, std::string(method) == "cvode-bdf") << integrator->quaternion_handling();
    double worst = 0;
    for (int n = 1; n <= 200; ++n) {
      integrator->advance(0.25 * n, t, y);
      // BDF: the output is CVODE's projected state; Adams: the state its last RHS call saw
      const Eigen::Vector4d raw = projected ? Eigen::Vector4d(y.segment<4>(k)) : Eigen::Vector4d(sys.q.segment<4>(k));
      worst = std::max(worst, std::abs(raw.norm() - 1.0));
    }
    EXPECT_LE(worst, projected ? 1e-12 : 1e-10) << method;
    final_quaternion.push_back(y.segment<4>(k));
  }
  // Adams and BDF reach the same orientation after 50 s of tumbling (q and −q are one rotation)
  const Eigen::Vector4d &a = final_quaternion[0], &b = final_quaternion[1];
  EXPECT_LE(std::min((a - b).norm(), (a + b).norm()), 1e-9) << a.transpose() << " vs " << b.transpose();
}

// (convergence orders of the fixed-step methods: test_integrators, ClaimedOrder)

// ---- HDF5 ----------------------------------------------------------------------------------

int run_cli(const std::string& args) { return std::system((std::string(SOADYN_CLI) + " " + args + " > /dev/null 2>&1").c_str()); }

// (the round trip of every dataset and attribute is in test_h5log.cpp)

TEST(Instability, Rk4BeyondItsLimitStopsCleanly) {
  const std::string out = tmp("unstable.h5");
  const std::string err = tmp("unstable.err");
  const int rc = std::system((std::string(SOADYN_CLI) + " run " + kDir + "double_pendulum.yaml --method rk4 --dt 0.5 -q -o " +
                              out + " 2> " + err).c_str());
  EXPECT_EQ(WEXITSTATUS(rc), 3);
  std::ifstream in(err);
  const std::string msg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(msg.find("unstable at t ="), std::string::npos) << msg;
  EXPECT_NE(msg.find("joint 'theta"), std::string::npos) << msg;
  const RunContents file = read_run_file(out);
  EXPECT_GE(file.rows(), 1);
  EXPECT_NE(file.solver.status.find("unstable"), std::string::npos) << file.solver.status;
  std::filesystem::remove(out);
  std::filesystem::remove(err);
}

// a CVODE failure (here: too much work) stops the run with the time and the worst DOF, keeps the data
TEST(Instability, CvodeFailureNamesTimeAndWorstDof) {
  Scenario sc = load_scenario(kDir + "double_pendulum.yaml");
  for (const char* method : {"cvode-adams", "cvode-bdf"}) {
    SimulationSettings s = sc.simulation;
    s.method = parse_method(method);
    s.max_steps = 200;  // far too few for 10 s at rtol 1e-10
    std::vector<Sample> samples;
    const RunSummary r = simulate(sc, s, nullptr, &samples);
    EXPECT_FALSE(r.completed);
    EXPECT_NE(r.status.find("failed at t ="), std::string::npos) << r.status;
    EXPECT_NE(r.status.find("worst DOF: joint 'theta"), std::string::npos) << r.status;
    EXPECT_GT(r.t_reached, 0.0);
    EXPECT_LT(r.t_reached, s.t_end);
    EXPECT_GE(samples.size(), 2u) << "what was logged before the failure is kept";
  }
}

TEST(Output, ModelWithoutDegreesOfFreedomIsRefused) {
  const Scenario sc = parse_scenario("bodies:\n  - {name: plate, joint: {type: fixed}, mass: 1.0, inertia: [0.1, 0.1, 0.1]}\n",
                                     "weld.yaml");
  EXPECT_EQ(sc.model.nv, 0);
  try {
    simulate(sc, sc.simulation);
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no degrees of freedom"), std::string::npos) << e.what();
  }
  const std::string file = tmp("weld.yaml");
  std::ofstream(file) << sc.text;
  EXPECT_EQ(WEXITSTATUS(run_cli("run " + file + " -o " + tmp("weld.h5"))), 2);
  std::filesystem::remove(file);
}

TEST(Output, UnwritablePathIsRefusedBeforeTheRun) {
  const std::string file = tmp("a_file");
  std::ofstream(file) << "x";
  EXPECT_EQ(WEXITSTATUS(run_cli("run " + kDir + "double_pendulum.yaml -o " + file + "/run.h5")), 2);
  std::filesystem::remove(file);
}

// joint springs keep the system conservative (E includes ½ k (q − rest)²); dampers dissipate
TEST(Inputs, SpringsConserveDampersDissipate) {
  const std::string base = R"(gravity: [0, 0, -9.81]
bodies:
  - name: arm
    joint: {type: revolute, axis: [1, 0, 0]}
    mass: 1.0
    com: [0, 0, -0.5]
    inertia: [0.08, 0.08, 0.01]
initial:
  q: {arm: 0.5}
simulation: {t_end: 10, rtol: 1.0e-11, atol: 1.0e-13}
)";
  const Scenario spring = parse_scenario(base + "inputs:\n  springs:\n    - {joint: arm, stiffness: 20, rest: 0.2}\n", "s.yaml");
  const RunSummary rs = simulate(spring, spring.simulation);
  ASSERT_TRUE(rs.completed);
  EXPECT_LE(rs.max_energy_balance_error, 1e-8);
  const Scenario damped = parse_scenario(base + "inputs:\n  dampers:\n    - {joint: arm, damping: 0.5}\n", "d.yaml");
  std::vector<Sample> s;
  simulate(damped, damped.simulation, nullptr, &s);
  for (size_t k = 1; k < s.size(); ++k) EXPECT_LE(s[k].total, s[k - 1].total + 1e-9);
  EXPECT_LT(s.back().total, s.front().total - 0.1);
}

}  // namespace
