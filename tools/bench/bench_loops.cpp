// Closed loops (loops.hpp): the constrained forward dynamics of a scene against its tree's own
// (the same model with no loops: one full right-hand side each, kinematics and velocities
// included), on the four-bar (one hinge loop, 5 rows) and the Delta robot (three point loops, 9
// rows), the Delta's constrained inverse dynamics (the motors' torques), the dense saddle-point
// route for scale; and the chains of bench_dynamics.cpp closed by a point loop from the tip to the
// world, against chain/rhs_on (the cost of a few loops on a tree of N: O(N) per row).
// Run from the top of the tree (the scenes are read from scenarios/).
#include "models.hpp"

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/frames.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/algorithm/loops.hpp"
#include "soadyn/io/scenario_file.hpp"

#include <benchmark/benchmark.h>

#include <exception>
#include <string>

using namespace soadyn;

namespace {

enum class Route { Tree, Loops, Dense, Inverse };

// one scene's rhs at its (assembled) initial state by `route`
void Scene(benchmark::State& st, const char* file, Route route) {
  Scenario sc;
  try {
    sc = load_scenario(std::string("scenarios/") + file);
  } catch (const std::exception& e) {
    st.SkipWithError((std::string(file) + ": " + e.what() + " (run from the top of the tree)").c_str());
    return;
  }
  const Model& m = sc.model;
  Data d(m);
  LoopData ld(m, sc.inputs.loops);
  const VecX tau = bench::random_vector(m.nv, 3);
  std::vector<int> actuated;
  for (const ControllerInput& c : sc.inputs.controllers) actuated.insert(actuated.end(), c.actuated.begin(), c.actuated.end());
  if (actuated.empty()) actuated.push_back(0);
  VecX qdd = bench::random_vector(m.nv, 4);
  for (auto _ : st) {
    update_kinematics(m, d, sc.q0);
    update_velocities(m, d, sc.v0);
    switch (route) {
      case Route::Tree: forward_dynamics(m, d, tau, FdMethod::ArticulatedBody); break;
      case Route::Loops: loop_forward_dynamics(m, d, sc.inputs.loops, sc.v0, tau, ld); break;
      case Route::Dense: loop_forward_dynamics_dense(m, d, sc.inputs.loops, tau, ld); break;
      case Route::Inverse: benchmark::DoNotOptimize(loop_inverse_dynamics(m, d, sc.inputs.loops, actuated, qdd, ld).data()); break;
    }
    benchmark::DoNotOptimize(d.qdd.data());
    benchmark::ClobberMemory();
  }
  st.counters["N"] = double(m.nbodies);
  st.counters["rows"] = double(ld.m);
}

// a chain of N closed by a point loop from its tip's frame to the world point where it is
void ChainLoop(benchmark::State& st) {
  const Model model = bench::make_tree(int(st.range(0)), false);
  Data d(model);
  const VecX q = bench::random_vector(model.nq, 1, 3.0), v = bench::random_vector(model.nv, 2),
             tau = bench::random_vector(model.nv, 3);
  update_kinematics(model, d, q);
  LoopConstraint tip;
  tip.name = "tip", tip.type = LoopType::Point, tip.body_a = model.nbodies - 1, tip.body_b = -1;
  tip.at_b.p = body_frame_placement(model, d, tip.body_a, tip.at_a).p;
  const std::vector<LoopConstraint> loops{tip};
  LoopData ld(model, loops);
  for (auto _ : st) {
    update_kinematics(model, d, q);
    update_velocities(model, d, v);
    loop_forward_dynamics(model, d, loops, v, tau, ld);
    benchmark::DoNotOptimize(d.qdd.data());
    benchmark::ClobberMemory();
  }
  st.counters["N"] = double(st.range(0));
}

}  // namespace

BENCHMARK_CAPTURE(Scene, four_bar_tree, "four_bar.yaml", Route::Tree)->Name("loops/four_bar_tree");
BENCHMARK_CAPTURE(Scene, four_bar_closed, "four_bar.yaml", Route::Loops)->Name("loops/four_bar_closed");
BENCHMARK_CAPTURE(Scene, four_bar_dense, "four_bar.yaml", Route::Dense)->Name("loops/four_bar_dense");
BENCHMARK_CAPTURE(Scene, delta_tree, "delta_robot.yaml", Route::Tree)->Name("loops/delta_tree");
BENCHMARK_CAPTURE(Scene, delta_closed, "delta_robot.yaml", Route::Loops)->Name("loops/delta_closed");
BENCHMARK_CAPTURE(Scene, delta_dense, "delta_robot.yaml", Route::Dense)->Name("loops/delta_dense");
BENCHMARK_CAPTURE(Scene, delta_inverse, "delta_robot.yaml", Route::Inverse)->Name("loops/delta_inverse");
BENCHMARK(ChainLoop)->Name("chain/rhs_loop_tip")->RangeMultiplier(2)->Range(2, 256);
