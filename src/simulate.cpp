#include "soadyn/simulate.hpp"

#include "soadyn/kinematics.hpp"

#include <charconv>
#include <csignal>
#include <cmath>
#include <ctime>

namespace soadyn {

Sample observe(System& sys, double t, const VecX& q, const VecX& v) {
  const Model& m = sys.model;
  Data& d = sys.data;
  Sample s;
  s.t = t;
  s.q = q;
  s.qd = v;
  update_kinematics(m, d, q);
  update_velocities(m, d, v);
  sys.inputs.evaluate(t, q, v, sys.tau);
  forward_dynamics(m, d, sys.tau, sys.method);
  s.qdd = d.qdd;
  s.kinetic = kinetic_energy(m, d);
  s.potential = potential_energy(m, d) + sys.inputs.spring_energy(q);
  s.total = s.kinetic + s.potential;
  const Momentum h = momentum(m, d);
  s.linear = h.linear;
  s.angular = h.angular;
  return s;
}

bool is_fixed_step(const std::string& method) {
  const IntegratorInfo* info = find_integrator(method);
  return info && info->fixed_step;
}

void check_run(const Scenario& sc, const SimulationSettings& settings) {
  if (!(settings.t_end > 0) || !(settings.output_dt > 0) || !(settings.dt > 0) || !(settings.rtol > 0) ||
      !(settings.atol > 0))
    throw Error("simulation settings: t_end, output_dt, dt, rtol and atol must be positive");
  if (sc.model.nv == 0)
    throw Error(sc.path + ": the model has no degrees of freedom (every joint is fixed): nothing to simulate");
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
  char at[32];  // t in the shortest form that reads back exactly
  const auto end = std::to_chars(at, at + sizeof at, t).ptr;
  return "interrupted" + by + " at t = " + std::string(at, end);
}

RunSummary simulate(const Scenario& sc, const SimulationSettings& settings, RunObserver* observer,
                    std::vector<Sample>* samples, const std::atomic<int>* stop) {
  const Model& m = sc.model;
  check_run(sc, settings);
  System sys(m, sc.inputs, parse_fd_method(settings.dynamics));
  VecX y(sys.size());
  y << sc.q0, sc.v0;
  m.normalize(y.head(m.nq));
  double t = 0.0;
  auto integrator = make_integrator(settings.method, sys, settings, t, y);

  RunSummary summary;
  summary.method = settings.method;
  summary.quaternion_handling = integrator->quaternion_handling();
  const std::clock_t cpu0 = std::clock();
  // sampling: |E(t) − E(0)| / max(|E(0)|, peak T)
  double E0 = 0.0, peak_T = 0.0;
  auto record = [&](const Sample& s) {
    if (samples) samples->push_back(s);
    if (observer) observer->on_sample(s);
    peak_T = std::max(peak_T, s.kinetic);
    const double scale = std::max({std::abs(E0), peak_T, 1e-300});
    summary.final_relative_energy_error = std::abs(s.total - E0) / scale;
    summary.max_relative_energy_error = std::max(summary.max_relative_energy_error, summary.final_relative_energy_error);
  };
  auto update = [&] {
    summary.stats = integrator->stats();
    summary.cpu_seconds = double(std::clock() - cpu0) / CLOCKS_PER_SEC;
    summary.t_reached = t;
  };

  const Sample first = observe(sys, t, y.head(m.nq), y.tail(m.nv));
  E0 = first.total;
  record(first);
  // fixed-step methods take steps of exactly dt: outputs every whole number of steps
  const double output_dt =
      is_fixed_step(settings.method) ? settings.dt * std::max(1.0, std::round(settings.output_dt / settings.dt)) : settings.output_dt;
  summary.output_dt = output_dt;
  const long outputs = std::max<long>(1, std::lround(std::ceil(settings.t_end / output_dt * (1 - 1e-12))));
  try {
    bool interrupted = false;
    for (long k = 1; k <= outputs; ++k) {
      if (stop && stop->load() != 0) {
        summary.status = interrupted_status(stop->load(), t);
        interrupted = true;
        break;
      }
      const double t_out = k == outputs ? settings.t_end : double(k) * output_dt;
      integrator->advance(t_out, t, y);
      record(observe(sys, t, y.head(m.nq), y.tail(m.nv)));  // not counted as the integrator's work
      update();
      if (observer) observer->on_progress(summary);
    }
    if (!interrupted) {
      summary.status = "completed";
      summary.completed = true;
    }
  } catch (const SimulationError& e) {
    summary.status = e.what();
  }
  update();
  if (observer) observer->on_finish(summary);
  return summary;
}

}  // namespace soadyn
