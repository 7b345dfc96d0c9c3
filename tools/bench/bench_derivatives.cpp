// Time of each derivative set against N, chains and binary trees (tools/bench/models.hpp), next to
// one O(N) forward dynamics; tools/bench/derivatives.py turns the JSON into
// tools/results/derivatives.md (ratios to forward dynamics, fitted exponents, BDF analytic vs DQ).
//   fd          kinematics + velocities + O(N) articulated-body q̈ (the unit)
//   id_deriv    kinematics + ∂τ/∂q, ∂τ/∂v (inverse_dynamics_derivatives)
//   fd_deriv    kinematics + velocities + ∂q̈/∂q, ∂q̈/∂v (forward_dynamics_derivatives)
//   fd_deriv_minv  the same and 𝓜⁻¹ = ∂q̈/∂τ
//   minverse       kinematics + 𝓜⁻¹ by the articulated-body recursion (minverse, O(N²) on a chain)
//   minverse_ltdl  kinematics + 𝓜 + its LᵀDL factor solved against the identity (O(N³) on a chain)
//   jac_analytic   System::jacobian: ∂f/∂y of ẏ = f(y) (what CVODE BDF and the midpoint rule use)
//   jac_dq         System::jacobian_dq: the same by nq + nv forward differences of f
#include "models.hpp"

#include "soadyn/derivatives.hpp"
#include "soadyn/integrators.hpp"
#include "soadyn/kinematics.hpp"

#include <benchmark/benchmark.h>

using namespace soadyn;

namespace {

struct Fixture {
  Model model;
  Data data;
  DerivativeData dd;
  VecX q, v, tau, qdd;
  Fixture(int n, bool binary)
      : model(bench::make_tree(n, binary)),
        data(model),
        dd(model),
        q(bench::random_vector(model.nq, 1, 3.0)),
        v(bench::random_vector(model.nv, 2)),
        tau(bench::random_vector(model.nv, 3)),
        qdd(bench::random_vector(model.nv, 4)) {}
};

template <bool Binary, class F>
void run(benchmark::State& st, F&& body) {
  Fixture f(int(st.range(0)), Binary);
  for (auto _ : st) {
    body(f);
    benchmark::ClobberMemory();
  }
  st.counters["N"] = double(st.range(0));
}

template <bool B> void Fd(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    update_kinematics(f.model, f.data, f.q);
    update_velocities(f.model, f.data, f.v);
    forward_dynamics(f.model, f.data, f.tau, FdMethod::ArticulatedBody);
    benchmark::DoNotOptimize(f.data.qdd.data());
  });
}
template <bool B> void IdDeriv(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    update_kinematics(f.model, f.data, f.q);
    inverse_dynamics_derivatives(f.model, f.data, f.v, f.qdd, f.dd);
    benchmark::DoNotOptimize(f.dd.dtau_dq.data());
  });
}
template <bool B, bool Minv> void FdDeriv(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    update_kinematics(f.model, f.data, f.q);
    update_velocities(f.model, f.data, f.v);
    forward_dynamics_derivatives(f.model, f.data, f.v, f.tau, f.dd, nullptr, Minv);
    benchmark::DoNotOptimize(f.dd.dqdd_dq.data());
  });
}
template <bool B> void Minverse(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    update_kinematics(f.model, f.data, f.q);
    minverse(f.model, f.data, f.dd.Minv);
    benchmark::DoNotOptimize(f.dd.Minv.data());
  });
}
template <bool B> void MinverseLtdl(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    update_kinematics(f.model, f.data, f.q);
    mass_matrix(f.model, f.data);
    ltdl_factor(f.model, f.data);
    f.dd.Minv.setIdentity();
    for (int c = 0; c < f.model.nv; ++c) ltdl_solve(f.model, f.data, f.dd.Minv.col(c));
    benchmark::DoNotOptimize(f.dd.Minv.data());
  });
}
template <bool B, bool Analytic> void Jacobian(benchmark::State& st) {
  const Model model = bench::make_tree(int(st.range(0)), B);
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
}
void tree_sizes(benchmark::internal::Benchmark* b) {
  for (int n : {1, 3, 7, 15, 31, 63, 127, 255}) b->Arg(n);
}

}  // namespace

BENCHMARK(Fd<false>)->Name("chain/fd")->Apply(sizes);
BENCHMARK(IdDeriv<false>)->Name("chain/id_deriv")->Apply(sizes);
BENCHMARK(FdDeriv<false, false>)->Name("chain/fd_deriv")->Apply(sizes);
BENCHMARK(FdDeriv<false, true>)->Name("chain/fd_deriv_minv")->Apply(sizes);
BENCHMARK(Minverse<false>)->Name("chain/minverse")->Apply(sizes);
BENCHMARK(MinverseLtdl<false>)->Name("chain/minverse_ltdl")->Apply(sizes);
BENCHMARK(Jacobian<false, true>)->Name("chain/jac_analytic")->Apply(sizes);
BENCHMARK(Jacobian<false, false>)->Name("chain/jac_dq")->Apply(sizes);
BENCHMARK(Fd<true>)->Name("tree/fd")->Apply(tree_sizes);
BENCHMARK(IdDeriv<true>)->Name("tree/id_deriv")->Apply(tree_sizes);
BENCHMARK(FdDeriv<true, false>)->Name("tree/fd_deriv")->Apply(tree_sizes);
BENCHMARK(FdDeriv<true, true>)->Name("tree/fd_deriv_minv")->Apply(tree_sizes);
BENCHMARK(Minverse<true>)->Name("tree/minverse")->Apply(tree_sizes);
BENCHMARK(MinverseLtdl<true>)->Name("tree/minverse_ltdl")->Apply(tree_sizes);
BENCHMARK(Jacobian<true, true>)->Name("tree/jac_analytic")->Apply(tree_sizes);
BENCHMARK(Jacobian<true, false>)->Name("tree/jac_dq")->Apply(tree_sizes);

BENCHMARK_MAIN();
