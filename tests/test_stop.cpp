// The library's stop hook: simulate() ends at the next output step once `stop` is non-zero, keeps
// what it logged, and says which signal (or none) ended it.
#include "soadyn/simulate.hpp"

#include <gtest/gtest.h>

#include <csignal>

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
    s.method = method;
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

}  // namespace
