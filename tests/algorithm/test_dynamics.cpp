// Equations of motion 𝓜(q) q̈ = τ − bias(q, q̇): three forward-dynamics routes, inverse dynamics,
// bias against finite differences of the Lagrangian, power balance, Lagrange closed forms.
#include "test_util.hpp"

using namespace soadyn;
using namespace soadyn::test;

namespace {

using Case = TreeCase;

const Case kCases[] = {
    {"chain8", {.n = 8, .branching = 0.0}},
    {"chain64_prismatic", {.n = 64, .branching = 0.0, .prismatic = 0.3}},
    {"tree50", {.n = 50, .branching = 0.7, .prismatic = 0.2}},
    {"free_tree40", {.n = 40, .branching = 0.5, .prismatic = 0.2, .free_root = true}},
    {"tree200", {.n = 200, .branching = 0.5, .prismatic = 0.2}},
    {"free_chain200", {.n = 200, .branching = 0.05, .prismatic = 0.1, .free_root = true}},
    {"fixed_tree30", {.n = 30, .branching = 0.5, .prismatic = 0.2, .free_root = true, .fixed = 6}},
    {"helical_tree30", {.n = 30, .branching = 0.5, .prismatic = 0.2, .ball = 0.1, .helical = 0.4, .free_root = true}},
};

class Routes : public ::testing::TestWithParam<Case> {};

TEST_P(Routes, ThreeForwardRoutesAgreeAndInvertInverseDynamics) {
  const Case& c = GetParam();
  for (int seed = 0; seed < 4; ++seed) {
    Rng rng(31 * seed + c.options.n);
    const Model model = random_model(rng, c.options);
    Data data(model);
    update_kinematics(model, data, random_q(rng, model));
    update_velocities(model, data, random_v(rng, model));
    const VecX tau = random_v(rng, model, 5.0);

    mass_matrix(model, data);
    bias_forces(model, data);
    const MatX Mass = data.M;
    const VecX bias = data.bias;
    std::vector<VecX> qdd;
    for (FdMethod m : {FdMethod::Dense, FdMethod::Sparse, FdMethod::ArticulatedBody}) {
      forward_dynamics(model, data, tau, m);
      qdd.push_back(data.qdd);
      // the residual ‖𝓜 q̈ + bias − τ‖ measures agreement even where 𝓜 is ill-conditioned
      const double scale = std::max({tau.norm(), bias.norm(), (Mass * data.qdd).norm()});
      EXPECT_LE((Mass * data.qdd + bias - tau).norm(), 1e-10 * scale) << c.name << " " << to_string(m);
      // inverse(forward(τ)) = τ
      inverse_dynamics(model, data, data.qdd);
      EXPECT_TRUE(near_rel(data.tau, tau, 1e-10)) << c.name << " " << to_string(m);
    }
    // q̈ agree to the conditioning of 𝓜
    const Eigen::JacobiSVD<MatX> svd(Mass);
    const double cond = svd.singularValues()(0) / svd.singularValues().tail<1>()(0);
    const double tol = std::max(1e-10, 1e-15 * cond);
    EXPECT_TRUE(near_rel(qdd[1], qdd[0], tol)) << c.name << " sparse vs dense, cond " << cond;
    EXPECT_TRUE(near_rel(qdd[2], qdd[0], tol)) << c.name << " O(N) vs dense, cond " << cond;
  }
}

// 𝓜⁻¹ by the articulated-body recursion against the composite 𝓜: 𝓜 𝓜⁻¹ = e to the conditioning,
// symmetric, and each column the O(N) route's q̈ for a unit force without velocity or gravity
TEST_P(Routes, MinverseInvertsTheCompositeMassMatrix) {
  const Case& c = GetParam();
  for (int seed = 0; seed < 3; ++seed) {
    Rng rng(37 * seed + c.options.n);
    const Model model = random_model(rng, c.options);
    Data data(model);
    update_kinematics(model, data, random_q(rng, model));
    mass_matrix(model, data);
    const MatX Mass = data.M;
    MatX Minv;
    minverse(model, data, Minv);
    const Eigen::JacobiSVD<MatX> svd(Mass);
    const double cond = svd.singularValues()(0) / svd.singularValues().tail<1>()(0);
    const double tol = std::max(1e-11, 1e-15 * cond);
    EXPECT_LE((Mass * Minv - MatX::Identity(model.nv, model.nv)).cwiseAbs().maxCoeff(), tol) << c.name << ", cond " << cond;
    EXPECT_TRUE(near_rel(Minv, Minv.transpose(), tol)) << c.name;
    // a second call on the same Data gives the same bits (no state carried over)
    MatX again(model.nv, model.nv);
    minverse(model, data, again);
    EXPECT_EQ((again - Minv).cwiseAbs().maxCoeff(), 0.0) << c.name;
  }
}

// 𝓜 e_i = τ(q̈ = e_i) − bias
TEST_P(Routes, MassMatrixColumnsFromInverseDynamics) {
  const Case& c = GetParam();
  Rng rng(5 + c.options.n);
  const Model model = random_model(rng, c.options);
  Data data(model);
  update_kinematics(model, data, random_q(rng, model));
  update_velocities(model, data, random_v(rng, model));
  mass_matrix(model, data);
  bias_forces(model, data);
  MatX cols(model.nv, model.nv);
  VecX e = VecX::Zero(model.nv);
  for (int k = 0; k < model.nv; ++k) {
    e.setZero();
    e(k) = 1.0;
    inverse_dynamics(model, data, e);
    cols.col(k) = data.tau - data.bias;
  }
  EXPECT_TRUE(near_rel(cols, data.M, 1e-10)) << c.name;
}

INSTANTIATE_TEST_SUITE_P(Trees, Routes, ::testing::ValuesIn(kCases),
                         [](const auto& info) { return std::string(info.param.name); });

// helpers: 𝓜, bias at a state
MatX mass_at(const Model& model, const VecX& q) {
  Data d(model);
  update_kinematics(model, d, q);
  mass_matrix(model, d);
  return d.M;
}


double potential_at(const Model& model, const VecX& q) {
  Data d(model);
  update_kinematics(model, d, q);
  return potential_energy(model, d);
}

// Lagrange: bias = 𝓜̇ q̇ − ∂T/∂q + ∂V/∂q, with 𝓜̇ and the partials by central differences.
TEST(Bias, MatchesLagrangeByFiniteDifferences) {
  for (int seed = 0; seed < 8; ++seed) {
    Rng rng(70 + seed);
    const Model model = random_model(rng, {.n = 12, .branching = 0.5, .prismatic = 0.3});
    const VecX q = random_q(rng, model), v = random_v(rng, model, 2.0);
    const double h = 1e-5;
    const MatX Mdot = (mass_at(model, q + h * v) - mass_at(model, q - h * v)) / (2 * h);
    VecX dT(model.nv), dV(model.nv);
    for (int k = 0; k < model.nv; ++k) {
      VecX dq = VecX::Zero(model.nq);
      dq(k) = h;
      dT(k) = 0.5 * v.dot((mass_at(model, q + dq) - mass_at(model, q - dq)) * v) / (2 * h);
      dV(k) = (potential_at(model, q + dq) - potential_at(model, q - dq)) / (2 * h);
    }
    const VecX gravity_part = bias_at(model, q, VecX::Zero(model.nv));
    const VecX velocity_part = bias_at(model, q, v) - gravity_part;
    EXPECT_TRUE(near_rel(velocity_part, Mdot * v - dT, 1e-7)) << "seed " << seed;
    EXPECT_TRUE(near_rel(gravity_part, dV, 1e-7)) << "seed " << seed;
  }
}

// q̇ᵀ (𝓜̇ − 2C) q̇ = 0 with C q̇ the velocity part of the bias; 𝓜̇ along the motion (free roots too)
TEST(Bias, SkewSymmetryOfMdotMinus2C) {
  for (int seed = 0; seed < 8; ++seed) {
    Rng rng(170 + seed);
    const Model model = random_model(rng, {.n = 15, .branching = 0.5, .prismatic = 0.3, .free_root = seed % 2 == 0});
    const VecX q = random_q(rng, model), v = random_v(rng, model, 2.0);
    const double h = 1e-5;
    const MatX Mdot = (mass_at(model, model.integrate(q, v, h)) - mass_at(model, model.integrate(q, v, -h))) / (2 * h);
    const VecX Cv = bias_at(model, q, v) - bias_at(model, q, VecX::Zero(model.nv));
    const double scale = v.cwiseAbs().dot(Mdot.cwiseAbs() * v.cwiseAbs()) + 1.0;
    EXPECT_NEAR(v.dot(Mdot * v - 2.0 * Cv), 0.0, 1e-7 * scale) << "seed " << seed;
  }
}

// E = T + V along the motion:  dE/dt = q̇ᵀ τ
struct State {
  VecX q, v;
};

double energy(const Model& model, const State& s) {
  Data d(model);
  update_kinematics(model, d, s.q);
  update_velocities(model, d, s.v);
  return kinetic_energy(model, d) + potential_energy(model, d);
}

VecX accel(const Model& model, Data& d, const State& s, const VecX& tau) {
  update_kinematics(model, d, s.q);
  update_velocities(model, d, s.v);
  forward_dynamics(model, d, tau, FdMethod::ArticulatedBody);
  return d.qdd;
}

// one classical RK4 step on y = [q; v] in the embedding (q̇ from Model::qdot, quaternions
// as four numbers), then the quaternions renormalized
State rk4(const Model& model, Data& d, const State& s, const VecX& tau, double h) {
  auto f = [&](const State& x) {
    VecX qd(model.nq);
    model.qdot(x.q, x.v, qd);
    return std::pair{qd, accel(model, d, x, tau)};
  };
  auto add = [&](const State& x, const std::pair<VecX, VecX>& k, double c) {
    return State{x.q + c * k.first, x.v + c * k.second};
  };
  const auto k1 = f(s);
  const auto k2 = f(add(s, k1, h / 2));
  const auto k3 = f(add(s, k2, h / 2));
  const auto k4 = f(add(s, k3, h));
  State out{s.q + h / 6 * (k1.first + 2 * k2.first + 2 * k3.first + k4.first),
            s.v + h / 6 * (k1.second + 2 * k2.second + 2 * k3.second + k4.second)};
  model.normalize(out.q);
  return out;
}

TEST(PowerBalance, EnergyRateEqualsJointPowerAlongATrajectory) {
  for (int seed = 0; seed < 4; ++seed) {
    Rng rng(300 + seed);
    const Model model = random_model(rng, {.n = 6, .branching = 0.5, .prismatic = 0.3, .free_root = seed >= 2});
    Data d(model);
    State s{random_q(rng, model), random_v(rng, model, 1.0)};
    for (bool driven : {false, true}) {
      const VecX tau = driven ? random_v(rng, model, 3.0) : VecX::Zero(model.nv);
      const double h = 1e-3;
      const int steps = 200;
      State x = s;
      const double E0 = energy(model, x);
      double work = 0.0;  // ∫ q̇ᵀ τ dt, Simpson over each step
      for (int k = 0; k < steps; ++k) {
        const State y = rk4(model, d, x, tau, h);
        const State mid = rk4(model, d, x, tau, h / 2);
        work += h / 6 * (x.v.dot(tau) + 4 * mid.v.dot(tau) + y.v.dot(tau));
        x = y;
      }
      const double E1 = energy(model, x);
      EXPECT_NEAR(E1 - E0, work, 1e-8 * std::max(1.0, std::abs(E0))) << "seed " << seed << " driven " << driven;
      if (driven) {
        EXPECT_GT(std::abs(work), 1e-3);  // the check has teeth
      }
    }
  }
}

// Pendulum on a cart (the note's Example 1) by Lagrange, gravity −g e_y:
//   (m1+m2) ẍ + m2 L cos θ θ̈ − m2 L sin θ θ̇² = τ_x
//   m2 L cos θ ẍ + (I + m2 L²) θ̈ + m2 g L sin θ = τ_θ
TEST(ClosedForm, PendulumOnCart) {
  Rng rng(11);
  for (int t = 0; t < 50; ++t) {
    BodySpec cart, pend;
    cart.name = "cart";
    cart.joint = JointType::Prismatic;
    cart.axis = Vec3::UnitX();
    cart.mass = rng.uniform(0.5, 5);
    cart.com = rng.vec3();
    cart.inertia = rng.inertia();
    pend.name = "pendulum";
    pend.parent = 0;
    pend.axis = Vec3::UnitZ();
    pend.mass = rng.uniform(0.5, 5);
    const double L = rng.uniform(0.2, 2);
    pend.com = Vec3(0, -L, 0);
    pend.inertia = rng.inertia();
    const double g = 9.81;
    const Model model = Model::build({cart, pend}, Vec3(0, -g, 0));
    const double th = rng.uniform(-3, 3), xd = rng.uniform(-2, 2), thd = rng.uniform(-3, 3);
    const double m1 = cart.mass, m2 = pend.mass, I = pend.inertia(2, 2);
    const VecX q = Eigen::Vector2d(rng.uniform(-1, 1), th), v = Eigen::Vector2d(xd, thd);
    Eigen::Matrix2d M;
    M << m1 + m2, m2 * L * std::cos(th), m2 * L * std::cos(th), I + m2 * L * L;
    const VecX bias = Eigen::Vector2d(-m2 * L * std::sin(th) * thd * thd, m2 * g * L * std::sin(th));
    EXPECT_TRUE(near_rel(bias_at(model, q, v), bias, 1e-12));
    const VecX tau = Eigen::Vector2d(rng.uniform(-5, 5), rng.uniform(-5, 5));
    Data d(model);
    update_kinematics(model, d, q);
    update_velocities(model, d, v);
    forward_dynamics(model, d, tau, FdMethod::ArticulatedBody);
    EXPECT_TRUE(near_rel(d.qdd, M.llt().solve(Eigen::Vector2d(tau - bias)), 1e-12));
  }
}

// Planar double pendulum about e_x by Lagrange (θ2 relative), gravity −g e_z; joint 2 at l1 along
// −z of body 1, centres of mass at c1, c2 along −z, J_k the moment about x.
TEST(ClosedForm, DoublePendulum) {
  Rng rng(12);
  for (int t = 0; t < 50; ++t) {
    const double m1 = rng.uniform(0.5, 3), m2 = rng.uniform(0.5, 3), l1 = rng.uniform(0.3, 2);
    const double c1 = rng.uniform(0.1, 1), c2 = rng.uniform(0.1, 1), g = 9.81;
    BodySpec b1, b2;
    b1.name = "upper";
    b1.axis = Vec3::UnitX();
    b1.mass = m1;
    b1.com = Vec3(0, 0, -c1);
    b1.inertia = rng.inertia();
    b2.name = "lower";
    b2.parent = 0;
    b2.axis = Vec3::UnitX();
    b2.placement.p = Vec3(0, 0, -l1);
    b2.mass = m2;
    b2.com = Vec3(0, 0, -c2);
    b2.inertia = rng.inertia();
    const Model model = Model::build({b1, b2}, Vec3(0, 0, -g));
    const double J1 = b1.inertia(0, 0), J2 = b2.inertia(0, 0);
    const double t1 = rng.uniform(-3, 3), t2 = rng.uniform(-3, 3), w1 = rng.uniform(-3, 3), w2 = rng.uniform(-3, 3);
    MatX M(2, 2);
    M(0, 0) = J1 + m1 * c1 * c1 + J2 + m2 * (l1 * l1 + c2 * c2 + 2 * l1 * c2 * std::cos(t2));
    M(0, 1) = M(1, 0) = J2 + m2 * (c2 * c2 + l1 * c2 * std::cos(t2));
    M(1, 1) = J2 + m2 * c2 * c2;
    const double hh = m2 * l1 * c2 * std::sin(t2);
    const VecX bias = Eigen::Vector2d(
        -hh * (2 * w1 * w2 + w2 * w2) + m1 * g * c1 * std::sin(t1) + m2 * g * (l1 * std::sin(t1) + c2 * std::sin(t1 + t2)),
        hh * w1 * w1 + m2 * g * c2 * std::sin(t1 + t2));
    const VecX q = Eigen::Vector2d(t1, t2), v = Eigen::Vector2d(w1, w2);
    EXPECT_TRUE(near_rel(mass_at(model, q), M, 1e-12));
    EXPECT_TRUE(near_rel(bias_at(model, q, v), bias, 1e-12));
  }
}

// Free-floating tree with no gravity and no torque: momentum is conserved to integration accuracy.
TEST(Momentum, ConservedByFreeFloatingTree) {
  Rng rng(21);
  TreeOptions o{.n = 7, .branching = 0.5, .prismatic = 0.3, .free_root = true};
  o.gravity = Vec3::Zero();
  const Model model = random_model(rng, o);
  Data d(model);
  State x{random_q(rng, model), random_v(rng, model, 1.0)};
  auto mom = [&](const State& s) {
    update_kinematics(model, d, s.q);
    update_velocities(model, d, s.v);
    return momentum(model, d);
  };
  const Momentum h0 = mom(x);
  auto drift = [&](double h) {  // momentum error after 0.6 s of RK4 with step h
    State y = x;
    for (int k = 0; k < int(std::lround(0.6 / h)); ++k) y = rk4(model, d, y, VecX::Zero(model.nv), h);
    const Momentum h1 = mom(y);
    return (h1.linear - h0.linear).norm() + (h1.angular - h0.angular).norm();
  };
  const double scale = h0.linear.norm() + h0.angular.norm();
  EXPECT_LE(drift(1e-3), 1e-9 * scale);
  // the residual is truncation error, not a modelling error: it falls ~16× per halving
  const double coarse = drift(0.04), fine = drift(0.02);
  EXPECT_GT(coarse / fine, 10.0) << coarse << " " << fine;
  EXPECT_GT(h0.angular.norm(), 1e-3);
}

}  // namespace

// The tree-sparse factor, both ways it is computed (the blocked dense one on a long chain, the
// tree walk elsewhere): 𝓜 = Lᵀ D L with L unit lower and zero off the ancestor chains.
TEST(ForwardDynamics, LtdlFactorReproducesMassMatrix) {
  for (const auto& [name, options] : std::vector<std::pair<const char*, TreeOptions>>{
           {"chain6", {.n = 6, .branching = 0.0}},
           {"chain40", {.n = 40, .branching = 0.0, .prismatic = 0.3}},
           {"tree40", {.n = 40, .branching = 0.6, .prismatic = 0.2, .ball = 0.1}}}) {
    Rng rng(31);
    const Model model = random_model(rng, options);
    Data data(model);
    update_kinematics(model, data, random_q(rng, model));
    mass_matrix(model, data);
    ltdl_factor(model, data);
    const int n = model.nv;
    MatX L = MatX::Identity(n, n), D = MatX::Zero(n, n);
    for (int k = 0; k < n; ++k) {
      D(k, k) = data.work.factor.L(k, k);
      for (int i = model.dof_parent[k]; i >= 0; i = model.dof_parent[i]) L(k, i) = data.work.factor.L(k, i);
    }
    EXPECT_TRUE(near_rel(L.transpose() * D * L, data.M, 1e-12)) << name;
  }
}
