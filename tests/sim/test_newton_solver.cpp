// NewtonSolver: (I − γJ) x = b through the nv×nv Schur complement, against the dense LU of
// I − γJ, on seeded random trees with revolute, prismatic, ball, planar and free joints and
// their inputs (so the quadratures W, D are in y); a Jacobian without the structure takes the
// dense route; a singular matrix is reported.
#include "soadyn/sim/integrators.hpp"
#include "soadyn/sim/newton_solver.hpp"

#include "test_util.hpp"

using namespace soadyn;
using namespace soadyn::test;

namespace {

// a System with springs, dampers and torques on every 1-DOF joint: y = [q; v; W, D]
Inputs inputs_for(Rng& rng, const Model& model) {
  Inputs in;
  for (int i = 0; i < model.nbodies; ++i)
    if (model.nv_i[i] == 1) {
      in.springs.push_back({model.joint_names[i], model.idx_v[i], model.idx_q[i], rng.uniform(5, 5e4), rng.uniform()});
      in.dampers.push_back({model.joint_names[i], model.idx_v[i], rng.uniform(0.5, 200)});
      in.torques.push_back({model.joint_names[i], model.idx_v[i], 0.3, 1.0, 2.0, 0.1});
    }
  return in;
}

// x against the dense partial-pivot LU of I − γJ, relative to |x|
double relative_error(const MatX& J, double gamma, const VecX& b, const VecX& x) {
  MatX M = -gamma * J;
  M.diagonal().array() += 1.0;
  const VecX ref = M.partialPivLu().solve(b);
  return (x - ref).norm() / ref.norm();
}

}  // namespace

TEST(NewtonSolver, SchurComplementMatchesTheDenseLU) {
  const TreeOptions cases[] = {
      {.n = 8, .branching = 0.3, .prismatic = 0.4},                                                // revolute, prismatic
      {.n = 10, .branching = 0.5, .prismatic = 0.2, .ball = 0.3, .planar = 0.2, .free_root = true},  // every type
      {.n = 7, .branching = 0.0, .ball = 0.6},                                                      // ball chain
      {.n = 12, .branching = 0.6, .ball = 0.2, .free_root = true},
  };
  int k = 0;
  for (const TreeOptions& o : cases) {
    Rng rng(41 + k);
    const Model model = random_model(rng, o);
    const Inputs in = inputs_for(rng, model);
    System sys(model, in, FdMethod::ArticulatedBody);
    NewtonSolver solver(model, sys.nquad);
    ASSERT_EQ(solver.size(), sys.size());
    for (int trial = 0; trial < 5; ++trial) {
      VecX y = sys.state(random_q(rng, model), random_v(rng, model, 3.0));
      y.tail(sys.nquad).setRandom();
      // quaternions a little off unit, as between CVODE's projections
      for (int i = 0; i < model.nbodies; ++i)
        if (const int qo = joint_traits(model.joint_type[i]).quaternion; qo >= 0)
          y.segment<4>(model.idx_q[i] + qo) *= 1.0 + 0.05 * rng.uniform();
      MatX J(sys.size(), sys.size());
      sys.jacobian(rng.uniform(0, 3), y.data(), J);
      ASSERT_TRUE(solver.set_jacobian(J)) << "case " << k;
      for (const double gamma : {1e-5, 1e-3, 3e-2}) {
        ASSERT_TRUE(solver.factor(gamma));
        EXPECT_TRUE(solver.reduced());
        const VecX b = VecX::Random(sys.size());
        VecX x(sys.size());
        solver.solve(b, x);
        EXPECT_LT(relative_error(J, gamma, b, x), 1e-12) << "case " << k << " trial " << trial << " gamma " << gamma;
        // x may alias b
        VecX xb = b;
        solver.solve(xb, xb);
        EXPECT_LT((xb - x).norm(), 1e-15 * x.norm());
      }
    }
    ++k;
  }
}

// Without inputs that do work there are no quadratures: y = [q; v]
TEST(NewtonSolver, WithoutQuadratures) {
  Rng rng(7);
  const Model model = random_model(rng, {.n = 9, .branching = 0.5, .prismatic = 0.2, .ball = 0.3, .free_root = true});
  const Inputs none;
  System sys(model, none, FdMethod::ArticulatedBody);
  ASSERT_EQ(sys.nquad, 0);
  NewtonSolver solver(model, 0);
  const VecX y = sys.state(random_q(rng, model), random_v(rng, model, 2.0));
  MatX J(sys.size(), sys.size());
  sys.jacobian(0.0, y.data(), J);
  ASSERT_TRUE(solver.set_jacobian(J));
  ASSERT_TRUE(solver.factor(0.01));
  const VecX b = VecX::Random(sys.size());
  VecX x(sys.size());
  solver.solve(b, x);
  EXPECT_LT(relative_error(J, 0.01, b, x), 1e-12);
}

// A Jacobian without System::jacobian's structure (a q row reaching another joint, a column of W)
// takes the dense LU of I − γJ, and still solves it
TEST(NewtonSolver, DenseRouteWhereTheStructureDoesNotHold) {
  Rng rng(9);
  const Model model = random_model(rng, {.n = 5, .branching = 0.5, .ball = 0.4, .free_root = true});
  const Inputs in = inputs_for(rng, model);
  System sys(model, in, FdMethod::ArticulatedBody);
  const VecX y = sys.state(random_q(rng, model), random_v(rng, model));
  MatX J(sys.size(), sys.size());
  sys.jacobian(0.0, y.data(), J);
  NewtonSolver solver(model, sys.nquad);
  for (const auto& [r, c] : {std::pair{0, model.nq - 1}, std::pair{model.nq, sys.size() - 1}}) {
    MatX Jx = J;
    Jx(r, c) = 0.5;
    EXPECT_FALSE(solver.set_jacobian(Jx)) << r << ", " << c;
    ASSERT_TRUE(solver.factor(0.02));
    EXPECT_FALSE(solver.reduced());
    const VecX b = VecX::Random(sys.size());
    VecX x(sys.size());
    solver.solve(b, x);
    EXPECT_LT(relative_error(Jx, 0.02, b, x), 1e-12);
  }
  // and the structured J again: the reduced route
  EXPECT_TRUE(solver.set_jacobian(J));
  ASSERT_TRUE(solver.factor(0.02));
  EXPECT_TRUE(solver.reduced());
}

// I − γJ singular: factor() says so (CVODE then retries with a smaller step)
TEST(NewtonSolver, ReportsASingularMatrix) {
  Rng rng(11);
  const Model model = random_model(rng, {.n = 4, .branching = 0.0, .prismatic = 0.5});
  NewtonSolver solver(model, 0);
  // q̇ = v, q̈ = v / γ: S = I − γ (I/γ) = 0
  const int n = model.nq + model.nv;
  MatX J = MatX::Zero(n, n);
  J.topRightCorner(model.nq, model.nv).setIdentity();
  J.bottomRightCorner(model.nv, model.nv) = MatX::Identity(model.nv, model.nv) / 0.1;
  ASSERT_TRUE(solver.set_jacobian(J));
  EXPECT_FALSE(solver.factor(0.1));
  EXPECT_TRUE(solver.factor(0.05));
  J(0, 0) = std::nan("");
  solver.set_jacobian(J);
  EXPECT_FALSE(solver.factor(0.05));
}
