// The library's stop hook: simulate() ends before the next integrator step once `stop` is non-zero,
// keeps what it logged (plus the state where it ended), and says which signal (or none) ended it.
#include "soadyn/sim/simulate.hpp"
#include "soadyn/io/scenario_file.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <thread>

using namespace soadyn;

namespace {

const std::string kDir = SOADYN_SOURCE_DIR "/scenarios/";

// sets the flag after `after` samples, as a signal handler would between two steps
class StopAfter : public RunObserver {
 public:
  StopAfter(std::atomic<int>& flag, int value, int after) : flag_(flag), value_(value), after_(after) {}
  void on_sample(const Sample& s) override {
    if (++seen_ == after_) flag_ = value_, t_at_stop = s.t;
  }
  void on_finish(const RunSummary& r) override { finished = r; }
  RunSummary finished;
  double t_at_stop = -1;

 private:
  std::atomic<int>& flag_;
  int value_, after_, seen_ = 0;
};

TEST(StopHook, EndsAtTheNextOutputStepWithTheSignalNamed) {
  const Scenario sc = load_scenario(kDir + "double_pendulum.yaml");
  for (const char* method : {"rk4", "cvode-adams"}) {
    SimulationSettings s = sc.simulation;
    s.method = parse_method(method);
    std::atomic<int> stop{0};
    StopAfter obs(stop, SIGTERM, 7);
    std::vector<Sample> samples;
    const RunSummary r = simulate(sc, s, &obs, &samples, &stop);
    EXPECT_FALSE(r.completed);
    ASSERT_EQ(samples.size(), 7u) << method << ": no step after the flag is seen";
    EXPECT_DOUBLE_EQ(r.t_reached, obs.t_at_stop);
    EXPECT_EQ(r.status, interrupted_status(SIGTERM, samples.back().t));
    EXPECT_EQ(r.status.rfind("interrupted by SIGTERM at t = 0.06", 0), 0u) << r.status;
    EXPECT_EQ(obs.finished.status, r.status) << "the observer is told how the run ended";
  }
}

TEST(StopHook, SetBeforeTheRunAndWithoutASignal) {
  const Scenario sc = load_scenario(kDir + "double_pendulum.yaml");
  std::atomic<int> stop{-1};
  std::vector<Sample> samples;
  const RunSummary r = simulate(sc, sc.simulation, nullptr, &samples, &stop);
  EXPECT_EQ(r.status, "interrupted at t = 0");
  EXPECT_EQ(samples.size(), 1u) << "the initial state is still logged";
  stop = SIGINT;
  EXPECT_EQ(simulate(sc, sc.simulation, nullptr, nullptr, &stop).status, "interrupted by SIGINT at t = 0");
  EXPECT_EQ(interrupted_status(SIGHUP, 1.25), "interrupted by SIGHUP at t = 1.25");
  EXPECT_EQ(interrupted_status(40, 0.1 + 0.2), "interrupted by signal 40 at t = 0.3");
  // a zero flag changes nothing
  stop = 0;
  EXPECT_TRUE(simulate(sc, sc.simulation, nullptr, nullptr, &stop).completed);
}

// One output interval of 10⁶ rk4 steps (about a second), the flag set from another thread 20 ms in,
// as a signal would: the run ends between two steps, far from any output time, and logs that state.
TEST(StopHook, EndsBetweenTwoStepsNotAtTheNextOutput) {
  const Scenario sc = load_scenario(kDir + "double_pendulum.yaml");
  for (const char* method : {"rk4", "cvode-adams"}) {
    SimulationSettings s = sc.simulation;
    s.method = parse_method(method);
    s.dt = 1e-3;
    s.t_end = s.output_dt = 1000.0;
    s.rtol = 1e-12, s.atol = 1e-12;
    s.max_steps = 100000000;
    std::atomic<int> stop{0};
    std::thread signaller([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      stop = SIGINT;
    });
    std::vector<Sample> samples;
    const RunSummary r = simulate(sc, s, nullptr, &samples, &stop);
    signaller.join();
    ASSERT_EQ(samples.size(), 2u) << method << ": the initial state and the state where the run ended";
    const double t = samples.back().t;
    EXPECT_GT(t, 0.0) << method;
    EXPECT_LT(t, 100.0) << method << ": ended long before the output time";
    EXPECT_EQ(r.t_reached, t);
    EXPECT_EQ(r.status, interrupted_status(SIGINT, t));
    if (std::string(method) == "rk4") {
      // a whole number of steps of 1 ms, and the state an uninterrupted run has there
      EXPECT_NEAR(t / s.dt, double(r.stats.steps), 1e-6) << "t = " << t << ", steps = " << r.stats.steps;
      SimulationSettings ref = s;
      ref.t_end = ref.output_dt = double(r.stats.steps) * s.dt;
      std::vector<Sample> full;
      ASSERT_TRUE(simulate(sc, ref, nullptr, &full).completed);
      EXPECT_LT((full.back().q - samples.back().q).norm(), 1e-9);
      EXPECT_LT((full.back().qd - samples.back().qd).norm(), 1e-9);
    } else {
      // CVODE's last internal step: energy kept as the tolerance allows, no interpolation past it
      EXPECT_LT(r.max_energy_balance_error, 1e-8);
    }
  }
}

// The poll runs before every integrator step, in the running thread (Python's signal check): on
// both kinds of integrator a poll that sets the flag at its k-th call ends the run after k − 1 steps.
TEST(StopHook, PollRunsBeforeEveryStepAndMaySetTheFlag) {
  const Scenario sc = load_scenario(kDir + "double_pendulum.yaml");
  for (const char* method : {"rk4", "cvode-bdf"}) {
    SimulationSettings s = sc.simulation;
    s.method = parse_method(method);
    s.t_end = s.output_dt = 10.0;
    std::atomic<int> stop{0};
    long calls = 0;
    const std::thread::id runner = std::this_thread::get_id();
    bool same_thread = true;
    auto poll = [&] {
      same_thread = same_thread && std::this_thread::get_id() == runner;
      if (++calls == 250) stop = -1;
    };
    const RunSummary r = simulate(sc, s, nullptr, nullptr, &stop, poll);
    EXPECT_TRUE(same_thread);
    EXPECT_EQ(r.stats.steps, 249) << method;
    EXPECT_EQ(calls, 250) << method << ": no call after the flag is set";
    EXPECT_EQ(r.status, interrupted_status(-1, r.t_reached));
    // without the flag, one call per step
    calls = -1000000000;
    stop = 0;
    const RunSummary full = simulate(sc, s, nullptr, nullptr, &stop, poll);
    EXPECT_TRUE(full.completed) << full.status;
    EXPECT_EQ(calls + 1000000000, full.stats.steps) << method;
  }
}

}  // namespace
