// The local-frame route, mass_matrix(model, data, q), against the inertial composite sweep it sits
// beside (update_kinematics + mass_matrix) and the note's literal procedure: every joint type,
// axes along ±e_k and not, placements that turn the frame and ones that do not, bodies numbered
// in an order that is not depth-first, several trees at once, and models past the depth where
// the entry point moves each column once to the inertial origin instead.
#include "test_util.hpp"

using namespace soadyn;
using namespace soadyn::test;

namespace {

// 𝓜 by the inertial sweep and by the note's literal procedure, on a Data of its own
Computed reference(const Model& model, const VecX& q) {
  Data data(model);
  return both(model, data, q);
}

// true where the model's body order is not depth-first: some subtree's bodies are not one run
bool not_depth_first(const Model& model) {
  for (int i = 0; i < model.nbodies; ++i)
    for (int j = i + 1; j < model.nbodies; ++j) {
      int a = j;
      while (a > i) a = model.parent[a];
      if (a != i) {  // j is outside the subtree of i: no later body may be inside it
        for (int k = j + 1; k < model.nbodies; ++k) {
          int b = k;
          while (b > i) b = model.parent[b];
          if (b == i) return true;
        }
        break;
      }
    }
  return false;
}

using Case = TreeCase;

class LocalRoute : public ::testing::TestWithParam<Case> {};

TEST_P(LocalRoute, EqualsInertialSweepAndLiteral) {
  const Case& c = GetParam();
  int shuffled = 0;
  for (int seed = 0; seed < 8; ++seed) {
    Rng rng(900 + 31 * seed + c.options.n);
    const Model model = random_model(rng, c.options);
    shuffled += not_depth_first(model);
    VecX q = random_q(rng, model);
    if (seed % 2 == 1)  // far turns: the batched sincos reduces large angles too
      for (int i = 0; i < model.nbodies; ++i)
        if (model.joint_type[i] == JointType::Revolute) q(model.idx_q[i]) *= 1e3;
    const Computed ref = reference(model, q);
    Data data(model);  // fresh: the route needs no [kin]
    mass_matrix(model, data, q);
    ASSERT_TRUE(near_rel(data.M, ref.composite, 1e-12)) << c.name << " seed " << seed;
    ASSERT_TRUE(near_rel(data.M, ref.literal, 1e-12)) << c.name << " seed " << seed;  // every entry, both triangles
    // a second configuration on the same Data: nothing of the first one is left in 𝓜
    const VecX q2 = random_q(rng, model);
    mass_matrix(model, data, q2);
    ASSERT_TRUE(near_rel(data.M, reference(model, q2).composite, 1e-12)) << c.name << " seed " << seed;
  }
  if (c.options.branching > 0.0) {
    EXPECT_GT(shuffled, 0) << "no model had a body order that is not depth-first";
  }
}

INSTANTIATE_TEST_SUITE_P(
    Trees, LocalRoute,
    ::testing::Values(
        Case{"unit_chain8", {.n = 8, .branching = 0.0, .unit_axis = 1.0}},
        Case{"unit_tree40", {.n = 40, .branching = 0.6, .prismatic = 0.3, .unit_axis = 1.0}},
        Case{"general_tree40", {.n = 40, .branching = 0.6, .prismatic = 0.3}},
        Case{"every_joint30", {.n = 30, .branching = 0.5, .prismatic = 0.2, .ball = 0.15, .planar = 0.15,
                               .free_root = true, .fixed = 4, .unit_axis = 0.5}},
        Case{"free_unit20", {.n = 20, .branching = 0.4, .free_root = true, .unit_axis = 0.8}},
        Case{"ball_planar25", {.n = 25, .branching = 0.5, .ball = 0.4, .planar = 0.4}},
        Case{"helical_tree30", {.n = 30, .branching = 0.5, .prismatic = 0.2, .helical = 0.4, .unit_axis = 0.5}},
        Case{"helical_chain30", {.n = 30, .branching = 0.0, .helical = 0.5, .unit_axis = 0.3}},  // deeper than kLocalDepth
        Case{"unit_chain22", {.n = 22, .branching = 0.0, .prismatic = 0.2, .unit_axis = 0.7}},  // deepest local
        Case{"unit_chain26", {.n = 26, .branching = 0.0, .prismatic = 0.2, .unit_axis = 0.7}},  // mixed, entry by entry
        Case{"unit_chain40", {.n = 40, .branching = 0.0, .prismatic = 0.2, .unit_axis = 0.7}},  // mixed, one product
        Case{"deep_chain120", {.n = 120, .branching = 0.0, .prismatic = 0.2, .unit_axis = 0.7}},
        Case{"deep_every_joint60", {.n = 60, .branching = 0.05, .prismatic = 0.2, .ball = 0.1, .planar = 0.1,
                                    .free_root = true, .fixed = 3, .unit_axis = 0.5}}),
    [](const auto& info) { return std::string(info.param.name); });

// Several trees hanging from the ground, numbered interleaved: each has its own depth-first run
TEST(LocalRoute, SeveralTreesInterleaved) {
  Rng rng(77);
  std::vector<BodySpec> specs = random_specs(rng, {.n = 12, .branching = 0.5, .unit_axis = 0.6});
  const std::vector<BodySpec> second = random_specs(rng, {.n = 12, .branching = 0.5, .prismatic = 0.3, .unit_axis = 0.6});
  // interleave: body k of the second tree goes after body k of the first
  std::vector<BodySpec> all;
  std::vector<int> first_at(specs.size()), second_at(second.size());
  for (size_t k = 0; k < specs.size(); ++k) {
    first_at[k] = int(all.size());
    all.push_back(specs[k]);
    second_at[k] = int(all.size());
    all.push_back(second[k]);
    all.back().name += "_2";
  }
  for (size_t k = 0; k < specs.size(); ++k) {
    if (specs[k].parent >= 0) all[size_t(first_at[k])].parent = first_at[size_t(specs[k].parent)];
    if (second[k].parent >= 0) all[size_t(second_at[k])].parent = second_at[size_t(second[k].parent)];
  }
  const Model model = Model::build(all, Vec3(0, 0, -9.81));
  ASSERT_TRUE(not_depth_first(model));
  for (int trial = 0; trial < 5; ++trial) {
    const VecX q = random_q(rng, model);
    Data data(model);
    mass_matrix(model, data, q);
    ASSERT_TRUE(near_rel(data.M, reference(model, q).composite, 1e-12)) << "trial " << trial;
  }
}

// The body order the route uses: every subtree's DOFs one run, the body's own first
TEST(LocalRoute, DepthFirstRunsCoverEachSubtree) {
  Rng rng(5);
  const Model model = random_model(rng, {.n = 60, .branching = 0.7, .ball = 0.2, .free_root = true});
  ASSERT_EQ(int(model.dfs_dof.size()), model.nv);
  std::vector<int> seen(size_t(model.nv), 0);
  for (int x : model.dfs_dof) ++seen[size_t(x)];
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), model.nv);  // a permutation
  for (int i = 0; i < model.nbodies; ++i) {
    EXPECT_EQ(model.dfs_dof[size_t(model.dfs_begin[i])], model.idx_v[i]);
    int count = 0;  // DOFs in the subtree of i
    for (int j = 0; j < model.nbodies; ++j) {
      int a = j;
      while (a > i) a = model.parent[a];
      if (a == i) count += model.nv_i[j];
    }
    EXPECT_EQ(model.dfs_end[i] - model.dfs_begin[i], count) << "body " << i;
    for (int x = model.dfs_begin[i]; x < model.dfs_end[i]; ++x) {
      int a = model.dof_body[size_t(model.dfs_dof[size_t(x)])];
      while (a > i) a = model.parent[a];
      EXPECT_EQ(a, i) << "position " << x << " is not in the subtree of body " << i;
    }
  }
}

// The state-only entry points fill their one result and leave every other result of Data as it
// was: [kin] and [vel] of another state survive mass_matrix(q) (shallow and past 22 bodies, whose
// frames go to the workspace) and bias_forces(q, v) (planar joints included), bit for bit.
TEST(LocalRoute, LeavesTheOtherResultsAsTheyWere) {
  for (const int n : {12, 40}) {
    Rng rng(9100 + n);
    const Model model = random_model(rng, {.n = n, .branching = n > 22 ? 0.0 : 0.5, .prismatic = 0.2, .ball = 0.1,
                                           .planar = 0.1, .free_root = true, .unit_axis = 0.6});
    Data data(model);
    const VecX q0 = random_q(rng, model), v0 = random_v(rng, model), q = random_q(rng, model), v = random_v(rng, model);
    update_kinematics(model, data, q0);
    update_velocities(model, data, v0);
    inverse_dynamics(model, data, v0);
    const Data before = data;
    mass_matrix(model, data, q);
    bias_forces(model, data, q, v);
    for (int i = 0; i < model.nbodies; ++i) {
      ASSERT_TRUE(data.R[i] == before.R[i]) << "n " << n << " body " << i;
      ASSERT_TRUE(data.inertia[i].I == before.inertia[i].I && data.inertia[i].h == before.inertia[i].h) << "n " << n;
    }
    for (const auto& [a, b] : {std::pair{&data.eta, &before.eta}, {&data.d, &before.d}, {&data.s, &before.s}, {&data.r, &before.r}})
      ASSERT_TRUE(*a == *b) << "n " << n;
    for (const auto& [a, b] : {std::pair{&data.G, &before.G}, {&data.V, &before.V}, {&data.Vbar, &before.Vbar},
                               {&data.coriolis, &before.coriolis}, {&data.A, &before.A}, {&data.F, &before.F}})
      ASSERT_TRUE(*a == *b) << "n " << n;
    ASSERT_TRUE(data.tau == before.tau) << "n " << n;
    // and the results they fill are this state's
    Data ref(model);
    update_kinematics(model, ref, q);
    mass_matrix(model, ref);
    update_velocities(model, ref, v);
    bias_forces(model, ref);
    EXPECT_TRUE(near_rel(data.M, ref.M, 1e-12)) << "n " << n;
    EXPECT_TRUE(near_rel(data.bias, ref.bias, 1e-11)) << "n " << n;
  }
}

}  // namespace
