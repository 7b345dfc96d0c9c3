// The body-axes route, bias_forces(model, data, q, v), against the inertial sweep it sits beside
// (update_kinematics + update_velocities + bias_forces): every joint type, axes along ±e_k and
// not, placements that turn the frame and ones that do not, free roots, gravity along any
// direction, far turns, and a planar joint (which takes the inertial route).
#include "test_util.hpp"

using namespace soadyn;
using namespace soadyn::test;

namespace {

using Case = TreeCase;

class BodyAxesBias : public ::testing::TestWithParam<Case> {};

TEST_P(BodyAxesBias, EqualsInertialSweep) {
  const Case& c = GetParam();
  for (int seed = 0; seed < 8; ++seed) {
    Rng rng(4100 + 37 * seed + c.options.n);
    TreeOptions o = c.options;
    o.gravity = rng.vec3(-10.0, 10.0);
    const Model model = random_model(rng, o);
    VecX q = random_q(rng, model);
    if (seed % 2 == 1)  // far turns: the batched sincos reduces large angles too
      for (int i = 0; i < model.nbodies; ++i)
        if (model.joint_type[i] == JointType::Revolute) q(model.idx_q[i]) *= 1e3;
    const VecX v = random_v(rng, model, 2.0);
    const VecX ref = bias_at(model, q, v);
    Data data(model);  // fresh: the route needs no [kin] or [vel]
    bias_forces(model, data, q, v);
    ASSERT_TRUE(near_rel(data.bias, ref, 1e-12)) << c.name << " seed " << seed;
    // gravity alone (v = 0) and velocity terms alone (g = 0) each agree too
    bias_forces(model, data, q, VecX::Zero(model.nv));
    ASSERT_TRUE(near_rel(data.bias, bias_at(model, q, VecX::Zero(model.nv)), 1e-12)) << c.name << " seed " << seed;
    TreeOptions w = c.options;
    w.gravity = Vec3::Zero();
    Rng rw(4100 + 37 * seed + c.options.n);
    const Model weightless = random_model(rw, w);
    Data dw(weightless);
    const VecX qw = random_q(rng, weightless), vw = random_v(rng, weightless, 2.0);
    bias_forces(weightless, dw, qw, vw);
    ASSERT_TRUE(near_rel(dw.bias, bias_at(weightless, qw, vw), 1e-12)) << c.name << " seed " << seed;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Trees, BodyAxesBias,
    ::testing::Values(
        Case{"unit_chain8", {.n = 8, .branching = 0.0, .unit_axis = 1.0}},
        Case{"unit_tree40", {.n = 40, .branching = 0.6, .prismatic = 0.3, .unit_axis = 1.0}},
        Case{"general_tree40", {.n = 40, .branching = 0.6, .prismatic = 0.3}},
        Case{"free_ball30", {.n = 30, .branching = 0.5, .prismatic = 0.2, .ball = 0.2, .free_root = true,
                             .fixed = 4, .unit_axis = 0.5}},
        Case{"free_alone", {.n = 1, .free_root = true}},
        Case{"planar25", {.n = 25, .branching = 0.5, .ball = 0.2, .planar = 0.3, .unit_axis = 0.5}},
        Case{"helical25", {.n = 25, .branching = 0.5, .ball = 0.2, .helical = 0.4, .unit_axis = 0.3}},
        Case{"unit_chain120", {.n = 120, .branching = 0.0, .prismatic = 0.2, .unit_axis = 0.7}}),
    [](const auto& info) { return std::string(info.param.name); });

// the bias is τ at q̈ = 0: 𝓜 q̈ + bias from the body-axes routes equals inverse dynamics
TEST(BodyAxesBias, WithMassMatrixGivesInverseDynamics) {
  for (int seed = 0; seed < 6; ++seed) {
    Rng rng(515 + seed);
    const Model model = random_model(rng, {.n = 25, .branching = 0.5, .prismatic = 0.2, .ball = 0.1,
                                           .free_root = seed % 2 == 0, .unit_axis = 0.6});
    const VecX q = random_q(rng, model), v = random_v(rng, model), qdd = random_v(rng, model);
    Data data(model);
    mass_matrix(model, data, q);
    bias_forces(model, data, q, v);
    const VecX tau = data.M * qdd + data.bias;
    Data ref(model);
    update_kinematics(model, ref, q);
    update_velocities(model, ref, v);
    inverse_dynamics(model, ref, qdd);
    ASSERT_TRUE(near_rel(tau, ref.tau, 1e-11)) << "seed " << seed;
  }
}

}  // namespace
