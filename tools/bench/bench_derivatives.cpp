// Time of each derivative set against N, chains, binary trees (tools/bench/models.hpp) and legged
// free-floating robots (a free trunk and four legs of N links: 6 + 4N DOFs), next to one O(N)
// forward dynamics; tools/bench/derivatives.py turns the JSON into tools/results/derivatives.md
// (ratios to forward dynamics, fitted exponents, BDF analytic vs DQ).
//   fd          kinematics + velocities + O(N) articulated-body q̈ (the unit)
//   id_deriv    kinematics + ∂τ/∂q, ∂τ/∂v (inverse_dynamics_derivatives)
//   fd_deriv    kinematics + velocities + ∂q̈/∂q, ∂q̈/∂v and ∂q̈/∂τ = 𝓜⁻¹ (forward_dynamics_derivatives)
//   minverse       kinematics + 𝓜⁻¹ by the articulated-body recursion (minverse, O(N²) on a chain)
//   minverse_ltdl  kinematics + 𝓜 + its LᵀDL factor solved against the identity (O(N³) on a chain)
//   jac_analytic   System::jacobian: ∂f/∂y of ẏ = f(y) (what CVODE BDF and the midpoint rule use)
//   jac_dq         System::jacobian_dq: the same by nq + nv forward differences of f
#include "models.hpp"

#include "soadyn/algorithm/derivatives.hpp"
#include "soadyn/sim/integrators.hpp"
#include "soadyn/algorithm/kinematics.hpp"

#include <benchmark/benchmark.h>

using namespace soadyn;

namespace {

enum class Shape { Chain, Tree, Legged };

Model make_model(Shape shape, int n) {
  return shape == Shape::Legged ? bench::make_legged(4, n) : bench::make_tree(n, shape == Shape::Tree);
}

struct Fixture {
  Model model;
  Data data;
  DerivativeData dd;
  VecX q, v, tau, qdd;
  Fixture(Shape shape, int n)
      : model(make_model(shape, n)),
        data(model),
        dd(model),
        q(bench::random_vector(model.nq, 1, 3.0)),
        v(bench::random_vector(model.nv, 2)),
        tau(bench::random_vector(model.nv, 3)),
        qdd(bench::random_vector(model.nv, 4)) {}
};

template <Shape B, class F>
void run(benchmark::State& st, F&& body) {
  Fixture f(B, int(st.range(0)));
  for (auto _ : st) {
    body(f);
    benchmark::ClobberMemory();
  }
  st.counters["N"] = double(st.range(0));
}

template <Shape B> void Fd(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    update_kinematics(f.model, f.data, f.q);
    update_velocities(f.model, f.data, f.v);
    forward_dynamics(f.model, f.data, f.tau, FdMethod::ArticulatedBody);
    benchmark::DoNotOptimize(f.data.qdd.data());
  });
}
template <Shape B> void IdDeriv(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    update_kinematics(f.model, f.data, f.q);
    inverse_dynamics_derivatives(f.model, f.data, f.v, f.qdd, f.dd);
    benchmark::DoNotOptimize(f.dd.dtau_dq.data());
  });
}
template <Shape B> void FdDeriv(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    update_kinematics(f.model, f.data, f.q);
    update_velocities(f.model, f.data, f.v);
    forward_dynamics_derivatives(f.model, f.data, f.v, f.tau, f.dd);
    benchmark::DoNotOptimize(f.dd.dqdd_dq.data());
  });
}
template <Shape B> void Minverse(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    update_kinematics(f.model, f.data, f.q);
    minverse(f.model, f.data, f.dd.Minv);
    benchmark::DoNotOptimize(f.dd.Minv.data());
  });
}
template <Shape B> void MinverseLtdl(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    update_kinematics(f.model, f.data, f.q);
    mass_matrix(f.model, f.data);
    ltdl_factor(f.model, f.data);
    f.dd.Minv.setIdentity();
    for (int c = 0; c < f.model.nv; ++c) ltdl_solve(f.model, f.data, f.dd.Minv.col(c));
    benchmark::DoNotOptimize(f.dd.Minv.data());
  });
}
template <Shape B, bool Analytic> void SystemJacobian(benchmark::State& st) {
  const Model model = make_model(B, int(st.range(0)));
  const Inputs none;
  System sys(model, none, FdMethod::ArticulatedBody);
  const VecX y = sys.state(bench::random_vector(model.nq, 1, 3.0), bench::random_vector(model.nv, 2));
  MatX J(sys.size(), sys.size());
  for (auto _ : st) {
    if (Analytic)
      sys.jacobian(0.0, y.data(), J);
    else
      sys.jacobian_dq(0.0, y.data(), J);
    benchmark::DoNotOptimize(J.data());
  }
  st.counters["N"] = double(st.range(0));
}

void sizes(benchmark::internal::Benchmark* b) {
  for (int n = 1; n <= 256; n *= 2) b->Arg(n);
  b->Arg(24);
}
void tree_sizes(benchmark::internal::Benchmark* b) {
  for (int n : {1, 3, 7, 15, 31, 63, 127, 255}) b->Arg(n);
}

}  // namespace

void leg_lengths(benchmark::internal::Benchmark* b) {
  for (int n : {1, 3, 6, 11, 20}) b->Arg(n);  // 10, 18, 30, 50, 86 DOFs
}

#define SETS(group, shape, range)                                                                      \
  BENCHMARK(Fd<shape>)->Name(group "/fd")->Apply(range);                                              \
  BENCHMARK(IdDeriv<shape>)->Name(group "/id_deriv")->Apply(range);                                   \
  BENCHMARK(FdDeriv<shape>)->Name(group "/fd_deriv")->Apply(range);                                   \
  BENCHMARK(Minverse<shape>)->Name(group "/minverse")->Apply(range);                                  \
  BENCHMARK(MinverseLtdl<shape>)->Name(group "/minverse_ltdl")->Apply(range);                         \
  BENCHMARK(SystemJacobian<shape, true>)->Name(group "/jac_analytic")->Apply(range);                        \
  BENCHMARK(SystemJacobian<shape, false>)->Name(group "/jac_dq")->Apply(range)

SETS("chain", Shape::Chain, sizes);
SETS("tree", Shape::Tree, tree_sizes);
SETS("legged", Shape::Legged, leg_lengths);

BENCHMARK_MAIN();
