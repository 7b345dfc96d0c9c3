// Closed loops (loops.hpp) against independent routes: on seeded random trees with every kind of
// loop closed at a random configuration, the rows K against central differences of the closure
// φ along the tangent, k̇ = K̇ v against differences of K along the motion, forward dynamics
// against the dense saddle-point system and the equations it must satisfy; a planar four-bar
// closed by a hinge (dependent rows: rank 2 of 5, λ of minimum norm); inverse dynamics of the
// four-bar driven at its crank against forward dynamics under the torque it returns.
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/frames.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/algorithm/loops.hpp"

#include "loop_util.hpp"
#include "test_util.hpp"

#include <Eigen/LU>
#include <Eigen/QR>

#include <cmath>

using namespace soadyn;
using namespace soadyn::test;

namespace {

// a loop of `type` from body a's frame `on_a` to body b, placed on b where A's frame is at q, so
// that it is closed there (distance: the frames' present distance, from a point off A's frame)
LoopConstraint closed_loop(const Model& m, const Data& d, LoopType type, int a, int b, const Placement& on_a) {
  LoopConstraint c;
  c.type = type;
  c.body_a = a, c.body_b = b;
  c.at_a = on_a;
  const Placement A = body_frame_placement(m, d, a, on_a);
  const Placement B = body_frame_placement(m, d, b, Placement{});
  // X_b = B⁻¹ A: the same frame seen from b
  c.at_b.R = B.R.transpose() * A.R;
  c.at_b.p = B.R.transpose() * (A.p - B.p);
  if (type == LoopType::Distance) {
    c.at_b.p += Vec3(0.3, -0.2, 0.25);
    c.distance = (A.p - body_frame_placement(m, d, b, c.at_b).p).norm();
  }
  c.name = std::string(to_string(type));
  return c;
}

Placement random_placement(Rng& rng) {
  Placement X;
  X.p = Vec3(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5));
  X.R = Eigen::AngleAxisd(rng.uniform(0, 3), Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)).normalized())
            .toRotationMatrix();
  return X;
}

struct Scene {
  Model model;
  VecX q, v, tau;
  std::vector<LoopConstraint> loops;
};

// a random tree (ball joints and a free root in some) with a loop of each of `kinds` between
// random bodies (or the world), closed at q
Scene random_scene(std::uint64_t seed, bool free_root,
                   const std::vector<LoopType>& kinds = {LoopType::Point, LoopType::Hinge, LoopType::Weld, LoopType::Distance}) {
  Rng rng(seed);
  Scene s;
  s.model = random_model(rng, {.n = 14, .branching = 0.5, .prismatic = 0.2, .ball = 0.3, .free_root = free_root});
  const Model& m = s.model;
  s.q = random_q(rng, m);
  s.v = random_v(rng, m);
  s.tau = VecX::Random(m.nv);
  Data d(m);
  update_kinematics(m, d, s.q);
  for (const LoopType type : kinds) {
    const int a = 1 + int(rng.uniform(0, m.nbodies - 1.001));
    int b = int(rng.uniform(-1, m.nbodies - 0.001));
    if (b == a) b = -1;
    s.loops.push_back(closed_loop(m, d, type, a, b, random_placement(rng)));
  }
  // v on the loops (K v = 0: the part of v the loops allow, of minimum change)
  update_velocities(m, d, s.v);
  LoopData ld(m, s.loops);
  loop_rows(m, d, s.loops, ld);
  s.v -= Eigen::CompleteOrthogonalDecomposition<MatX>(ld.K).pseudoInverse() * (ld.K * s.v);
  return s;
}

// φ at q ⊕ e (the tangent increment e)
VecX closure_at(const Scene& s, const VecX& e) {
  Data d(s.model);
  update_kinematics(s.model, d, s.model.integrate(s.q, e, 1.0));
  LoopData ld(s.model, s.loops);
  loop_closure(s.model, d, s.loops, ld);
  return ld.phi;
}

// K at q ⊕ h v, times v
VecX rows_times_v_at(const Scene& s, double h) {
  Data d(s.model);
  update_kinematics(s.model, d, s.model.integrate(s.q, s.v, h));
  update_velocities(s.model, d, s.v);
  LoopData ld(s.model, s.loops);
  loop_rows(s.model, d, s.loops, ld);
  return ld.K * s.v;
}

}  // namespace

class Loops : public ::testing::TestWithParam<int> {};

TEST_P(Loops, RowsAreTheClosuresDerivativeAndKdotTheirRate) {
  const Scene s = random_scene(100 + GetParam(), GetParam() % 2 == 1);
  const Model& m = s.model;
  Data d(m);
  update_kinematics(m, d, s.q);
  update_velocities(m, d, s.v);
  LoopData ld(m, s.loops);
  ASSERT_EQ(ld.m, 3 + 5 + 6 + 1);
  loop_rows(m, d, s.loops, ld);
  EXPECT_LT(ld.phi.cwiseAbs().maxCoeff(), 1e-12) << "closed at q";
  // K = ∂φ/∂δ at the closure, by central differences
  MatX D(ld.m, m.nv);
  const double h = 1e-6;
  for (int k = 0; k < m.nv; ++k) D.col(k) = (closure_at(s, h * VecX::Unit(m.nv, k)) - closure_at(s, -h * VecX::Unit(m.nv, k))) / (2 * h);
  EXPECT_TRUE(near_rel(ld.K, D, 1e-7)) << "K\n" << ld.K << "\ndifferences\n" << D;
  // k̇ = d/dt (K(q(t)) v) along q̇ = v (at any v, on the loop or not)
  const double e = 1e-5;
  const VecX rate = (rows_times_v_at(s, e) - rows_times_v_at(s, -e)) / (2 * e);
  EXPECT_TRUE(near_rel(ld.kdot, rate, 1e-6)) << ld.kdot.transpose() << "\n" << rate.transpose();
}

TEST_P(Loops, ForwardDynamicsMatchesTheDenseSaddlePointSystem) {
  // two loops of the kinds in turn: fewer rows than the tree has DOFs, each independent
  const LoopType kinds[] = {LoopType::Point, LoopType::Hinge, LoopType::Weld, LoopType::Distance};
  const Scene s = random_scene(200 + GetParam(), GetParam() % 2 == 0, {kinds[GetParam() % 4], kinds[(GetParam() + 1) % 4]});
  const Model& m = s.model;
  Data d(m), dense(m);
  update_kinematics(m, d, s.q), update_velocities(m, d, s.v);
  update_kinematics(m, dense, s.q), update_velocities(m, dense, s.v);
  LoopData ld(m, s.loops), ldd(m, s.loops);
  loop_forward_dynamics(m, d, s.loops, s.v, s.tau, ld);
  loop_forward_dynamics_dense(m, dense, s.loops, s.tau, ldd);
  EXPECT_TRUE(near_rel(d.qdd, dense.qdd, 1e-9));
  EXPECT_TRUE(near_rel(ld.lambda, ldd.lambda, 1e-8));
  // (a loop on a short chain can have more rows than the chain has DOFs: then rows depend, and λ
  // is the one of minimum norm on both routes)
  EXPECT_LT((ld.K * s.v).cwiseAbs().maxCoeff(), 1e-10);
  // the loops' acceleration K q̈ + k̇ = 0 and the equations of motion 𝓜 q̈ + Kᵀ λ = τ − bias
  EXPECT_LT((ld.K * d.qdd + ld.kdot).cwiseAbs().maxCoeff(), 1e-9 * std::max(1.0, d.qdd.norm()));
  mass_matrix(m, dense);
  bias_forces(m, dense);
  const VecX residual = dense.M * d.qdd + ld.K.transpose() * ld.lambda - (s.tau - dense.bias);
  EXPECT_LT(residual.cwiseAbs().maxCoeff(), 1e-9 * std::max(1.0, s.tau.norm()));
}

INSTANTIATE_TEST_SUITE_P(RandomTrees, Loops, ::testing::Range(0, 6));

TEST(LoopsFourBar, ClosedByAHingeItsRowsDependAndLambdaIsOfMinimumNorm) {
  const FourBar f = four_bar(0.7, 1.3);
  const Model& m = f.model;
  Data d(m), dense(m);
  update_kinematics(m, d, f.q), update_velocities(m, d, f.v);
  update_kinematics(m, dense, f.q), update_velocities(m, dense, f.v);
  LoopData ld(m, f.loops), ldd(m, f.loops);
  const VecX tau = Eigen::Vector3d(0.5, 0.0, 0.0);
  loop_forward_dynamics(m, d, f.loops, f.v, tau, ld);
  EXPECT_LT(ld.phi.cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((ld.K * f.v).cwiseAbs().maxCoeff(), 1e-12);
  // in the plane: x and y of the point, nothing along z or about x and y
  EXPECT_EQ(ld.rank, 2);
  EXPECT_LT((ld.K * d.qdd + ld.kdot).cwiseAbs().maxCoeff(), 1e-10);
  // the out-of-plane rows take no force (λ of minimum norm), and the dense route agrees
  EXPECT_LT(ld.lambda.tail(3).cwiseAbs().maxCoeff(), 1e-9);
  loop_forward_dynamics_dense(m, dense, f.loops, tau, ldd);
  EXPECT_TRUE(near_rel(d.qdd, dense.qdd, 1e-9));
  EXPECT_TRUE(near_rel(ld.lambda, ldd.lambda, 1e-8));
}

// the crank's torque that makes q̈_crank = 2 rad/s², then forward dynamics under it: the same q̈ at
// every joint, and the passive joints' τ zero
TEST(LoopsFourBar, InverseDynamicsAtTheCrankIsUndoneByForwardDynamics) {
  for (const double theta : {0.3, 1.9, 4.0}) {
    const FourBar f = four_bar(theta, -0.8);
    const Model& m = f.model;
    Data d(m);
    update_kinematics(m, d, f.q), update_velocities(m, d, f.v);
    LoopData ld(m, f.loops);
    VecX qdd = VecX::Zero(3);
    qdd(0) = 2.0;
    const VecX tau = loop_inverse_dynamics(m, d, f.loops, {0}, qdd, ld);
    EXPECT_EQ(tau(1), 0.0);
    EXPECT_EQ(tau(2), 0.0);
    Data fd(m);
    update_kinematics(m, fd, f.q), update_velocities(m, fd, f.v);
    LoopData lf(m, f.loops);
    loop_forward_dynamics(m, fd, f.loops, f.v, tau, lf);
    EXPECT_TRUE(near_rel(fd.qdd, qdd, 1e-9)) << "theta " << theta << ": " << fd.qdd.transpose() << " vs " << qdd.transpose();
  }
}

// too few actuators (none) leaves the passive DOFs free: one line
TEST(LoopsFourBar, InverseDynamicsWithoutActuatorsIsRefused) {
  const FourBar f = four_bar(0.7, 1.0);
  Data d(f.model);
  update_kinematics(f.model, d, f.q), update_velocities(f.model, d, f.v);
  LoopData ld(f.model, f.loops);
  VecX qdd = VecX::Zero(3);
  EXPECT_NE(message_of([&] { loop_inverse_dynamics(f.model, d, f.loops, {}, qdd, ld); }).find("passive DOF(s) free"),
            std::string::npos);
}
