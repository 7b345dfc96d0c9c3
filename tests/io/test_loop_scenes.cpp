// The closed-loop scenes of scenarios/ (slider_crank.yaml, delta_robot.yaml, four_bar.yaml) as a
// user runs them: assembled onto their loops and said so, their dependent rows said once, closed
// and with their books balanced over the run; the Delta robot's motors on their targets by
// computed torque, and its constrained inverse dynamics at the logged motion giving back the
// torques the run applied (inverse against forward dynamics with three loops).
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/algorithm/loops.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/sim/simulate.hpp"

#include "test_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

using namespace soadyn;

namespace {

Scenario scene(const char* name) { return load_scenario(std::string(SOADYN_SOURCE_DIR) + "/scenarios/" + name); }

bool says(const std::vector<std::string>& lines, const std::string& what) {
  return std::count_if(lines.begin(), lines.end(), [&](const std::string& l) { return l.find(what) != std::string::npos; }) == 1;
}

double worst_closure(const std::vector<Sample>& out) {
  double c = 0;
  for (const Sample& s : out) c = std::max(c, s.loop_closure);
  return c;
}

}  // namespace

TEST(LoopScenes, TheSliderCrankSpinsUpClosedWithItsBooksBalanced) {
  Scenario sc = scene("slider_crank.yaml");
  // the assembly and the planar hinge's 5 rows of rank 2, each said once before the run
  const std::vector<std::string> warnings = check_run(sc, sc.simulation);
  EXPECT_TRUE(says(warnings, "the initial state was assembled onto the loops"));
  EXPECT_TRUE(says(warnings, "5 constraint rows of rank 2: 3 depend on the others"));
  // the rod's end on the piston's axis, ahead of the crank (the assembled branch)
  EXPECT_GT(sc.q0(2), 0.3);
  std::vector<Sample> out;
  const RunSummary r = simulate(sc, sc.simulation, nullptr, &out);
  ASSERT_TRUE(r.completed) << r.status;
  double fastest = 0;
  for (const Sample& s : out) fastest = std::max(fastest, s.qd(0));
  std::printf("  closure %.1e, energy balance %.1e, crank up to %.1f rad/s, piston force up to %.1f N\n",
              worst_closure(out), r.max_energy_balance_error, fastest, out.back().loop_force.cwiseAbs().maxCoeff());
  EXPECT_LE(worst_closure(out), 1e-9);
  // CVODE's ~15 600 steps at rtol 1e-10 each leave their error in the books: 1.7e-7 here
  EXPECT_LE(r.max_energy_balance_error, 1e-6);
  EXPECT_GT(fastest, 10.0);  // spun up by the motor
  EXPECT_LT(fastest, 50.0);  // below its no-load speed
  // rk4 at 0.1 ms, projected after each step: the books to 1e-9
  SimulationSettings s = sc.simulation;
  s.method = Method::Rk4, s.dt = 1e-4, s.t_end = 2.0;
  const RunSummary fixed = simulate(sc, s, nullptr, nullptr);
  ASSERT_TRUE(fixed.completed) << fixed.status;
  std::printf("  rk4 at dt 1e-4: energy balance %.1e\n", fixed.max_energy_balance_error);
  EXPECT_LE(fixed.max_energy_balance_error, 1e-9);
}

TEST(LoopScenes, TheDeltaRobotFollowsItsMotorsTargetsByTheLoopsInverseDynamics) {
  Scenario sc = scene("delta_robot.yaml");
  sc.simulation.t_end = 2.0;
  // assembled, and 9 independent rows
  const std::vector<std::string> warnings = check_run(sc, sc.simulation);
  EXPECT_EQ(warnings.size(), 1u);
  EXPECT_TRUE(says(warnings, "the initial state was assembled onto the loops"));
  std::vector<Sample> out;
  const RunSummary r = simulate(sc, sc.simulation, nullptr, &out);
  ASSERT_TRUE(r.completed) << r.status;
  const Model& m = sc.model;
  const ControllerInput& c = sc.inputs.controllers[0];
  ASSERT_EQ(c.actuated.size(), 3u);
  double track = 0, torque = 0, scale = 0, travel = 0;
  Data d(m);
  LoopData ld(m, sc.inputs.loops);
  // the platform's position: its Cartesian chain's x, y, z
  const int x = m.idx_q[size_t(m.joint_index("x"))], y = m.idx_q[size_t(m.joint_index("y"))],
            z = m.idx_q[size_t(m.joint_index("z"))];
  const auto platform = [&](const Sample& s) { return Vec3(s.q(x), s.q(y), s.q(z)); };
  for (const Sample& s : out) {
    for (const int k : c.actuated) track = std::max(track, std::abs(s.q(k) - c.targets[size_t(k)].value(s.t)));
    travel = std::max(travel, (platform(s) - platform(out[0])).norm());
    // the loops' inverse dynamics of the logged motion: the motors' torques the run applied
    update_kinematics(m, d, s.q);
    update_velocities(m, d, s.qd);
    VecX qdd = s.qdd;
    const VecX tau = loop_inverse_dynamics(m, d, sc.inputs.loops, c.actuated, qdd, ld);
    torque = std::max(torque, (tau - s.control).cwiseAbs().maxCoeff());
    scale = std::max(scale, s.control.cwiseAbs().maxCoeff());
  }
  std::printf("  motors on target to %.1e rad, inverse dynamics against the applied torques %.1e N m of %.2f, platform "
              "travel %.3f m, closure %.1e, balance %.1e\n",
              track, torque, scale, travel, worst_closure(out), r.max_energy_balance_error);
  EXPECT_LE(track, 1e-6);
  EXPECT_GT(scale, 0.5);
  EXPECT_LE(torque, 1e-6 * scale);
  EXPECT_GT(travel, 0.01);
  EXPECT_LE(worst_closure(out), 1e-9);
  EXPECT_LE(r.max_energy_balance_error, 1e-7);
}

TEST(LoopScenes, TheFourBarIsAssembledAndSaysSo) {
  const Scenario sc = scene("four_bar.yaml");
  EXPECT_TRUE(sc.model.warnings.empty());  // nothing said before a run would be refused
  const std::vector<std::string> warnings = check_run(sc, sc.simulation);
  EXPECT_TRUE(says(warnings, "the initial state was assembled onto the loops"));
  EXPECT_TRUE(says(warnings, "depend on the others"));
}
