// Time per call against N, chains and binary trees: 𝓜 literal, composite, and from q alone (the
// local-frame route), bias after [kin] + [vel] and from (q, v) alone (the body-axes route), inverse
// dynamics, each forward-dynamics route, one full right-hand side, and the hybrid dynamics with a
// quarter or a half of the joints prescribed.
#include "models.hpp"

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/hybrid.hpp"
#include "soadyn/sim/integrators.hpp"
#include "soadyn/algorithm/kinematics.hpp"

#include <benchmark/benchmark.h>

#include <exception>
#include <string>

using namespace soadyn;

namespace {

struct Fixture {
  Model model;
  Data data;
  VecX q, v, tau, qdd;
  Fixture(int n, bool binary)
      : model(bench::make_tree(n, binary)),
        data(model),
        q(bench::random_vector(model.nq, 1, 3.0)),
        v(bench::random_vector(model.nv, 2)),
        tau(bench::random_vector(model.nv, 3)),
        qdd(bench::random_vector(model.nv, 4)) {
    update_kinematics(model, data, q);
    update_velocities(model, data, v);
  }
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

template <bool B> void Kinematics(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    update_kinematics(f.model, f.data, f.q);
    benchmark::DoNotOptimize(f.data.eta.data());
  });
}
template <bool B> void Velocities(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    update_velocities(f.model, f.data, f.v);
    benchmark::DoNotOptimize(f.data.V.data());
  });
}
template <bool B> void MassLiteral(benchmark::State& st) {
  MatX M;
  run<B>(st, [&](Fixture& f) {
    update_kinematics(f.model, f.data, f.q);
    mass_matrix_literal(f.model, f.data, M);
    benchmark::DoNotOptimize(M.data());
  });
}
template <bool B> void MassComposite(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    update_kinematics(f.model, f.data, f.q);
    mass_matrix(f.model, f.data);
    benchmark::DoNotOptimize(f.data.M.data());
  });
}
template <bool B> void MassFromQ(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    mass_matrix(f.model, f.data, f.q);
    benchmark::DoNotOptimize(f.data.M.data());
  });
}
template <bool B> void BiasFromQV(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    bias_forces(f.model, f.data, f.q, f.v);
    benchmark::DoNotOptimize(f.data.bias.data());
  });
}
template <bool B> void Bias(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    update_kinematics(f.model, f.data, f.q);
    update_velocities(f.model, f.data, f.v);
    bias_forces(f.model, f.data);
    benchmark::DoNotOptimize(f.data.bias.data());
  });
}
template <bool B> void Inverse(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    update_kinematics(f.model, f.data, f.q);
    update_velocities(f.model, f.data, f.v);
    inverse_dynamics(f.model, f.data, f.qdd);
    benchmark::DoNotOptimize(f.data.tau.data());
  });
}
// full right-hand side: kinematics + velocities + bias + forward dynamics
template <bool B, FdMethod M> void Forward(benchmark::State& st) {
  run<B>(st, [](Fixture& f) {
    update_kinematics(f.model, f.data, f.q);
    update_velocities(f.model, f.data, f.v);
    forward_dynamics(f.model, f.data, f.tau, M);
    benchmark::DoNotOptimize(f.data.qdd.data());
  });
}

// the same right-hand side with every `Every`-th joint prescribed (q̈ given there, τ solved): the
// hybrid dynamics (hybrid.hpp), to set beside rhs_on on the same model
template <bool B, int Every> void Hybrid(benchmark::State& st) {
  Fixture f(int(st.range(0)), B);
  std::vector<int> bodies;
  for (int i = Every - 1; i < f.model.nbodies; i += Every) bodies.push_back(i);
  const PrescribedJoints pj(f.model, bodies);
  VecX tau_out(f.model.nv);
  for (auto _ : st) {
    update_kinematics(f.model, f.data, f.q);
    update_velocities(f.model, f.data, f.v);
    hybrid_dynamics(f.model, f.data, pj, f.tau, f.qdd, tau_out);
    benchmark::DoNotOptimize(f.data.qdd.data());
    benchmark::DoNotOptimize(tau_out.data());
    benchmark::ClobberMemory();
  }
  st.counters["N"] = double(st.range(0));
  st.counters["prescribed"] = double(bodies.size());
}

// one step of a fixed-step method, h = 1 ms, on the chain (O(N) route inside).  A method that
// cannot take the step (symplectic-euler's Newton not converging on a long chain) is a row marked
// failed with the integrator's reason (report.py lists it under "Not timed"), and the run goes on.
void Step(benchmark::State& st, const char* method, Newton newton = Newton::Full) {
  const Model model = bench::make_tree(int(st.range(0)), false);
  const Inputs none;
  System sys(model, none, FdMethod::ArticulatedBody);
  SimulationSettings s;
  s.dt = 1e-3;
  s.newton = newton;
  VecX y(sys.size());
  y << bench::random_vector(model.nq, 1, 0.3), bench::random_vector(model.nv, 2, 0.1);
  const VecX y0 = y;
  double t = 0.0;
  auto integrator = make_integrator(parse_method(method), sys, s, t, y);
  auto failed = [&](const std::exception& e) {
    st.SkipWithError((std::string(method) + " on the " + std::to_string(st.range(0)) + "-link chain at dt 1e-3 failed: " +
                      e.what()).c_str());
  };
  try {  // the step once before timing: the same step every iteration times
    integrator->advance(t + s.dt, t, y);
  } catch (const std::exception& e) {
    failed(e);
    return;
  }
  for (auto _ : st) {
    y = y0;  // every iteration times the same step from the same state
    t = 0.0;
    try {
      integrator->advance(t + s.dt, t, y);
    } catch (const std::exception& e) {
      failed(e);
      break;
    }
    benchmark::DoNotOptimize(y.data());
  }
  // the nonlinear iterations per step, and the Jacobians formed per step (variational: its chord
  // iterations gave way to Newton's)
  const IntegratorStats stats = integrator->stats();
  if (stats.steps > 0) {
    st.counters["iterations"] = double(stats.nonlinear_iterations) / double(stats.steps);
    st.counters["jacobians"] = double(stats.jac_evals) / double(stats.steps);
  }
}

void sizes(benchmark::internal::Benchmark* b) {
  for (int n = 1; n <= 256; n *= 2) b->Arg(n);
}
void tree_sizes(benchmark::internal::Benchmark* b) {
  for (int n : {1, 3, 7, 15, 31, 63, 127, 255}) b->Arg(n);
}

}  // namespace

BENCHMARK(Kinematics<false>)->Name("chain/kinematics")->Apply(sizes);
BENCHMARK(Velocities<false>)->Name("chain/velocities")->Apply(sizes);
BENCHMARK(MassLiteral<false>)->Name("chain/mass_literal")->Apply(sizes);
BENCHMARK(MassComposite<false>)->Name("chain/mass_composite")->Apply(sizes);
BENCHMARK(MassFromQ<false>)->Name("chain/mass_q")->Apply(sizes);
BENCHMARK(BiasFromQV<false>)->Name("chain/bias_qv")->Apply(sizes);
BENCHMARK(Bias<false>)->Name("chain/bias")->Apply(sizes);
BENCHMARK(Inverse<false>)->Name("chain/inverse")->Apply(sizes);
BENCHMARK(Forward<false, FdMethod::Dense>)->Name("chain/rhs_dense")->Apply(sizes);
BENCHMARK(Forward<false, FdMethod::Sparse>)->Name("chain/rhs_sparse")->Apply(sizes);
BENCHMARK(Forward<false, FdMethod::ArticulatedBody>)->Name("chain/rhs_on")->Apply(sizes);
BENCHMARK(Hybrid<false, 4>)->Name("chain/rhs_hybrid_quarter")->Apply(sizes);
BENCHMARK(Hybrid<false, 2>)->Name("chain/rhs_hybrid_half")->Apply(sizes);
BENCHMARK_CAPTURE(Step, euler, "euler")->Name("chain/step_euler")->Apply(sizes);
BENCHMARK_CAPTURE(Step, symplectic_euler, "symplectic-euler")->Name("chain/step_symplectic_euler")->Apply(sizes);
BENCHMARK_CAPTURE(Step, rk4, "rk4")->Name("chain/step_rk4")->Apply(sizes);
BENCHMARK_CAPTURE(Step, implicit_midpoint, "implicit-midpoint")->Name("chain/step_implicit_midpoint")->DenseRange(1, 1)->Arg(2)->Arg(4)->Arg(8)->Arg(16)->Arg(32)->Arg(64);
BENCHMARK_CAPTURE(Step, variational, "variational")->Name("chain/step_variational")->Apply(sizes);
BENCHMARK_CAPTURE(Step, variational_simplified, "variational", Newton::Simplified)
    ->Name("chain/step_variational_simplified")
    ->Apply(sizes);
BENCHMARK(MassLiteral<true>)->Name("tree/mass_literal")->Apply(tree_sizes);
BENCHMARK(MassComposite<true>)->Name("tree/mass_composite")->Apply(tree_sizes);
BENCHMARK(MassFromQ<true>)->Name("tree/mass_q")->Apply(tree_sizes);
BENCHMARK(BiasFromQV<true>)->Name("tree/bias_qv")->Apply(tree_sizes);
BENCHMARK(Bias<true>)->Name("tree/bias")->Apply(tree_sizes);
BENCHMARK(Inverse<true>)->Name("tree/inverse")->Apply(tree_sizes);
BENCHMARK(Forward<true, FdMethod::Dense>)->Name("tree/rhs_dense")->Apply(tree_sizes);
BENCHMARK(Forward<true, FdMethod::Sparse>)->Name("tree/rhs_sparse")->Apply(tree_sizes);
BENCHMARK(Forward<true, FdMethod::ArticulatedBody>)->Name("tree/rhs_on")->Apply(tree_sizes);
BENCHMARK(Hybrid<true, 4>)->Name("tree/rhs_hybrid_quarter")->Apply(tree_sizes);

namespace soadyn::bench {
void register_peers();  // bench_peers.cpp
}

int main(int argc, char** argv) {
  soadyn::bench::register_peers();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
