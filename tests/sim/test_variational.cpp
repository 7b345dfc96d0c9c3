// method: variational (variational.cpp), each of its claims measured:
//   the derivatives it is built on against central differences: ∂T/∂δ = ½ P(w)ᵀ w, and a step's
//     momenta p_k = 𝓜(q_k) v_k, p_k+1 = 𝓜(q_k+1) v_k+1 against −D₁L_d and D₂L_d of the midpoint
//     discrete Lagrangian differenced along the group (free root, ball joints, gravity, springs, a
//     constant torque as a potential);
//   order 2 (the error at h, h/2, h/4 against CVODE at rtol 1e-12) on the double pendulum and the
//     heavy top;
//   linear and angular momentum of a free-floating random tree (free root, ball joints, no gravity)
//     conserved to ≤ 1e-12 relative over 10⁵ steps;
//   energy bounded without drift on the double pendulum over 10⁶ steps;
//   time reversibility: N steps, the momentum flipped, N steps return to q_0 to round-off;
//   the quaternions unit to 1e-15 with nothing renormalizing them;
//   Newton's iterations per step few (its Jacobian nearly exact), and the refusal of loops;
//   each of these with both solvers (newton: full, Newton's iterations by LU or, past 128 DOFs,
//   GMRES; simplified, the O(N) chord iterations with 𝓜), and the two solvers' steps agreeing.
#include "soadyn/algorithm/derivatives.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/multibody/configuration.hpp"
#include "soadyn/sim/simulate.hpp"

#include "order_util.hpp"
#include "test_util.hpp"

#include <cstdio>

using namespace soadyn;
using namespace soadyn::test;

namespace {

const std::string kDir = SOADYN_SOURCE_DIR "/scenarios/";

constexpr Newton kSolvers[] = {Newton::Full, Newton::Simplified};
const char* name(Newton n) { return n == Newton::Full ? "newton" : "chord"; }

// variational at dt by `solver`, everything else default: the tests that step an integrator by hand
SimulationSettings stepping(double dt, Newton solver) {
  SimulationSettings s;
  s.method = Method::Variational;
  s.newton = solver;
  s.dt = dt;
  return s;
}

SimulationSettings fixed(const Scenario& sc, double dt, double t_end, double output_dt = 0, Newton newton = Newton::Full) {
  SimulationSettings s = sc.simulation;
  s.method = Method::Variational;
  s.newton = newton;
  s.dt = dt;
  s.t_end = t_end;
  s.output_dt = output_dt > 0 ? output_dt : t_end;
  return s;
}

// a free-floating tree: a free root, ball, revolute and (prismatic > 0) prismatic joints
Model floating_tree(Rng& rng, int n, const Vec3& gravity, double prismatic = 0.2) {
  TreeOptions o;
  o.n = n;
  o.branching = 0.5;
  o.ball = 0.4;
  o.prismatic = prismatic;
  o.free_root = true;
  o.gravity = gravity;
  return random_model(rng, o);
}

double potential(const Model& m, const Inputs& in, const VecX& q) {
  Data d(m);
  update_kinematics(m, d, q);
  double V = potential_energy(m, d) + in.spring_energy(q);
  for (const TorqueInput& t : in.torques) V -= t.constant * q(m.idx_q[size_t(m.dof_body[size_t(t.dof)])]);
  return V;
}

// L_d(q0, q1) = h [½ ξᵀ 𝓜(q_m) ξ − V(q_m)],  ξ = (q1 ⊖ q0)/h,  q_m = q0 ⊕ (h/2) ξ
double discrete_lagrangian(const Model& m, const Inputs& in, const VecX& q0, const VecX& q1, double h) {
  const VecX xi = difference(m, q0, q1) / h;
  VecX qm(m.nq);
  integrate(m, q0, xi, 0.5 * h, qm);
  Data d(m);
  update_kinematics(m, d, qm);
  mass_matrix(m, d);
  return h * (0.5 * xi.dot(d.M * xi) - potential(m, in, qm));
}

VecX momentum_of(const Model& m, const VecX& q, const VecX& v) {
  Data d(m);
  update_kinematics(m, d, q);
  mass_matrix(m, d);
  return d.M * v;
}

// ∂T/∂δ = ½ P(w)ᵀ w, P(w) = ∂(𝓜 w)/∂δ from inverse dynamics' ∂τ/∂q at (q, 0, w) with gravity off,
// against central differences of T(q ⊕ ε e_i, w) = ½ wᵀ 𝓜(q ⊕ ε e_i) w along the group
TEST(VariationalDerivatives, KineticEnergyAlongTheTangent) {
  Rng rng(7);
  for (int k = 0; k < 3; ++k) {
    const Model m = floating_tree(rng, 8, Vec3::Zero());
    const VecX q = random_q(rng, m), w = random_v(rng, m, 2.0);
    Data d(m);
    DerivativeData dd(m);
    update_kinematics(m, d, q);
    inverse_dynamics_derivatives(m, d, VecX::Zero(m.nv), w, dd);
    const VecX analytic = 0.5 * dd.dtau_dq.transpose() * w;
    VecX central(m.nv), qp(m.nq), qm(m.nq);
    const double e = 1e-6;
    for (int i = 0; i < m.nv; ++i) {
      integrate(m, q, VecX::Unit(m.nv, i), e, qp);
      integrate(m, q, VecX::Unit(m.nv, i), -e, qm);
      central(i) = (0.5 * w.dot(momentum_of(m, qp, w)) - 0.5 * w.dot(momentum_of(m, qm, w))) / (2 * e);
    }
    EXPECT_TRUE(near_rel(analytic, central, 1e-8)) << "tree " << k << ": " << (analytic - central).norm();
  }
}

// one step from (q0, v0) to (q1, v1): the discrete Legendre transforms hold, p0 = −D₁L_d(q0, q1)
// and p1 = D₂L_d(q0, q1), each by central differences along q ⊕ ±ε e_i at its end; with gravity,
// springs and a constant torque (their forces at the midpoint, h/2 to each end, are a potential's)
TEST(VariationalDerivatives, MomentaAreTheDiscreteLagrangiansDerivatives) {
  for (const Newton solver : kSolvers) {
  Rng rng(3);
  for (int k = 0; k < 3; ++k) {
    const Model m = floating_tree(rng, 7, Vec3(0, 0, -9.81));
    Inputs in;
    for (int i = 0; i < m.nbodies; ++i)
      if (m.nv_i[i] == 1) {
        in.springs.push_back({m.joint_names[i], m.idx_v[i], m.idx_q[i], rng.uniform(5, 50), rng.uniform()});
        if (in.torques.empty()) in.torques.push_back({m.joint_names[i], m.idx_v[i], rng.uniform(0.5, 2.0)});
      }
    const double h = 0.02;
    const SimulationSettings s = stepping(h, solver);
    System sys(m, in, FdMethod::ArticulatedBody);
    VecX y = sys.state(random_q(rng, m), random_v(rng, m, 2.0));
    const VecX q0 = y.head(m.nq), v0 = y.segment(m.nq, m.nv);
    double t = 0.0;
    make_integrator(s.method, sys, s, t, y)->advance(h, t, y);
    const VecX q1 = y.head(m.nq), v1 = y.segment(m.nq, m.nv);
    VecX d0(m.nv), d1(m.nv), a(m.nq), b(m.nq);
    const double e = 1e-6;
    for (int i = 0; i < m.nv; ++i) {
      integrate(m, q0, VecX::Unit(m.nv, i), e, a);
      integrate(m, q0, VecX::Unit(m.nv, i), -e, b);
      d0(i) = (discrete_lagrangian(m, in, a, q1, h) - discrete_lagrangian(m, in, b, q1, h)) / (2 * e);
      integrate(m, q1, VecX::Unit(m.nv, i), e, a);
      integrate(m, q1, VecX::Unit(m.nv, i), -e, b);
      d1(i) = (discrete_lagrangian(m, in, q0, a, h) - discrete_lagrangian(m, in, q0, b, h)) / (2 * e);
    }
    const VecX p0 = momentum_of(m, q0, v0), p1 = momentum_of(m, q1, v1);
    EXPECT_TRUE(near_rel(p0, -d0, 1e-7)) << name(solver) << " tree " << k << ": " << (p0 + d0).norm() << " of " << p0.norm();
    EXPECT_TRUE(near_rel(p1, d1, 1e-7)) << name(solver) << " tree " << k << ": " << (p1 - d1).norm() << " of " << p1.norm();
    // the step moved: p changed by far more than the tolerance
    EXPECT_GT((p1 - p0).norm(), 1e-3 * p0.norm());
  }
  }
}

// the error at T on the group, ‖[q_ref ⊖ q; v − v_ref; W − W_ref]‖ (W the inputs' work), at h, h/2,
// h/4 against CVODE at rtol 1e-12: each log2 ratio within 2 ± 0.2; the driven pendulum (a sinusoidal
// torque, a damper: the discrete Lagrange–d'Alembert forcing) as well as the conservative scenes
TEST(Variational, OrderTwoOnTheDoublePendulumTheHeavyTopAndTheDrivenPendulum) {
  struct Case {
    const char* scene;
    double dt, T;
  };
  for (const Case& c : {Case{"double_pendulum", 1e-2, 2.0}, Case{"heavy_top", 1e-3, 0.5}, Case{"driven_pendulum", 1e-2, 2.0}}) {
    const Scenario sc = load_scenario(kDir + c.scene + ".yaml");
    for (const Newton solver : kSolvers) {
    Sample ref;
    std::vector<double> err;
    ASSERT_NO_FATAL_FAILURE(halving_errors(
        sc, c.dt, c.T, [&](double h) { return fixed(sc, h, c.T, 0, solver); }, ref, err,
        [](const Sample& x) { return x.work_inputs; }));
    const double p1 = std::log2(err[0] / err[1]), p2 = std::log2(err[1] / err[2]);
    std::printf("[ order ] variational (%s) %-16s errors %.3e %.3e %.3e, ratios %.3f %.3f (log2 %.3f %.3f)\n",
                name(solver), c.scene, err[0], err[1], err[2], err[0] / err[1], err[1] / err[2], p1, p2);
    EXPECT_NEAR(p1, 2.0, 0.2) << c.scene << " " << name(solver);
    EXPECT_NEAR(p2, 2.0, 0.2) << c.scene << " " << name(solver);
    }
  }
}

// linear and angular momentum (about the inertial origin) of a free-floating tree (free root, ball
// and revolute joints, nv 12) with no force: the largest change over 10⁵ steps of 10 ms, sampled
// every 100, relative to |L0| and to Σ m_i |ṙ_i| (l = 0 here), ≤ 1e-12; the quaternions unit to
// 1e-15 at every sample with System::normalize never called.  (Stopping Newton at 4 ε of G's terms
// instead of ε, these drifted to 1e-12–6e-12 on such trees)
void momentum_over_1e5_steps(Newton solver) {
  Rng rng(17);
  const Model m = floating_tree(rng, 5, Vec3::Zero(), 0.0);  // no prismatic joint: nothing drifts apart
  const Inputs in;
  System sys(m, in, FdMethod::ArticulatedBody);
  VecX q0 = random_q(rng, m);
  q0.head<3>().setZero();  // the free root's origin at the inertial origin
  VecX v0 = random_v(rng, m, 2.0);
  // the centre of mass at rest (the free root's velocity less l / m_total, 𝓜's translation block
  // being m_total e): the tree tumbles about a fixed point near the origin, where the quantities
  // about the origin the algorithms form carry no growing rounding (|l|'s scale: Σ m_i |ṙ_i|)
  {
    Data d(m);
    update_kinematics(m, d, q0);
    update_velocities(m, d, v0);
    mass_matrix(m, d);
    v0.segment<3>(3) -= momentum(m, d).linear / d.M(3, 3);
  }
  VecX y = sys.state(q0, v0);
  const SimulationSettings s = stepping(1e-2, solver);
  double t = 0.0;
  auto integrator = make_integrator(s.method, sys, s, t, y);
  Data d(m);
  auto momenta = [&](const VecX& x) {
    update_kinematics(m, d, x.head(m.nq));
    update_velocities(m, d, x.segment(m.nq, m.nv));
    return momentum(m, d);
  };
  const Momentum h0 = momenta(y);
  double l_scale = 0;  // Σ m_i |ṙ_i|
  for (int i = 0; i < m.nbodies; ++i) l_scale += m.mass[size_t(i)] * d.Vbar.col(i).tail<3>().norm();
  const long before = sys.normalizations;
  double worst_l = 0, worst_a = 0, unit = 0;
  for (int k = 1; k <= 1000; ++k) {
    integrator->advance(k * 100 * s.dt, t, y);
    const Momentum h = momenta(y);
    worst_l = std::max(worst_l, (h.linear - h0.linear).norm() / l_scale);
    worst_a = std::max(worst_a, (h.angular - h0.angular).norm() / h0.angular.norm());
    for (const int at : sys.quaternions()) unit = std::max(unit, std::abs(y.segment<4>(at).norm() - 1.0));
  }
  const IntegratorStats st = integrator->stats();
  std::printf("[ momentum ] %s, nv %d, 1e5 steps: max rel |Δl| %.2e, |ΔL| %.2e; max |‖Q‖ − 1| %.2e; %.2f iterations per step\n",
              name(solver), m.nv, worst_l, worst_a, unit, double(st.nonlinear_iterations) / double(st.steps));
  EXPECT_EQ(st.steps, 100000);
  EXPECT_LE(worst_l, 1e-12);
  EXPECT_LE(worst_a, 1e-12);
  EXPECT_LE(unit, 1e-15);
  EXPECT_EQ(sys.normalizations, before);
  EXPECT_GT(difference(m, q0, y.head(m.nq)).norm(), 1.0);  // it moved
}

TEST(Variational, MomentumOfAFreeFloatingTreeOver1e5Steps) { momentum_over_1e5_steps(Newton::Full); }
TEST(Variational, MomentumOfAFreeFloatingTreeOver1e5StepsByTheChord) { momentum_over_1e5_steps(Newton::Simplified); }

// the largest |E(t) − E(0)| in the first and the last tenth of n steps of dt 1e-3 on the double pendulum
std::pair<double, double> energy_tenths(long n) {
  const Scenario sc = load_scenario(kDir + "double_pendulum.yaml");
  const double dt = 1e-3, T = double(n) * dt;
  std::vector<Sample> x;
  const RunSummary r = simulate(sc, fixed(sc, dt, T, 100 * dt), nullptr, &x);
  EXPECT_TRUE(r.completed) << r.status;
  double first = 0, last = 0;
  for (const Sample& s : x) {
    const double e = std::abs(s.total - x.front().total);
    if (s.t <= 0.1 * T) first = std::max(first, e);
    if (s.t >= 0.9 * T) last = std::max(last, e);
  }
  std::printf("[ energy ] variational, double pendulum, %ld steps of 1e-3: max |ΔE| first tenth %.3e, last tenth %.3e (ratio %.3f), "
              "%.2f Newton iterations per step\n",
              n, first, last, last / first, double(r.stats.nonlinear_iterations) / double(r.stats.steps));
  return {first, last};
}

// 10⁶ steps (1000 s, about 9 s of CPU): no drift, the last tenth's largest |ΔE| at most 1.5× the
// first's, and small (O(h²))
TEST(Variational, EnergyBoundedOnTheDoublePendulumOver1e6Steps) {
  const auto [first, last] = energy_tenths(1000000);
  EXPECT_GT(first, 0.0);
  EXPECT_LE(last, 1.5 * first);
  EXPECT_LE(last, 1e-4);
}

// N steps forward, the momentum flipped (v → −v, so p → −p), N steps more, flipped again: back at
// (q0, v0) to round-off, on the heavy top, the T-handle and a random free tree under gravity, by
// either solver
TEST(Variational, TimeReversible) {
  std::vector<Scenario> scenes{load_scenario(kDir + "heavy_top.yaml"), load_scenario(kDir + "tumbling_t_handle.yaml")};
  Rng rng(23);
  Scenario tree;
  tree.model = floating_tree(rng, 6, Vec3(0, 0, -9.81));
  tree.q0 = random_q(rng, tree.model);
  tree.v0 = random_v(rng, tree.model, 2.0);
  tree.path = "random tree";
  scenes.push_back(tree);
  for (const Newton solver : kSolvers)
  for (const Scenario& sc : scenes) {
    const Model& m = sc.model;
    System sys(m, sc.inputs, FdMethod::ArticulatedBody);
    VecX y = sys.state(sc.q0, sc.v0);
    sys.normalize(y.head(m.nq));
    const VecX y0 = y;
    const SimulationSettings s = stepping(1e-3, solver);
    const int N = 1000;
    double t = 0.0;
    make_integrator(s.method, sys, s, t, y)->advance(N * s.dt, t, y);
    const double moved = difference(m, y0.head(m.nq), y.head(m.nq)).norm();
    y.segment(m.nq, m.nv) *= -1.0;
    t = 0.0;
    make_integrator(s.method, sys, s, t, y)->advance(N * s.dt, t, y);
    y.segment(m.nq, m.nv) *= -1.0;
    const double eq = difference(m, y0.head(m.nq), y.head(m.nq)).norm();
    const double ev = (y - y0).segment(m.nq, m.nv).norm() / y0.segment(m.nq, m.nv).norm();
    std::printf("[ reverse ] %s %-18s %d steps there and back: |q ⊖ q0| %.2e (moved %.3g), rel |v − v0| %.2e\n", name(solver),
                sc.path.c_str(), N, eq, moved, ev);
    EXPECT_GT(moved, 0.1) << sc.path;
    // rounding: 2e-15 per step of the 2N, relative to the motion's size (measured: Newton 3.8e-13 on
    // the top, the chord 2.3e-12, each step's momenta solved to ε of their size by both)
    EXPECT_LE(eq, 2e-15 * 2 * N * std::max(1.0, moved)) << sc.path << " " << name(solver);
    EXPECT_LE(ev, 1e-12) << sc.path;
  }
}

// Newton's Jacobian is the exact one but for an O(h²) term: few iterations per step on the top
// spinning 0.05 rad per step and on the satellite
TEST(Variational, NewtonConvergesInFewIterations) {
  for (const char* scene : {"heavy_top", "satellite_two_arrays"}) {
    const Scenario sc = load_scenario(kDir + scene + ".yaml");
    const double dt = std::string(scene) == "heavy_top" ? 1e-3 : 1e-2;
    const RunSummary r = simulate(sc, fixed(sc, dt, 1.0));
    ASSERT_TRUE(r.completed) << r.status;
    std::printf("[ newton ] %-22s %.2f iterations per step\n", scene, double(r.stats.nonlinear_iterations) / double(r.stats.steps));
    EXPECT_LE(r.stats.nonlinear_iterations, 5 * r.stats.steps) << scene;
  }
}

// The two solvers solve the same equations by different iterations: from one state, 20 steps of
// 1 ms by each agree to rounding (q within 1e-12 of the motion, v within 1e-11 relative) on a
// random free tree under gravity of about 20 DOFs (Newton by LU) and one past 128 (Newton's
// corrections by GMRES with 𝓜⁻¹); on the small one the chord iterations never give way to Newton
TEST(Variational, TheSolversAgree) {
  Rng rng(29);
  for (const int n : {8, 74}) {
    const Model m = floating_tree(rng, n, Vec3(0, 0, -9.81));
    const Inputs in;
    const VecX q0 = random_q(rng, m), v0 = random_v(rng, m, 1.0);
    std::vector<VecX> end;
    std::vector<IntegratorStats> stats;
    for (const Newton solver : kSolvers) {
      System sys(m, in, FdMethod::ArticulatedBody);
      VecX y = sys.state(q0, v0);
      const SimulationSettings s = stepping(1e-3, solver);
      double t = 0.0;
      auto integrator = make_integrator(s.method, sys, s, t, y);
      integrator->advance(20 * s.dt, t, y);
      end.push_back(y);
      stats.push_back(integrator->stats());
    }
    const double moved = difference(m, q0, end[0].head(m.nq)).norm();
    const double dq = difference(m, end[0].head(m.nq), end[1].head(m.nq)).norm();
    const double dv = (end[0] - end[1]).segment(m.nq, m.nv).norm() / end[0].segment(m.nq, m.nv).norm();
    std::printf("[ solvers ] nv %d, 20 steps: |q_newton ⊖ q_chord| %.2e (moved %.3g), rel |Δv| %.2e; iterations per step "
                "%.2f (Newton), %.2f (chord, %.2f of them Newton's)\n",
                m.nv, dq, moved, dv, double(stats[0].nonlinear_iterations) / 20.0, double(stats[1].nonlinear_iterations) / 20.0,
                double(stats[1].jac_evals) / 20.0);
    EXPECT_GT(moved, 1e-3);
    EXPECT_LE(dq, 1e-12 * std::max(1.0, moved)) << m.nv;
    EXPECT_LE(dv, 1e-11) << m.nv;
    if (n > 8) EXPECT_GE(m.nv, 128);  // the GMRES corrections
    else EXPECT_EQ(stats[1].jac_evals, 0);
  }
}

// what it does not take yet, refused in one line before the run: closed loops (at loops:).
// Prescribed motion it takes (test_variational_prescribed)
TEST(Variational, RefusesLoops) {
  for (const auto& [scene, field] : {std::pair{"four_bar", "loops: variational"}}) {
    const Scenario sc = load_scenario(kDir + scene + ".yaml");
    const std::string why = message_of([&] { check_run(sc, fixed(sc, 1e-3, 0.1)); });
    // file:line:column: field: …
    EXPECT_THAT(why, ::testing::ContainsRegex(std::string(scene) + "\\.yaml:[0-9]+:[0-9]+: " + field)) << why;
    EXPECT_EQ(why.find('\n'), std::string::npos) << why;
    EXPECT_THROW(simulate(sc, fixed(sc, 1e-3, 0.1)), Error);
  }
}

}  // namespace
