// The benchmark mechanisms exist twice: in C++ (tools/bench/models.hpp, timed alone) and as URDF
// (tools/bench/make_models.py, loaded by MuJoCo and soadyn for the peer comparison).  They must be
// the same mechanisms: the same 𝓜 and bias at random states.
#include "../tools/bench/models.hpp"

#include "soadyn/io/scenario_file.hpp"

#include "test_util.hpp"

#include <unistd.h>

#include <filesystem>

using namespace soadyn;
using namespace soadyn::test;

TEST(BenchModels, CppAndUrdfAreTheSameMechanisms) {
  const std::string dir = (std::filesystem::temp_directory_path() / ("soadyn_bench_models_" + std::to_string(getpid()))).string();
  ASSERT_EQ(std::system(("/usr/bin/python3 " SOADYN_SOURCE_DIR "/tools/bench/make_models.py " + dir + " > /dev/null").c_str()), 0);
  Rng rng(9);
  for (auto [n, binary] : {std::pair{8, false}, std::pair{64, false}, std::pair{15, true}, std::pair{63, true}}) {
    const Model cpp = bench::make_tree(n, binary);
    const Model urdf = load_urdf(dir + "/" + (binary ? "tree_" : "chain_") + std::to_string(n) + ".urdf", false,
                                 Vec3(0, 0, -9.81));
    ASSERT_EQ(cpp.nv, urdf.nv);
    EXPECT_EQ(cpp.parent, urdf.parent);
    Data dc(cpp), du(urdf);
    const VecX q = random_q(rng, cpp), v = random_v(rng, cpp);
    for (auto* p : {&dc, &du}) {
      const Model& m = p == &dc ? cpp : urdf;
      update_kinematics(m, *p, q);
      mass_matrix(m, *p);
      update_velocities(m, *p, v);
      bias_forces(m, *p);
    }
    EXPECT_TRUE(near_rel(dc.M, du.M, 1e-13)) << n;
    EXPECT_TRUE(near_rel(dc.bias, du.bias, 1e-12)) << n;
  }
  std::filesystem::remove_all(dir);
}

// Every route on the benchmark's largest mechanisms, against each other: the literal 𝓜 (the
// note's Jᵀ M J, dense matrix products of 6N × nv blocks, the library's biggest) against the
// composite one, and the three forward-dynamics routes.  Large products pack their operands into
// buffers the vectorized kernels expect aligned to the full AVX width; with plain malloc's 16 bytes
// they crashed here (chain of 128, binary tree of 63 and up).
TEST(BenchModels, LargeMechanismsEveryRouteAgrees) {
  Rng rng(10);
  for (auto [n, binary] : {std::pair{128, false}, std::pair{256, false}, std::pair{63, true}, std::pair{255, true}}) {
    const Model model = bench::make_tree(n, binary);
    Data data(model);
    update_kinematics(model, data, random_q(rng, model));
    update_velocities(model, data, random_v(rng, model));
    MatX literal;
    mass_matrix_literal(model, data, literal);
    mass_matrix(model, data);
    EXPECT_TRUE(near_rel(literal, data.M, 1e-12)) << n;
    const VecX tau = random_v(rng, model);
    std::vector<VecX> qdd;
    for (FdMethod m : {FdMethod::Dense, FdMethod::Sparse, FdMethod::ArticulatedBody}) {
      forward_dynamics(model, data, tau, m);
      qdd.push_back(data.qdd);
    }
    EXPECT_TRUE(near_rel(qdd[1], qdd[0], 1e-8)) << n;
    EXPECT_TRUE(near_rel(qdd[2], qdd[0], 1e-8)) << n;
  }
}
