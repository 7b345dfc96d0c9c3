#include "soadyn/sim/simulate.hpp"

#include "stiffness.hpp"

#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/sim/sensitivity.hpp"
#include "soadyn/multibody/text.hpp"

#include <csignal>
#include <cmath>
#include <ctime>
#include <cstdio>
#include <limits>
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
  s.q = y.head(m.nq);
  s.qd = y.segment(m.nq, m.nv);
  const VecX& q = s.q;
  if (sys.nquad > 0) {
    s.work_inputs = y(m.nq + m.nv);
    s.dissipated = y(m.nq + m.nv + 1);
  }
  // q̈ as the integrator sees it: inputs, controllers, joints held at a limit (rhs does the
  // kinematics and velocities; not counted as the integrator's work)
  sys.rhs(t, y.data(), sys.f0.data());
  --sys.rhs_evals;
  s.qdd = d.qdd;
  s.control = sys.feedback_tau;
  if (sys.controlled) s.control += sys.control;
  if (sys.limits) s.impact_loss = sys.limits->energy_lost();
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

namespace {
std::string at_time(double t) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", t);
  return buf;
}
}  // namespace

std::vector<std::string> check_run(const Scenario& sc, const SimulationSettings& s) {
  // each setting: positive and finite, said with its value
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
  // joint limits: root finding (CVODE), e in [0, 1], a start inside the limits
  if (!(s.restitution >= 0 && s.restitution <= 1))
    throw Error("simulation settings: restitution must lie in [0, 1], got " + short_number(s.restitution));
  // named at the file's line where the scenario file gives the field (Scenario::locations), else
  // with the scenario
  const std::string scene = sc.path.empty() ? "" : sc.path + ": ";
  auto at = [&](const std::string& field) {
    const auto it = sc.locations.find(field);
    return it == sc.locations.end() ? std::string() : it->second + ": " + field + ": ";
  };
  if (s.limits && sc.model.has_limits()) {
    if (is_fixed_step(s.method)) {
      const std::string where = at("simulation.limits");
      throw Error((where.empty() ? scene + "simulation settings: limits: " : where) +
                  "true needs an integrator that locates events (cvode-adams or cvode-bdf); " +
                  std::string(to_string(s.method)) + " takes fixed steps");
    }
    try {
      JointLimits(sc.model, s.restitution).check_inside(sc.q0);
    } catch (const Error& e) {
      // the first 1-DOF joint outside its range (the one check_inside names), where the file
      // gives its start, else its range, else limits: true
      std::string where;
      for (int i = 0; i < sc.model.nbodies && where.empty(); ++i) {
        if (sc.model.nv_i[size_t(i)] != 1 || sc.model.nq_i[size_t(i)] != 1) continue;
        const double q = sc.q0(sc.model.idx_q[size_t(i)]);
        const int k = sc.model.idx_v[size_t(i)];
        if (q >= sc.model.lower[size_t(k)] && q <= sc.model.upper[size_t(k)]) continue;
        const std::string& joint = sc.model.joint_names[size_t(i)];
        where = at("initial.q." + joint);
        if (where.empty()) where = at("limits." + joint);
      }
      if (where.empty()) where = at("simulation.limits");
      throw Error((where.empty() ? scene : where) + e.what());
    }
  }
  if (!(s.control_dt >= 0) || !std::isfinite(s.control_dt))
    throw Error("simulation settings: control_dt must be 0 (continuous) or a positive finite number, got " + short_number(s.control_dt));
  if (const std::string p = control_ticks_problem(s.t_end, s.control_dt); !p.empty()) throw Error("simulation settings: " + p);
  check_sensitivities(sc, s, false);
  std::vector<std::string> warnings;
  if (s.control_dt > 0 && is_fixed_step(s.method) &&
      std::abs(s.control_dt / s.dt - std::round(s.control_dt / s.dt)) > 1e-9 * std::max(1.0, s.control_dt / s.dt))
    warnings.push_back("control_dt " + short_number(s.control_dt) + " is not a whole number of steps dt " + short_number(s.dt) +
                       ": each tick ends a shorter step and the steps restart there");
  // a fixed step longer than the run or than the output interval: the run is then not what was written
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

// A cvode-adams run of many steps whose mean step h̄ sat at the edge of stability, h̄ ρ(∂f/∂y) ≥
// kStiffIndex (stiffness.hpp): the summary says so once and names cvode-bdf.
void assess_stiffness(System& sys, const SimulationSettings& settings, const VecX& y0, double t, const VecX& y,
                      RunSummary& summary) {
  if (settings.method != Method::CvodeAdams || summary.stats.steps < detail::kStiffSteps || !(summary.t_reached > 0)) return;
  const double h = summary.t_reached / double(summary.stats.steps);
  const double rho = std::fmax(detail::spectral_radius(sys, 0.0, y0), detail::spectral_radius(sys, t, y));
  if (!std::isfinite(rho)) return;  // neither state gave an estimate
  summary.stiffness_index = h * rho;
  if (summary.stiffness_index < detail::kStiffIndex) return;
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "the run looks stiff: %ld cvode-adams steps of %.3g s on average, held by stability (mean step x the "
                "largest |eigenvalue| of df/dy, %.3g, is %.2g), not by accuracy; cvode-bdf (method: cvode-bdf, or "
                "--method cvode-bdf) takes its steps from the accuracy alone",
                summary.stats.steps, h, rho, summary.stiffness_index);
  summary.stiffness_hint = buf;
}

}  // namespace

RunSummary simulate(const Scenario& sc, const SimulationSettings& settings, RunObserver* observer,
                    std::vector<Sample>* samples, const std::atomic<int>* stop, std::function<void()> poll,
                    ControlFunction controller) {
  const Model& m = sc.model;
  check_run(sc, settings);
  check_sensitivities(sc, settings, bool(controller));
  // the control law: the scenario's built-in controllers and the caller's, summed
  std::optional<BuiltinControllers> builtin;
  if (!sc.inputs.controllers.empty()) builtin.emplace(m, sc.inputs.controllers);
  const ControlFunction law =
      sum_controllers({builtin ? ControlFunction(std::ref(*builtin)) : ControlFunction{}, std::move(controller)}, m.nv);
  System sys(m, sc.inputs, settings.dynamics, bool(law));
  // a controller that throws or returns a non-finite τ ends the run, said with the time
  ControlFunction checked;
  if (law)
    checked = [&](double t, const VecX& q, const VecX& v, Eigen::Ref<VecX> tau) {
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
  const bool sampled = law && settings.control_dt > 0;
  if (law && !sampled) sys.feedback = checked;
  sys.controlled = sampled;
  std::optional<JointLimits> limits;
  if (settings.limits && m.has_limits()) {
    limits.emplace(m, settings.restitution);
    sys.limits = &*limits;
  }
  VecX y = sys.state(sc.q0, sc.v0);
  const VecX y0 = y;
  m.normalize(y.head(m.nq));
  double t = 0.0;
  // with sensitivities: CVODES carries ∂y/∂x₀ and ∂y/∂π along (sensitivity.hpp)
  std::unique_ptr<Integrator> integrator;
  SensitivitySource* sensitivities = nullptr;
  if (settings.sensitivities.any()) {
    SensitivityIntegrator si = make_sensitivity_integrator(sys, settings, plan_sensitivities(m, settings.sensitivities), t, y);
    integrator = std::move(si.integrator);
    sensitivities = si.source;
  } else {
    integrator = make_integrator(settings.method, sys, settings, t, y);
  }
  auto observed = [&] {
    Sample s = observe(sys, t, y);
    if (sensitivities) sensitivities->sensitivities(t, s.sensitivity_initial_state, s.sensitivity_parameters);
    return s;
  };
  if (limits) integrator->set_roots(limits->count(), [&](double tr, const double* yr, double* gr) { limits->roots(sys, tr, yr, gr); });
  if (sampled) integrator->set_exact_stops(true);

  RunSummary summary;
  summary.method = to_string(settings.method);
  summary.quaternion_handling = integrator->quaternion_handling();
  const double cpu0 = thread_cpu_seconds();
  // sampling: the balance error |E(t) − E(0) − W(t) + L(t)| / max(|E(0)|, peak T)
  double E0 = 0.0, peak_T = 0.0;
  // limits off on a model with limits: the first sample past each DOF's bound, for one warning
  std::vector<double> past_at(size_t(m.nv), -1.0), past_q(size_t(m.nv), 0.0);
  const bool watch_limits = !limits && m.has_limits();
  auto record = [&](const Sample& s) {
    if (watch_limits)
      for (int i = 0; i < m.nbodies; ++i) {
        if (m.nq_i[i] != 1 || m.nv_i[i] != 1) continue;
        const int k = m.idx_v[i];
        const double q = s.q(m.idx_q[i]), tol = 1e-9 * std::max(1.0, std::abs(q));
        if (past_at[size_t(k)] < 0 && (q < m.lower[size_t(k)] - tol || q > m.upper[size_t(k)] + tol))
          past_at[size_t(k)] = s.t, past_q[size_t(k)] = q;
      }
    if (samples) samples->push_back(s);
    if (observer) observer->on_sample(s);
    peak_T = std::max(peak_T, s.kinetic);
    const double scale = std::max({std::abs(E0), peak_T, 1e-300});
    summary.final_energy_balance_error = std::abs(s.total - E0 - s.work_inputs + s.impact_loss) / scale;
    summary.max_energy_balance_error = std::max(summary.max_energy_balance_error, summary.final_energy_balance_error);
  };
  auto update = [&] {
    summary.stats = integrator->stats();
    summary.cpu_seconds = thread_cpu_seconds() - cpu0;
    summary.t_reached = t;
  };
  auto emit = [&](const std::vector<LimitEvent>& events) {
    for (const LimitEvent& e : events) {
      summary.events.push_back(e);
      if (observer) observer->on_event(e);
    }
  };
  // sampled control: τ_c(t_k, q, v) held from tick k = t / control_dt on
  long tick = 0;
  auto sample_control = [&] {
    sys.control.setZero();
    checked(t, y.head(m.nq), y.segment(m.nq, m.nv), sys.control);
    ++summary.control_ticks;
    ++tick;
  };
  // from t to t_out through the control ticks and the limits' events; false when stopped before
  long events_here = 0;
  double t_events = -1.0;
  auto reach = [&](double t_out) {
    for (;;) {
      double target = t_out;
      bool at_tick = false;
      if (sampled) {
        const double next = double(tick) * settings.control_dt;
        if (std::abs(next - t_out) <= 1e-12 * std::max(1.0, t_out)) at_tick = true;
        else if (next < t_out) target = next, at_tick = true;
      }
      integrator->advance(target, t, y);
      if (!integrator->roots().empty()) {
        // events that do not let time advance (a joint pinned between pushes) would loop for ever
        events_here = t == t_events ? events_here + 1 : 0;
        t_events = t;
        if (events_here > 100)
          throw SimulationError("joint limits: more than 100 events at t = " + at_time(t) + " s without time advancing", t);
        emit(limits->on_roots(sys, t, y, integrator->roots()));
        integrator->restart(t, y);
        continue;
      }
      if (t < target) return false;
      if (at_tick) {
        sample_control();
        integrator->restart(t, y);
      }
      if (target == t_out) return true;
    }
  };

  // outputs: CVODE every output_dt; fixed-step methods (steps of exactly dt) every `stride` steps,
  // output_dt = stride·dt, never between two steps (the k-th output lands on step k·stride, whose
  // time it reports as k·output_dt, the time a CVODE run at that output_dt reports); both at t_end last
  const double output_dt = output_interval(settings);
  summary.output_dt = output_dt;
  const long outputs = long(output_count(settings));
  try {
    // t = 0: the first control sample, the limits already reached, then the first row (E(0)
    // before any impact there: the energy it took is in L)
    if (sampled) sample_control();
    if (limits) emit(limits->start(sys, t, y));
    if (sampled || limits) integrator->restart(t, y);
    const Sample first = observed();
    E0 = first.total + first.impact_loss;
    record(first);
    bool interrupted = false;
    integrator->set_stop(stop, std::move(poll));
    for (long k = 1; k <= outputs; ++k) {
      if (stop && stop->load() != 0) {
        summary.status = interrupted_status(stop->load(), t);
        interrupted = true;
        break;
      }
      const double t_out = k == outputs ? settings.t_end : double(k) * output_dt;
      const double t_before = t;
      // a stop between steps: the last row is the state where the run ended, off the output grid
      const bool stopped = !reach(t_out) && stop;
      if (stopped) {
        summary.status = interrupted_status(stop->load(), t);
        interrupted = true;
        if (t == t_before) break;  // no step since the last row
      }
      record(observed());  // not counted as the integrator's work
      update();
      if (observer) observer->on_progress(summary);
      if (stopped) break;
    }
    if (!interrupted) {
      summary.status = "completed";
      summary.completed = true;
    }
  } catch (const SimulationError& e) {
    summary.status = e.what();
  }
  update();
  assess_stiffness(sys, settings, y0, t, y, summary);
  if (watch_limits) {
    std::string past;
    for (int k = 0; k < m.nv; ++k)
      if (past_at[size_t(k)] >= 0)
        past += (past.empty() ? "" : ", ") + m.v_names()[size_t(k)] + " (to " + short_number(past_q[size_t(k)]) + " at t = " +
                short_number(past_at[size_t(k)]) + " s; limits " + short_number(m.lower[size_t(k)]) + ", " + short_number(m.upper[size_t(k)]) + ")";
    if (!past.empty())
      summary.warnings.push_back("joints past their limits, which this run does not enforce (simulation: limits: true "
                                 "does): " + past);
  }
  if (observer) observer->on_finish(summary);
  return summary;
}

}  // namespace soadyn
