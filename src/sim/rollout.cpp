#include "soadyn/sim/rollout.hpp"

#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/sim/simulate.hpp"

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <exception>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

namespace soadyn {

RolloutSettings rollout_settings(const SimulationSettings& s) {
  RolloutSettings r;
  static_cast<IntegrationSettings&>(r) = s;
  return r;
}

namespace {

// "gravity_compensation, pd on elbow, …": what the scene's controllers are
std::string controller_list(const Model& m, const Inputs& inputs) {
  std::string out;
  for (const ControllerInput& c : inputs.controllers) {
    out += out.empty() ? "" : ", ";
    switch (c.kind) {
      case ControllerInput::Kind::Pd: out += "pd on " + m.v_names()[size_t(c.dofs.at(0))]; break;
      case ControllerInput::Kind::GravityCompensation: out += "gravity_compensation"; break;
      case ControllerInput::Kind::ComputedTorque: out += "computed_torque"; break;
    }
  }
  return out;
}

const char* const kRolloutInstead =
    "; use soadyn.simulate (one run per initial state; soadyn sweep for many), or a scene without them "
    "(the controls then carry the torques)";

}  // namespace

void check_rollout_scene(const Scenario& sc) {
  const bool controllers = !sc.inputs.controllers.empty(), limits = sc.simulation.limits && sc.model.has_limits();
  if (!controllers && !limits) return;
  std::string what;
  if (controllers) what = "built-in controllers (" + controller_list(sc.model, sc.inputs) + ")";
  if (limits) what += std::string(controllers ? " and its " : "") + "joint limits (simulation: limits: true)";
  throw Error("rollout: " + sc.path + ": rollout does not apply the scene's " + what + ", so its states would not be " +
              "the scene's" + kRolloutInstead);
}

namespace {

SimulationSettings simulation_settings(const RolloutSettings& r) {
  SimulationSettings s;
  static_cast<IntegrationSettings&>(s) = r;
  s.output_dt = r.dt;
  s.t_end = double(r.steps) * r.dt;
  return s;
}

std::string shape(Eigen::Index rows, Eigen::Index cols) { return std::to_string(rows) + "×" + std::to_string(cols); }

void check_shape(const char* what, Eigen::Index rows, Eigen::Index cols, Eigen::Index n, Eigen::Index m,
                 const char* layout) {
  if (rows == n && cols == m) return;
  throw Error(std::string("rollout: ") + what + ": expected " + shape(n, m) + " (" + layout + "), got " +
              shape(rows, cols));
}

// the first non-finite entry of an argument, named by column
void check_finite(const char* what, const batch::In& X, const char* column) {
  if (X.allFinite()) return;
  for (Eigen::Index c = 0; c < X.cols(); ++c)
    for (Eigen::Index r = 0; r < X.rows(); ++r)
      if (!std::isfinite(X(r, c))) {
        char value[32];
        std::snprintf(value, sizeof value, "%g", X(r, c));
        throw Error(std::string("rollout: ") + what + ": entry " + std::to_string(r) + " of " + column + " " +
                    std::to_string(c) + " is " + value + ": expected a finite number");
      }
}

// One thread's System and the rollouts it takes, one at a time, from a shared counter.
struct Runner {
  const Model& model;
  const RolloutSettings& rs;
  const SimulationSettings ss;
  const batch::In& Y0;
  const batch::In* controls;
  const ControlFn* control;
  batch::Out& states;
  batch::Out& energies;
  const std::atomic<int>* stop;
  RolloutReport& report;
  std::atomic<long>& next;
  std::atomic<long>& completed;

  bool stopped() const { return stop && stop->load(std::memory_order_relaxed) != 0; }

  void run(System& sys, const std::function<void()>& poll) {
    const long K = Y0.cols(), T = rs.steps;
    const int nq = model.nq, nv = model.nv, ny = nq + nv;
    VecX y(sys.size()), previous(nv), qe(nq), ve(nv);
    // the energies' own Data: the System's holds what rhs and linearize evaluated (System::holds_rhs_at)
    std::optional<Data> energy_data;
    if (energies.size() > 0) energy_data.emplace(model);
    sys.controlled = controls || control;
    for (;;) {
      const long k = next.fetch_add(1);
      if (k >= K) return;
      if (poll) poll();
      if (stopped()) return;
      // y0 = [q; v; W = 0; D = 0], quaternions unit
      y.setZero();
      y.head(ny) = Y0.col(k);
      model.normalize(y.head(nq));
      double t = 0.0;
      auto integrator = make_integrator(rs.method, sys, ss, t, y);
      integrator->set_stop(stop, poll);
      long s = 0;
      try {
        for (; s < T; ++s) {
          if (controls) sys.control = controls->col(k * T + s);
          if (control) (*control)(k, s, t, y.data(), sys.control.data());
          // a multistep method restarts where the control jumps
          if (sys.controlled && s > 0 && sys.control != previous) integrator->restart(t, y);
          previous = sys.control;
          const double t_out = double(s + 1) * rs.dt;
          integrator->advance(t_out, t, y);
          if (t < t_out) break;  // stopped before a step
          states.col(k * T + s) = y.head(ny);
          if (energy_data) {
            qe = y.head(nq);
            ve = y.segment(nq, nv);
            update_kinematics(model, *energy_data, qe);
            update_velocities(model, *energy_data, ve);
            energies(s, k) = kinetic_energy(model, *energy_data) + potential_energy(model, *energy_data) +
                             sys.inputs.spring_energy(qe);
          }
        }
        if (s == T) {
          report.status[size_t(k)] = "completed";
          completed.fetch_add(1);
        } else {
          report.status[size_t(k)] = interrupted_status(stop->load(), t);
        }
      } catch (const SimulationError& e) {
        report.status[size_t(k)] = e.what();
      }
      // the states the rollout did not reach: NaN
      const double nan = std::numeric_limits<double>::quiet_NaN();
      if (s < T) {
        states.middleCols(k * T + s, T - s).setConstant(nan);
        if (energies.size() > 0) energies.col(k).segment(s, T - s).setConstant(nan);
      }
    }
  }
};

// every argument of rollout checked before any rollout starts (the integrator's own refusals: rollout's probe)
void check_arguments(const Model& model, const Inputs& inputs, const batch::In& Y0, const batch::In* controls,
                     const ControlFn* control, const RolloutSettings& rs, const batch::Out& states,
                     const batch::Out& energies) {
  const int ny = model.nq + model.nv;
  const long K = Y0.cols(), T = rs.steps;
  if (!(rs.dt > 0) || !std::isfinite(rs.dt)) throw Error("rollout: dt: expected a positive finite number");
  if (T < 0) throw Error("rollout: steps: expected T ≥ 0, got " + std::to_string(T));
  if (model.nv == 0) throw Error("rollout: the model has no degrees of freedom (every joint is fixed)");
  if (controls && control) throw Error("rollout: controls: give a control matrix or a callback, not both");
  if (!inputs.controllers.empty())
    throw Error("rollout: the inputs have built-in controllers (" + controller_list(model, inputs) +
                "), which rollout does not apply" + kRolloutInstead);
  check_shape("initial_states", Y0.rows(), K, ny, K, "nq + nv rows, one column per rollout");
  check_finite("initial_states", Y0, "rollout");
  if (model.has_quaternions())
    for (long k = 0; k < K; ++k)
      model.check_unit_quaternions(Y0.col(k).head(model.nq), "rollout: initial_states[" + std::to_string(k) + "]");
  if (controls) {
    check_shape("controls", controls->rows(), controls->cols(), model.nv, T * K, "nv rows, column k·T + s");
    check_finite("controls", *controls, "column");
  }
  check_shape("states", states.rows(), states.cols(), ny, T * K, "nq + nv rows, column k·T + s");
  if (rs.energies) check_shape("energies", energies.rows(), energies.cols(), T, K, "T rows, one column per rollout");
}

// n threads, each with its own System, take the K rollouts; the calling thread polls while they work.
// The first exception a thread throws stops the others after their current rollout and is rethrown.
void run_threads(Runner& runner, const Model& model, const Inputs& inputs, FdMethod fd, int n, long K,
                 std::atomic<long>& next, const std::function<void()>& poll) {
  std::exception_ptr error;
  std::mutex mutex;
  std::condition_variable cv;
  int running = n;
  std::vector<std::thread> threads;
  threads.reserve(size_t(n));
  for (int w = 0; w < n; ++w)
    threads.emplace_back([&] {
      try {
        System sys(model, inputs, fd);
        runner.run(sys, {});
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!error) error = std::current_exception();
        next = K;  // the others stop after their current rollout
      }
      std::lock_guard<std::mutex> lock(mutex);
      --running;
      cv.notify_all();
    });
  {
    std::unique_lock<std::mutex> lock(mutex);
    while (running > 0) {
      cv.wait_for(lock, std::chrono::milliseconds(10));
      if (poll && running > 0) {
        lock.unlock();
        poll();
        lock.lock();
      }
    }
  }
  for (auto& t : threads) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace

RolloutReport rollout(const Model& model, const Inputs& inputs, batch::In Y0, const batch::In* controls,
                      const ControlFn* control, const RolloutSettings& rs, batch::Out states, batch::Out energies,
                      const std::atomic<int>* stop, std::function<void()> poll) {
  check_arguments(model, inputs, Y0, controls, control, rs, states, energies);
  const long K = Y0.cols();
  const SimulationSettings ss = simulation_settings(rs);
  const FdMethod fd = rs.dynamics;
  {
    System probe(model, inputs, fd);  // a method that refuses the model throws here
    make_integrator(rs.method, probe, ss, 0.0, probe.state(model.neutral_configuration(), VecX::Zero(model.nv)));
  }

  RolloutReport report;
  report.status.assign(size_t(K), "not run");
  std::atomic<long> next{0}, completed{0};
  batch::Out no_energies = energies.leftCols(0);
  Runner runner{model, rs, ss, Y0, controls, control, states, rs.energies ? energies : no_energies, stop, report, next,
                completed};
  const int n = int(std::min<long>(batch::resolve_threads(rs.threads), std::max(1L, K)));
  if (n == 1) {
    System sys(model, inputs, fd);
    runner.run(sys, poll);
  } else {
    run_threads(runner, model, inputs, fd, n, K, next, poll);
  }
  report.completed = completed.load();
  if (stop && stop->load() != 0) {
    report.interrupted = true;
    report.stop = stop->load();
  }
  return report;
}

namespace {

// What simulate_states keeps of each sample: the first one's energy, and with `states` t and [q; v].
class StateRecorder : public RunObserver {
 public:
  StateRecorder(StateRun& run, bool states) : run_(run), states_(states) {}
  void on_sample(const Sample& s) override {
    if (first_) run_.initial_energy = s.total, first_ = false;
    if (!states_) return;
    run_.t.push_back(s.t);
    run_.y.insert(run_.y.end(), s.q.data(), s.q.data() + s.q.size());
    run_.y.insert(run_.y.end(), s.qd.data(), s.qd.data() + s.qd.size());
  }
  void on_finish(const RunSummary&) override {}

 private:
  StateRun& run_;
  bool states_, first_ = true;
};

}  // namespace

std::vector<StateRun> simulate_states(const Scenario& sc, const SimulationSettings& settings, batch::In Q0, batch::In V0,
                                      int threads, bool record_states, const std::atomic<int>* stop,
                                      std::function<void()> poll) {
  const Model& m = sc.model;
  const long K = Q0.cols();
  check_shape("simulate_states: Q0", Q0.rows(), K, m.nq, K, "nq rows, one column per run");
  check_shape("simulate_states: V0", V0.rows(), V0.cols(), m.nv, K, "nv rows, one column per run");
  std::vector<StateRun> runs(static_cast<size_t>(K));
  std::atomic<long> next{0};
  // one thread's runs, taken one at a time from `next`, on its own copy of the scenario (simulate
  // reads q₀ and v₀ from it); each run is simulate() itself, so nothing depends on which thread
  // takes it
  auto work = [&](const std::function<void()>& thread_poll) {
    Scenario own = sc;
    for (;;) {
      const long k = next.fetch_add(1);
      if (k >= K) return;
      if (stop && stop->load(std::memory_order_relaxed) != 0) return;
      StateRun& run = runs[size_t(k)];
      own.q0 = Q0.col(k);
      own.v0 = V0.col(k);
      StateRecorder recorder(run, record_states);
      try {
        run.warnings = check_run(own, settings);  // what soadyn.simulate warns of, in its order
        run.summary = simulate(own, settings, &recorder, nullptr, stop, thread_poll);
      } catch (const Error& e) {
        run.refused = e.what();
        run.warnings.clear();
        continue;
      }
      run.ran = true;
      run.warnings.insert(run.warnings.end(), run.summary.warnings.begin(), run.summary.warnings.end());
    }
  };
  const int n = int(std::min<long>(batch::resolve_threads(threads), std::max(1L, K)));
  if (n == 1) {
    work(poll);
    return runs;
  }
  // the calling thread takes runs too, and is the one that polls
  std::exception_ptr error;
  std::mutex mutex;
  std::vector<std::thread> others;
  others.reserve(size_t(n - 1));
  auto guarded = [&](const std::function<void()>& thread_poll) {
    try {
      work(thread_poll);
    } catch (...) {  // not a refusal (those are kept per run): e.g. out of memory
      std::lock_guard<std::mutex> lock(mutex);
      if (!error) error = std::current_exception();
      next = K;
    }
  };
  for (int w = 1; w < n; ++w) others.emplace_back([&] { guarded({}); });
  guarded(poll);
  for (auto& t : others) t.join();
  if (error) std::rethrow_exception(error);
  return runs;
}

}  // namespace soadyn
