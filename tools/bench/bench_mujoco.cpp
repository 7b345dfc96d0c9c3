// MuJoCo as a peer in the same run, on the same URDF chains (tools/bench/make_models.py):
//   mujoco/mass  mj_kinematics + mj_comPos + mj_crb + mj_fullM   vs  soadyn update_kinematics + mass_matrix
//   mujoco/bias  ... + mj_comVel + mj_rne(flg_acc = 0)              vs  soadyn kinematics + velocities + bias
//   mujoco/rhs   mj_forward, contacts/limits/passive/constraints off vs soadyn kinematics + velocities + O(N) q̈
// Before timing, both libraries must give the same 𝓜 at a random state.
#include "models.hpp"

#include "soadyn/algorithms.hpp"
#include "soadyn/kinematics.hpp"
#include "soadyn/scenario.hpp"

#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <cstdlib>
#include <iostream>
#include <memory>
#include <stdexcept>

namespace {

std::string models_dir() {
  const char* d = std::getenv("SOADYN_BENCH_MODELS");
  return d ? d : "build/bench_models";
}

struct MjOwner {
  mjModel* m = nullptr;
  mjData* d = nullptr;
  MjOwner(const MjOwner&) = delete;
  MjOwner& operator=(const MjOwner&) = delete;
  explicit MjOwner(const std::string& path) {
    char err[1000] = "";
    m = mj_loadXML(path.c_str(), nullptr, err, sizeof err);
    if (!m) throw std::runtime_error("MuJoCo could not load " + path + ": " + err);
    m->opt.disableflags |= mjDSBL_CONTACT | mjDSBL_LIMIT | mjDSBL_PASSIVE | mjDSBL_CONSTRAINT;
    d = mj_makeData(m);
  }
  ~MjOwner() {
    if (d) mj_deleteData(d);
    if (m) mj_deleteModel(m);
  }
};

struct Pair {
  std::unique_ptr<MjOwner> mj;
  soadyn::Model model;
  soadyn::Data data;
  soadyn::VecX q, v, tau;
  explicit Pair(int n)
      : mj(std::make_unique<MjOwner>(models_dir() + "/chain_" + std::to_string(n) + ".urdf")),
        model(soadyn::load_urdf(models_dir() + "/chain_" + std::to_string(n) + ".urdf", false, soadyn::Vec3(0, 0, -9.81))),
        data(model),
        q(soadyn::bench::random_vector(model.nq, 1, 3.0)),
        v(soadyn::bench::random_vector(model.nv, 2)),
        tau(soadyn::bench::random_vector(model.nv, 3)) {
    if (mj->m->nv != model.nv) throw std::runtime_error("MuJoCo and soadyn disagree on nv");
    for (int k = 0; k < model.nv; ++k) {
      mj->d->qpos[k] = q(k);
      mj->d->qvel[k] = v(k);
      mj->d->qfrc_applied[k] = tau(k);
    }
    // the same 𝓜 in both, before any timing
    mj_kinematics(mj->m, mj->d);
    mj_comPos(mj->m, mj->d);
    mj_crb(mj->m, mj->d);
    soadyn::MatX Mmj(model.nv, model.nv);
    mj_fullM(mj->m, Mmj.data(), mj->d->qM);  // symmetric: row/column order does not matter
    soadyn::update_kinematics(model, data, q);
    soadyn::mass_matrix(model, data);
    const double err = (Mmj - data.Mass).cwiseAbs().maxCoeff(), scale = data.Mass.cwiseAbs().maxCoeff();
    if (!(err <= 1e-9 * scale)) {
      std::cerr << "MuJoCo and soadyn mass matrices differ on chain_" << n << ": " << err << " (scale " << scale << ")\n";
      std::exit(1);
    }
  }
};

void MjMass(benchmark::State& st) {
  Pair p(int(st.range(0)));
  for (auto _ : st) {
    mj_kinematics(p.mj->m, p.mj->d);
    mj_comPos(p.mj->m, p.mj->d);
    mj_crb(p.mj->m, p.mj->d);
    mj_fullM(p.mj->m, p.data.Mass.data(), p.mj->d->qM);
    benchmark::ClobberMemory();
  }
}
void MjBias(benchmark::State& st) {
  Pair p(int(st.range(0)));
  soadyn::VecX out(p.model.nv);
  for (auto _ : st) {
    mj_kinematics(p.mj->m, p.mj->d);
    mj_comPos(p.mj->m, p.mj->d);
    mj_comVel(p.mj->m, p.mj->d);
    mj_rne(p.mj->m, p.mj->d, 0, out.data());
    benchmark::DoNotOptimize(out.data());
  }
}
void MjRhs(benchmark::State& st) {
  Pair p(int(st.range(0)));
  for (auto _ : st) {
    mj_forward(p.mj->m, p.mj->d);
    benchmark::DoNotOptimize(p.mj->d->qacc);
  }
}
void SdMass(benchmark::State& st) {
  Pair p(int(st.range(0)));
  for (auto _ : st) {
    soadyn::update_kinematics(p.model, p.data, p.q);
    soadyn::mass_matrix(p.model, p.data);
    benchmark::DoNotOptimize(p.data.Mass.data());
  }
}
void SdBias(benchmark::State& st) {
  Pair p(int(st.range(0)));
  for (auto _ : st) {
    soadyn::update_kinematics(p.model, p.data, p.q);
    soadyn::update_velocities(p.model, p.data, p.v);
    soadyn::bias_forces(p.model, p.data);
    benchmark::DoNotOptimize(p.data.bias.data());
  }
}
void SdRhs(benchmark::State& st) {
  Pair p(int(st.range(0)));
  for (auto _ : st) {
    soadyn::update_kinematics(p.model, p.data, p.q);
    soadyn::update_velocities(p.model, p.data, p.v);
    soadyn::forward_dynamics(p.model, p.data, p.tau, soadyn::FdMethod::ArticulatedBody);
    benchmark::DoNotOptimize(p.data.qdd.data());
  }
}

void sizes(benchmark::internal::Benchmark* b) {
  for (int n = 1; n <= 256; n *= 2) b->Arg(n);
}

}  // namespace

BENCHMARK(MjMass)->Name("peer/mujoco/mass")->Apply(sizes);
BENCHMARK(SdMass)->Name("peer/soadyn/mass")->Apply(sizes);
BENCHMARK(MjBias)->Name("peer/mujoco/bias")->Apply(sizes);
BENCHMARK(SdBias)->Name("peer/soadyn/bias")->Apply(sizes);
BENCHMARK(MjRhs)->Name("peer/mujoco/rhs")->Apply(sizes);
BENCHMARK(SdRhs)->Name("peer/soadyn/rhs")->Apply(sizes);
