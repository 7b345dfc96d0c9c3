// Controllers in the simulation (controller.hpp): PD settling at the closed-form offset under
// gravity, computed torque decaying at its designed poles on the 7-DOF arm, sampled control held
// between ticks, a controller that throws or returns NaN, and the controllers' work in the balance.
#include "soadyn/io/h5log.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/io/run_file.hpp"
#include "soadyn/sim/simulate.hpp"

#include "test_util.hpp"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>

using namespace soadyn;

namespace {

const std::string kPendulum = R"(gravity: [0, 0, -9.81]
bodies:
  - name: arm
    joint: {type: revolute, axis: [1, 0, 0]}
    mass: 1.0
    com: [0, 0, -0.5]
    inertia: [0.08, 0.08, 0.01]
)";

// PD to θ_d = 0.8 under gravity: at rest m g l sin θ = K_p (θ_d − θ), solved here by Newton
TEST(Control, PdSettlesAtTheGravityOffset) {
  const double kp = 20, thd = 0.8, mgl = 1.0 * 9.81 * 0.5;
  const Scenario sc = parse_scenario(kPendulum + "simulation: {t_end: 15, rtol: 1.0e-11, atol: 1.0e-13}\n"
                                                 "inputs:\n  controllers:\n    - {type: pd, joint: arm, kp: 20, kd: 2, target: 0.8}\n",
                                     "pd.yaml");
  std::vector<Sample> s;
  const RunSummary r = simulate(sc, sc.simulation, nullptr, &s);
  ASSERT_TRUE(r.completed) << r.status;
  double th = thd;
  for (int it = 0; it < 50; ++it) th -= (mgl * std::sin(th) - kp * (thd - th)) / (mgl * std::cos(th) + kp);
  EXPECT_GT(thd - th, 0.1);  // a real offset
  EXPECT_NEAR(s.back().q(0), th, 1e-8);
  EXPECT_NEAR(s.back().control(0), kp * (thd - th), 1e-6);
  // the controller's work is in W: E(t) − E(0) = W(t) (its damping dissipates, its spring stores in W)
  EXPECT_LE(r.max_energy_balance_error, 1e-7);
}

// computed torque on the 7-DOF arm: ë + K_d ė + K_p e = 0 exactly, poles −5 and −20 for K_p = 100,
// K_d = 25; from e(0) = 0.3, ė(0) = 0: e(t) = 0.3 (4 e^{−5t} − e^{−20t}) / 3 on every joint
TEST(Control, ComputedTorqueDecaysAtTheDesignedPoles) {
  const std::string dir = SOADYN_SOURCE_DIR "/tests/data/";
  std::string targets;
  const char* joints[] = {"j1", "j2", "j3", "j4", "j5", "j6", "j7"};
  const Scenario probe = load_scenario(dir + "arm7.urdf");
  ASSERT_EQ(probe.model.nv, 7);
  for (int k = 0; k < 7; ++k) targets += (k ? ", " : "") + probe.model.joint_names[size_t(k)] + ": 0.3";
  (void)joints;
  const Scenario sc = parse_scenario("urdf: arm7.urdf\nsimulation: {t_end: 4, rtol: 1.0e-11, atol: 1.0e-13, output_dt: 0.05}\n"
                                     "inputs:\n  controllers:\n    - {type: computed_torque, kp: 100, kd: 25, targets: {" +
                                         targets + "}}\n",
                                     dir + "ct.yaml");
  std::vector<Sample> s;
  const RunSummary r = simulate(sc, sc.simulation, nullptr, &s);
  ASSERT_TRUE(r.completed) << r.status;
  double worst = 0;
  for (const Sample& x : s) {
    const double e = 0.3 * (4 * std::exp(-5 * x.t) - std::exp(-20 * x.t)) / 3;
    for (int k = 0; k < 7; ++k) {
      const double got = 0.3 - x.q(k);
      if (e > 1e-7) worst = std::max(worst, std::abs(got / e - 1));
      EXPECT_NEAR(got, e, 1e-9) << "joint " << k << " t = " << x.t;
    }
  }
  EXPECT_LE(worst, 0.01);
  for (int k = 0; k < 7; ++k) EXPECT_LT(std::abs(0.3 - s.back().q(k)), 1e-8);
}

// sampled at control_dt = 0.01 s (zero-order hold): τ is constant between ticks and changes at them;
// the controller is called once per tick
TEST(Control, SampledControllerChangesOnlyAtTicks) {
  for (const std::string method : {"cvode-adams", "rk4"}) {
    const Scenario sc = parse_scenario(kPendulum + "initial: {q: {arm: 0.5}}\nsimulation: {t_end: 0.5, output_dt: 0.001, "
                                                   "control_dt: 0.01, method: " + method + "}\n",
                                       "s.yaml");
    long calls = 0;
    std::vector<double> at;
    ControlFunction pd = [&](double t, const VecX& q, const VecX& v, Eigen::Ref<VecX> tau) {
      ++calls;
      at.push_back(t);
      tau(0) = 10 * (0.0 - q(0)) - 1.0 * v(0);
    };
    std::vector<Sample> s;
    const RunSummary r = simulate(sc, sc.simulation, nullptr, &s, nullptr, {}, pd);
    ASSERT_TRUE(r.completed) << r.status;
    EXPECT_EQ(calls, 51) << method;  // t = 0, 0.01, …, 0.5
    EXPECT_EQ(r.control_ticks, calls);
    for (size_t k = 0; k < at.size(); ++k) EXPECT_NEAR(at[k], 0.01 * double(k), 1e-12) << method;
    int changes = 0;
    for (size_t k = 1; k < s.size(); ++k) {
      const double tick = std::round(s[k].t / 0.01) * 0.01;
      const bool on_tick = std::abs(s[k].t - tick) < 1e-9;
      const bool changed = std::abs(s[k].control(0) - s[k - 1].control(0)) > 1e-14;
      if (changed) ++changes;
      if (!on_tick) {
        EXPECT_FALSE(changed) << method << " t = " << s[k].t;
      }
    }
    EXPECT_GE(changes, 45) << method;
  }
}

// a controller that throws ends the run with its message and the time; the file stays readable
TEST(Control, ThrowingControllerLeavesAReadableFile) {
  const Scenario sc = parse_scenario(kPendulum + "initial: {q: {arm: 0.5}}\nsimulation: {t_end: 2}\n", "x.yaml");
  const std::string path = (std::filesystem::temp_directory_path() / ("soadyn_control_" + std::to_string(getpid()) + ".h5")).string();
  ControlFunction bad = [](double t, const VecX&, const VecX&, Eigen::Ref<VecX>) {
    if (t > 0.5) throw std::runtime_error("sensor lost");
  };
  RunSummary r;
  {
    H5Log log(path, sc, sc.simulation, "test");
    r = simulate(sc, sc.simulation, &log, nullptr, nullptr, {}, bad);
  }
  EXPECT_FALSE(r.completed);
  EXPECT_NE(r.status.find("the controller failed at t = 0.5"), std::string::npos) << r.status;
  EXPECT_NE(r.status.find("sensor lost"), std::string::npos) << r.status;
  EXPECT_GE(read_run_file(path).rows(), 45);  // the rows up to about t = 0.5 (CVODE steps past the last output)
  std::filesystem::remove(path);
  // sampled, a NaN torque: one error naming the time and the joint
  SimulationSettings st = sc.simulation;
  st.control_dt = 0.1;
  ControlFunction nan = [](double t, const VecX&, const VecX&, Eigen::Ref<VecX> tau) {
    if (t > 0.25) tau(0) = std::nan("");
  };
  const RunSummary n = simulate(sc, st, nullptr, nullptr, nullptr, {}, nan);
  EXPECT_NE(n.status.find("non-finite torque at t = 0.3 s (arm = nan)"), std::string::npos) << n.status;
}

// the run file: /events (one row per limit event), /energy/impact_loss and the controller's /control
// columns, equal to what simulate reported
TEST(Control, LimitEventsAndControlInTheRunFile) {
  const Scenario sc = parse_scenario(kPendulum + "initial: {q: {arm: 1.0}}\nlimits: {arm: [0.0, 3.0]}\n"
                                                 "simulation: {t_end: 1, limits: true, restitution: 0.5}\n"
                                                 "inputs:\n  controllers:\n    - {type: pd, joint: arm, kp: 1, kd: 0.1}\n",
                                     "e.yaml");
  const std::string path = (std::filesystem::temp_directory_path() / ("soadyn_events_" + std::to_string(getpid()) + ".h5")).string();
  RunSummary r;
  std::vector<Sample> s;
  {
    H5Log log(path, sc, sc.simulation, "test");
    r = simulate(sc, sc.simulation, &log, &s);
  }
  ASSERT_TRUE(r.completed) << r.status;
  ASSERT_GE(r.events.size(), 1u);
  const RunContents file = read_run_file(path);
  ASSERT_EQ(file.events.size(), r.events.size());
  for (size_t k = 0; k < r.events.size(); ++k) {
    EXPECT_EQ(file.events[k].t, r.events[k].t);  // stored doubles: the same bits
    EXPECT_EQ(file.events[k].side, -1);           // the lower limit
    EXPECT_EQ(file.events[k].v_before, r.events[k].v_before);
    EXPECT_EQ(file.events[k].energy_lost, r.events[k].energy_lost);
  }
  const MatX& lost = file.values("/energy/impact_loss");
  ASSERT_EQ(lost.rows(), Eigen::Index(s.size()));
  EXPECT_EQ(lost(lost.rows() - 1, 0), s.back().impact_loss);
  EXPECT_GT(lost(lost.rows() - 1, 0), 0.1);
  const MatX& tau = file.values("/control");
  EXPECT_EQ(tau.cols(), 1);
  for (Eigen::Index k = 0; k < tau.rows(); ++k) EXPECT_EQ(tau(k, 0), s[size_t(k)].control(0));
  std::filesystem::remove(path);
}

// gravity compensation holds the arm where it starts; saturation clamps the torque
TEST(Control, GravityCompensationHoldsAndSaturationClamps) {
  const Scenario sc = parse_scenario(kPendulum + "initial: {q: {arm: 0.7}}\nsimulation: {t_end: 2}\n"
                                                 "inputs:\n  controllers:\n    - {type: gravity_compensation}\n",
                                     "g.yaml");
  std::vector<Sample> s;
  simulate(sc, sc.simulation, nullptr, &s);
  EXPECT_NEAR(s.back().q(0), 0.7, 1e-8);
  EXPECT_NEAR(s.back().control(0), 9.81 * 0.5 * std::sin(0.7), 1e-9);
  const Scenario sat = parse_scenario(kPendulum + "initial: {q: {arm: 0.7}}\nsimulation: {t_end: 0.2}\n"
                                                  "inputs:\n  controllers:\n    - {type: gravity_compensation, max_torque: 1.5}\n",
                                      "g.yaml");
  s.clear();
  simulate(sat, sat.simulation, nullptr, &s);
  for (const Sample& x : s) EXPECT_LE(std::abs(x.control(0)), 1.5 + 1e-15);
  EXPECT_NEAR(s.front().control(0), 1.5, 1e-15);
  EXPECT_THROW(parse_scenario(kPendulum + "inputs:\n  controllers:\n    - {type: pid, joint: arm}\n", "x.yaml"), Error);
}

}  // namespace
