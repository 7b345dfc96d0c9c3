// The fixed-step methods on the group (fixed_step.cpp): a free or ball joint's quaternion moved by
// the exponential map stays unit over 10⁴ steps with nothing renormalizing it; euler and
// semi-implicit-euler are exactly q ⊕ h v; each method's order measured on the heavy top (ball
// joint) and the tumbling T-handle (free joint), configurations compared on the group; the implicit
// midpoint rule on the group is symmetric (a step from (q⁺, −v⁺) returns to (q, −v)); the Jacobian on
// the tangent its Newton iterations use, against differences along the group.
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

// the fixed-step methods that take a free or ball joint (symplectic-euler refuses them)
std::vector<std::string> group_methods() {
  std::vector<std::string> names;
  for (const auto& info : integrators())
    if (info.fixed_step && !info.refuses) names.emplace_back(info.name);
  return names;
}

std::string test_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string n = info.param;
  for (char& ch : n)
    if (ch == '-') ch = '_';
  return n;
}

SimulationSettings fixed(const Scenario& sc, const std::string& method, double dt, double t_end) {
  SimulationSettings s = sc.simulation;
  s.method = parse_method(method);
  s.dt = dt;
  s.t_end = t_end;
  s.output_dt = t_end;
  return s;
}

class LieGroupIntegrator : public ::testing::TestWithParam<std::string> {};

// 10⁴ steps on the heavy top (ball), the T-handle (free) and the antenna slew (a free bus whose
// gimbal's joints are prescribed: the state's reduced layout): after every step, as the method left
// it, each quaternion's norm is 1 to 1e-14, and System::normalize was never called (only once,
// before the run, on the initial state, as simulate does)
TEST_P(LieGroupIntegrator, QuaternionStaysUnitWithoutRenormalizing) {
  struct Case {
    const char* scene;
    double dt, turn;  // the step, and how far the quaternion at least turns in 10⁴ of them
  };
  for (const auto& [scene, dt, turn] : {Case{"heavy_top", 1e-3, 0.1}, Case{"tumbling_t_handle", 1e-2, 0.1},
                                        Case{"antenna_slew", 1e-2, 1e-3}}) {
    const Scenario sc = load_scenario(kDir + scene + ".yaml");
    const SimulationSettings s = fixed(sc, GetParam(), dt, 1e4 * dt);
    System sys(sc.model, sc.inputs, s.dynamics);
    VecX y = sys.state(sc.q0, sc.v0);
    sys.normalize(y.head(sys.nq_state()));
    const long before = sys.normalizations;
    ASSERT_FALSE(sys.quaternions().empty());
    double t = 0.0, worst = 0.0;
    auto integrator = make_integrator(s.method, sys, s, t, y);
    EXPECT_EQ(integrator->quaternion_handling(), "on the group (exponential map), never renormalized");
    const VecX q0 = y.head(sys.nq_state());
    for (int k = 1; k <= 10000; ++k) {
      integrator->advance(k * dt, t, y);
      for (const int at : sys.quaternions()) worst = std::max(worst, std::abs(y.segment<4>(at).norm() - 1.0));
    }
    EXPECT_EQ(sys.normalizations, before) << GetParam() << " on " << scene;
    EXPECT_LE(worst, 1e-14) << GetParam() << " on " << scene;
    EXPECT_TRUE(y.allFinite());
    // it turned: the check is not vacuous
    const int at = sys.quaternions().front();
    const double turned = std::min((y.segment<4>(at) - q0.segment<4>(at)).norm(), (y.segment<4>(at) + q0.segment<4>(at)).norm());
    EXPECT_GT(turned, turn) << GetParam() << " on " << scene;
    std::printf("[ unit ] %-20s %-18s max |‖Q‖ − 1| over 10⁴ steps %.2e, normalizations %ld, turned %.3g\n",
                GetParam().c_str(), scene, worst, sys.normalizations - before, turned);
  }
}

// the configuration error at T on the group, ‖[q_ref ⊖ q; v − v_ref]‖, for dt, dt/2, dt/4 against
// CVODE at rtol 1e-12: the two log2 ratios
std::pair<double, double> observed_orders(const Scenario& sc, const std::string& method, double dt, double T) {
  SCOPED_TRACE(method);
  Sample ref;
  std::vector<double> err;
  halving_errors(sc, dt, T, [&](double h) { return fixed(sc, method, h, T); }, ref, err);
  if (::testing::Test::HasFatalFailure()) return {std::nan(""), std::nan("")};
  std::printf("[ order ] %-20s errors %.3e %.3e %.3e\n", method.c_str(), err[0], err[1], err[2]);
  return {std::log2(err[0] / err[1]), std::log2(err[1] / err[2])};
}

// each method's order as the registry states it, both ratios within ±0.3, on the ball joint's top
// (spinning at 50 rad/s) and the free T-handle (its intermediate-axis spin at 6 rad/s)
TEST_P(LieGroupIntegrator, OrderOnTheHeavyTopAndTheTHandle) {
  const IntegratorInfo* info = find_integrator(GetParam());
  ASSERT_TRUE(info);
  struct Case {
    const char* scene;
    double dt_order_1, dt_order_2, dt_order_4, T;
  };
  for (const Case& c : {Case{"heavy_top", 1e-4, 1e-3, 4e-3, 0.5}, Case{"tumbling_t_handle", 1e-3, 1e-2, 4e-2, 2.0}}) {
    const Scenario sc = load_scenario(kDir + c.scene + ".yaml");
    const double dt = info->order == 1 ? c.dt_order_1 : info->order == 2 ? c.dt_order_2 : c.dt_order_4;
    const auto [p1, p2] = observed_orders(sc, GetParam(), dt, c.T);
    EXPECT_NEAR(p1, info->order, 0.3) << GetParam() << " on " << c.scene << " (dt → dt/2)";
    EXPECT_NEAR(p2, info->order, 0.3) << GetParam() << " on " << c.scene << " (dt/2 → dt/4)";
    std::printf("[ order ] %-20s %-18s %.3f %.3f (claimed %d)\n", GetParam().c_str(), c.scene, p1, p2, info->order);
  }
}

INSTANTIATE_TEST_SUITE_P(FixedStepMethods, LieGroupIntegrator, ::testing::ValuesIn(group_methods()), test_name);

// one step of euler is q ⊕ h v (the exponential map), of semi-implicit-euler q ⊕ h v⁺; an additive
// step renormalized, normalize(q + h q̇), differs from both by far more than rounding
TEST(LieGroupEuler, OneStepIsTheExponentialMap) {
  for (const char* scene : {"heavy_top", "tumbling_t_handle"}) {
    const Scenario sc = load_scenario(kDir + scene + ".yaml");
    const Model& m = sc.model;
    for (const char* method : {"euler", "semi-implicit-euler"}) {
      const double h = 1e-2;
      const SimulationSettings s = fixed(sc, method, h, h);
      System sys(m, sc.inputs, s.dynamics);
      VecX y = sys.state(sc.q0, sc.v0);
      sys.normalize(y.head(m.nq));
      const VecX q = y.head(m.nq), v = y.segment(m.nq, m.nv);
      double t = 0.0;
      make_integrator(s.method, sys, s, t, y)->advance(h, t, y);
      const VecX vq = std::string(method) == "euler" ? v : VecX(y.segment(m.nq, m.nv));
      VecX expected(m.nq), additive(m.nq), qd(m.nq);
      integrate(m, q, vq, h, expected);
      m.qdot(q, vq, qd);
      additive = q + h * qd;
      m.normalize(additive);
      EXPECT_LE((y.head(m.nq) - expected).norm(), 1e-15) << method << " on " << scene;
      EXPECT_GT((additive - expected).norm(), 1e-7) << method << " on " << scene;
    }
  }
}

// symmetric: from (q⁺, −v⁺) one step of h returns to (q, −v), to the Newton tolerance, on the
// top and the T-handle (conservative, so their equations are reversible)
TEST(LieGroupImplicitMidpoint, SymmetricStepReturns) {
  for (const char* scene : {"heavy_top", "tumbling_t_handle"}) {
    const Scenario sc = load_scenario(kDir + scene + ".yaml");
    const Model& m = sc.model;
    const double h = 1e-2;
    const SimulationSettings s = fixed(sc, "implicit-midpoint", h, h);
    System sys(m, sc.inputs, s.dynamics);
    VecX y = sys.state(sc.q0, sc.v0);
    sys.normalize(y.head(m.nq));
    const VecX y0 = y;
    double t = 0.0;
    make_integrator(s.method, sys, s, t, y)->advance(h, t, y);
    EXPECT_GT((y - y0).norm(), 1e-3);
    y.segment(m.nq, m.nv) *= -1.0;
    t = 0.0;
    make_integrator(s.method, sys, s, t, y)->advance(h, t, y);
    y.segment(m.nq, m.nv) *= -1.0;
    VecX e(2 * m.nv);
    e << difference(m, y0.head(m.nq), y.head(m.nq)), y.segment(m.nq, m.nv) - y0.segment(m.nq, m.nv);
    EXPECT_LE(e.norm(), 1e-12) << scene;
  }
}

// full Newton on the tangent converges as Newton does, its Jacobian chained to the increment by
// dexp (System::times_increment_jacobian): at most 4 iterations per step on the top spinning 0.5 rad
// per step (5 when the chain is left out), one Jacobian per iterate
TEST(LieGroupImplicitMidpoint, FullNewtonConvergesInFewIterations) {
  const Scenario sc = load_scenario(kDir + "heavy_top.yaml");
  const RunSummary r = simulate(sc, fixed(sc, "implicit-midpoint", 1e-2, 2.0));
  ASSERT_TRUE(r.completed) << r.status;
  EXPECT_EQ(r.stats.steps, 200);
  EXPECT_LE(r.stats.nonlinear_iterations, 4 * r.stats.steps);
  EXPECT_EQ(r.stats.jac_evals, r.stats.nonlinear_iterations);
}

// ∂f/∂(δ, v, W) on the tangent (System::tangent_jacobian) by central differences of System::rhs
// along q ⊕ ±ε e_c (the δ columns) and y ± ε e_c (the others); the q rows are [0 e 0]
MatX central_tangent_jacobian(System& sys, double t, const VecX& y, double eps = 1e-6) {
  const int nq = sys.nq_state(), n = sys.nv_state(), m = sys.size(), nt = sys.tangent_size();
  MatX J = MatX::Zero(nt, nt);
  J.block(0, n, n, n).setIdentity();
  VecX yp = y, ym = y, fp(m), fm(m);
  for (int c = 0; c < nt; ++c) {
    if (c < n) {
      const VecX e = VecX::Unit(n, c);
      sys.integrate(y.head(nq), e, eps, yp.head(nq));
      sys.integrate(y.head(nq), e, -eps, ym.head(nq));
    } else {
      yp(nq + c - n) += eps;
      ym(nq + c - n) -= eps;
    }
    sys.rhs(t, yp.data(), fp.data());
    sys.rhs(t, ym.data(), fm.data());
    J.col(c).tail(nt - n) = (fp - fm).tail(m - nq) / (2 * eps);
    yp = y, ym = y;
  }
  return J;
}

// the analytic tangent Jacobian and its forward differences against central differences along the
// group: random trees with ball joints and a free root, springs, dampers and torques (the
// quadratures' rows), and the antenna slew's reduced layout (the gimbal prescribed; W_p's row
// left zero by design)
TEST(SystemTangentJacobian, AgainstCentralDifferencesAlongTheGroup) {
  const TreeOptions cases[] = {
      {.n = 10, .branching = 0.5, .prismatic = 0.2, .ball = 0.3, .planar = 0.2, .free_root = true},
      {.n = 6, .branching = 0.0, .ball = 0.6},
  };
  int k = 0;
  for (const TreeOptions& o : cases) {
    Rng rng(31 + k++);
    const Model model = random_model(rng, o);
    Inputs in;
    for (int i = 0; i < model.nbodies; ++i)
      if (model.nv_i[i] == 1) {
        in.springs.push_back({model.joint_names[i], model.idx_v[i], model.idx_q[i], rng.uniform(5, 500), rng.uniform()});
        in.dampers.push_back({model.joint_names[i], model.idx_v[i], rng.uniform(0.5, 20)});
      }
    System sys(model, in, FdMethod::ArticulatedBody);
    const VecX y = sys.state(random_q(rng, model), random_v(rng, model, 2.0));
    MatX J(sys.tangent_size(), sys.tangent_size()), Jdq(sys.tangent_size(), sys.tangent_size());
    sys.tangent_jacobian(0.7, y.data(), J);
    sys.tangent_jacobian_dq(0.7, y.data(), Jdq);
    const MatX ref = central_tangent_jacobian(sys, 0.7, y);
    EXPECT_TRUE(near_rel(J, ref, 2e-6)) << "case " << k;
    EXPECT_TRUE(near_rel(Jdq, ref, 1e-4)) << "case " << k;
  }
  const Scenario sc = load_scenario(kDir + "antenna_slew.yaml");
  System sys(sc.model, sc.inputs, FdMethod::ArticulatedBody);
  ASSERT_TRUE(sys.has_prescribed());
  Rng rng(5);
  const VecX y = sys.state(sc.q0, sc.v0 + random_v(rng, sc.model, 0.5));
  MatX J(sys.tangent_size(), sys.tangent_size());
  sys.tangent_jacobian(12.0, y.data(), J);  // mid-slew
  // W_p's row is left zero (it feeds nothing back, as System::jacobian's): the rows above it
  const int rows = sys.tangent_size() - 1;
  EXPECT_TRUE(near_rel(J.topRows(rows), central_tangent_jacobian(sys, 12.0, y).topRows(rows), 2e-6));
  EXPECT_TRUE(J.bottomRows(1).isZero(0.0));
}

}  // namespace
