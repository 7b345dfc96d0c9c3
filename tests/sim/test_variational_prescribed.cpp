// method: variational with prescribed motion (variational.cpp): the free rows of the DEL equations,
// the prescribed joints' motion given, their holding work from the impulses the prescribed rows miss:
//   order 2 on the crane's slew (gravity, a swinging load) and the antenna's slew (a free-floating
//     bus), the free coordinates, velocities and the holding work W_p against CVODE at rtol 1e-12;
//   the antenna's slew is internal: the whole satellite's linear and angular momentum are conserved
//     to rounding while the gimbal turns 90° and the bus turns in reaction;
//   the energy books E − E₀ = W + W_p − D close to O(h²) (the balance falls 4× as h halves);
//   both solvers (Newton, the chord) take the same steps.
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/multibody/configuration.hpp"
#include "soadyn/sim/simulate.hpp"

#include "order_util.hpp"
#include "test_util.hpp"

#include <cmath>
#include <cstdio>

using namespace soadyn;
using namespace soadyn::test;

namespace {

const std::string kDir = SOADYN_SOURCE_DIR "/scenarios/";

SimulationSettings fixed(const Scenario& sc, double dt, double t_end, Newton newton = Newton::Full) {
  SimulationSettings s = sc.simulation;
  s.method = Method::Variational;
  s.newton = newton;
  s.dt = dt;
  s.t_end = t_end;
  s.output_dt = t_end / 20;
  return s;
}

TEST(VariationalPrescribed, OrderTwoOnTheCraneAndTheAntenna) {
  struct Case {
    const char* scene;
    double dt, T;
  };
  for (const Case& c : {Case{"crane_slew", 0.02, 8.0}, Case{"antenna_slew", 0.2, 15.0}}) {
    const Scenario sc = load_scenario(kDir + c.scene + ".yaml");
    // ‖[q_ref ⊖ q; v − v_ref; W_p − W_p,ref]‖ at T
    Sample ref;
    std::vector<double> err;
    ASSERT_NO_FATAL_FAILURE(halving_errors(
        sc, c.dt, c.T, [&](double h) { return fixed(sc, h, c.T); }, ref, err,
        [](const Sample& x) { return x.work_prescribed; }));
    const double p1 = std::log2(err[0] / err[1]), p2 = std::log2(err[1] / err[2]);
    std::printf("[ order ] variational, prescribed, %-13s errors %.3e %.3e %.3e (log2 %.3f %.3f); W_p %.4g\n", c.scene,
                err[0], err[1], err[2], p1, p2, ref.work_prescribed);
    EXPECT_GT(std::abs(ref.work_prescribed), 1e-3) << c.scene;  // the holding torques did work
    EXPECT_NEAR(p1, 2.0, 0.2) << c.scene;
    EXPECT_NEAR(p2, 2.0, 0.2) << c.scene;
  }
}

// the gimbal's slew is internal to the satellite: its linear and angular momentum stay what they
// were to rounding (relative to |L| of the slewing dish about the bus, ≤ 1e-12), by both solvers,
// while the bus turns in reaction by far more
TEST(VariationalPrescribed, TheAntennaSlewConservesTheSatellitesMomentum) {
  const Scenario sc = load_scenario(kDir + "antenna_slew.yaml");
  for (const Newton solver : {Newton::Full, Newton::Simplified}) {
    std::vector<Sample> x;
    SimulationSettings s = fixed(sc, 0.05, 40.0, solver);
    s.output_dt = 0.5;
    const RunSummary sum = simulate(sc, s, nullptr, &x);
    ASSERT_TRUE(sum.completed) << sum.status;
    double dl = 0, dL = 0, scale = 0, turned = 0;
    for (const Sample& k : x) {
      dl = std::max(dl, (k.linear - x.front().linear).norm());
      dL = std::max(dL, (k.angular - x.front().angular).norm());
      scale = std::max({scale, k.angular.norm(), 52.0 * k.qd.tail<2>().norm()});  // the bus's and the gimbal's scale
      turned = std::max(turned, difference(sc.model, x.front().q, k.q).head<6>().norm());
    }
    std::printf("[ momentum ] antenna slew (%s): max |Δl| %.2e, |ΔL| %.2e (scale %.3g); the bus turned %.3g rad\n",
                solver == Newton::Full ? "newton" : "chord", dl, dL, scale, turned);
    EXPECT_LE(dL, 1e-12 * std::max(scale, 1.0));
    EXPECT_LE(dl, 1e-12 * std::max(scale, 1.0));
    EXPECT_GT(turned, 1e-3);
  }
}

// the books E − E₀ = W + W_p − D close to O(h²): the run's largest balance error falls about
// 4× as h halves (crane: gravity, the trolley's drive doing work on the swinging load), and the
// two solvers' runs end at the same state
TEST(VariationalPrescribed, EnergyBooksCloseToOrderTwo) {
  const Scenario sc = load_scenario(kDir + "crane_slew.yaml");
  std::vector<double> balance;
  for (const double h : {0.02, 0.01, 0.005}) {
    const RunSummary sum = simulate(sc, fixed(sc, h, 10.0));
    ASSERT_TRUE(sum.completed) << sum.status;
    balance.push_back(sum.max_energy_balance_error);
  }
  std::printf("[ balance ] variational, crane slew: %.3e %.3e %.3e (ratios %.2f %.2f)\n", balance[0], balance[1],
              balance[2], balance[0] / balance[1], balance[1] / balance[2]);
  EXPECT_GT(balance[0] / balance[1], 3.0);
  EXPECT_GT(balance[1] / balance[2], 3.0);
  EXPECT_LT(balance[2], 1e-4);
  std::vector<Sample> a, b;
  ASSERT_TRUE(simulate(sc, fixed(sc, 0.01, 2.0), nullptr, &a).completed);
  ASSERT_TRUE(simulate(sc, fixed(sc, 0.01, 2.0, Newton::Simplified), nullptr, &b).completed);
  EXPECT_LE(difference(sc.model, a.back().q, b.back().q).norm(), 1e-12);
  EXPECT_LE((a.back().qd - b.back().qd).norm(), 1e-11 * a.back().qd.norm());
}

}  // namespace
