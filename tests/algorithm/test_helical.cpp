// The helical (screw) joint: 𝓜 and bias against closed forms (one body, and a body with a pendulum
// hanging from it), the routes against each other and the derivatives against central
// differences on small screws, a pitch of 0 against a revolute twin, and the scenario reader's
// pitch.  Random trees with helical joints run through the other suites (TreeOptions::helical).
#include "test_util.hpp"

#include "soadyn/multibody/configuration.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/algorithm/derivatives.hpp"
#include "soadyn/sim/scenario.hpp"
#include "soadyn/sim/simulate.hpp"

#include <cmath>
#include <fstream>

namespace soadyn::test {
namespace {

constexpr double g0 = 9.81;

BodySpec helical_body(const std::string& name, int parent, const Vec3& axis, double pitch, double mass, const Vec3& com,
                      const Mat3& inertia, const Placement& X = {}) {
  BodySpec b;
  b.name = name;
  b.parent = parent;
  b.joint = JointType::Helical;
  b.axis = axis;
  b.pitch = pitch;
  b.mass = mass;
  b.com = com;
  b.inertia = inertia;
  b.placement = X;
  return b;
}

struct Dyn {
  MatX M;
  VecX bias;
};
Dyn dynamics_at(const Model& m, const VecX& q, const VecX& v) {
  Data d(m);
  update_kinematics(m, d, q);
  mass_matrix(m, d);
  update_velocities(m, d, v);
  bias_forces(m, d);
  return {d.M, d.bias};
}

// One body on a screw about z through the origin, pitch h, centre of mass c in its frame: the cm is
// at R_z(θ) c + h θ z, so ṙ = θ̇ (z × R c + h z) and |z × R c|² = cx² + cy²; the inertia about z is
// turned about z, unchanged.  So 𝓜 = I_zz + m (cx² + cy² + h²), constant (no Coriolis term), and
// with gravity g: bias = ∂V/∂θ = −m gᵀ (z × R(θ) c + h z)
TEST(Helical, OneBodyMassAndBiasInClosedForm) {
  Rng rng(59);
  for (int trial = 0; trial < 5; ++trial) {
    const double h = rng.uniform(-0.2, 0.2), mass = rng.uniform(0.5, 3.0);
    const Vec3 c = rng.vec3(-0.5, 0.5), g = rng.vec3(-10, 10);
    const Mat3 I = rng.inertia();
    const Model m = Model::build({helical_body("nut", -1, Vec3::UnitZ(), h, mass, c, I)}, g);
    const VecX q = VecX::Constant(1, rng.uniform(-3, 3)), v = VecX::Constant(1, rng.uniform(-2, 2));
    const Dyn dyn = dynamics_at(m, q, v);
    const Mat3 R = Eigen::AngleAxisd(q(0), Vec3::UnitZ()).toRotationMatrix();
    const double M = I(2, 2) + mass * (c.x() * c.x() + c.y() * c.y() + h * h);
    const double bias = -mass * g.dot(Vec3::UnitZ().cross(R * c) + h * Vec3::UnitZ());
    EXPECT_NEAR(dyn.M(0, 0), M, 1e-12 * M);
    EXPECT_NEAR(dyn.bias(0), bias, 1e-12 * (1 + std::abs(bias)));
  }
}

// A nut on a screw about z (pitch h; m1, cm c1, I1) carrying a pendulum on a parallel hinge at
// L x (m2, cm c2, I2): with ρ² = cx² + cy² and k(θ2) = c2x cos θ2 − c2y sin θ2 (the arm's and
// the pendulum's cm, in the plane),
//   𝓜11 = I1zz + m1 (ρ1² + h²) + I2zz + m2 (L² + ρ2² + 2 L k + h²),
//   𝓜12 = I2zz + m2 (ρ2² + L k),   𝓜22 = I2zz + m2 ρ2²,
// and with k' = dk/dθ2 and gravity −g0 z (V = g0 h θ1 (m1 + m2) + const), Lagrange's equations give
//   bias1 = m2 L k' (2 θ̇1 θ̇2 + θ̇2²) + g0 h (m1 + m2),   bias2 = −m2 L k' θ̇1²
TEST(Helical, NutWithPendulumMassAndBiasInClosedForm) {
  Rng rng(590);
  for (int trial = 0; trial < 5; ++trial) {
    const double h = rng.uniform(-0.2, 0.2), m1 = rng.uniform(0.5, 3.0), m2 = rng.uniform(0.5, 3.0), L = 0.7;
    const Vec3 c1 = rng.vec3(-0.5, 0.5), c2 = rng.vec3(-0.5, 0.5);
    const Mat3 I1 = rng.inertia(), I2 = rng.inertia();
    BodySpec pend;
    pend.name = "pendulum";
    pend.parent = 0;
    pend.joint = JointType::Revolute;
    pend.axis = Vec3::UnitZ();
    pend.placement.p = Vec3(L, 0, 0);
    pend.mass = m2;
    pend.com = c2;
    pend.inertia = I2;
    const Model m = Model::build({helical_body("nut", -1, Vec3::UnitZ(), h, m1, c1, I1), pend}, Vec3(0, 0, -g0));
    const VecX q = Eigen::Vector2d(rng.uniform(-3, 3), rng.uniform(-3, 3)),
               v = Eigen::Vector2d(rng.uniform(-2, 2), rng.uniform(-2, 2));
    const Dyn dyn = dynamics_at(m, q, v);
    const double rho1 = c1.x() * c1.x() + c1.y() * c1.y(), rho2 = c2.x() * c2.x() + c2.y() * c2.y();
    const double k = c2.x() * std::cos(q(1)) - c2.y() * std::sin(q(1)), kd = -c2.x() * std::sin(q(1)) - c2.y() * std::cos(q(1));
    Eigen::Matrix2d M;
    M(0, 0) = I1(2, 2) + m1 * (rho1 + h * h) + I2(2, 2) + m2 * (L * L + rho2 + 2 * L * k + h * h);
    M(0, 1) = M(1, 0) = I2(2, 2) + m2 * (rho2 + L * k);
    M(1, 1) = I2(2, 2) + m2 * rho2;
    const Eigen::Vector2d bias(m2 * L * kd * (2 * v(0) * v(1) + v(1) * v(1)) + g0 * h * (m1 + m2), -m2 * L * kd * v(0) * v(0));
    EXPECT_TRUE(near_rel(dyn.M, M, 1e-12));
    EXPECT_TRUE(near_rel(dyn.bias, bias, 1e-12));
  }
}

// a small tree of screws along skew axes, turned placements, gravity and a ball and a free root
Model screw_tree(Rng& rng) { return random_model(rng, {.n = 7, .branching = 0.5, .ball = 0.15, .helical = 0.7, .free_root = true}); }

// q̈ by every forward-dynamics route equals 𝓜⁻¹ (τ − bias), and inverse dynamics at that q̈ gives τ
// back, which is 𝓜 q̈ + bias
TEST(Helical, ForwardRoutesAndInverseDynamicsAgreeWithMassAndBias) {
  Rng rng(5901);
  for (int trial = 0; trial < 4; ++trial) {
    const Model m = screw_tree(rng);
    const VecX q = random_q(rng, m), v = random_v(rng, m), tau = random_v(rng, m, 3.0);
    const Dyn dyn = dynamics_at(m, q, v);
    const VecX qdd_ref = dyn.M.llt().solve(tau - dyn.bias);
    Data d(m);
    update_kinematics(m, d, q);
    update_velocities(m, d, v);
    for (const FdMethod method : {FdMethod::Dense, FdMethod::Sparse, FdMethod::ArticulatedBody}) {
      forward_dynamics(m, d, tau, method);
      EXPECT_TRUE(near_rel(d.qdd, qdd_ref, 1e-10)) << int(method);
    }
    inverse_dynamics(m, d, q, v, qdd_ref);
    EXPECT_TRUE(near_rel(d.tau, dyn.M * qdd_ref + dyn.bias, 1e-10));
    EXPECT_TRUE(near_rel(d.tau, tau, 1e-9));
  }
}

// ∂τ/∂q, ∂τ/∂v (inverse dynamics) and ∂q̈/∂q, ∂q̈/∂v (forward dynamics) against central differences,
// q moved along the tangent (q ⊕ δ)
TEST(Helical, DerivativesMatchCentralDifferences) {
  Rng rng(5902);
  const double e = 1e-6;
  for (int trial = 0; trial < 3; ++trial) {
    const Model m = screw_tree(rng);
    const VecX q = random_q(rng, m), v = random_v(rng, m), a = random_v(rng, m), tau = random_v(rng, m, 3.0);
    Data d(m);
    DerivativeData dd(m);
    update_kinematics(m, d, q);
    inverse_dynamics_derivatives(m, d, v, a, dd);
    const MatX dtau_dq = dd.dtau_dq, dtau_dv = dd.dtau_dv;
    update_velocities(m, d, v);
    forward_dynamics_derivatives(m, d, v, tau, dd);
    const MatX dqdd_dq = dd.dqdd_dq, dqdd_dv = dd.dqdd_dv;
    const auto id = [&](const VecX& qq, const VecX& vv) {
      Data w(m);
      inverse_dynamics(m, w, qq, vv, a);
      return VecX(w.tau);
    };
    const auto fd = [&](const VecX& qq, const VecX& vv) {
      const Dyn dyn = dynamics_at(m, qq, vv);
      return VecX(dyn.M.llt().solve(tau - dyn.bias));
    };
    MatX n_tq(m.nv, m.nv), n_tv(m.nv, m.nv), n_aq(m.nv, m.nv), n_av(m.nv, m.nv);
    for (int c = 0; c < m.nv; ++c) {
      const VecX dc = VecX::Unit(m.nv, c) * e;
      const VecX qp = m.integrate(q, dc, 1.0), qm = m.integrate(q, dc, -1.0);
      n_tq.col(c) = (id(qp, v) - id(qm, v)) / (2 * e);
      n_tv.col(c) = (id(q, v + dc) - id(q, v - dc)) / (2 * e);
      n_aq.col(c) = (fd(qp, v) - fd(qm, v)) / (2 * e);
      n_av.col(c) = (fd(q, v + dc) - fd(q, v - dc)) / (2 * e);
    }
    EXPECT_TRUE(near_rel(dtau_dq, n_tq, 1e-6));
    EXPECT_TRUE(near_rel(dtau_dv, n_tv, 1e-6));
    EXPECT_TRUE(near_rel(dqdd_dq, n_aq, 1e-6));
    EXPECT_TRUE(near_rel(dqdd_dv, n_av, 1e-6));
  }
}

// pitch 0 is a revolute joint: the same tree with every helical joint made revolute gives the same
// 𝓜, bias, q̈, ∂τ/∂q, kinetic and potential energy
TEST(Helical, ZeroPitchIsRevolute) {
  Rng rng(5903);
  for (int trial = 0; trial < 3; ++trial) {
    std::vector<BodySpec> screws = random_specs(rng, {.n = 9, .branching = 0.5, .prismatic = 0.1, .helical = 0.6});
    std::vector<BodySpec> hinges = screws;
    int helical = 0;
    for (size_t k = 0; k < screws.size(); ++k)
      if (screws[k].joint == JointType::Helical) {
        screws[k].pitch = 0.0;
        hinges[k].joint = JointType::Revolute;
        ++helical;
      }
    ASSERT_GT(helical, 0);
    const Model ms = Model::build(screws, Vec3(0, 0, -g0)), mr = Model::build(hinges, Vec3(0, 0, -g0));
    const VecX q = random_q(rng, ms), v = random_v(rng, ms), a = random_v(rng, ms);
    const Dyn ds = dynamics_at(ms, q, v), dr = dynamics_at(mr, q, v);
    EXPECT_TRUE(near_rel(ds.M, dr.M, 1e-13));
    EXPECT_TRUE(near_rel(ds.bias, dr.bias, 1e-13));
    Data es(ms), er(mr);
    DerivativeData dds(ms), ddr(mr);
    update_kinematics(ms, es, q), update_kinematics(mr, er, q);
    inverse_dynamics_derivatives(ms, es, v, a, dds);
    inverse_dynamics_derivatives(mr, er, v, a, ddr);
    EXPECT_TRUE(near_rel(dds.dtau_dq, ddr.dtau_dq, 1e-12));
    EXPECT_TRUE(near_rel(dds.dtau_dv, ddr.dtau_dv, 1e-12));
    update_kinematics(ms, es, q), update_velocities(ms, es, v);
    update_kinematics(mr, er, q), update_velocities(mr, er, v);
    EXPECT_NEAR(kinetic_energy(ms, es), kinetic_energy(mr, er), 1e-12 * (1 + kinetic_energy(mr, er)));
    EXPECT_NEAR(potential_energy(ms, es), potential_energy(mr, er), 1e-12 * (1 + std::abs(potential_energy(mr, er))));
  }
}

// The screw's energy: E = ½ q̇ᵀ 𝓜 q̇ + V changes by the joint's work, dE/dt = q̇ᵀ τ along q̈ of
// forward dynamics (checked by a central difference in time along the motion)
TEST(Helical, EnergyRateIsThePowerOfTheTorques) {
  Rng rng(5904);
  const Model m = screw_tree(rng);
  const VecX q = random_q(rng, m), v = random_v(rng, m), tau = random_v(rng, m, 3.0);
  const auto energy = [&](const VecX& qq, const VecX& vv) {
    Data d(m);
    update_kinematics(m, d, qq), update_velocities(m, d, vv);
    return kinetic_energy(m, d) + potential_energy(m, d);
  };
  const Dyn dyn = dynamics_at(m, q, v);
  const VecX qdd = dyn.M.llt().solve(tau - dyn.bias);
  const double h = 1e-6;
  const double rate = (energy(m.integrate(q, v, h), v + h * qdd) - energy(m.integrate(q, v, -h), v - h * qdd)) / (2 * h);
  EXPECT_NEAR(rate, v.dot(tau), 1e-6 * (1 + std::abs(v.dot(tau))));
}

// the scenario reader: `pitch:` is required on a helical joint, finite, and refused on the others,
// each at the file's line and column
std::string load_error(const std::string& joint) {
  const std::string path = ::testing::TempDir() + "soadyn_helical_" + std::to_string(std::hash<std::string>{}(joint)) + ".yaml";
  std::ofstream(path) << "bodies:\n  - name: nut\n    joint: " << joint << "\n    mass: 1.0\n    inertia: [0.1, 0.1, 0.1]\n";
  return message_of([&] { load_scenario(path); });
}

TEST(Helical, ScenarioReadsThePitchAndRefusesABadOne) {
  const std::string ok = ::testing::TempDir() + "soadyn_helical_ok.yaml";
  std::ofstream(ok) << "bodies:\n  - name: nut\n    joint: {type: helical, axis: [0, 0, 2], pitch: 0.05}\n    mass: 1.0\n"
                       "    inertia: [0.1, 0.1, 0.1]\n";
  const Scenario sc = load_scenario(ok);
  ASSERT_EQ(sc.model.nbodies, 1);
  EXPECT_EQ(sc.model.joint_type[0], JointType::Helical);
  EXPECT_EQ(sc.model.pitch[0], 0.05);
  EXPECT_STREQ(kind_name(sc.model.joint_model[0]), "helical");
  EXPECT_THAT(load_error("{type: helical, axis: [0, 0, 1]}"),
              ::testing::EndsWith(".yaml:3:12: body 'nut'.joint: missing required field 'pitch'"));
  EXPECT_THAT(load_error("{type: helical, axis: [0, 0, 1], pitch: .inf}"),
              ::testing::EndsWith(".yaml:3:52: body 'nut'.joint.pitch: expected a finite number, got '.inf'"));
  EXPECT_THAT(load_error("{type: helical, axis: [0, 0, 1], pitch: .nan}"), ::testing::HasSubstr("joint.pitch: expected a finite number"));
  EXPECT_THAT(load_error("{type: revolute, axis: [0, 0, 1], pitch: 0.1}"),
              ::testing::HasSubstr(".yaml:3:53: body 'nut'.joint.pitch: a revolute joint has no pitch"));
  // Model::build refuses a non-finite pitch given in C++
  BodySpec b = helical_body("nut", -1, Vec3::UnitZ(), std::nan(""), 1.0, Vec3::Zero(), Mat3::Identity());
  EXPECT_THAT(message_of([&] { Model::build({b}); }), ::testing::HasSubstr("pitch"));
}

// the scene: a nut on a vertical screw rises by pitch · θ, and its energy balance holds in a run
TEST(Helical, ScrewLiftScenarioConservesEnergy) {
  const Scenario sc = load_scenario(SOADYN_SOURCE_DIR "/scenarios/screw_lift.yaml");
  ASSERT_EQ(sc.model.joint_type[0], JointType::Helical);
  Data d(sc.model);
  VecX q = sc.model.neutral_configuration();
  q(0) = 2.0;
  update_kinematics(sc.model, d, q);
  EXPECT_NEAR(d.eta.col(0).z(), 0.05 * 2.0, 1e-15);
  SimulationSettings s = sc.simulation;
  s.t_end = 3.0;
  s.rtol = 1e-10, s.atol = 1e-12;
  const RunSummary r = simulate(sc, s);
  ASSERT_TRUE(r.completed) << r.status;
  EXPECT_LE(r.max_energy_balance_error, 1e-7);
}

}  // namespace
}  // namespace soadyn::test
