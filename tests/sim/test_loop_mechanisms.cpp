// Closed-loop mechanisms against what is known of them independently (loops.hpp, system.hpp): a
// four-bar against a one-degree-of-freedom model written here (its coupler and rocker angles by
// position analysis of the crank angle, its energy from the links' planar motion); the loop
// forces against the inverse dynamics of the cut tree; a parallelogram four-bar reaching its
// change point (a dead point) stops the run there, at the closed-form time, naming the loop; a 7R
// spatial loop closed by a hinge moves as the same loop closed by two points on the hinge's axis;
// the built-in controllers with loops: gravity compensation holds a four-bar still, computed
// torque on the crank makes its q̈.
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/frames.hpp"
#include "soadyn/sim/simulate.hpp"

#include "loop_util.hpp"
#include "test_util.hpp"

#include <Eigen/QR>

#include <cstdio>
#include <random>

using namespace soadyn;
using namespace soadyn::test;

namespace {

Scenario scene_of(const FourBar& f, double t_end, Method method = Method::CvodeBdf) {
  Scenario sc;
  sc.path = "four-bar";
  sc.model = f.model;
  sc.inputs.loops = f.loops;
  sc.q0 = f.q, sc.v0 = f.v;
  sc.simulation.t_end = t_end;
  sc.simulation.output_dt = 0.01;
  sc.simulation.rtol = 1e-10, sc.simulation.atol = 1e-12;
  sc.simulation.method = method;
  return sc;
}

// The four-bar as a one-DOF system in its crank angle θ, written from its planar geometry alone:
// the joint C where |C − B| = b, |C − D| = c (B the crank's end, D the rocker's pivot; the open
// branch), the links' absolute angles, and the energy ½ Σ (m |ṙ_c|² + I ω²) + Σ m g y_c with the
// rates by central differences in θ times θ̇.
struct OneDof {
  double a = 0.3, b = 1.0, c = 0.8, g = 0.9, grav = 9.81;
  double m[3] = {1.0, 1.5, 2.0};
  // the links' absolute angles at θ
  Eigen::Vector3d angles(double th) const {
    const Eigen::Vector2d B(a * std::cos(th), a * std::sin(th)), D(g, 0);
    const double r = (D - B).norm(), x = (b * b - c * c + r * r) / (2 * r), y = std::sqrt(b * b - x * x);
    const Eigen::Vector2d u = (D - B) / r, C = B + x * u + y * Eigen::Vector2d(-u.y(), u.x());
    return {th, std::atan2(C.y() - B.y(), C.x() - B.x()), std::atan2(C.y(), C.x() - g)};
  }
  // each link's centre of mass (x, y) at θ, as a 6-vector
  Eigen::Matrix<double, 6, 1> centres(double th) const {
    const Eigen::Vector3d ang = angles(th);
    const Eigen::Vector2d B(a * std::cos(th), a * std::sin(th));
    Eigen::Matrix<double, 6, 1> out;
    out << a / 2 * std::cos(ang(0)), a / 2 * std::sin(ang(0)), B.x() + b / 2 * std::cos(ang(1)),
        B.y() + b / 2 * std::sin(ang(1)), g + c / 2 * std::cos(ang(2)), c / 2 * std::sin(ang(2));
    return out;
  }
  double energy(double th, double thd) const {
    const double h = 1e-6;
    const Eigen::Vector3d w = (angles(th + h) - angles(th - h)) / (2 * h) * thd;
    const Eigen::Matrix<double, 6, 1> rd = (centres(th + h) - centres(th - h)) / (2 * h) * thd, r = centres(th);
    const double len[3] = {a, b, c};
    double e = 0;
    for (int i = 0; i < 3; ++i)
      e += 0.5 * m[i] * rd.segment<2>(2 * i).squaredNorm() + 0.5 * (m[i] * len[i] * len[i] / 12) * w(i) * w(i) +
           m[i] * grav * r(2 * i + 1);
    return e;
  }
};

}  // namespace

// the run's coupler and rocker angles are the position analysis' of its crank angle, and the
// one-DOF energy of (θ, θ̇) stays what it was
TEST(LoopMechanisms, AFourBarMovesAsItsOneDofModel) {
  const Scenario sc = scene_of(four_bar(0.7, 3.0), 10.0);
  std::vector<Sample> out;
  const RunSummary r = simulate(sc, sc.simulation, nullptr, &out);
  ASSERT_TRUE(r.completed) << r.status;
  const OneDof one;
  const double e0 = one.energy(out[0].q(0), out[0].qd(0));
  double angle = 0, energy = 0, lo = 1e9, hi = -1e9;
  for (const Sample& s : out) {
    const Eigen::Vector3d ang = one.angles(s.q(0));
    // the tree's relative angles: coupler = its absolute angle less the crank's
    angle = std::max({angle, std::abs(std::remainder(s.q(1) - (ang(1) - ang(0)), 2 * M_PI)),
                      std::abs(std::remainder(s.q(2) - ang(2), 2 * M_PI))});
    energy = std::max(energy, std::abs(one.energy(s.q(0), s.qd(0)) - e0));
    lo = std::min(lo, s.q(0)), hi = std::max(hi, s.q(0));
  }
  std::printf("  position analysis %.1e rad, one-DOF energy %.1e J of %.3f, crank over %.2f rad\n", angle, energy,
              std::abs(e0), hi - lo);
  EXPECT_LE(angle, 1e-9);
  EXPECT_LE(energy, 1e-7 * std::max(1.0, std::abs(e0)));
  EXPECT_GT(hi - lo, M_PI);  // the crank swings through most of a turn
}

// λ of the run against the cut tree's inverse dynamics: 𝓜 q̈ + bias = τ − Kᵀ λ with τ = 0, so λ
// is the least-squares solution of Kᵀ λ = −ID(q, v, q̈) of minimum norm
TEST(LoopMechanisms, LoopForcesAreTheCutTreesInverseDynamics) {
  const Scenario sc = scene_of(four_bar(0.7, 3.0), 2.0);
  std::vector<Sample> out;
  ASSERT_TRUE(simulate(sc, sc.simulation, nullptr, &out).completed);
  Data d(sc.model);
  LoopData ld(sc.model, sc.inputs.loops);
  double worst = 0, scale = 0;
  for (size_t k = 0; k < out.size(); k += 10) {
    const Sample& s = out[k];
    update_kinematics(sc.model, d, s.q);
    update_velocities(sc.model, d, s.qd);
    loop_rows(sc.model, d, sc.inputs.loops, ld);
    inverse_dynamics(sc.model, d, s.qdd);
    Eigen::CompleteOrthogonalDecomposition<MatX> cod(ld.K.transpose());
    cod.setThreshold(kLoopRankTolerance);
    const VecX lambda = cod.solve(VecX(-d.tau));
    worst = std::max(worst, (lambda - s.loop_force).cwiseAbs().maxCoeff());
    scale = std::max(scale, lambda.cwiseAbs().maxCoeff());
  }
  std::printf("  λ against the cut tree's inverse dynamics: %.1e N of %.1f N\n", worst, scale);
  EXPECT_GT(scale, 1.0);
  EXPECT_LE(worst, 1e-7 * scale);
}

// a parallelogram four-bar (crank = rocker, coupler = ground) turning freely at ω keeps θ̇ = ω (its
// inertia does not change with θ) and reaches its change point, every link on the ground line, at
// θ = π, t = (π − θ₀)/ω: there its rows lose rank and the run stops, naming the loop and t
TEST(LoopMechanisms, AParallelogramStopsAtItsDeadPointNamingTheLoop) {
  FourBarShape parallelogram;
  parallelogram.a = 0.3, parallelogram.b = 0.9, parallelogram.c = 0.3, parallelogram.g = 0.9;
  parallelogram.gravity = Vec3::Zero();
  const double theta0 = M_PI / 2, omega = 2.0;
  const Scenario sc = scene_of(four_bar(theta0, omega, parallelogram), 3.0);
  std::vector<Sample> out;
  const RunSummary r = simulate(sc, sc.simulation, nullptr, &out);
  const double t_dead = (M_PI - theta0) / omega;
  std::printf("  stopped at t = %.6f s (the change point at %.6f s): %s\n", r.t_reached, t_dead, r.status.c_str());
  EXPECT_FALSE(r.completed);
  EXPECT_NE(r.status.find("closed loop 'closing' at a singular configuration (a dead point)"), std::string::npos) << r.status;
  EXPECT_NEAR(r.t_reached, t_dead, 2e-3);
  // what was logged before it is finite and on the loop
  ASSERT_FALSE(out.empty());
  for (const Sample& s : out) EXPECT_TRUE(s.q.allFinite() && s.qd.allFinite() && s.loop_force.allFinite());
  EXPECT_NEAR(out.back().qd(0), omega, 1e-6);
}

namespace {

// a chain of six revolute joints with seeded random axes and offsets, its last body closed onto
// the world at q: `hinge` by a hinge about a random axis through a point on it, else by two point
// loops 0.2 m apart on that axis (the same constraint: 6 rows of rank 5)
Scenario seven_r(bool hinge) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<BodySpec> s(6);
  for (int i = 0; i < 6; ++i) {
    BodySpec& b = s[size_t(i)];
    b.name = "link" + std::to_string(i);
    b.parent = i - 1;
    b.axis = Vec3(u(rng), u(rng), u(rng)).normalized();
    if (i > 0) b.placement.p = Vec3(0.3 + 0.1 * u(rng), 0.1 * u(rng), 0.1 * u(rng));
    b.mass = 1.0 + 0.5 * u(rng);
    b.com = Vec3(0.15, 0.02 * u(rng), 0.02 * u(rng));
    b.inertia = Vec3(0.01, 0.02, 0.02).asDiagonal();
  }
  Scenario sc;
  sc.path = hinge ? "7R-hinge" : "7R-points";
  sc.model = Model::build(s, Vec3(0, 0, -9.81));
  sc.q0 = VecX::Zero(6);
  for (int k = 0; k < 6; ++k) sc.q0(k) = 0.5 * u(rng);
  Data d(sc.model);
  update_kinematics(sc.model, d, sc.q0);
  // the hinge's frame on the last body and, where it is at q0, on the world
  Placement on_a;
  on_a.p = Vec3(0.3, 0.05, 0);
  on_a.R = Eigen::AngleAxisd(1.0, Vec3(u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
  const Placement at = body_frame_placement(sc.model, d, 5, on_a);
  if (hinge) {
    LoopConstraint c;
    c.name = "hinge", c.type = LoopType::Hinge, c.body_a = 5, c.at_a = on_a, c.body_b = -1, c.at_b = at;
    sc.inputs.loops.push_back(c);
  } else {
    for (int k = 0; k < 2; ++k) {
      LoopConstraint c;
      c.name = "point" + std::to_string(k), c.type = LoopType::Point, c.body_a = 5, c.body_b = -1;
      c.at_a.p = on_a.p + 0.2 * k * on_a.R.col(2);
      c.at_b.p = at.p + 0.2 * k * at.R.col(2);
      sc.inputs.loops.push_back(c);
    }
  }
  // at rest: gravity moves it along its one DOF
  sc.v0 = VecX::Zero(6);
  sc.simulation.t_end = 1.0;
  sc.simulation.output_dt = 0.01;
  sc.simulation.rtol = 1e-10, sc.simulation.atol = 1e-12;
  sc.simulation.method = Method::CvodeBdf;
  return sc;
}

}  // namespace

TEST(LoopMechanisms, AHingeMovesAsTwoPointsOnItsAxis) {
  const Scenario hinge = seven_r(true), points = seven_r(false);
  MotionGap g;
  ASSERT_NO_FATAL_FAILURE(motion_gap(hinge, points, g));
  std::printf("  hinge (5 rows) against two points (6 rows of rank 5): q within %.1e rad, moved %.3f rad\n", g.gap, g.moved);
  EXPECT_GT(g.moved, 0.05);
  EXPECT_LE(g.gap, 1e-7);
  EXPECT_LE(g.run_a.max_energy_balance_error, 1e-7);
}

// gravity compensation with loops holds the four-bar still: q stays where it started
TEST(LoopMechanisms, GravityCompensationHoldsAFourBarStill) {
  Scenario sc = scene_of(four_bar(0.7, 0.0), 2.0);
  ControllerInput c;
  c.kind = ControllerInput::Kind::GravityCompensation;
  sc.inputs.controllers.push_back(c);
  std::vector<Sample> out;
  ASSERT_TRUE(simulate(sc, sc.simulation, nullptr, &out).completed);
  double drift = 0;
  for (const Sample& s : out) drift = std::max(drift, (s.q - sc.q0).cwiseAbs().maxCoeff());
  EXPECT_LE(drift, 1e-8);
  // without it, it falls
  sc.inputs.controllers.clear();
  out.clear();
  ASSERT_TRUE(simulate(sc, sc.simulation, nullptr, &out).completed);
  EXPECT_GT((out.back().q - sc.q0).cwiseAbs().maxCoeff(), 0.1);
}

// computed torque on the crank, its inverse dynamics the loops': the crank follows its target to
// the tolerance while the coupler and the rocker, unactuated, follow the loop
TEST(LoopMechanisms, ComputedTorqueOnTheCrankFollowsItsTarget) {
  Scenario sc = scene_of(four_bar(0.7, M_PI / 2), 3.0);  // on the target's start: 0.7 rad at 0.5 · 2π · 0.5 rad/s
  ControllerInput c;
  c.kind = ControllerInput::Kind::ComputedTorque;
  c.kp = 100, c.kd = 20;
  for (int k = 0; k < 3; ++k) {
    c.dofs.push_back(k), c.coords.push_back(k);
    JointTarget t;
    t.constant = sc.q0(k);
    c.targets.push_back(t);
  }
  c.targets[0].constant = 0.7, c.targets[0].amplitude = 0.5, c.targets[0].frequency = 0.5;
  c.actuated = {0};
  sc.inputs.controllers.push_back(c);
  std::vector<Sample> out;
  const RunSummary r = simulate(sc, sc.simulation, nullptr, &out);
  ASSERT_TRUE(r.completed) << r.status;
  double err = 0;
  for (const Sample& s : out) err = std::max(err, std::abs(s.q(0) - c.targets[0].value(s.t)));
  std::printf("  crank tracking %.1e rad, energy balance %.1e\n", err, r.max_energy_balance_error);
  EXPECT_LE(err, 1e-6);
  EXPECT_LE(r.max_energy_balance_error, 1e-7);
  // the passive joints take no torque from it
  for (const Sample& s : out) {
    EXPECT_EQ(s.control(1), 0.0);
    EXPECT_EQ(s.control(2), 0.0);
  }
}
