// Many short simulations in one call: K rollouts from K initial states, each T steps of dt under
// its own control sequence (or a control callback), split across threads, as MuJoCo's rollout.
//
// Rollout k starts at t = 0 from y0_k = [q; v] (quaternions normalized) and records its state after
// every step, at t = (s + 1)·dt, s = 0 … T − 1.  Over step s the generalized force is the model's
// inputs (a scenario's torques, springs, dampers) plus the control u_{k,s}, held constant.  The
// integrator is any of integrators(): a fixed-step method steps by dt exactly, on the grid
// simulate() uses (the same states as a simulate() run with output_dt = dt); CVODE advances to each
// (s + 1)·dt under rtol/atol and, when the control changes there, restarts from that state (its
// history would otherwise straddle the jump).
//
// Layout (batch.hpp's: column-major, the memory of row-major numpy arrays):
//   Y0        ny×K,          ny = nq + nv                       numpy (K, ny)
//   controls  nv×(T·K),      column k·T + s = u_{k,s}           numpy (K, T, nv)
//   states    ny×(T·K),      column k·T + s = y_k((s + 1)·dt)   numpy (K, T, ny)
//   energies  T×K,           E = T + V (+ springs) at those states numpy (K, T)
// Each rollout runs on one thread with that thread's System, so its states are the same, to the
// last bit, whatever the thread count.
#pragma once

#include "soadyn/algorithm/batch.hpp"
#include "soadyn/algorithm/inputs.hpp"
#include "soadyn/sim/integrators.hpp"
#include "soadyn/sim/settings.hpp"
#include "soadyn/sim/simulate.hpp"

#include <atomic>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace soadyn {

// The integration settings (settings.hpp: method, rtol, atol, dt, max_step, max_steps, dynamics,
// jacobian, newton) with rk4 as the method, and what a batch adds.  dt is also the control and
// output interval; max_steps counts each rollout's steps.
struct RolloutSettings : IntegrationSettings {
  RolloutSettings() { method = Method::Rk4; }
  long steps = 0;                     // T (with a control matrix: its T)
  int threads = 1;                    // ≤ 0: one per hardware thread
  bool energies = true;               // fill `energies` (an extra kinematics pass per state)
};

// u_{k,s} for rollout k before step s, at time t, from its state y (ny numbers): writes nv numbers
// into tau.  Called on the rollout's thread; with threads > 1, from several threads at once.
using ControlFn = std::function<void(long k, long s, double t, const double* y, double* tau)>;

struct RolloutReport {
  long completed = 0;                // rollouts that ran all T steps
  bool interrupted = false;          // a stop request ended the call (unfinished rollouts: NaN)
  int stop = 0;                      // the stop value that ended it
  std::vector<std::string> status;   // per rollout: "completed", the integrator's error (the states
                                     //   from there on NaN), or "not run" after a stop
};

// Throws soadyn::Error (naming the argument, what was expected and what was got) for a wrong shape,
// a non-finite initial state or control, a free or ball joint's quaternion not of unit norm
// (Model::check_unit_quaternions), inputs with built-in controllers (check_rollout_scene), dt not positive and finite, a negative T, a model without
// degrees of freedom or a method that refuses the model, before any rollout starts.  A rollout that
// fails midway does not throw: its status says why.  `controls` may be null (no control) and so may
// `control` (no callback); not both given.  `stop` and `poll` as in simulate(): `stop` is read
// before every step; `poll` runs on the calling thread (with threads = 1 before every step; with
// more, every 10 ms while the threads work) and may set it.
RolloutReport rollout(const Model& model, const Inputs& inputs, batch::In Y0, const batch::In* controls,
                      const ControlFn* control, const RolloutSettings& settings, batch::Out states,
                      batch::Out energies, const std::atomic<int>* stop = nullptr, std::function<void()> poll = {});

// A scenario's integration settings (IntegrationSettings: method, dt, rtol, atol, dynamics, …)
RolloutSettings rollout_settings(const SimulationSettings& s);

// rollout() applies a scene's torques, springs and dampers and the caller's controls, not its
// built-in controllers (their sampling at control_dt) nor its joint limits (events with impacts):
// a scene that asks for either is refused (soadyn::Error naming the file and what rollout does not
// apply) rather than run without them.  rollout() itself refuses inputs with controllers.
void check_rollout_scene(const Scenario& sc);

// One run of simulate_states: what simulate() gave from that initial state.
struct StateRun {
  bool ran = false;                   // false: refused (simulate threw soadyn::Error before its first
                                      //   step, `refused` says why) or not run (a stop came first)
  std::string refused;
  RunSummary summary;
  std::vector<std::string> warnings;  // check_run's about the settings, then the run's own
  double initial_energy = std::numeric_limits<double>::quiet_NaN();  // E at the first sample (t = 0; NaN: none)
  std::vector<double> t;              // with record_states: each sample's time
  std::vector<double> y;              //   and [q; v] (nq + nv numbers per sample, in sample order)
};

// K runs of one scenario from K initial states (Q0 nq×K, V0 nv×K: column k = q₀, v₀ of run k),
// each simulate(sc with that q₀ and v₀, settings): the same function as one run, so the same
// samples and summary to the last bit (the CPU time aside), whatever the thread count; every
// method, the scenario's controllers and limits included.  What a batch of scenarios that differ
// only in their initial state saves over one simulate() each: parsing the scenarios and handing
// each run's samples one by one to the caller (soadyn sweep, per Dask task).  The runs go to
// `threads` threads (≤ 0: one per hardware thread), each with its own copy of the scenario;
// `stop` is read before every step of every run and `poll` runs on the calling thread (before
// every step of the runs it takes), as in simulate(); the runs a stop leaves unstarted have
// ran = false and an empty `refused`.  Throws soadyn::Error for Q0 or V0 of the wrong shape.
std::vector<StateRun> simulate_states(const Scenario& sc, const SimulationSettings& settings, batch::In Q0, batch::In V0,
                                      int threads, bool record_states, const std::atomic<int>* stop = nullptr,
                                      std::function<void()> poll = {});

}  // namespace soadyn
