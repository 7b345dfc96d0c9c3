// Hybrid dynamics (hybrid.hpp): q̈ given at some joints, τ at the others.  On seeded random trees
// (every joint kind, free roots) with a random subset of joints prescribed: the O(N) recursion's
// q̈ and τ satisfy inverse dynamics of the whole model, agree with the dense partition of 𝓜, and
// reduce to forward dynamics (nothing prescribed) and inverse dynamics (everything prescribed);
// the factor it leaves solves with 𝓜_ff.
#include "soadyn/algorithm/hybrid.hpp"

#include "test_util.hpp"

using namespace soadyn;
using namespace soadyn::test;

namespace {

const TreeCase kCases[] = {
    {"chain12", {.n = 12, .branching = 0.0, .prismatic = 0.3}},
    {"tree40", {.n = 40, .branching = 0.7, .prismatic = 0.2, .ball = 0.1, .planar = 0.05}},
    {"free_tree30", {.n = 30, .branching = 0.5, .prismatic = 0.2, .ball = 0.1, .free_root = true}},
    {"helical_tree25", {.n = 25, .branching = 0.5, .prismatic = 0.1, .helical = 0.4, .free_root = true, .fixed = 4}},
};

class Hybrid : public ::testing::TestWithParam<TreeCase> {};

// a random subset of the bodies (each with probability `share`), never the root when it is free
std::vector<int> random_subset(Rng& rng, const Model& m, double share) {
  std::vector<int> out;
  for (int i = 0; i < m.nbodies; ++i)
    if (!(i == 0 && m.nv_i[0] == 6) && rng.uniform(0, 1) < share) out.push_back(i);
  return out;
}

TEST_P(Hybrid, SatisfiesInverseDynamicsAndTheDensePartition) {
  const TreeCase& c = GetParam();
  for (int seed = 0; seed < 5; ++seed) {
    Rng rng(977 * seed + c.options.n);
    const Model model = random_model(rng, c.options);
    Data data(model);
    update_kinematics(model, data, random_q(rng, model));
    update_velocities(model, data, random_v(rng, model));
    const PrescribedJoints pj(model, random_subset(rng, model, 0.4));
    const VecX tau = random_v(rng, model, 5.0), qdd_given = random_v(rng, model, 3.0);

    VecX tau_h, tau_d;
    hybrid_dynamics(model, data, pj, tau, qdd_given, tau_h);
    const VecX qdd_h = data.qdd;
    // the prescribed entries are q̈*, the free entries of τ are the inputs
    for (int k = 0; k < model.nv; ++k) {
      if (pj.dof_locked(model, k)) {
        EXPECT_EQ(qdd_h(k), qdd_given(k));
      } else {
        EXPECT_EQ(tau_h(k), tau(k));
      }
    }
    // inverse dynamics of the whole model at that q̈ gives back every τ
    inverse_dynamics(model, data, qdd_h);
    EXPECT_TRUE(near_rel(data.tau, tau_h, 1e-10)) << "seed " << seed;
    // the dense partition agrees
    hybrid_dynamics_dense(model, data, pj, tau, qdd_given, tau_d);
    EXPECT_TRUE(near_rel(data.qdd, qdd_h, 1e-9)) << "seed " << seed;
    EXPECT_TRUE(near_rel(tau_d, tau_h, 1e-9)) << "seed " << seed;
  }
}

TEST_P(Hybrid, LeavesTheFactorOfTheFreeBlock) {
  const TreeCase& c = GetParam();
  Rng rng(4242 + c.options.n);
  const Model model = random_model(rng, c.options);
  Data data(model);
  update_kinematics(model, data, random_q(rng, model));
  update_velocities(model, data, random_v(rng, model));
  const PrescribedJoints pj(model, random_subset(rng, model, 0.3));
  VecX tau_out;
  hybrid_dynamics(model, data, pj, random_v(rng, model), random_v(rng, model), tau_out);
  MatX X = MatX::Random(model.nv, 5), work = articulated_solve_work(model);
  const MatX B = X;
  articulated_solve(model, data, X, work);
  // 𝓜_ff X_f = B_f on the free rows; X_p = 0
  mass_matrix(model, data);
  std::vector<int> f;
  for (int k = 0; k < model.nv; ++k) {
    if (pj.dof_locked(model, k)) {
      EXPECT_TRUE(X.row(k).isZero(0.0));
    } else {
      f.push_back(k);
    }
  }
  MatX Mff(f.size(), f.size()), Xf(f.size(), 5), Bf(f.size(), 5);
  for (size_t a = 0; a < f.size(); ++a) {
    Xf.row(Eigen::Index(a)) = X.row(f[a]), Bf.row(Eigen::Index(a)) = B.row(f[a]);
    for (size_t b = 0; b < f.size(); ++b) Mff(Eigen::Index(a), Eigen::Index(b)) = data.M(f[a], f[b]);
  }
  EXPECT_TRUE(near_rel(Mff * Xf, Bf, 1e-10));
}

TEST_P(Hybrid, NothingPrescribedIsForwardDynamicsAndEverythingIsInverse) {
  const TreeCase& c = GetParam();
  Rng rng(99 + c.options.n);
  const Model model = random_model(rng, c.options);
  Data data(model);
  update_kinematics(model, data, random_q(rng, model));
  update_velocities(model, data, random_v(rng, model));
  const VecX tau = random_v(rng, model, 5.0), qdd_given = random_v(rng, model, 3.0);
  VecX tau_out;
  hybrid_dynamics(model, data, PrescribedJoints(model, {}), tau, qdd_given, tau_out);
  const VecX qdd = data.qdd;
  forward_dynamics(model, data, tau, FdMethod::ArticulatedBody);
  EXPECT_TRUE(near_rel(qdd, data.qdd, 1e-12));
  std::vector<int> all;
  for (int i = 0; i < model.nbodies; ++i) all.push_back(i);
  hybrid_dynamics(model, data, PrescribedJoints(model, all), tau, qdd_given, tau_out);
  inverse_dynamics(model, data, qdd_given);
  EXPECT_TRUE(near_rel(tau_out, data.tau, 1e-12));
}

// ∂q̈/∂(q, v) of the hybrid dynamics against central differences of hybrid_dynamics, on trees of
// 1-DOF joints (the coordinate is the tangent), with springs and dampers among the inputs
TEST(HybridDerivatives, MatchCentralDifferences) {
  for (int seed = 0; seed < 4; ++seed) {
    Rng rng(515 + seed);
    const Model model = random_model(rng, {.n = 14, .branching = 0.5, .prismatic = 0.3, .helical = 0.2});
    Data data(model);
    const PrescribedJoints pj(model, random_subset(rng, model, 0.35));
    Inputs in;
    for (int k = 0; k < model.nv; k += 3) in.springs.push_back({"", k, model.idx_q[model.dof_body[k]], 2.0 + k, 0.1});
    for (int k = 1; k < model.nv; k += 4) in.dampers.push_back({"", k, 0.3 + 0.1 * k});
    const VecX q0 = random_q(rng, model), v0 = random_v(rng, model), qdd_given = random_v(rng, model, 2.0);
    const VecX tau0 = random_v(rng, model, 3.0);
    // q̈(q, v) with τ = τ0 + τ_in(q, v)
    auto qdd = [&](const VecX& q, const VecX& v) {
      update_kinematics(model, data, q);
      update_velocities(model, data, v);
      VecX tau(model.nv), out;
      in.evaluate(0.0, q, v, tau);
      tau += tau0;
      hybrid_dynamics(model, data, pj, tau, qdd_given, out);
      return VecX(data.qdd);
    };
    update_kinematics(model, data, q0);
    update_velocities(model, data, v0);
    VecX tau(model.nv), out;
    in.evaluate(0.0, q0, v0, tau);
    tau += tau0;
    DerivativeData dd(model);
    MatX work = articulated_solve_work(model);
    hybrid_dynamics_derivatives(model, data, pj, v0, tau, qdd_given, dd, out, &in, work);
    MatX fq(model.nv, model.nv), fv(model.nv, model.nv);
    const double h = 1e-6;
    for (int c = 0; c < model.nv; ++c) {
      VecX a = q0, b = q0;
      a(c) += h, b(c) -= h;
      fq.col(c) = (qdd(a, v0) - qdd(b, v0)) / (2 * h);
      a = v0, b = v0;
      a(c) += h, b(c) -= h;
      fv.col(c) = (qdd(q0, a) - qdd(q0, b)) / (2 * h);
    }
    EXPECT_TRUE(near_rel(dd.dqdd_dq, fq, 1e-6)) << "seed " << seed;
    EXPECT_TRUE(near_rel(dd.dqdd_dv, fv, 1e-6)) << "seed " << seed;
    for (int k = 0; k < model.nv; ++k)
      if (pj.dof_locked(model, k)) {
        EXPECT_TRUE(dd.dqdd_dq.row(k).isZero(0.0) && dd.dqdd_dv.row(k).isZero(0.0));
      }
  }
}

TEST(HybridRefuses, AnotherModelsJointsAndWrongSizes) {
  Rng rng(7);
  const Model a = random_model(rng, {.n = 5}), b = random_model(rng, {.n = 6});
  Data data(a);
  update_kinematics(a, data, random_q(rng, a));
  update_velocities(a, data, random_v(rng, a));
  VecX out;
  EXPECT_NE(message_of([&] { hybrid_dynamics(a, data, PrescribedJoints(b, {1}), VecX::Zero(a.nv), VecX::Zero(a.nv), out); })
                .find("another model"),
            std::string::npos);
  EXPECT_THROW(hybrid_dynamics(a, data, PrescribedJoints(a, {1}), VecX::Zero(a.nv + 1), VecX::Zero(a.nv), out), Error);
  EXPECT_THROW(PrescribedJoints(a, {9}), Error);
}

INSTANTIATE_TEST_SUITE_P(RandomTrees, Hybrid, ::testing::ValuesIn(kCases),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
