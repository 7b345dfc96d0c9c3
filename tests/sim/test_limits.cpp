// Joint limits as events (limits.hpp): the event times and rebounds of a pendulum released onto a
// limit against the closed forms of the pendulum (elliptic integrals), holds and releases, energy
// balance across impacts, impulses through 𝓜, URDF limits, refusals.
#include "soadyn/io/h5log.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/sim/simulate.hpp"

#include "test_util.hpp"

#include <cmath>
#include <numbers>

using namespace soadyn;

namespace {

// a physical pendulum about x, θ = 0 hanging: I θ̈ = −m g l sin θ + τ, m = 1, l = 0.5, I_cm = 0.08
constexpr double kM = 1.0, kL = 0.5, kG = 9.81, kIp = 0.08 + kM * kL * kL;
const double kW0 = std::sqrt(kM * kG * kL / kIp);  // ω₀

std::string pendulum(const std::string& extra) {
  return std::string(R"(gravity: [0, 0, -9.81]
bodies:
  - name: arm
    joint: {type: revolute, axis: [1, 0, 0]}
    mass: 1.0
    com: [0, 0, -0.5]
    inertia: [0.08, 0.08, 0.01]
)") + extra;
}

// the time a pendulum released at rest from θ0 > 0 takes to fall to θ (0 ≤ θ < θ0):
// t = (K(k) − F(φ, k)) / ω₀, k = sin(θ0/2), sin φ = sin(θ/2) / k
double fall_time(double theta0, double theta) {
  const double k = std::sin(theta0 / 2);
  return (std::comp_ellint_1(k) - std::ellint_1(k, std::asin(std::sin(theta / 2) / k))) / kW0;
}

// released from θ0 = 1 rad onto a lower limit at 0: it arrives at the quarter period K(k)/ω₀ with
// v⁻ = −2 ω₀ sin(θ0/2), leaves with −e v⁻, and is back 2 K(e k)/ω₀ later (a swing of amplitude
// 2 asin(e k)); the rebound then loses ½(1 − e²) I v⁻², which the energy balance accounts for
TEST(Limits, RestitutionReboundAtClosedFormTimes) {
  for (const double e : {0.5, 0.8}) {
    const Scenario sc = parse_scenario(pendulum("initial: {q: {arm: 1.0}}\nlimits: {arm: [0.0, 3.0]}\n"
                                                "simulation: {t_end: 1.5, rtol: 1.0e-12, atol: 1.0e-14, limits: true, "
                                                "restitution: " + std::to_string(e) + "}\n"),
                                       "p.yaml");
    const RunSummary r = simulate(sc, sc.simulation);
    ASSERT_TRUE(r.completed) << r.status;
    ASSERT_GE(r.events.size(), 2u);
    const double k = std::sin(0.5), t1 = fall_time(1.0, 0.0), v1 = -2 * kW0 * k;
    const LimitEvent& a = r.events[0];
    EXPECT_EQ(a.kind, "impact");
    EXPECT_EQ(a.joint, "arm");
    EXPECT_EQ(a.side, -1);
    EXPECT_NEAR(a.t, t1, 1e-9);
    EXPECT_NEAR(a.v_before, v1, 1e-8);
    EXPECT_NEAR(a.v_after, -e * a.v_before, 1e-12);
    EXPECT_NEAR(a.energy_lost, 0.5 * (1 - e * e) * kIp * v1 * v1, 1e-8);
    const double t2 = t1 + 2 * std::comp_ellint_1(e * k) / kW0;
    EXPECT_NEAR(r.events[1].t, t2, 1e-9);
    EXPECT_NEAR(r.events[1].v_before, e * v1, 1e-8);
    EXPECT_LE(r.max_energy_balance_error, 1e-8) << "e = " << e;
  }
}

// the balance E(t) − E(0) = −L(t) sample by sample, L the impacts' losses, and without the loss
// it would be off by L: a test that fails if the loss is left out or miscounted
TEST(Limits, EnergyBalanceAcrossImpacts) {
  const Scenario sc = parse_scenario(pendulum("initial: {q: {arm: 1.0}}\nlimits: {arm: [0.0, 3.0]}\n"
                                              "simulation: {t_end: 3, rtol: 1.0e-11, atol: 1.0e-13, limits: true, "
                                              "restitution: 0.7}\n"),
                                     "p.yaml");
  std::vector<Sample> s;
  const RunSummary r = simulate(sc, sc.simulation, nullptr, &s);
  ASSERT_TRUE(r.completed) << r.status;
  double lost = 0;
  for (const LimitEvent& e : r.events) lost += e.energy_lost;
  EXPECT_GT(lost, 0.1 * s.front().total + 0.1);
  EXPECT_NEAR(s.back().impact_loss, lost, 1e-12);
  for (const Sample& x : s) EXPECT_NEAR(x.total - s.front().total, -x.impact_loss, 1e-8) << "t = " << x.t;
  EXPECT_LE(r.max_energy_balance_error, 1e-8);
}

// e = 0: the pendulum falls from 1 rad onto a lower limit at 0.5 and is held there, pushed into
// it by gravity (λ = m g l sin 0.5 − τ > 0), until a torque τ = A sin(2π f t) outgrows gravity's
// pull, at sin(2π f t_r) = m g l sin 0.5 / A: it leaves at rest and swings up
TEST(Limits, PlasticImpactHoldsUntilTheConstraintWouldPull) {
  const double A = 4.0, f = 0.25;
  const Scenario sc = parse_scenario(pendulum("initial: {q: {arm: 1.0}}\nlimits: {arm: [0.5, 3.0]}\n"
                                              "simulation: {t_end: 1.5, rtol: 1.0e-12, atol: 1.0e-14, limits: true, "
                                              "output_dt: 0.001}\n"
                                              "inputs:\n  torques:\n    - {joint: arm, amplitude: 4.0, frequency: 0.25}\n"),
                                     "p.yaml");
  std::vector<Sample> s;
  const RunSummary r = simulate(sc, sc.simulation, nullptr, &s);
  ASSERT_TRUE(r.completed) << r.status;
  ASSERT_EQ(r.events.size(), 2u);
  EXPECT_EQ(r.events[0].kind, "hold");
  EXPECT_NEAR(r.events[0].v_after, 0.0, 1e-15);
  EXPECT_EQ(r.events[1].kind, "release");
  const double tr = std::asin(kM * kG * kL * std::sin(0.5) / A) / (2 * std::numbers::pi * f);
  ASSERT_LT(r.events[0].t, tr);
  EXPECT_NEAR(r.events[1].t, tr, 1e-9);
  for (const Sample& x : s) {
    EXPECT_GE(x.q(0), 0.5 - 1e-12) << "t = " << x.t;
    if (x.t > r.events[0].t && x.t < tr) {
      EXPECT_NEAR(x.q(0), 0.5, 1e-12) << "t = " << x.t;
      EXPECT_NEAR(x.qd(0), 0.0, 1e-12);
      EXPECT_NEAR(x.qdd(0), 0.0, 1e-9);
    }
  }
  EXPECT_GT(s.back().q(0), 0.5 + 1e-3);  // it left
  EXPECT_LE(r.max_energy_balance_error, 1e-8);
}

// an elastic limit on the shoulder of a double pendulum: the impulse acts through 𝓜, so the elbow's
// speed jumps too, and with e = 1 no energy is lost
TEST(Limits, ImpulseThroughMassMatrixReachesTheOtherJoint) {
  const Scenario sc = parse_scenario(R"(gravity: [0, 0, -9.81]
bodies:
  - {name: upper, joint: {type: revolute, axis: [1, 0, 0]}, mass: 1.0, com: [0, 0, -0.5], inertia: [0.08, 0.08, 0.01]}
  - {name: lower, parent: upper, joint: {type: revolute, axis: [1, 0, 0]}, origin: {xyz: [0, 0, -1]}, mass: 1.0, com: [0, 0, -0.5], inertia: [0.08, 0.08, 0.01]}
initial: {q: {upper: 1.0, lower: 0.3}}
limits: {upper: [0.0, 3.0]}
simulation: {t_end: 1.0, rtol: 1.0e-12, atol: 1.0e-14, limits: true, restitution: 1.0, output_dt: 0.0005}
)",
                                     "d.yaml");
  std::vector<Sample> s;
  const RunSummary r = simulate(sc, sc.simulation, nullptr, &s);
  ASSERT_TRUE(r.completed) << r.status;
  ASSERT_FALSE(r.events.empty());
  const LimitEvent& e = r.events[0];
  EXPECT_NEAR(e.v_after, -e.v_before, 1e-12);
  EXPECT_NEAR(e.energy_lost, 0.0, 1e-10);
  EXPECT_LE(r.max_energy_balance_error, 1e-8);
  // the elbow's speed across the impact: a jump far beyond one output interval's change
  size_t k = 0;
  while (k + 1 < s.size() && s[k + 1].t < e.t) ++k;
  const double jump = std::abs(s[k + 1].qd(1) - s[k].qd(1));
  const double smooth = std::abs(s[k].qd(1) - s[k - 1].qd(1));
  EXPECT_GT(jump, 0.2);
  EXPECT_GT(jump, 20 * smooth);
}

// the URDF's <limit> reaches the model (revolute), continuous joints and absent bounds stay ±inf
TEST(Limits, UrdfLimitsOnTheModel) {
  const Model m = load_urdf(SOADYN_SOURCE_DIR "/tests/data/arm7.urdf", false, urdf_gravity());
  ASSERT_EQ(int(m.lower.size()), m.nv);
  EXPECT_NEAR(m.lower[0], -2.9, 1e-15);
  EXPECT_NEAR(m.upper[0], 2.9, 1e-15);
  EXPECT_TRUE(m.has_limits());
  const Model free = load_urdf(SOADYN_SOURCE_DIR "/tests/data/arm7.urdf", true, urdf_gravity());
  for (int k = 0; k < 6; ++k) EXPECT_TRUE(std::isinf(free.lower[size_t(k)]));
}

// limits off (the default): the pendulum swings through the limit as before; fixed-step methods
// and a start beyond a limit are refused when they are on
TEST(Limits, OffByDefaultAndRefusals) {
  const Scenario off = parse_scenario(pendulum("initial: {q: {arm: 1.0}}\nlimits: {arm: [0.0, 3.0]}\nsimulation: {t_end: 1.5}\n"), "p.yaml");
  std::vector<Sample> s;
  const RunSummary r = simulate(off, off.simulation, nullptr, &s);
  EXPECT_TRUE(r.events.empty());
  double lowest = 1;
  for (const Sample& x : s) lowest = std::min(lowest, x.q(0));
  EXPECT_LT(lowest, -0.9);
  // and the run says so, once, naming the joint, where it went and when it first did
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("joints past their limits, which this run does not enforce"), std::string::npos);
  EXPECT_NE(r.warnings[0].find("arm (to -"), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[0].find("limits 0, 3)"), std::string::npos) << r.warnings[0];
  SimulationSettings on = off.simulation;
  on.limits = true;
  EXPECT_TRUE(simulate(off, on).warnings.empty());
  SimulationSettings fixed = off.simulation;
  fixed.limits = true;
  fixed.method = Method::Rk4;
  EXPECT_THROW(check_run(off, fixed), Error);
  const Scenario beyond = parse_scenario(pendulum("initial: {q: {arm: -0.5}}\nlimits: {arm: [0.0, 3.0]}\nsimulation: {limits: true}\n"), "b.yaml");
  try {
    check_run(beyond, beyond.simulation);
    ADD_FAILURE() << "a start beyond the limit was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'arm' starts at -0.5, beyond its lower limit 0"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_scenario(pendulum("limits: {arm: [1.0, 0.0]}\n"), "x.yaml"), Error);
  EXPECT_THROW(parse_scenario(pendulum("simulation: {restitution: 1.5}\n"), "x.yaml"), Error);
}

}  // namespace
