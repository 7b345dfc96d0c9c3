// check_run (simulate.hpp): what a run refuses before any output, and what it warns of.
#include "soadyn/sim/simulate.hpp"

#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/algorithm/loops.hpp"
#include "soadyn/sim/sensitivity.hpp"
#include "soadyn/multibody/text.hpp"

#include <cmath>
#include <limits>

namespace soadyn {

namespace {

// each number positive and finite, the counts exactly representable, the method's matrices within
// memory and the model one it takes
void check_numbers(const Scenario& sc, const SimulationSettings& s) {
  const std::pair<const char*, double> positive[] = {
      {"t_end", s.t_end}, {"output_dt", s.output_dt}, {"dt", s.dt}, {"atol", s.atol}};
  for (const auto& [name, x] : positive)
    if (!(x > 0) || !std::isfinite(x))
      throw Error(std::string("simulation settings: ") + name + " must be a positive finite number, got " + short_number(x));
  if (!(s.rtol > 0 && s.rtol < 1)) throw Error("simulation settings: rtol must lie in (0, 1), got " + short_number(s.rtol));
  // counts: time advances by whole steps and rows, counted exactly only up to 2^53
  const double limit = 9007199254740992.0;
  const double rows = output_rows(s);
  if (!(rows <= limit))
    throw Error("simulation settings: t_end / output_dt = " + short_number(s.t_end) + " / " + short_number(s.output_dt) + " gives " + short_number(rows) +
                " rows, more than 2^53: raise output_dt or lower t_end");
  if (is_fixed_step(s.method) && !(s.t_end / s.dt <= limit))
    throw Error("simulation settings: t_end / dt = " + short_number(s.t_end) + " / " + short_number(s.dt) + " gives " + short_number(s.t_end / s.dt) +
                " steps, more than 2^53: raise dt or lower t_end");
  if (!is_fixed_step(s.method) && s.max_steps <= 0)
    throw Error("simulation settings: max_steps must be positive, got " + std::to_string(s.max_steps));
  if (sc.model.nv == 0)
    throw Error(sc.path + ": the model has no degrees of freedom (every joint is fixed): nothing to simulate");
  // q0 as a caller set it (a file's initial: q is checked where it is read)
  sc.model.check_unit_quaternions(sc.q0, sc.path + ": initial q");
  // the run's nv×nv matrices (Data's 3, the method's), before any is allocated
  const IntegratorInfo& info = find_integrator(s.method);
  try {
    const double nv = sc.model.nv;
    check_memory(8.0 * (3 + info.dense_workspace) * nv * nv, sc.model.nv,
                 "the nv×nv matrices of a " + std::string(info.name) + " run");
  } catch (const Error& e) {
    throw Error(sc.path + ": " + e.what());
  }
  if (info.refuses)
    if (const std::string why = info.refuses(sc.model); !why.empty()) throw Error(sc.path + ": " + why);
}

// joint limits: root finding (CVODE), e in [0, 1], a start inside the limits; named at the file's
// line where the scenario file gives the field (Scenario::locations), else with the scenario
void check_limits(const Scenario& sc, const SimulationSettings& s) {
  if (!(s.restitution >= 0 && s.restitution <= 1))
    throw Error("simulation settings: restitution must lie in [0, 1], got " + short_number(s.restitution));
  if (!s.limits || !sc.model.has_limits()) return;
  const std::string scene = sc.path.empty() ? "" : sc.path + ": ";
  auto at = [&](const std::string& field) {
    const auto it = sc.locations.find(field);
    return it == sc.locations.end() ? std::string() : it->second + ": " + field + ": ";
  };
  if (is_fixed_step(s.method)) {
    const std::string where = at("simulation.limits");
    throw Error((where.empty() ? scene + "simulation settings: limits: " : where) +
                "true needs an integrator that locates events (cvode-adams or cvode-bdf); " +
                std::string(to_string(s.method)) + " takes fixed steps");
  }
  const Model& m = sc.model;
  try {
    JointLimits(m, s.restitution, sc.inputs.prescribed).check_inside(sc.q0);
  } catch (const Error& e) {
    // the first 1-DOF joint outside its range (the one check_inside names), where the file gives
    // its start, else its range, else limits: true
    std::string where;
    for (int i = 0; i < m.nbodies && where.empty(); ++i) {
      if (m.nv_i[size_t(i)] != 1 || m.nq_i[size_t(i)] != 1) continue;
      const double q = sc.q0(m.idx_q[size_t(i)]);
      const int k = m.idx_v[size_t(i)];
      if (q >= m.lower[size_t(k)] && q <= m.upper[size_t(k)]) continue;
      const std::string& joint = m.joint_names[size_t(i)];
      where = at("initial.q." + joint);
      if (where.empty()) where = at("limits." + joint);
    }
    if (where.empty()) where = at("simulation.limits");
    throw Error((where.empty() ? scene : where) + e.what());
  }
}

// prescribed motion (Inputs::prescribed): the methods and features that take it, and no limit
// enforced on a joint whose motion is given
void check_prescribed(const Scenario& sc, const SimulationSettings& s) {
  const std::vector<PrescribedInput>& pres = sc.inputs.prescribed;
  if (pres.empty()) return;
  const std::string scene = sc.path.empty() ? "" : sc.path + ": ";
  const Model& m = sc.model;
  for (const PrescribedInput& p : pres)
    if (p.body < 0 || p.body >= m.nbodies || m.nv_i[p.body] != 1 || m.nq_i[p.body] != 1)
      throw Error(scene + "prescribed: joint '" + p.joint + "' is not a 1-DOF joint of the model");
  if (s.limits && m.has_limits()) {
    for (const PrescribedInput& p : pres) {
      const int k = p.dof;
      const auto it = sc.locations.find("prescribed." + p.joint);
      const std::string where = it == sc.locations.end() ? scene : it->second + ": ";
      if (std::isfinite(m.lower[size_t(k)]) || std::isfinite(m.upper[size_t(k)]))
        throw Error(where + "prescribed: joint '" + p.joint + "' has limits, and limits: true would enforce them on a "
                    "motion that is given; drop its limits or set limits: false");
    }
  }
}

// closed loops (Inputs::loops): their bodies, and the features that do not take them yet, each
// refused in one line at the scenario's loops: (or the setting's line); a start at a singular
// configuration refused, and rows that depend on the others said once
std::vector<std::string> check_loops(const Scenario& sc, const SimulationSettings& s) {
  const std::vector<LoopConstraint>& loops = sc.inputs.loops;
  if (loops.empty()) return {};
  const std::string scene = sc.path.empty() ? "" : sc.path + ": ";
  const auto it = sc.locations.find("loops");
  const std::string where = it == sc.locations.end() ? scene : it->second + ": ";
  const Model& m = sc.model;
  for (const LoopConstraint& c : loops) {
    if (c.body_a < -1 || c.body_a >= m.nbodies || c.body_b < -1 || c.body_b >= m.nbodies || c.body_a == c.body_b)
      throw Error(where + "loops: '" + c.name + "' must join two different bodies of the model (or one and the world)");
    if (c.type == LoopType::Distance && !(c.distance > 0))
      throw Error(where + "loops: '" + c.name + "': a distance loop needs a length > 0");
  }
  const auto refuse = [&](const std::string& what) {
    throw Error(where + "loops: " + what + " is not available with closed loops yet");
  };
  if (!sc.inputs.prescribed.empty()) refuse("prescribed motion");
  if (s.limits && m.has_limits()) refuse("limits: true");
  if (s.sensitivities.any()) refuse("simulation.sensitivities");
  if (s.method == Method::SymplecticEuler) refuse("symplectic-euler (use rk4, implicit-midpoint or a CVODE method)");
  if (s.method == Method::Variational) refuse("variational (use rk4, implicit-midpoint or a CVODE method)");
  // the rows at the initial state: A = K 𝓜⁻¹ Kᵀ's rank and margin (loops.hpp)
  if (sc.q0.size() != m.nq || sc.v0.size() != m.nv || !sc.q0.allFinite() || !sc.v0.allFinite()) return {};
  Data d(m);
  LoopData ld(m, loops);
  update_kinematics(m, d, sc.q0);
  update_velocities(m, d, sc.v0);
  loop_forward_dynamics(m, d, loops, sc.v0, VecX::Zero(m.nv), ld);
  if (ld.margin < kLoopSingular)
    throw Error(where + "loops: the initial state is at a singular configuration of the loops (a dead point: their rows' margin " +
                short_number(ld.margin) + "): start the mechanism off it");
  // computed torque actuates the joints its targets name: they must determine the rest
  for (size_t i = 0; i < sc.inputs.controllers.size(); ++i) {
    const ControllerInput& c = sc.inputs.controllers[i];
    if (c.kind != ControllerInput::Kind::ComputedTorque) continue;
    const std::string f = "inputs.controllers[" + std::to_string(i) + "]";
    if (c.actuated.empty())
      throw Error(where + f + ": with closed loops, computed_torque actuates the joints its targets name: name them");
    VecX qdd = VecX::Zero(m.nv);
    try {
      loop_inverse_dynamics(m, d, loops, c.actuated, qdd, ld);
    } catch (const Error& e) {
      throw Error(where + f + ": " + e.what());
    }
  }
  std::vector<std::string> notes = sc.notes;
  if (ld.rank == ld.m) return notes;
  notes.push_back("loops: " + std::to_string(ld.m) + " constraint rows of rank " + std::to_string(ld.rank) + ": " +
          std::to_string(ld.m - ld.rank) + " depend on the others (a planar mechanism's out-of-plane rows, say); " +
          "the loop forces are the ones of minimum norm");
  return notes;
}

// what the settings allow but make a run other than written: a tick off the steps, a step longer
// than the run or the output interval, one output interval, a tolerance below double precision
std::vector<std::string> run_warnings(const SimulationSettings& s) {
  std::vector<std::string> warnings;
  if (s.control_dt > 0 && is_fixed_step(s.method) &&
      std::abs(s.control_dt / s.dt - std::round(s.control_dt / s.dt)) > 1e-9 * std::max(1.0, s.control_dt / s.dt))
    warnings.push_back("control_dt " + short_number(s.control_dt) + " is not a whole number of steps dt " + short_number(s.dt) +
                       ": each tick ends a shorter step and the steps restart there");
  if (is_fixed_step(s.method) && s.dt > s.t_end)
    warnings.push_back("dt " + short_number(s.dt) + " is longer than t_end " + short_number(s.t_end) + ": the run is one step of " +
                       short_number(s.t_end));
  else if (is_fixed_step(s.method) && s.dt > s.output_dt)
    warnings.push_back("dt " + short_number(s.dt) + " is longer than output_dt " + short_number(s.output_dt) +
                       ": a sample after every step, every " + short_number(s.dt) + " s");
  if (s.output_dt > s.t_end)
    warnings.push_back("output_dt " + short_number(s.output_dt) + " is longer than t_end " + short_number(s.t_end) +
                       ": the run has only its first and last sample");
  // CVODE's local error test compares against rtol·|y|: below ~100 ε it asks for more digits than a double holds
  const double reach = 100 * std::numeric_limits<double>::epsilon();
  if (!is_fixed_step(s.method) && s.rtol < reach)
    warnings.push_back("rtol " + short_number(s.rtol) + " is below what double precision can deliver (about " + short_number(reach) +
                       "): CVODE will take tiny steps or fail");
  return warnings;
}

}  // namespace

std::vector<std::string> check_run(const Scenario& sc, const SimulationSettings& s) {
  check_numbers(sc, s);
  check_limits(sc, s);
  if (!(s.control_dt >= 0) || !std::isfinite(s.control_dt))
    throw Error("simulation settings: control_dt must be 0 (continuous) or a positive finite number, got " + short_number(s.control_dt));
  if (const std::string p = control_ticks_problem(s.t_end, s.control_dt); !p.empty()) throw Error("simulation settings: " + p);
  check_sensitivities(sc, s, false);
  check_prescribed(sc, s);
  std::vector<std::string> warnings = check_loops(sc, s);
  for (std::string& w : run_warnings(s)) warnings.push_back(std::move(w));
  return warnings;
}

}  // namespace soadyn
