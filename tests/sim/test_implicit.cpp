// The implicit methods with the exact Jacobian: System::jacobian against central differences of
// the right-hand side in the coordinates the integrators hold (quaternions unnormalized, inputs
// included); CVODE BDF with the analytic Jacobian against BDF with difference quotients; the
// implicit midpoint rule's full Newton on the stiff arm at steps where the simplified Newton
// diverges, and its energy on conservative scenes.
#include "soadyn/sim/simulate.hpp"
#include "soadyn/io/scenario_file.hpp"

#include "test_util.hpp"

using namespace soadyn;
using namespace soadyn::test;

namespace {

const std::string kDir = SOADYN_SOURCE_DIR "/scenarios/";

VecX state(const Sample& s) {
  VecX y(s.q.size() + s.qd.size());
  y << s.q, s.qd;
  return y;
}

// ∂f/∂y by central differences of System::rhs
MatX central_jacobian(System& sys, double t, const VecX& y, double h = 1e-6) {
  const int n = sys.size();
  MatX J(n, n);
  VecX yp = y, fp(n), fm(n);
  for (int c = 0; c < n; ++c) {
    yp(c) = y(c) + h;
    sys.rhs(t, yp.data(), fp.data());
    yp(c) = y(c) - h;
    sys.rhs(t, yp.data(), fm.data());
    yp(c) = y(c);
    J.col(c) = (fp - fm) / (2 * h);
  }
  return J;
}

TEST(SystemJacobian, AgainstCentralDifferencesOfTheRightHandSide) {
  const TreeOptions cases[] = {
      {.n = 8, .branching = 0.3, .prismatic = 0.3},
      {.n = 10, .branching = 0.5, .prismatic = 0.2, .ball = 0.3, .planar = 0.2, .free_root = true},
      {.n = 6, .branching = 0.0, .ball = 0.6},
  };
  int k = 0;
  for (const TreeOptions& o : cases) {
    Rng rng(17 + k++);
    const Model model = random_model(rng, o);
    Inputs in;
    for (int i = 0; i < model.nbodies; ++i)
      if (model.nv_i[i] == 1) {
        in.springs.push_back({model.joint_names[i], model.idx_v[i], model.idx_q[i], rng.uniform(5, 500), rng.uniform()});
        in.dampers.push_back({model.joint_names[i], model.idx_v[i], rng.uniform(0.5, 20)});
        in.torques.push_back({model.joint_names[i], model.idx_v[i], 0.3, 1.0, 2.0, 0.1});
      }
    System sys(model, in, FdMethod::ArticulatedBody);
    VecX y = sys.state(random_q(rng, model), random_v(rng, model, 2.0));
    for (int k = model.nq + model.nv; k < sys.size(); ++k) y(k) = rng.uniform();  // W, D: the inputs do work
    EXPECT_EQ(sys.nquad, 2);
    // quaternions a little off unit, as in an integrator's state between projections
    for (int i = 0; i < model.nbodies; ++i)
      if (const int qo = joint_traits(model.joint_type[i]).quaternion; qo >= 0) y.segment<4>(model.idx_q[i] + qo) *= 1.03;
    MatX J(sys.size(), sys.size());
    sys.jacobian(0.7, y.data(), J);
    const MatX ref = central_jacobian(sys, 0.7, y);
    EXPECT_TRUE(near_rel(J, ref, 2e-6)) << "case " << k;
    EXPECT_EQ(sys.jac_evals, 1);
    // and the forward-difference Jacobian the simplified Newton and CVODE's DQ use agrees too
    MatX Jdq(sys.size(), sys.size());
    sys.jacobian_dq(0.7, y.data(), Jdq);
    EXPECT_TRUE(near_rel(Jdq, ref, 1e-4)) << "case " << k;
    // the product without the matrix (forward sensitivities) against the matrix times random columns
    MatX S(sys.size(), 5), JS;
    for (Eigen::Index c = 0; c < S.size(); ++c) S.data()[c] = rng.uniform();
    sys.jacobian_times(0.7, y.data(), S, JS);
    EXPECT_TRUE(near_rel(JS, J * S, 1e-11)) << "case " << k;
    // with generalized forces F on the last two columns (the sensitivities' −Y): their q̈ rows gain
    // 𝓜⁻¹ F, and nothing else moves
    MatX F(model.nv, 2), JSF;
    for (Eigen::Index c = 0; c < F.size(); ++c) F.data()[c] = rng.uniform();
    EXPECT_EQ(sys.linearize(0.7, y.data()), sys.linearize(0.7, y.data()));  // kept at the same state
    sys.linearized_times(S, JSF, &F);
    MatX moved = JSF - JS;
    mass_matrix(model, sys.data);  // at the linearized state's kinematics
    EXPECT_TRUE(near_rel(sys.data.M * moved.block(model.nq, 3, model.nv, 2), F, 1e-10)) << "case " << k;
    moved.block(model.nq, 3, model.nv, 2).setZero();
    EXPECT_LT(moved.cwiseAbs().maxCoeff(), 1e-12) << "case " << k;
  }
}

// the same on a scene: the flexible satellite (free root, 16 sprung and damped hinges) mid-motion
TEST(SystemJacobian, FlexibleSatelliteAgainstCentralDifferences) {
  const Scenario sc = load_scenario(kDir + "flexible_satellite.yaml");
  System sys(sc.model, sc.inputs, FdMethod::ArticulatedBody);
  Rng rng(3);
  VecX y = sys.state(sc.q0, sc.v0 + random_v(rng, sc.model, 0.5));
  MatX J(sys.size(), sys.size());
  sys.jacobian(0.0, y.data(), J);
  EXPECT_TRUE(near_rel(J, central_jacobian(sys, 0.0, y), 2e-6));
}

SimulationSettings bdf(const Scenario& sc, const std::string& jacobian, double rtol, double t_end) {
  SimulationSettings s = sc.simulation;
  s.method = Method::CvodeBdf;
  s.jacobian = parse_jacobian(jacobian);
  s.rtol = rtol;
  s.atol = 1e-2 * rtol;
  s.t_end = t_end;
  s.output_dt = 0.05;
  return s;
}

// The same solution with either Jacobian (to the tolerance asked), on the stiff arm and on the
// satellite (a free root: quaternion coordinates in the Jacobian); the analytic one needs no
// difference-quotient right-hand sides.
TEST(BdfJacobian, AnalyticReachesTheSameSolutionAsDifferenceQuotients) {
  for (auto [name, t_end] : {std::pair{"stiff_arm", 2.0}, std::pair{"satellite_two_arrays", 2.0},
                             std::pair{"heavy_top", 2.0}, std::pair{"flexible_satellite", 0.5}}) {
    const Scenario sc = load_scenario(kDir + name + ".yaml");
    std::vector<Sample> a, d;
    const RunSummary ra = simulate(sc, bdf(sc, "analytic", 1e-9, t_end), nullptr, &a);
    const RunSummary rd = simulate(sc, bdf(sc, "dq", 1e-9, t_end), nullptr, &d);
    ASSERT_TRUE(ra.completed) << name << ": " << ra.status;
    ASSERT_TRUE(rd.completed) << name << ": " << rd.status;
    ASSERT_EQ(a.size(), d.size());
    double worst = 0, moved = 0;
    for (size_t k = 0; k < a.size(); ++k) {
      worst = std::max(worst, (state(a[k]) - state(d[k])).cwiseAbs().maxCoeff());
      moved = std::max(moved, (state(a[k]) - state(a[0])).cwiseAbs().maxCoeff());
    }
    EXPECT_LE(worst, 1e-6) << name;
    EXPECT_GT(moved, 0.01) << name << ": the scene moved";
    EXPECT_GT(ra.stats.jac_evals, 0) << name;
    EXPECT_GT(rd.stats.jac_evals, 0) << name;
  }
}

// CVODE calls the analytic Jacobian (and no difference-quotient right-hand sides) only when asked
TEST(BdfJacobian, CvodeUsesTheJacobianAsked) {
  const Scenario sc = load_scenario(kDir + "stiff_arm.yaml");
  for (const char* jacobian : {"analytic", "dq"}) {
    System sys(sc.model, sc.inputs, FdMethod::ArticulatedBody);
    VecX y = sys.state(sc.q0, sc.v0);
    double t = 0;
    auto integrator = make_cvode(true, sys, bdf(sc, jacobian, 1e-8, 1.0), t, y);
    integrator->advance(1.0, t, y);
    const IntegratorStats st = integrator->stats();
    EXPECT_GT(st.jac_evals, 0);
    if (std::string(jacobian) == "analytic") {
      EXPECT_EQ(sys.jac_evals, st.jac_evals);
      EXPECT_EQ(st.rhs_evals, sys.rhs_evals) << "no difference-quotient evaluations";
    } else {
      EXPECT_EQ(sys.jac_evals, 0);
      EXPECT_GE(st.rhs_evals, sys.rhs_evals);
    }
  }
}

SimulationSettings midpoint(const Scenario& sc, const std::string& newton, double dt, double t_end) {
  SimulationSettings s = sc.simulation;
  s.method = Method::ImplicitMidpoint;
  s.newton = parse_newton(newton);
  s.dt = dt;
  s.t_end = t_end;
  s.output_dt = dt;
  return s;
}

// At 52 ms (10× the 5.2 ms where the simplified Newton first fails) the full Newton completes and
// follows the slow motion; the simplified Newton blows up.
TEST(MidpointNewton, FullNewtonIsStableOnTheStiffArmAtTenTimesTheSimplifiedLimit) {
  const Scenario sc = load_scenario(kDir + "stiff_arm.yaml");
  const double t_end = 2.08;  // 40 steps of 52 ms
  std::vector<Sample> full, ref;
  const RunSummary rf = simulate(sc, midpoint(sc, "full", 0.052, t_end), nullptr, &full);
  ASSERT_TRUE(rf.completed) << rf.status;
  const RunSummary rs = simulate(sc, midpoint(sc, "simplified", 0.052, t_end));
  EXPECT_FALSE(rs.completed) << "the simplified Newton was expected to diverge at 52 ms";
  // the slow swing (θ1, θ2) against BDF at a tight tolerance; the stiff θ3 decays to its rest
  SimulationSettings tight = bdf(sc, "analytic", 1e-10, t_end);
  tight.output_dt = 0.052;
  ASSERT_TRUE(simulate(sc, tight, nullptr, &ref).completed);
  ASSERT_EQ(full.size(), ref.size());
  for (size_t k = 0; k < full.size(); ++k) {
    ASSERT_TRUE(state(full[k]).allFinite());
    EXPECT_NEAR(full[k].q(0), ref[k].q(0), 0.05) << "t = " << ref[k].t;
    EXPECT_NEAR(full[k].q(1), ref[k].q(1), 0.05) << "t = " << ref[k].t;
  }
  EXPECT_GT(std::abs(ref.back().q(0) - ref.front().q(0)), 0.5) << "the arm turned";
  // Newton's quadratic convergence: a few iterations per step, even at 52 ms
  EXPECT_LE(double(rf.stats.nonlinear_iterations), 6.0 * double(rf.stats.steps));
  EXPECT_EQ(rf.stats.jac_evals, rf.stats.nonlinear_iterations) << "one Jacobian per iterate";
}

// Where both converge they solve the same implicit equations: the same states; and the method
// keeps the energy error of these conservative scenes small, full Newton as before (symmetric, not
// symplectic where 𝓜 depends on q: its long-run energy is measured in test_integrators).
TEST(MidpointNewton, FullAndSimplifiedAgreeAndConserveEnergy) {
  for (const char* name : {"double_pendulum", "satellite_two_arrays"}) {
    const Scenario sc = load_scenario(kDir + name + ".yaml");
    std::vector<Sample> f, s;
    SimulationSettings sf = midpoint(sc, "full", 1e-3, 5.0), ss = midpoint(sc, "simplified", 1e-3, 5.0);
    sf.output_dt = ss.output_dt = 0.1;
    const RunSummary rf = simulate(sc, sf, nullptr, &f);
    const RunSummary rs = simulate(sc, ss, nullptr, &s);
    ASSERT_TRUE(rf.completed) << rf.status;
    ASSERT_TRUE(rs.completed) << rs.status;
    double worst = 0;
    for (size_t k = 0; k < f.size(); ++k) worst = std::max(worst, (state(f[k]) - state(s[k])).cwiseAbs().maxCoeff());
    EXPECT_LE(worst, 1e-8) << name;
    EXPECT_LE(rf.max_energy_balance_error, 1e-4) << name;
    // full Newton converges in few iterations per step
    EXPECT_LE(double(rf.stats.nonlinear_iterations), 4.0 * double(rf.stats.steps)) << name;
  }
}

// the words are checked where they come in (the settings table); inside, the enums
TEST(Settings, JacobianAndNewtonAreCheckedWords) {
  const Scenario sc = load_scenario(kDir + "double_pendulum.yaml");
  SimulationSettings s = midpoint(sc, "full", 1e-3, 0.01);
  EXPECT_THAT([&] { set_setting(s, *find_setting("jacobian"), std::string("numeric")); },
              testing::ThrowsMessage<Error>(testing::StartsWith("jacobian: expected analytic or dq, got 'numeric'")));
  EXPECT_THAT([&] { parse_newton("quasi"); },
              testing::ThrowsMessage<Error>(testing::StartsWith("newton: expected full or simplified, got 'quasi'")));
  EXPECT_EQ(s.jacobian, Jacobian::Analytic);
  set_setting(s, *find_setting("jacobian"), std::string("dq"));
  s.newton = parse_newton("simplified");
  EXPECT_EQ(s.jacobian, Jacobian::Dq);
  EXPECT_TRUE(simulate(sc, s).completed);
}

}  // namespace
