// Running a scenario: integrate, observe, log.
#pragma once

#include "soadyn/sim/integrators.hpp"
#include "soadyn/sim/limits.hpp"
#include "soadyn/sim/scenario.hpp"

#include <atomic>
#include <functional>
#include <string>
#include <vector>

namespace soadyn {

// What is logged at every output time.
struct Sample {
  double t = 0.0;
  VecX q, qd, qdd;
  double kinetic = 0.0, potential = 0.0, total = 0.0;  // potential includes joint springs
  // W(t): the work of the inputs (torques, dampers; springs are in the potential) since t = 0, and
  // D(t) ≥ 0 the dampers' share, dissipated; both integrated by the integrator (System), so
  // E(t) − E(0) = W(t) up to its error
  double work_inputs = 0.0, dissipated = 0.0;
  // prescribed motion (Inputs::prescribed): W_p(t), the work of the torques that hold the given
  // motion since t = 0 (so E(t) − E(0) = W(t) + W_p(t) − L(t)), and those torques at t, one per
  // prescribed joint in Inputs::prescribed's order (N·m or N; empty without prescribed motion)
  double work_prescribed = 0.0;
  VecX prescribed_torque;
  // closed loops (Inputs::loops): their multipliers λ at t, one per row (loop_row_names; N or N m),
  // the force each loop's frame B exerts on A along its rows' directions, and the largest closure
  // error |φ| (m or rad); empty and 0 without loops
  VecX loop_force;
  double loop_closure = 0.0;
  // L(t): the kinetic energy joint-limit impacts took since t = 0 (limits.hpp), so that
  // E(t) − E(0) = W(t) − L(t); and the controllers' τ_c at t (nv; zero without one)
  double impact_loss = 0.0;
  VecX control;
  Vec3 linear = Vec3::Zero(), angular = Vec3::Zero();
  // each body's frame origin η_i and centre of mass r_i (inertial, 3×N), and its attitude as a unit
  // quaternion [w x y z], body → inertial, with w ≥ 0 (4×N); N bodies after fixed joints are merged
  Mat3X body_position, body_com;
  Eigen::Matrix<double, 4, Eigen::Dynamic> body_orientation;
  // settings.sensitivities (sensitivity.hpp): ∂x(t)/∂x₀ (2nv × 2nv) and ∂x(t)/∂π (2nv × 10·bodies),
  // x = [q along the tangent; v]; empty when not asked for
  MatX sensitivity_initial_state, sensitivity_parameters;
};

struct RunSummary {
  std::string method;
  std::string quaternion_handling;
  double output_dt = 0.0;             // as used: a whole number of steps for fixed-step methods
  IntegratorStats stats;
  double cpu_seconds = 0.0;           // CPU time of the thread that ran it
  std::string status = "running";     // "completed", "interrupted by SIGINT at t = …", or the error
  double t_reached = 0.0;
  bool completed = false;
  // the energy-balance error |E(t) − E(0) − W(t) − W_p(t) + L(t)| / max(|E(0)|, peak T, peak |W|, peak |W_p|),
  // the run's energy scale: its maximum over the samples and its value at the last one (W ≡ 0
  // without torques or dampers: the energy error)
  double max_energy_balance_error = 0.0;
  double final_energy_balance_error = 0.0;
  std::vector<LimitEvent> events;     // joint-limit events, in time order (settings.limits)
  long control_ticks = 0;             // sampled control: the controller's evaluations
  // what the run did that its settings allowed but a user should hear (one line each): joints
  // that went past limits which were not enforced (limits off)
  std::vector<std::string> warnings;
  // a cvode-adams run of many steps (2000 or more): h̄ ρ, its mean step times the spectral radius of
  // ∂f/∂y (the larger at the start and the end; 0 when not estimated: other methods, fewer steps,
  // more than 400 state numbers); and, when h̄ ρ ≥ 0.2 (the steps were spent on stability, not accuracy), the one-line
  // hint that the run was stiff and cvode-bdf would take far fewer steps ("" otherwise)
  double stiffness_index = 0.0;
  std::string stiffness_hint;
};

// Receives samples and the run's state as it goes (the HDF5 log implements it): the loop's
// observers (run_loop.hpp: the energy books, the stiffness assessment, …) fill their part of the
// summary before it is passed on.
class RunObserver {
 public:
  virtual ~RunObserver() = default;
  virtual void on_sample(const Sample& s) = 0;
  virtual void on_progress(const RunSummary&) {}
  virtual void on_event(const LimitEvent&) {}  // a joint-limit event, before the next sample
  virtual void on_finish(const RunSummary& summary) = 0;
};

// Evaluates the logged quantities at (t, y), y the integrator's state [q; v; W; D] (System); the
// events' impact_loss L(t) and the sensitivities are the run's to add (simulate.cpp).
Sample observe(System& system, double t, const VecX& y);

// Throws soadyn::Error if sc cannot be run with settings: t_end, output_dt, dt or atol not positive
// and finite, rtol outside (0, 1), more steps or rows than 2^53 (time would no longer count
// exactly), a model without degrees of freedom (names are checked as UTF-8 by Model::build), or a
// model the method refuses (IntegratorInfo::refuses: symplectic-euler and quaternions).  Returns
// warnings (a tolerance below what double precision can deliver).  simulate() calls it; call it
// first to refuse before any output.
std::vector<std::string> check_run(const Scenario& sc, const SimulationSettings& settings);

// Fixed-step methods log every `output_stride` steps: output_dt / dt rounded to the nearest whole
// number, at least 1 (so an output_dt that is not a multiple of dt is taken as the nearest one),
// at the step times t0 + (k·stride)·dt, and at t_end (the end of the run's last step, shorter when
// t_end is not a whole number of steps: count_steps, integrators.hpp).
double output_stride(const SimulationSettings& settings);

// The time between logged samples as used: output_stride · dt for fixed-step methods, else output_dt.
double output_interval(const SimulationSettings& settings);

// Output times after the initial state (the last one at t_end), and the rows a run logs: the
// initial state and one per output time.
double output_count(const SimulationSettings& settings);
double output_rows(const SimulationSettings& settings);


// Fixed-step methods (rk4, euler, …) as opposed to CVODE's.
bool is_fixed_step(Method method);

// Simulates sc with settings (its own `simulation` section, possibly overridden).  Never throws
// for a run that fails midway: the summary says how it ended (completed = false) and the
// observer has everything logged up to then.  Throws soadyn::Error for bad settings.
// `stop` (nullptr: none) ends the run before the next integrator step once it holds a non-zero value
// (the last logged row is the state there, off the output grid): a
// signal number gives the status "interrupted by SIG<NAME> at t = <t>", −1 "interrupted at t = <t>".
// It is only read, so a signal handler may set it.  `poll` (empty: none) runs before every step and
// may set `stop` (Integrator::set_stop).
// `controller` (empty: none) adds its τ_c(t, q, v) to the inputs', with the scenario's built-in
// controllers (sc.inputs.controllers), continuous or sampled every settings.control_dt
// (controller.hpp).  One that throws, or returns a τ that is not finite, ends the run there: the
// status says so with the time, and the observer is finished as for any failed run.
// settings.limits: the model's joint limits as events (limits.hpp), in summary.events.
RunSummary simulate(const Scenario& sc, const SimulationSettings& settings, RunObserver* observer = nullptr,
                    std::vector<Sample>* samples = nullptr, const std::atomic<int>* stop = nullptr,
                    std::function<void()> poll = {}, ControlFunction controller = {});

// CPU time of the calling thread, s: a run's own, also when other runs share the process
double thread_cpu_seconds();

// "interrupted by SIGINT at t = 1.25" (stop > 0: a signal number), "interrupted at t = 1.25" (stop = −1)
std::string interrupted_status(int stop, double t);

}  // namespace soadyn
