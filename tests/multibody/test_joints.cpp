// Ball and planar joints: each against an equivalent description built from 1-DOF joints, the
// algorithms against each other on random trees that contain them, and conservation in simulation.
#include "test_util.hpp"

#include "soadyn/sim/integrators.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/sim/simulate.hpp"

#include <Eigen/Cholesky>

namespace soadyn::test {
namespace {

// The mass matrix, bias and q̈ (O(N) route) of a model at (q, v), with zero τ.
struct Dyn {
  MatX M;
  VecX bias, qdd_on, qdd_dense;
  double T = 0, V = 0;
};

Dyn dynamics(const Model& m, const VecX& q, const VecX& v) {
  Data d(m);
  Dyn out;
  update_kinematics(m, d, q);
  mass_matrix(m, d);
  out.M = d.M;
  update_velocities(m, d, v);
  bias_forces(m, d);
  out.bias = d.bias;
  const VecX tau = VecX::Zero(m.nv);
  forward_dynamics(m, d, tau, FdMethod::ArticulatedBody);
  out.qdd_on = d.qdd;
  forward_dynamics(m, d, tau, FdMethod::Dense);
  out.qdd_dense = d.qdd;
  out.T = kinetic_energy(m, d);
  out.V = potential_energy(m, d);
  return out;
}

BodySpec body(const std::string& name, int parent, JointType joint, const Vec3& axis, double mass, const Vec3& com,
              const Mat3& inertia, const Placement& placement = {}) {
  BodySpec b;
  b.name = name;
  b.parent = parent;
  b.joint = joint;
  b.axis = axis;
  b.mass = mass;
  b.com = com;
  b.inertia = inertia;
  b.placement = placement;
  return b;
}

// A carrier body, then a payload on a ball joint.  The twin turns the payload by three revolute
// joints z, y, x about successive child axes through one point, C = Rz(a) Ry(b) Rx(c); its two
// gimbal bodies carry mass of their own.  Kinetic energy adds over bodies, so
//   𝓜_rev = Eᵀ 𝓜_ball E + 𝓜_gimbal,   bias_rev = Eᵀ (bias_ball + 𝓜_ball Ė θ̇) + bias_gimbal,
// with ω_payload (its own frame) = E(θ) θ̇ and 𝓜_gimbal, bias_gimbal those of the twin without the
// payload, less the carrier's own (counted in both): 𝓜_gimbal = 𝓜(carrier, ga, gb) − 𝓜(carrier).
struct BallTwin {
  Rng rng{42};
  Placement carrier_place{rng.rotation(), rng.vec3()}, pivot{rng.rotation(), rng.vec3()};
  Vec3 carrier_axis = rng.vec3().normalized(), gravity{0, 0, -9.81};
  BodySpec carrier = body("carrier", -1, JointType::Revolute, carrier_axis, 2.0, rng.vec3(), rng.inertia(), carrier_place);
  BodySpec payload = body("payload", 0, JointType::Ball, Vec3::Zero(), 1.5, rng.vec3(), rng.inertia(), pivot);
  BodySpec gimbal_a = body("ga", 0, JointType::Revolute, Vec3::UnitZ(), 0.3, rng.vec3(), rng.inertia(), pivot);
  BodySpec gimbal_b = body("gb", 1, JointType::Revolute, Vec3::UnitY(), 0.2, rng.vec3(), rng.inertia());

  Model ball() const { return Model::build({carrier, payload}, gravity); }
  Model carrier_only() const { return Model::build({carrier}, gravity); }
  Model revolute(bool with_payload) const {
    BodySpec p = payload;
    p.parent = 2;
    p.joint = JointType::Revolute;
    p.axis = Vec3::UnitX();
    p.placement = {};
    std::vector<BodySpec> specs{carrier, gimbal_a, gimbal_b};
    if (with_payload) specs.push_back(p);
    return Model::build(specs, gravity);
  }
};

// E(θ) = [Rxᵀ Ryᵀ e_z, Rxᵀ e_y, e_x] and Ė θ̇ = −ω_rel × E₁ ȧ − ċ e_x × E₂ ḃ, ω_rel = E₂ ḃ + e_x ċ
void gimbal_map(const Vec3& th, const Vec3& thd, Mat3& E, Vec3& Edot_thd) {
  const Mat3 Ry = Eigen::AngleAxisd(th(1), Vec3::UnitY()).toRotationMatrix();
  const Mat3 Rx = Eigen::AngleAxisd(th(2), Vec3::UnitX()).toRotationMatrix();
  E.col(0) = Rx.transpose() * Ry.transpose() * Vec3::UnitZ();
  E.col(1) = Rx.transpose() * Vec3::UnitY();
  E.col(2) = Vec3::UnitX();
  const Vec3 w_rel = E.col(1) * thd(1) + Vec3::UnitX() * thd(2);
  Edot_thd = -w_rel.cross(Vec3(E.col(0))) * thd(0) - thd(2) * Vec3::UnitX().cross(Vec3(E.col(1))) * thd(1);
}

TEST(BallJoint, EqualsThreeRevoluteJointsThroughTheAngularVelocityMap) {
  const BallTwin tw;
  const Model ball = tw.ball(), rev = tw.revolute(true), gimbal = tw.revolute(false), alone = tw.carrier_only();
  ASSERT_EQ(ball.nq, 5);
  ASSERT_EQ(ball.nv, 4);
  Rng rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    // away from the gimbal singularity b = ±π/2
    const double q0 = rng.uniform(-2, 2);
    const Vec3 th(rng.uniform(-3, 3), rng.uniform(-1.2, 1.2), rng.uniform(-3, 3));
    const double v0 = rng.uniform(-2, 2);
    const Vec3 thd = rng.vec3(-2, 2);
    Mat3 E;
    Vec3 Edot_thd;
    gimbal_map(th, thd, E, Edot_thd);
    const Eigen::Quaterniond quat(Eigen::AngleAxisd(th(0), Vec3::UnitZ()) * Eigen::AngleAxisd(th(1), Vec3::UnitY()) *
                                  Eigen::AngleAxisd(th(2), Vec3::UnitX()));

    VecX qb(5), vb(4), qr(4), vr(4), qg(3), vg(3);
    qb << q0, quat.w(), quat.x(), quat.y(), quat.z();
    vb << v0, E * thd;
    qr << q0, th;
    vr << v0, thd;
    qg << q0, th.head<2>();
    vg << v0, thd.head<2>();
    Dyn g = dynamics(gimbal, qg, vg);
    const Dyn b = dynamics(ball, qb, vb), r = dynamics(rev, qr, vr), c = dynamics(alone, qb.head(1), vb.head(1));
    g.M(0, 0) -= c.M(0, 0);
    g.bias(0) -= c.bias(0);
    g.T -= c.T;
    g.V -= c.V;

    // the carrier's DOF maps to itself, the three angles to the ball's ω
    MatX T = MatX::Zero(4, 4);
    T(0, 0) = 1;
    T.bottomRightCorner<3, 3>() = E;
    MatX Mexp = T.transpose() * b.M * T;
    Mexp.topLeftCorner<3, 3>() += g.M;
    EXPECT_TRUE(near_rel(r.M, Mexp, 1e-12)) << "trial " << trial;

    VecX acc = VecX::Zero(4);  // 𝓜_ball Ė θ̇ enters through the ball's acceleration
    acc.tail<3>() = Edot_thd;
    VecX bexp = T.transpose() * (b.bias + b.M * acc);
    bexp.head<3>() += g.bias;
    EXPECT_TRUE(near_rel(r.bias, bexp, 1e-11)) << "trial " << trial;
    EXPECT_NEAR(r.T, b.T + g.T, 1e-12 * std::max(1.0, r.T));
    EXPECT_NEAR(r.V, b.V + g.V, 1e-12 * std::max(1.0, std::abs(r.V)));
  }
}

// A payload on a planar joint against prismatic e1, prismatic e2, revolute n (two carriers with mass
// of their own, whose 𝓜 and bias are added as above; here the coordinates map one to one).
TEST(PlanarJoint, EqualsPrismaticPrismaticRevolute) {
  Rng rng(11);
  for (const Vec3& n : {Vec3(Vec3::UnitZ()), Vec3(Vec3::UnitX()), Vec3(rng.vec3().normalized())}) {
    Vec3 e1, e2;
    plane_basis(n, e1, e2);
    EXPECT_NEAR(e1.dot(n), 0, 1e-15);
    EXPECT_NEAR(e2.dot(n), 0, 1e-15);
    EXPECT_NEAR(e1.cross(e2).dot(n), 1, 1e-15);
    const Placement root{rng.rotation(), rng.vec3()}, place{rng.rotation(), rng.vec3()};
    const BodySpec carrier = body("carrier", -1, JointType::Revolute, rng.vec3().normalized(), 2.0, rng.vec3(), rng.inertia(), root);
    const BodySpec payload = body("payload", 0, JointType::Planar, n, 1.3, rng.vec3(), rng.inertia(), place);
    const BodySpec p1 = body("p1", 0, JointType::Prismatic, e1, 0.4, rng.vec3(), rng.inertia(), place);
    const BodySpec p2 = body("p2", 1, JointType::Prismatic, e2, 0.5, rng.vec3(), rng.inertia());
    BodySpec r3 = payload;
    r3.parent = 2;
    r3.joint = JointType::Revolute;
    r3.placement = {};
    const Vec3 g(0.3, -2.0, -9.81);
    const Model planar = Model::build({carrier, payload}, g), ppr = Model::build({carrier, p1, p2, r3}, g),
                carriers = Model::build({carrier, p1, p2}, g), alone = Model::build({carrier}, g);
    ASSERT_EQ(planar.nq, 4);
    for (int trial = 0; trial < 20; ++trial) {
      const VecX q = VecX::NullaryExpr(4, [&](Eigen::Index) { return rng.uniform(-2, 2); });
      const VecX v = VecX::NullaryExpr(4, [&](Eigen::Index) { return rng.uniform(-2, 2); });
      const Dyn a = dynamics(planar, q, v), b = dynamics(ppr, q, v);
      Dyn c = dynamics(carriers, q.head(3), v.head(3));
      const Dyn c0 = dynamics(alone, q.head(1), v.head(1));  // the carrier is in both: counted once
      c.M(0, 0) -= c0.M(0, 0);
      c.bias(0) -= c0.bias(0);
      c.T -= c0.T;
      c.V -= c0.V;
      MatX Mexp = a.M;
      Mexp.topLeftCorner<3, 3>() += c.M;
      VecX bexp = a.bias;
      bexp.head<3>() += c.bias;
      EXPECT_TRUE(near_rel(b.M, Mexp, 1e-12));
      EXPECT_TRUE(near_rel(b.bias, bexp, 1e-12));
      EXPECT_NEAR(b.T, a.T + c.T, 1e-12 * std::max(1.0, b.T));
      EXPECT_NEAR(b.V, a.V + c.V, 1e-12 * std::max(1.0, std::abs(b.V)));
    }
  }
}

// Random trees with ball and planar joints (and a free root): the literal mass matrix, columns of
// inverse dynamics, and the three forward-dynamics routes agree.
TEST(MultiDofJoints, AlgorithmsAgreeOnRandomTrees) {
  for (int seed = 0; seed < 20; ++seed) {
    Rng rng(1000 + seed);
    TreeOptions o{.n = 9, .branching = 0.5, .prismatic = 0.15, .ball = 0.3, .planar = 0.2, .free_root = seed % 2 == 0,
                  .fixed = 2};
    const Model m = random_model(rng, o);
    Data d(m);
    const VecX q = random_q(rng, m), v = random_v(rng, m, 1.5), tau = random_v(rng, m, 3.0);
    update_kinematics(m, d, q);
    mass_matrix(m, d);
    const MatX M = d.M;
    MatX Mlit;
    mass_matrix_literal(m, d, Mlit);
    EXPECT_TRUE(near_rel(M, Mlit, 1e-12)) << "seed " << seed;
    update_velocities(m, d, v);
    bias_forces(m, d);
    const VecX bias = d.bias;
    // column k of 𝓜 = τ(q̈ = e_k) − bias
    for (int k = 0; k < m.nv; ++k) {
      inverse_dynamics(m, d, VecX::Unit(m.nv, k));
      EXPECT_TRUE(near_rel(d.tau - bias, M.col(k), 1e-12)) << "seed " << seed << " column " << k;
    }
    const VecX ref = M.llt().solve(tau - bias);
    for (const auto& route : fd_methods()) {
      forward_dynamics(m, d, tau, route.method);
      EXPECT_TRUE(near_rel(d.qdd, ref, 1e-10)) << "seed " << seed << " route " << route.name;
    }
  }
}

// q ⊕ h v and the q̇ map agree: (q ⊕ h v − q)/h → q̇(q, v), and the reverse map returns v.
TEST(MultiDofJoints, IntegrateQdotAndVelocityMapsAgree) {
  Rng rng(5);
  for (JointType t : {JointType::Ball, JointType::Planar, JointType::Free}) {
    const JointTraits& tr = joint_traits(t);
    VecX q(tr.nq), v(tr.nv), qd(tr.nq), qp(tr.nq), qm(tr.nq), back(tr.nv);
    for (int k = 0; k < tr.nq; ++k) q(k) = rng.uniform();
    if (tr.quaternion >= 0) q.segment<4>(tr.quaternion).normalize();
    for (int k = 0; k < tr.nv; ++k) v(k) = rng.uniform(-2, 2);
    joint_qdot(t, q.data(), v.data(), qd.data());
    const double h = 1e-6;
    joint_integrate(t, q.data(), v.data(), h, qp.data());
    joint_integrate(t, q.data(), v.data(), -h, qm.data());
    EXPECT_TRUE(near_rel((qp - qm) / (2 * h), qd, 1e-8)) << tr.name;
    joint_velocity(t, q.data(), qd.data(), back.data());
    EXPECT_TRUE(near_rel(back, v, 1e-13)) << tr.name;
    if (tr.quaternion >= 0) {
      EXPECT_NEAR(qp.segment<4>(tr.quaternion).norm(), 1.0, 1e-15) << tr.name;
    }
  }
}

std::string scenario_path(const std::string& name) { return std::string(SOADYN_SOURCE_DIR) + "/scenarios/" + name; }

// Gravity and a pivot at the inertial origin: energy and the vertical angular momentum are
// conserved, and every method keeps the ball's quaternion unit.
TEST(BallJointScenarios, ConserveEnergyAndVerticalMomentumWithEveryMethod) {
  for (const char* file : {"spherical_pendulum.yaml", "heavy_top.yaml"}) {
    const Scenario sc = load_scenario(scenario_path(file));
    ASSERT_EQ(sc.model.joint_type[0], JointType::Ball) << file;
    for (const auto& info : integrators()) {
      if (info.refuses && !info.refuses(sc.model).empty()) continue;  // symplectic-euler: no quaternions
      SimulationSettings s = sc.simulation;
      s.method = info.method;
      s.t_end = 2.0;
      s.dt = 1e-4;
      s.rtol = 1e-10;
      s.atol = 1e-12;
      std::vector<Sample> samples;
      const RunSummary r = simulate(sc, s, nullptr, &samples);
      ASSERT_TRUE(r.completed) << file << " " << info.name << ": " << r.status;
      const double E0 = samples.front().total, L0 = samples.front().angular.z();
      // first-order methods drift by O(h); the others hold to their order
      const bool first_order = info.order == 1;
      const double tol = info.name == "euler" ? 5e-2 : first_order ? 5e-3 : 1e-6;
      for (const Sample& x : samples) {
        EXPECT_NEAR(x.total, E0, tol * std::max(1.0, std::abs(E0))) << file << " " << info.name << " t=" << x.t;
        EXPECT_NEAR(x.angular.z(), L0, tol * std::max(1.0, std::abs(L0))) << file << " " << info.name << " t=" << x.t;
        EXPECT_NEAR(x.q.segment<4>(0).norm(), 1.0, 1e-10) << file << " " << info.name;
      }
    }
  }
}

// A free body carrying a ball-jointed body, no gravity: linear and angular momentum are conserved.
TEST(BallJointScenarios, FreeBodyWithBallJointConservesMomentum) {
  Rng rng(3);
  const BodySpec base = body("base", -1, JointType::Free, Vec3::Zero(), 3.0, rng.vec3(0, 0), rng.inertia());
  const BodySpec arm = body("arm", 0, JointType::Ball, Vec3::Zero(), 1.0, Vec3(0.5, 0, 0), rng.inertia(),
                            Placement{Mat3::Identity(), Vec3(0.4, 0.1, 0)});
  Scenario sc;
  sc.path = "free_ball";
  sc.model = Model::build({base, arm});
  sc.q0 = sc.model.neutral_configuration();
  sc.v0 = random_v(rng, sc.model, 1.0);
  SimulationSettings s;
  s.method = Method::CvodeAdams;
  s.t_end = 5.0;
  s.output_dt = 0.05;
  s.rtol = 1e-11;
  s.atol = 1e-13;
  std::vector<Sample> samples;
  ASSERT_TRUE(simulate(sc, s, nullptr, &samples).completed);
  const Sample& a = samples.front();
  for (const Sample& x : samples) {
    EXPECT_TRUE(near_rel(x.linear, a.linear, 1e-9)) << "t = " << x.t;
    EXPECT_TRUE(near_rel(x.angular, a.angular, 1e-9)) << "t = " << x.t;
    EXPECT_NEAR(x.total, a.total, 1e-9 * std::max(1.0, a.total));
  }
}

}  // namespace
}  // namespace soadyn::test
