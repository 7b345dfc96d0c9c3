// rollout(): K simulations in one call against simulate() run one by one, for any thread count.
#include "soadyn/sim/rollout.hpp"

#include "soadyn/io/scenario_file.hpp"
#include "soadyn/sim/simulate.hpp"
#include "test_util.hpp"

#include <cmath>
#include <csignal>
#include <string>

namespace soadyn {
namespace {

std::string scenario_path(const char* name) { return std::string(SOADYN_SOURCE_DIR) + "/scenarios/" + name; }

// K initial states around the scenario's own: rollout k perturbs q0 and v0 by 0.01·k
MatX initial_states(const Scenario& sc, long K) {
  const Model& m = sc.model;
  MatX Y0(m.nq + m.nv, K);
  for (long k = 0; k < K; ++k) {
    VecX q = sc.q0, v = sc.v0;
    q.array() += 0.01 * double(k);
    v.array() += 0.01 * double(k);
    m.normalize(q);
    Y0.col(k) << q, v;
  }
  return Y0;
}

struct Result {
  MatX states, energies;
  RolloutReport report;
};

Result run(const Scenario& sc, const MatX& Y0, const MatX* U, RolloutSettings rs, const ControlFn* cb = nullptr) {
  const long K = Y0.cols();
  Result r{MatX(sc.model.nq + sc.model.nv, rs.steps * K), MatX(rs.steps, K), {}};
  if (U) {
    const batch::In controls(*U);
    r.report = rollout(sc.model, sc.inputs, Y0, &controls, cb, rs, r.states, r.energies);
  } else {
    r.report = rollout(sc.model, sc.inputs, Y0, nullptr, cb, rs, r.states, r.energies);
  }
  return r;
}

// Each rollout against simulate() from the same state with output_dt = dt: the same integrator on
// the same grid, so the states agree to rounding (in fact to the bit: the same calls in the same
// order; the tolerance leaves room for a compiler's contraction choices between the two call sites).
void expect_matches_simulate(const char* scenario, const char* method, double dt, long T) {
  Scenario sc = load_scenario(scenario_path(scenario));
  const long K = 3;
  const MatX Y0 = initial_states(sc, K);
  RolloutSettings rs = rollout_settings(sc.simulation);
  rs.method = parse_method(method);
  rs.dt = dt;
  rs.steps = T;
  const Result r = run(sc, Y0, nullptr, rs);
  EXPECT_EQ(r.report.completed, K) << scenario << " " << method;
  SimulationSettings ss = sc.simulation;
  ss.method = parse_method(method);
  ss.dt = dt;
  ss.output_dt = dt;
  ss.t_end = double(T) * dt;
  const int nq = sc.model.nq, nv = sc.model.nv;
  for (long k = 0; k < K; ++k) {
    sc.q0 = Y0.col(k).head(nq);
    sc.v0 = Y0.col(k).tail(nv);
    std::vector<Sample> samples;
    const RunSummary summary = simulate(sc, ss, nullptr, &samples);
    ASSERT_TRUE(summary.completed) << summary.status;
    ASSERT_EQ(long(samples.size()), T + 1);
    for (long s = 0; s < T; ++s) {
      const Sample& x = samples[size_t(s + 1)];
      VecX y(nq + nv);
      y << x.q, x.qd;
      EXPECT_TRUE(test::near_rel(r.states.col(k * T + s), y, 1e-12)) << scenario << " " << method << " k " << k << " s " << s;
      EXPECT_NEAR(r.energies(s, k), x.total, 1e-12 * std::max(1.0, std::abs(x.total)));
    }
  }
}

TEST(Rollout, FixedStepMatchesSimulate) {
  expect_matches_simulate("double_pendulum.yaml", "rk4", 1e-3, 200);
  expect_matches_simulate("driven_pendulum.yaml", "rk4", 2e-3, 100);  // torques and dampers (quadratures)
  expect_matches_simulate("tumbling_t_handle.yaml", "rk4", 1e-3, 100);  // a free root's quaternion
  expect_matches_simulate("double_pendulum.yaml", "semi-implicit-euler", 1e-3, 100);
  expect_matches_simulate("double_pendulum.yaml", "symplectic-euler", 1e-3, 50);
  expect_matches_simulate("three_link_arm.yaml", "implicit-midpoint", 1e-3, 50);
}

TEST(Rollout, CvodeMatchesSimulate) {
  expect_matches_simulate("double_pendulum.yaml", "cvode-adams", 1e-2, 50);
  expect_matches_simulate("stiff_arm.yaml", "cvode-bdf", 1e-2, 20);
}

TEST(Rollout, SameStatesWhateverTheThreadCount) {
  const Scenario sc = load_scenario(scenario_path("tumbling_t_handle.yaml"));
  const long K = 7, T = 40;
  const MatX Y0 = initial_states(sc, K);
  MatX U(sc.model.nv, T * K);
  for (long c = 0; c < U.cols(); ++c) U.col(c).setConstant(0.1 * std::sin(0.3 * double(c)));
  for (const char* method : {"rk4", "cvode-adams"}) {
    RolloutSettings rs;
    rs.method = parse_method(method);
    rs.dt = 5e-3;
    rs.steps = T;
    const Result one = run(sc, Y0, &U, rs);
    for (int threads : {2, 3}) {
      rs.threads = threads;
      const Result many = run(sc, Y0, &U, rs);
      // exact: each rollout runs the same code on the same inputs, only on another thread
      EXPECT_TRUE(many.states == one.states) << method << ", " << threads << " threads";
      EXPECT_TRUE(many.energies == one.energies) << method << ", " << threads << " threads";
    }
  }
}

// a constant control is a constant torque: the rollout equals simulate() with that torque as an input
TEST(Rollout, ControlsActAsTorques) {
  Scenario sc = load_scenario(scenario_path("double_pendulum.yaml"));
  const long K = 2, T = 100;
  const MatX Y0 = initial_states(sc, K);
  MatX U = MatX::Zero(sc.model.nv, T * K);
  U.row(0).setConstant(0.7);
  RolloutSettings rs;
  rs.method = Method::Rk4;
  rs.dt = 1e-3;
  rs.steps = T;
  const Result r = run(sc, Y0, &U, rs);
  TorqueInput torque;
  torque.joint = sc.model.joint_names[0];
  torque.dof = 0;
  torque.constant = 0.7;
  sc.inputs.torques.push_back(torque);
  const Result ref = run(sc, Y0, nullptr, rs);
  EXPECT_TRUE(test::near_rel(r.states, ref.states, 1e-13));
  // the callback giving the same control: the same rollouts to the bit
  const ControlFn cb = [](long, long, double, const double*, double* tau) { tau[0] = 0.7, tau[1] = 0.0; };
  sc.inputs.torques.clear();
  const Result by_callback = run(sc, Y0, nullptr, rs, &cb);
  EXPECT_TRUE(by_callback.states == r.states);
}

// CVODE restarts where the control jumps (t = 0.25 here) and follows the jump as RK4 does
TEST(Rollout, CvodeFollowsAControlJump) {
  const Scenario sc = load_scenario(scenario_path("double_pendulum.yaml"));
  const long T = 50;
  const MatX Y0 = initial_states(sc, 1);
  MatX U = MatX::Zero(sc.model.nv, T);
  U.rightCols(T / 2).row(1).setConstant(2.0);
  RolloutSettings rs;
  rs.method = Method::Rk4;
  rs.dt = 1e-2;
  rs.steps = T;
  const Result rk = run(sc, Y0, &U, rs);
  rs.method = Method::CvodeAdams;
  rs.rtol = 1e-11;
  rs.atol = 1e-12;
  const Result cv = run(sc, Y0, &U, rs);
  EXPECT_TRUE(test::near_rel(cv.states, rk.states, 1e-6));
}

TEST(Rollout, BadArgumentsRefused) {
  const Scenario sc = load_scenario(scenario_path("double_pendulum.yaml"));
  const int ny = sc.model.nq + sc.model.nv;
  RolloutSettings rs;
  rs.steps = 5;
  MatX Y0 = initial_states(sc, 2), states(ny, 10), energies(5, 2);
  auto message = [&](const MatX& y0, const MatX* U, const RolloutSettings& s, MatX& st) {
    try {
      if (U) {
        const batch::In u(*U);
        rollout(sc.model, sc.inputs, y0, &u, nullptr, s, st, energies);
      } else {
        rollout(sc.model, sc.inputs, y0, nullptr, nullptr, s, st, energies);
      }
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  using ::testing::HasSubstr;
  EXPECT_THAT(message(Y0.topRows(2), nullptr, rs, states), HasSubstr("rollout: initial_states: expected 4×2"));
  const MatX U(2, 9);
  EXPECT_THAT(message(Y0, &U, rs, states), HasSubstr("rollout: controls: expected 2×10 (nv rows, column k·T + s), got 2×9"));
  MatX small(ny, 9);
  EXPECT_THAT(message(Y0, nullptr, rs, small), HasSubstr("rollout: states: expected 4×10"));
  MatX bad = Y0;
  bad(1, 1) = std::nan("");
  EXPECT_THAT(message(bad, nullptr, rs, states), HasSubstr("initial_states: entry 1 of rollout 1 is nan"));
  RolloutSettings wrong = rs;
  wrong.dt = 0;
  EXPECT_THAT(message(Y0, nullptr, wrong, states), HasSubstr("rollout: dt"));
}

// an unstable rollout reports why and leaves NaN from there; the others complete
TEST(Rollout, FailedRolloutReportedOthersComplete) {
  const Scenario sc = load_scenario(scenario_path("double_pendulum.yaml"));
  MatX Y0 = initial_states(sc, 3);
  Y0.col(1).tail(2).setConstant(1e5);  // explicit Euler at dt = 0.05 blows up
  RolloutSettings rs;
  rs.method = Method::Euler;
  rs.dt = 0.05;
  rs.steps = 400;
  const Result r = run(sc, Y0, nullptr, rs);
  EXPECT_EQ(r.report.status[0], "completed");
  EXPECT_THAT(r.report.status[1], ::testing::HasSubstr("unstable"));
  EXPECT_EQ(r.report.status[2], "completed");
  EXPECT_EQ(r.report.completed, 2);
  EXPECT_TRUE(std::isnan(r.states(0, 1 * 400 + 399)));
}

// a stop request ends every rollout before its next step
TEST(Rollout, StopEndsTheCall) {
  const Scenario sc = load_scenario(scenario_path("double_pendulum.yaml"));
  const MatX Y0 = initial_states(sc, 4);
  RolloutSettings rs;
  rs.steps = 1000;
  MatX states(4, 4000), energies(1000, 4);
  // one thread: poll runs before every step; the fifth call asks to stop
  std::atomic<int> stop{0};
  long polls = 0;
  RolloutReport rep = rollout(sc.model, sc.inputs, Y0, nullptr, nullptr, rs, states, energies, &stop, [&] {
    if (++polls == 5) stop = SIGINT;
  });
  EXPECT_TRUE(rep.interrupted);
  EXPECT_EQ(rep.stop, SIGINT);
  EXPECT_EQ(rep.completed, 0);
  EXPECT_THAT(rep.status[0], ::testing::HasSubstr("interrupted by SIGINT at t = 0.003"));
  EXPECT_EQ(rep.status[1], "not run");
  EXPECT_FALSE(std::isnan(states(0, 2)));
  EXPECT_TRUE(std::isnan(states(0, 3)));
  // two threads, a stop already requested: nothing runs
  rs.threads = 2;
  rep = rollout(sc.model, sc.inputs, Y0, nullptr, nullptr, rs, states, energies, &stop);
  EXPECT_TRUE(rep.interrupted);
  EXPECT_EQ(rep.completed, 0);
}

// simulate_states (soadyn sweep's runs of one scenario from K initial states): each run is
// simulate() from that state, to the last bit, on 1 and 2 threads; a start past an enforced limit
// is that run's refusal alone
TEST(SimulateStates, EachRunIsSimulateWhateverTheThreadCount) {
  for (const char* name : {"double_pendulum.yaml", "arm_control_limits.yaml"}) {
    Scenario sc = load_scenario(scenario_path(name));
    sc.simulation.t_end = 0.3;
    if (sc.simulation.method != Method::CvodeAdams) sc.simulation.method = Method::Rk4;
    const Model& m = sc.model;
    const long K = 5;
    MatX Y0 = initial_states(sc, K);
    Y0(m.idx_q[m.nbodies - 1], 2) = 2.6;  // past the arm's elbow limit (2.5); the pendulum just swings
    const MatX Q0 = Y0.topRows(m.nq), V0 = Y0.bottomRows(m.nv);
    for (int threads : {1, 2}) {
      const std::vector<StateRun> runs = simulate_states(sc, sc.simulation, Q0, V0, threads, true);
      ASSERT_EQ(runs.size(), size_t(K));
      for (long k = 0; k < K; ++k) {
        SCOPED_TRACE(std::string(name) + " run " + std::to_string(k) + ", " + std::to_string(threads) + " threads");
        Scenario one = sc;
        one.q0 = Q0.col(k);
        one.v0 = V0.col(k);
        std::vector<Sample> samples;
        RunSummary expected;
        try {
          expected = simulate(one, one.simulation, nullptr, &samples);
        } catch (const Error& e) {
          EXPECT_FALSE(runs[k].ran);
          EXPECT_EQ(runs[k].refused, e.what());
          continue;
        }
        ASSERT_TRUE(runs[k].ran) << runs[k].refused;
        EXPECT_EQ(runs[k].summary.status, expected.status);
        EXPECT_EQ(runs[k].summary.stats.steps, expected.stats.steps);
        EXPECT_EQ(runs[k].summary.stats.rhs_evals, expected.stats.rhs_evals);
        EXPECT_EQ(runs[k].summary.max_energy_balance_error, expected.max_energy_balance_error);
        EXPECT_EQ(runs[k].summary.final_energy_balance_error, expected.final_energy_balance_error);
        EXPECT_EQ(runs[k].initial_energy, samples.front().total);
        const long ny = m.nq + m.nv;
        ASSERT_EQ(runs[k].t.size(), samples.size());
        for (size_t j = 0; j < samples.size(); ++j) {
          EXPECT_EQ(runs[k].t[j], samples[j].t);
          const Eigen::Map<const VecX> y(runs[k].y.data() + long(j) * ny, ny);
          EXPECT_EQ(y.head(m.nq), samples[j].q);
          EXPECT_EQ(y.tail(m.nv), samples[j].qd);
        }
      }
      if (std::string(name) == "arm_control_limits.yaml") {
        EXPECT_FALSE(runs[2].ran);
      }
    }
  }
}

}  // namespace
}  // namespace soadyn
