// Running a scenario (simulate.hpp) in parts: the set-up (Run: the control law, the System, the
// joint limits, the integrator, the scheduler and the observers), then the loop over the output
// grid (run_outputs), whose scheduler and observers are in run_loop.hpp.  The integrator steps
// through the scheduler (Schedule, integrators.hpp); the loop reads no log or book itself.
#include "soadyn/sim/simulate.hpp"

#include "run_loop.hpp"

#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/sim/sensitivity.hpp"
#include "soadyn/multibody/text.hpp"

#include <csignal>
#include <cmath>
#include <ctime>
#include <cstdio>
#include <optional>
#include <time.h>

namespace soadyn {

double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

Sample observe(System& sys, double t, const VecX& y) {
  const Model& m = sys.model;
  Data& d = sys.data;
  Sample s;
  s.t = t;
  // q̈ as the integrator sees it: inputs, controllers, joints held at a limit, prescribed motion
  // (rhs does the kinematics and velocities; not counted as the integrator's work)
  VecX ydot(sys.size());
  sys.rhs(t, y.data(), ydot.data());
  --sys.rhs_evals;
  // the model's q and v: the state's, and the prescribed joints' from their motion at t
  s.q = sys.q;
  s.qd = sys.v;
  const VecX& q = s.q;
  const int w = sys.nq_state() + sys.nv_state();
  if (sys.nquad > 0) {
    s.work_inputs = y(w);
    s.dissipated = y(w + 1);
  }
  if (sys.nquad > 2) {
    s.work_prescribed = y(w + 2);
    s.prescribed_torque = sys.prescribed_tau;
  }
  if (sys.has_loops()) {
    s.loop_force = sys.loop_data().lambda;
    s.loop_closure = sys.loop_data().phi.cwiseAbs().maxCoeff();
  }
  s.qdd = d.qdd;
  s.control = sys.feedback_tau;
  if (sys.controlled) s.control += sys.control;
  // body poses: η_i, r_i, and C_i as a quaternion with w ≥ 0
  s.body_position = d.eta;
  s.body_com = d.r;
  s.body_orientation.resize(4, m.nbodies);
  for (int i = 0; i < m.nbodies; ++i) {
    s.body_orientation.col(i) = attitude_quaternion(d.R[i]);
  }
  s.kinetic = kinetic_energy(m, d);
  s.potential = potential_energy(m, d) + sys.inputs.spring_energy(q);
  s.total = s.kinetic + s.potential;
  const Momentum h = momentum(m, d);
  s.linear = h.linear;
  s.angular = h.angular;
  return s;
}

bool is_fixed_step(Method method) { return find_integrator(method).fixed_step; }

double output_stride(const SimulationSettings& s) { return std::max(1.0, std::round(s.output_dt / s.dt)); }

double output_interval(const SimulationSettings& s) {
  return is_fixed_step(s.method) ? s.dt * output_stride(s) : s.output_dt;
}

double output_count(const SimulationSettings& s) {
  if (!is_fixed_step(s.method)) return std::max(1.0, std::ceil(s.t_end / s.output_dt * (1 - 1e-12)));
  // every `stride` steps, and at t_end: ⌈steps / stride⌉ outputs
  const StepCount n = count_steps(s.t_end, s.dt);
  return std::max(1.0, std::ceil((n.whole + (n.partial ? 1.0 : 0.0)) / output_stride(s)));
}

double output_rows(const SimulationSettings& s) { return 1 + output_count(s); }

std::string interrupted_status(int stop, double t) {
  std::string by;
  switch (stop) {
    case -1: break;
    case SIGINT: by = " by SIGINT"; break;
    case SIGTERM: by = " by SIGTERM"; break;
    case SIGHUP: by = " by SIGHUP"; break;
    case SIGQUIT: by = " by SIGQUIT"; break;
    case SIGUSR1: by = " by SIGUSR1"; break;
    case SIGUSR2: by = " by SIGUSR2"; break;
    case SIGALRM: by = " by SIGALRM"; break;
    default: by = " by signal " + std::to_string(stop);
  }
  char at[32];
  std::snprintf(at, sizeof at, "%.9g", t);
  return "interrupted" + by + " at t = " + at;
}


namespace {

using namespace detail;

std::string at_time(double t) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", t);
  return buf;
}

// the control law: the scenario's built-in controllers and the caller's, summed
ControlFunction control_law(const Scenario& sc, std::optional<BuiltinControllers>& builtin, ControlFunction controller) {
  if (!sc.inputs.controllers.empty()) builtin.emplace(sc.model, sc.inputs.controllers, sc.inputs.loops);
  return sum_controllers({builtin ? ControlFunction(std::ref(*builtin)) : ControlFunction{}, std::move(controller)},
                         sc.model.nv);
}

// a controller that throws or returns a non-finite τ ends the run, said with the time
ControlFunction checked(const Model& m, ControlFunction law) {
  if (!law) return {};
  return [&m, law = std::move(law)](double t, const VecX& q, const VecX& v, Eigen::Ref<VecX> tau) {
    try {
      law(t, q, v, tau);
    } catch (const SimulationError&) {
      throw;
    } catch (const std::exception& e) {
      throw SimulationError("the controller failed at t = " + at_time(t) + " s: " + e.what(), t);
    }
    if (const int bad = first_non_finite(tau); bad >= 0)
      throw SimulationError("the controller returned a non-finite torque at t = " + at_time(t) + " s (" +
                                m.v_names()[size_t(bad)] + " = " + short_number(tau(bad)) + ")",
                            t);
  };
}

// A run's parts, set up from the scenario and the settings: the control law (continuous: in the
// System's feedback; sampled: the scheduler's ticks), the System, the joint limits, the state, the
// integrator (CVODES with the sensitivities when asked), the scheduler it steps through and the
// observers, attached in the order they fill the summary: the books before the caller's.
struct Run {
  Run(const Scenario& sc, const SimulationSettings& s, ControlFunction controller, RunObserver* observer,
      std::vector<Sample>* samples);
  Sample sample();  // the logged quantities at (t, y)

  const Model& m;
  std::optional<BuiltinControllers> builtin;
  ControlFunction law;
  System sys;
  bool sampled;
  std::optional<JointLimits> limits;
  std::optional<LimitEvents> limit_events;
  std::optional<LoopSingularity> loop_singularity;
  double t = 0.0;
  VecX y, y0;
  std::unique_ptr<Integrator> integrator;
  SensitivitySource* sensitivities = nullptr;
  RunSummary summary;
  Observers observers{summary};
  Scheduler scheduler;
  EnergyBooks books;
  std::optional<LimitWatch> watch;
  StiffnessCheck stiffness;
  CallerObservers caller;
};

Run::Run(const Scenario& sc, const SimulationSettings& s, ControlFunction controller, RunObserver* observer,
         std::vector<Sample>* samples)
    : m(sc.model),
      law(checked(m, control_law(sc, builtin, std::move(controller)))),
      sys(m, sc.inputs, s.dynamics, bool(law)),
      sampled(law && s.control_dt > 0),
      y(sys.state(sc.q0, sc.v0)),
      y0(y),
      scheduler(sys, s, sampled ? law : ControlFunction{}, observers),
      stiffness(sys, s.method, y0),
      caller(observer, samples) {
  if (law && !sampled) sys.feedback = law;
  sys.controlled = sampled;
  if (s.limits && m.has_limits()) {
    limits.emplace(m, s.restitution, sc.inputs.prescribed);
    sys.constraint = &*limits;
    limit_events.emplace(*limits, sys);
    scheduler.add(*limit_events);
  } else if (m.has_limits()) {
    watch.emplace(m);
  }
  if (sys.has_loops() && !is_fixed_step(s.method)) {  // dead points located as events by CVODE
    loop_singularity.emplace(sys);
    scheduler.add(*loop_singularity);
  }
  sys.normalize(y.head(sys.nq_state()));
  if (s.sensitivities.any()) {
    SensitivityIntegrator si = make_sensitivity_integrator(sys, s, plan_sensitivities(m, s.sensitivities, sc.inputs.prescribed), t, y);
    integrator = std::move(si.integrator);
    sensitivities = si.source;
  } else {
    integrator = make_integrator(s.method, sys, s, t, y);
  }
  integrator->set_schedule(&scheduler);
  observers.attach(books);
  if (watch) observers.attach(*watch);
  observers.attach(stiffness);
  observers.attach(caller);
  summary.method = to_string(s.method);
  summary.quaternion_handling = integrator->quaternion_handling();
  summary.output_dt = output_interval(s);
}

Sample Run::sample() {
  Sample s = observe(sys, t, y);  // not counted as the integrator's work
  s.impact_loss = scheduler.energy_lost();
  if (sensitivities) sensitivities->sensitivities(t, s.sensitivity_initial_state, s.sensitivity_parameters);
  return s;
}

// The run's counters as they stand: the integrator's, the CPU time since cpu0, the time reached.
void update(Run& run, double cpu0) {
  run.summary.stats = run.integrator->stats();
  run.summary.cpu_seconds = thread_cpu_seconds() - cpu0;
  run.summary.t_reached = run.t;
  run.summary.control_ticks = run.scheduler.control_ticks();
}

// The first sample at t = 0 (after the scheduler's start), then each output time in turn, reached
// through the schedule and sampled.  A stop request ends it: the last row is then the state where
// the run stopped, off the output grid (none when no step was taken since the last row).
void run_outputs(Run& run, const std::atomic<int>* stop, std::function<void()> poll, double cpu0) {
  RunSummary& summary = run.summary;
  run.scheduler.start(*run.integrator, run.t, run.y);
  run.observers.sample(run.sample());
  run.integrator->set_stop(stop, std::move(poll));
  const long outputs = run.scheduler.output_count();
  for (long k = 1; k <= outputs; ++k) {
    if (stop && stop->load() != 0) {
      summary.status = interrupted_status(stop->load(), run.t);
      return;
    }
    const double t_out = run.scheduler.output_time(k), t_before = run.t;
    run.integrator->advance(t_out, run.t, run.y);
    const bool stopped = run.t < t_out && stop;
    if (stopped) {
      summary.status = interrupted_status(stop->load(), run.t);
      if (run.t == t_before) return;
    }
    run.observers.sample(run.sample());
    update(run, cpu0);
    run.observers.progress();
    if (stopped) return;
  }
  summary.status = "completed";
  summary.completed = true;
}

}  // namespace

RunSummary simulate(const Scenario& sc, const SimulationSettings& settings, RunObserver* observer,
                    std::vector<Sample>* samples, const std::atomic<int>* stop, std::function<void()> poll,
                    ControlFunction controller) {
  check_run(sc, settings);
  check_sensitivities(sc, settings, bool(controller));
  Run run(sc, settings, std::move(controller), observer, samples);
  const double cpu0 = thread_cpu_seconds();
  try {
    run_outputs(run, stop, std::move(poll), cpu0);
  } catch (const SimulationError& e) {
    run.summary.status = e.what();
  }
  update(run, cpu0);
  run.observers.finish(run.t, run.y);
  return std::move(run.summary);
}

}  // namespace soadyn
