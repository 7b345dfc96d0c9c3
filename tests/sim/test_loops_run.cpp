// Closed loops in a run (system.hpp, loops.hpp): a planar four-bar under gravity stays closed (q
// on φ = 0, v on K v = 0) and keeps its energy with every method that takes loops (CVODE BDF by
// its projection, Adams by projected outputs, the fixed-step methods projected after each step);
// a crank driven by a torque feeds the books through W; the refusals of what does not take loops.
#include "soadyn/sim/simulate.hpp"
#include "soadyn/sim/system.hpp"

#include "loop_util.hpp"
#include "test_util.hpp"

#include <cstdio>

using namespace soadyn;
using namespace soadyn::test;

namespace {

Scenario four_bar_scene(double theta = 0.7, double omega = 2.0) {
  const FourBar f = four_bar(theta, omega);
  Scenario sc;
  sc.path = "four-bar";
  sc.model = f.model;
  sc.inputs.loops = f.loops;
  sc.q0 = f.q, sc.v0 = f.v;
  sc.simulation.t_end = 5.0;
  sc.simulation.output_dt = 0.05;
  sc.simulation.rtol = 1e-10, sc.simulation.atol = 1e-12;
  return sc;
}

// the largest closure |φ| and |K v| over the samples
std::pair<double, double> closure(const Scenario& sc, const std::vector<Sample>& out) {
  double phi = 0, kv = 0;
  Data d(sc.model);
  LoopData ld(sc.model, sc.inputs.loops);
  for (const Sample& s : out) {
    update_kinematics(sc.model, d, s.q);
    update_velocities(sc.model, d, s.qd);
    loop_rows(sc.model, d, sc.inputs.loops, ld);
    phi = std::max(phi, ld.phi.cwiseAbs().maxCoeff());
    kv = std::max(kv, (ld.K * s.qd).cwiseAbs().maxCoeff());
  }
  return {phi, kv};
}

}  // namespace

TEST(LoopsRun, AFourBarStaysClosedAndKeepsItsEnergy) {
  const Scenario sc = four_bar_scene();
  const std::tuple<Method, double, double, double> methods[] = {
      // method, dt, closure bound, energy bound
      // (CVODE's outputs are interpolated between its projected steps: closed to the tolerance)
      {Method::CvodeBdf, 0, 1e-10, 1e-7},
      {Method::CvodeAdams, 0, 1e-10, 1e-7},
      {Method::Rk4, 1e-3, 1e-11, 1e-6},
      {Method::ImplicitMidpoint, 1e-3, 1e-11, 1e-3},
  };
  for (const auto& [method, dt, closed, energy] : methods) {
    SimulationSettings s = sc.simulation;
    s.method = method;
    if (dt > 0) s.dt = dt;
    std::vector<Sample> out;
    const RunSummary r = simulate(sc, s, nullptr, &out);
    ASSERT_TRUE(r.completed) << to_string(method) << ": " << r.status;
    const auto [phi, kv] = closure(sc, out);
    EXPECT_LE(phi, closed) << to_string(method);
    std::printf("  %s: closure %.1e, K v %.1e, energy balance %.1e\n", std::string(to_string(method)).c_str(), phi, kv,
                r.max_energy_balance_error);
    EXPECT_LE(kv, 1e-9) << to_string(method);
    EXPECT_LE(r.max_energy_balance_error, energy) << to_string(method);
    // it moves: the crank turns through a good part of a turn
    double lo = 1e9, hi = -1e9;
    for (const Sample& x : out) lo = std::min(lo, x.q(0)), hi = std::max(hi, x.q(0));
    EXPECT_GT(hi - lo, 1.0) << to_string(method);
  }
}

// without projection (a System's own rhs under a plain RK4 loop) the loop drifts: the projection is
// what holds it
TEST(LoopsRun, WithoutProjectionTheLoopDrifts) {
  const Scenario sc = four_bar_scene();
  System sys(sc.model, sc.inputs, FdMethod::ArticulatedBody);
  VecX y = sys.state(sc.q0, sc.v0), k1(y.size()), k2(y.size()), k3(y.size()), k4(y.size());
  const double h = 0.02;
  for (int n = 0; n < 250; ++n) {
    const double t = n * h;
    sys.rhs(t, y.data(), k1.data());
    VecX a = y + 0.5 * h * k1;
    sys.rhs(t + h / 2, a.data(), k2.data());
    a = y + 0.5 * h * k2;
    sys.rhs(t + h / 2, a.data(), k3.data());
    a = y + h * k3;
    sys.rhs(t + h, a.data(), k4.data());
    y += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  Data d(sc.model);
  update_kinematics(sc.model, d, VecX(y.head(3)));
  LoopData ld(sc.model, sc.inputs.loops);
  loop_closure(sc.model, d, sc.inputs.loops, ld);
  const double drift = ld.phi.cwiseAbs().maxCoeff();
  EXPECT_GT(drift, 1e-9);
  ASSERT_TRUE(sys.project(y));
  update_kinematics(sc.model, d, VecX(y.head(3)));
  loop_closure(sc.model, d, sc.inputs.loops, ld);
  EXPECT_LE(ld.phi.cwiseAbs().maxCoeff(), kLoopClosure);
}

// a torque on the crank does work, and the books take it: E − E₀ = W
TEST(LoopsRun, ADrivenCrankFeedsTheBooks) {
  Scenario sc = four_bar_scene(0.2, 0.0);
  sc.inputs.torques.push_back({"crank", 0, 2.0, 0.0, 0.0, 0.0});
  sc.simulation.method = Method::CvodeBdf;
  std::vector<Sample> out;
  const RunSummary r = simulate(sc, sc.simulation, nullptr, &out);
  ASSERT_TRUE(r.completed) << r.status;
  EXPECT_GT(std::abs(out.back().work_inputs), 0.1);
  EXPECT_LE(r.max_energy_balance_error, 1e-7);
}

TEST(LoopsRun, WhatDoesNotTakeLoopsIsRefusedInOneLine) {
  Scenario sc = four_bar_scene();
  SimulationSettings s = sc.simulation;
  s.method = Method::SymplecticEuler;
  EXPECT_NE(message_of([&] { check_run(sc, s); }).find("symplectic-euler"), std::string::npos);
  s = sc.simulation;
  s.sensitivities.initial_state = true;
  EXPECT_NE(message_of([&] { check_run(sc, s); }).find("not available with closed loops"), std::string::npos);
  Scenario bad = sc;
  bad.inputs.loops[0].body_b = bad.inputs.loops[0].body_a;
  EXPECT_NE(message_of([&] { check_run(bad, bad.simulation); }).find("two different bodies"), std::string::npos);
}
