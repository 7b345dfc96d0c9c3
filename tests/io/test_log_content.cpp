// What the run log says, checked against independent routes to the same numbers: every column's
// name leads (through the model, not the log's own layout code) to the number stored under it, for
// every scenario; body poses agree with the velocities the Jacobian gives, integrated along the
// run; the energy balance E(t) − E(0) = W(t) closes to the integrator's tolerance on a damped and
// a driven scene, and W and D agree with a quadrature of the power taken from the logged samples.
#include "soadyn/io/h5log.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/sim/simulate.hpp"

#include "h5_reader.hpp"
#include "test_util.hpp"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <numbers>

using namespace soadyn;
using namespace soadyn::test;

namespace {

const std::string kDir = SOADYN_SOURCE_DIR "/scenarios/";

std::string tmp(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("soadyn_lc_" + std::to_string(getpid()) + "_" + name)).string();
}

bool starts(const std::string& s, const std::string& prefix) { return s.rfind(prefix, 0) == 0; }

// The number a column name stands for in sample x, found through the model: "q.<joint>[.<label>]"
// by the joint's first q index and the label's place in its traits, "bodies.<kind>.<body>.<c>" by
// the body's index, and so on.  NaN for a name that means nothing.
double value_by_name(const Model& m, const Sample& x, const std::string& name,
                     const std::vector<PrescribedInput>& prescribed = {}, const std::vector<std::string>& loop_rows = {}) {
  const double nan = std::nan("");
  if (name == "time") return x.t;
  for (const auto& [prefix, of_q] : {std::pair{"q.", true}, {"qd.", false}, {"qdd.", false}}) {
    if (!starts(name, prefix)) continue;
    const std::string rest = name.substr(std::string(prefix).size());
    for (int i = 0; i < m.nbodies; ++i) {
      const JointTraits& tr = joint_traits(m.joint_type[i]);
      const auto& labels = of_q ? tr.q_labels : tr.v_labels;
      for (size_t k = 0; k < labels.size(); ++k) {
        const std::string full = labels[k].empty() ? m.joint_names[i] : m.joint_names[i] + "." + std::string(labels[k]);
        if (full != rest) continue;
        if (of_q) return x.q(m.idx_q[i] + int(k));
        return std::string(prefix) == "qd." ? x.qd(m.idx_v[i] + int(k)) : x.qdd(m.idx_v[i] + int(k));
      }
    }
    return nan;
  }
  if (name == "energy.kinetic") return x.kinetic;
  if (name == "energy.potential") return x.potential;
  if (name == "energy.total") return x.total;
  if (name == "energy.work_inputs") return x.work_inputs;
  if (name == "energy.dissipated") return x.dissipated;
  if (name == "energy.impact_loss") return x.impact_loss;
  if (name == "energy.work_prescribed") return x.work_prescribed;
  // the prescribed joints' holding torques, in the scenario's order (Inputs::prescribed)
  for (size_t j = 0; j < prescribed.size(); ++j)
    if (name == "prescribed." + prescribed[j].joint) return x.prescribed_torque(Eigen::Index(j));
  // the loops' multipliers, row by row (loop_row_names), and the closure
  if (name == "loops.closure") return x.loop_closure;
  for (size_t r = 0; r < loop_rows.size(); ++r)
    if (name == "loops.force." + loop_rows[r]) return x.loop_force(Eigen::Index(r));
  if (starts(name, "control.")) {
    const std::vector<std::string> vn = m.v_names();
    for (int k = 0; k < m.nv; ++k)
      if (name == "control." + vn[size_t(k)]) return x.control(k);
  }
  const std::string xyz = "xyz", wxyz = "wxyz";
  if (starts(name, "momentum.linear.")) return x.linear(int(xyz.find(name.back())));
  if (starts(name, "momentum.angular.")) return x.angular(int(xyz.find(name.back())));
  for (const char* kind : {"position", "orientation", "com"})
    for (int i = 0; i < m.nbodies; ++i) {
      const std::string p = std::string("bodies.") + kind + "." + m.body_names[i] + ".";
      if (!starts(name, p) || name.size() != p.size() + 1) continue;
      const char c = name.back();
      if (std::string(kind) == "orientation") return x.body_orientation(int(wxyz.find(c)), i);
      return (std::string(kind) == "position" ? x.body_position : x.body_com)(int(xyz.find(c)), i);
    }
  return nan;
}

// every scenario the repository ships (less the sweep files)
std::vector<std::string> scenarios() {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::directory_iterator(kDir)) {
    const std::string f = e.path().filename().string();
    if (e.path().extension() == ".yaml" && f.find(".sweep.") == std::string::npos) out.push_back(e.path().stem().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(LogContent, EveryColumnNameLeadsToItsNumberInEveryScenario) {
  const std::vector<std::string> all = scenarios();
  ASSERT_GE(all.size(), 8u);
  for (const std::string& name : all) {
    SCOPED_TRACE(name);
    const Scenario sc = load_scenario(kDir + name + ".yaml");
    SimulationSettings s = sc.simulation;
    s.t_end = 0.2;
    s.output_dt = 0.05;
    const std::string out = tmp(name + ".h5");
    std::vector<Sample> x;
    {
      H5Log log(out, sc, s, "test");
      ASSERT_TRUE(simulate(sc, s, &log, &x).completed);
    }
    H5File f(out);
    ASSERT_GE(f.id, 0);
    const std::vector<std::string> names = string_list_attribute(f.id, "/samples", "column_names");
    const std::vector<std::string> units = string_list_attribute(f.id, "/samples", "column_units");
    const Table t = read_table(f.id, "/samples");
    ASSERT_EQ(names.size(), t.cols);
    ASSERT_EQ(units.size(), t.cols);
    ASSERT_EQ(t.rows, x.size());
    // each name once; each names a number of the sample, stored bit for bit
    EXPECT_EQ(std::set<std::string>(names.begin(), names.end()).size(), names.size());
    int wrong = 0;
    for (size_t j = 0; j < names.size(); ++j)
      for (size_t k = 0; k < x.size(); ++k) {
        const double want = value_by_name(sc.model, x[k], names[j], sc.inputs.prescribed, loop_row_names(sc.inputs.loops));
        if (!(t.at(k, j) == want) && wrong++ < 5) ADD_FAILURE() << names[j] << " row " << k << ": " << t.at(k, j) << " vs " << want;
      }
    EXPECT_EQ(wrong, 0);
    // and every number the sample holds has a column: q, q̇, q̈, 5 energies, 6 momenta, 10 per body,
    // the impacts' loss with limits on, the controllers' τ with controllers, the prescribed joints'
    // torques and their work with prescribed motion, the loops' multipliers and closure with loops
    const Model& m = sc.model;
    const size_t impacts = s.limits && m.has_limits() ? 1 : 0, control = sc.inputs.controllers.empty() ? 0 : size_t(m.nv);
    const size_t held = sc.inputs.prescribed.empty() ? 0 : sc.inputs.prescribed.size() + 1;
    const size_t loops = sc.inputs.loops.empty() ? 0 : loop_row_names(sc.inputs.loops).size() + 1;  // λ rows, closure
    EXPECT_EQ(names.size(), size_t(1 + m.nq + 2 * m.nv + 5 + 6 + 10 * m.nbodies) + impacts + control + held + loops);
    std::filesystem::remove(out);
  }
}

// Positions from velocities.  At each logged state the velocities of the frame origins, η̇_i (the
// note's v = Ψ_D G q̇, eq. 4) and of the centres of mass, ṙ_i (rows of J = S Ψ_D G, eq. 7), and
// the angular velocities ω_i; integrated by the trapezoid rule between fine output rows they must
// give the logged positions (error O(h²)), and q̇ = ½ [0; ω] ⊗ quat the logged attitudes.
TEST(LogContent, BodyPosesAgreeWithTheJacobianIntegratedVelocities) {
  for (const char* name :
       {"satellite_two_arrays", "heavy_top", "three_link_arm", "pendulum_on_cart", "spherical_pendulum", "screw_lift"}) {
    SCOPED_TRACE(name);
    const Scenario sc = load_scenario(kDir + name + ".yaml");
    const Model& m = sc.model;
    SimulationSettings s = sc.simulation;
    s.method = Method::CvodeAdams;
    s.rtol = 1e-11;
    s.atol = 1e-13;
    s.t_end = 1.0;
    s.output_dt = 1e-3;
    std::vector<Sample> x;
    ASSERT_TRUE(simulate(sc, s, nullptr, &x).completed);
    Data d(m);
    MatX J;
    std::vector<Mat3X> eta_dot, com_dot, omega;
    for (const Sample& k : x) {
      update_kinematics(m, d, k.q);
      update_velocities(m, d, k.qd);
      jacobian(m, d, J);
      const VecX vbar = J * k.qd;  // [ω_i; ṙ_i] stacked
      Mat3X e(3, m.nbodies), c(3, m.nbodies), w(3, m.nbodies);
      for (int i = 0; i < m.nbodies; ++i) {
        e.col(i) = d.V.col(i).tail<3>();
        w.col(i) = vbar.segment<3>(6 * i);
        c.col(i) = vbar.segment<3>(6 * i + 3);
      }
      eta_dot.push_back(e), com_dot.push_back(c), omega.push_back(w);
    }
    // Simpson's rule over each pair of intervals: x(t+h) − x(t−h) = h/3 (ẋ₋ + 4 ẋ₀ + ẋ₊) + O(h⁵)
    auto rate = [](const Vec3& w, const Eigen::Vector4d& q) {  // q̇ = ½ [0; ω] ⊗ q, ω inertial
      const Eigen::Quaterniond r = Eigen::Quaterniond(0, w.x(), w.y(), w.z()) * Eigen::Quaterniond(q(0), q(1), q(2), q(3));
      return Eigen::Vector4d(0.5 * r.w(), 0.5 * r.x(), 0.5 * r.y(), 0.5 * r.z());
    };
    double moved = 0, worst_p = 0, worst_c = 0, worst_u = 0;
    for (size_t k = 1; k + 1 < x.size(); k += 2) {
      const double h = x[k].t - x[k - 1].t;
      ASSERT_NEAR(x[k + 1].t - x[k].t, h, 1e-12);
      auto simpson = [&](const std::vector<Mat3X>& v, int i) {
        return Vec3(h / 3 * (v[k - 1].col(i) + 4 * v[k].col(i) + v[k + 1].col(i)));
      };
      for (int i = 0; i < m.nbodies; ++i) {
        const Vec3 dp = x[k + 1].body_position.col(i) - x[k - 1].body_position.col(i);
        const Vec3 dc = x[k + 1].body_com.col(i) - x[k - 1].body_com.col(i);
        moved = std::max(moved, dc.norm() / (2 * h));
        worst_p = std::max(worst_p, (dp - simpson(eta_dot, i)).norm() / (2 * h));
        worst_c = std::max(worst_c, (dc - simpson(com_dot, i)).norm() / (2 * h));
        // attitude: the logged quaternions (w ≥ 0) aligned in sign with the middle one
        Eigen::Vector4d u[3];
        for (int j = 0; j < 3; ++j) {
          u[j] = x[k - 1 + j].body_orientation.col(i);
          if (j != 1 && u[j].dot(x[k].body_orientation.col(i)) < 0) u[j] = -u[j];
        }
        const Eigen::Vector4d du = u[2] - u[0];
        const Eigen::Vector4d s4 = h / 3 * (rate(omega[k - 1].col(i), u[0]) + 4 * rate(omega[k].col(i), u[1]) +
                                            rate(omega[k + 1].col(i), u[2]));
        worst_u = std::max(worst_u, (du - s4).norm() / (2 * h));
      }
    }
    EXPECT_GT(moved, 0.05) << "nothing moved: the check would be vacuous";
    // Simpson's error per unit time ~ h⁴ |x⁽⁵⁾| / 180 with h = 1e-3 (the fast top: ω ≈ 50 rad/s)
    EXPECT_LE(worst_p, 1e-6) << "frame origins";
    EXPECT_LE(worst_c, 1e-6) << "centres of mass";
    EXPECT_LE(worst_u, 1e-6) << "attitudes";
  }
}

// The balance error of a run and the time series behind it
struct Balance {
  RunSummary r;
  std::vector<Sample> x;
};
Balance run(const std::string& name, const std::string& method, double tol_or_dt, double t_end = 10.0) {
  const Scenario sc = load_scenario(kDir + name + ".yaml");
  SimulationSettings s = sc.simulation;
  s.method = parse_method(method);
  s.t_end = t_end;
  if (is_fixed_step(s.method)) s.dt = tol_or_dt;
  else s.rtol = tol_or_dt, s.atol = tol_or_dt * 1e-2;
  Balance b;
  b.r = simulate(sc, s, nullptr, &b.x);
  EXPECT_TRUE(b.r.completed) << b.r.status;
  return b;
}

// the damped stiff arm: the damper takes a large share of the energy (the old "energy error" of
// 0.98), yet E(t) − E(0) − W(t) stays at the level of CVODE's tolerance and falls with it
TEST(EnergyBalance, ClosesToTheToleranceOnTheDampedStiffArm) {
  const Balance loose = run("stiff_arm", "cvode-bdf", 1e-6), tight = run("stiff_arm", "cvode-bdf", 1e-9);
  const Sample& last = loose.x.back();
  const double E0 = loose.x.front().total;
  EXPECT_GT(last.dissipated, 0.5 * std::abs(E0)) << "the damper must matter for the test to mean anything";
  EXPECT_LE(loose.r.max_energy_balance_error, 1e-4);
  EXPECT_LE(tight.r.max_energy_balance_error, 1e-6);
  EXPECT_LE(tight.r.max_energy_balance_error, 0.1 * loose.r.max_energy_balance_error);
  // W = −D here (no torques) and D never decreases
  for (size_t k = 1; k < loose.x.size(); ++k) {
    EXPECT_NEAR(loose.x[k].work_inputs, -loose.x[k].dissipated, 1e-6 * std::abs(E0));
    EXPECT_GE(loose.x[k].dissipated, loose.x[k - 1].dissipated - 1e-9 * std::abs(E0));  // rounding of ~1e3 J
  }
}

// the driven pendulum (a sinusoidal shoulder torque, a damped elbow): the balance closes with
// every method to its accuracy, and RK4's balance error falls as h⁴
TEST(EnergyBalance, ClosesOnTheDrivenPendulumWithEveryMethod) {
  const Balance adams = run("driven_pendulum", "cvode-adams", 1e-8);
  const double E0 = adams.x.front().total;
  double peak_W = 0;
  for (const Sample& k : adams.x) peak_W = std::max(peak_W, std::abs(k.work_inputs));
  EXPECT_GT(peak_W, 0.1 * std::abs(E0)) << "the torque does work";
  EXPECT_GT(adams.x.back().dissipated, 0.1 * std::abs(E0)) << "the damper takes some";
  EXPECT_LE(adams.r.max_energy_balance_error, 1e-6);
  EXPECT_LE(run("driven_pendulum", "cvode-bdf", 1e-8).r.max_energy_balance_error, 1e-6);
  EXPECT_LE(run("driven_pendulum", "implicit-midpoint", 1e-3).r.max_energy_balance_error, 1e-5);
  EXPECT_LE(run("driven_pendulum", "symplectic-euler", 1e-3).r.max_energy_balance_error, 1e-2);
  const double coarse = run("driven_pendulum", "rk4", 4e-3, 2.0).r.max_energy_balance_error;
  const double fine = run("driven_pendulum", "rk4", 2e-3, 2.0).r.max_energy_balance_error;
  EXPECT_GT(coarse / fine, 10.0) << coarse << " vs " << fine << ": order 4 gives 16";
  EXPECT_LT(coarse / fine, 25.0) << coarse << " vs " << fine;
}

// W and D are what the integrator made of ∫ P dt; a trapezoid quadrature of the power taken from
// the logged samples (τ(t) · q̇ with the scenario's own torque formula) gives the same numbers
TEST(EnergyBalance, WorkAndDissipationAgreeWithAQuadratureOfTheLoggedPower) {
  const Scenario sc = load_scenario(kDir + "driven_pendulum.yaml");
  SimulationSettings s = sc.simulation;
  s.rtol = 1e-11, s.atol = 1e-13, s.t_end = 5.0, s.output_dt = 1e-3;
  std::vector<Sample> x;
  ASSERT_TRUE(simulate(sc, s, nullptr, &x).completed);
  ASSERT_EQ(sc.inputs.torques.size(), 1u);
  ASSERT_EQ(sc.inputs.dampers.size(), 1u);
  const TorqueInput& u = sc.inputs.torques[0];
  const DamperInput& c = sc.inputs.dampers[0];
  auto power = [&](const Sample& k) {
    const double tau = u.constant + u.amplitude * std::sin(2 * std::numbers::pi * u.frequency * k.t + u.phase);
    return std::pair{tau * k.qd(u.dof) - c.damping * k.qd(c.dof) * k.qd(c.dof), c.damping * k.qd(c.dof) * k.qd(c.dof)};
  };
  double W = 0, D = 0, worst = 0;
  for (size_t k = 1; k < x.size(); ++k) {
    const auto [p0, d0] = power(x[k - 1]);
    const auto [p1, d1] = power(x[k]);
    W += 0.5 * (x[k].t - x[k - 1].t) * (p0 + p1);
    D += 0.5 * (x[k].t - x[k - 1].t) * (d0 + d1);
    worst = std::max({worst, std::abs(W - x[k].work_inputs), std::abs(D - x[k].dissipated)});
  }
  EXPECT_GT(D, 0.1);
  EXPECT_LE(worst, 1e-5) << "trapezoid error with h = 1e-3";
}

// without torques and dampers W ≡ 0: the balance error is the energy error as before
TEST(EnergyBalance, IsTheEnergyErrorOnAConservativeScene) {
  const Balance b = run("satellite_two_arrays", "rk4", 1e-2, 2.0);
  double worst = 0, peak = 0;
  const double E0 = b.x.front().total;
  for (const Sample& k : b.x) {
    EXPECT_EQ(k.work_inputs, 0.0);
    peak = std::max(peak, k.kinetic);
    worst = std::max(worst, std::abs(k.total - E0) / std::max(std::abs(E0), peak));
  }
  EXPECT_GT(worst, 0.0);
  EXPECT_DOUBLE_EQ(b.r.max_energy_balance_error, worst);
}

}  // namespace
