// Time integration of 𝓜(q) q̈ = τ(t, q, q̇) − bias(q, q̇) with state y = [q; v].
//
// One interface, several methods:
//   cvode-adams          SUNDIALS CVODE, Adams–Moulton, fixed-point iteration (non-stiff)
//   cvode-bdf            SUNDIALS CVODE, BDF, Newton with a direct solver (stiff): the Jacobian of f
//                        analytic (System::jacobian) with I − γJ solved by its structure through an
//                        nv×nv Schur complement (NewtonSolver), or CVODE's difference quotients and
//                        its dense LU
//   euler                explicit Euler, q ← q ⊕ h v, v ← v + h q̈(q, v) (order 1)
//   semi-implicit-euler  v ← v + h q̈(q, v), then q ← q ⊕ h v (order 1).  Symplectic only where 𝓜 is
//                        constant: with 𝓜(q) the update in velocities is not a symplectic map
//   symplectic-euler     symplectic Euler in the canonical momenta p = 𝓜(q) v (order 1, symplectic):
//                        p⁺ = p − h ∂H/∂q(q, p⁺) by Newton, then q⁺ = q + h 𝓜(q)⁻¹ p⁺.  Models
//                        without quaternions (revolute, prismatic, planar joints), where q̇ = v
//   rk4                  Runge–Kutta–Munthe-Kaas: classical RK4 on the increment z of q0 ⊕ z, whose
//                        rate is dexp⁻¹_z(v) (order 4; the classical method where no joint holds a
//                        quaternion)
//   implicit-midpoint    q ← q ⊕ h v_m, v ← v + h q̈(q ⊕ (h/2) v_m, v_m), v_m = (v + v⁺)/2, Newton
//                        iterations on the tangent (order 2, symmetric, A-stable; not symplectic where
//                        𝓜 depends on q): the one fixed-step baseline that stays stable on stiff
//                        scenes.  Full Newton (the Jacobian at every iterate, from y) or simplified
//                        (once per step, at the explicit-Euler predictor)
//   variational          the discrete Euler–Lagrange equations of the midpoint discrete Lagrangian
//                        L_d = h L(q_k ⊕ u/2, u/h), u = q_k+1 ⊖ q_k, in position–momentum form, on the
//                        group, forced by discrete Lagrange–d'Alembert (the forces at the midpoint),
//                        by Newton (order 2, symplectic, symmetric; conserves momentum where no
//                        force acts); reports v_k = 𝓜(q_k)⁻¹ p_k (variational.cpp).  Full Newton
//                        (analytic Jacobian, dense LU: O(nv³) per iteration) or simplified: chord
//                        iterations with 𝓜(q_m) by the articulated-body factor, O(N) each, Newton's
//                        where they contract by less than half (faster from about 16 DOFs on:
//                        chain/step_variational{,_simplified}).  With prescribed motion, the free
//                        rows of the DEL equations (the holding work from the impulses the
//                        prescribed rows miss).  Not with closed loops yet
// Free and ball joints keep a unit quaternion: CVODE projects it (CVodeSetProjFn); the fixed-step
// methods move it on the group, q ⊕ δ by the exponential map (configuration.hpp), so it is unit by
// construction and never renormalized after a step (fixed_step.hpp).
//
// Fixed steps.  Step k of a fixed-step method ends at t0 + k·dt, k an integer (times are never
// accumulated).  A span T is round(T/dt) steps when T/dt is that whole number to within rounding
// (kWholeSteps, relative); otherwise floor(T/dt) steps of dt and one last, shorter step ending at T.
#pragma once

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/sim/controller.hpp"
#include "soadyn/algorithm/derivatives.hpp"
#include "soadyn/algorithm/inputs.hpp"
#include "soadyn/sim/settings.hpp"
#include "soadyn/sim/system.hpp"

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace soadyn {

// A run that went unstable or that the integrator could not continue.
class SimulationError : public Error {
 public:
  SimulationError(const std::string& what, double t) : Error(what), t(t) {}
  double t;
};

struct IntegratorStats {
  long steps = 0;
  long rhs_evals = 0;
  long jac_evals = 0;
  long error_test_failures = 0;
  long nonlinear_iterations = 0;
};

// What an integrator asks of the run it steps (the run's scheduler, simulate.cpp): where its steps
// must end and what happens there (a control tick), and the events, as root functions of the state,
// and what happens at one (joint limits: an impact, a hold, a release).  Integrator::advance goes to
// t_out through them, restarting after each (the right-hand side or the state jumps there).
class Schedule {
 public:
  virtual ~Schedule() = default;
  struct Stop {
    double t;   // the next time the steps end at, ≤ t_out
    bool acts;  // at_stop acts there (a control tick), then the integrator restarts
  };
  virtual Stop next_stop(double t_out) = 0;
  virtual void at_stop(double t, VecX& y) = 0;
  // whether every advance must end its steps exactly at t_out (a restart may follow there), rather
  // than step past it and interpolate
  virtual bool exact_stops() const = 0;
  // n root functions g(t, y) → g[0 … n), each located where it crosses zero going down; at_roots
  // acts on those found at (t, y), y changed in place
  virtual int root_count() const = 0;
  virtual void roots(double t, const double* y, double* g) = 0;
  virtual void at_roots(double t, VecX& y, const std::vector<int>& which) = 0;
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  // advance (t, y) to t_out through the schedule's stops and events (set_schedule); throws
  // SimulationError when the run cannot continue.  Returns early, with t < t_out and y the state
  // at t, when a stop was requested (set_stop) before a step.
  void advance(double t_out, double& t, VecX& y);
  // the run's schedule (nullptr: none, steps straight to each t_out).  Throws soadyn::Error for a
  // schedule with events when the method cannot locate them (locates_events)
  void set_schedule(Schedule* schedule);
  // whether the method locates the roots of a schedule's events (CVODE's root finding)
  bool locates_events() const { return locates_events_; }
  // `stop` (nullptr: none) is read before every step; a non-zero value ends advance() there.  Only
  // read, so a signal handler may set it.  `poll` (empty: none) runs just before each read, for a
  // caller whose signal handlers do not run by themselves (Python's run only when asked) to ask.
  void set_stop(const std::atomic<int>* stop, std::function<void()> poll = {}) {
    stop_ = stop;
    poll_ = std::move(poll);
  }
  bool stop_requested() const {
    if (poll_) poll_();
    return stop_ && stop_->load(std::memory_order_relaxed) != 0;
  }
  virtual IntegratorStats stats() const = 0;
  // start afresh at (t, y), forgetting the history of earlier steps: after a jump in the
  // right-hand side (a new control) or the state (an impact), which a multistep method must not
  // step across.  Fixed-step methods keep no history between steps: nothing to do
  virtual void restart(double t, const VecX& y) {
    (void)t;
    (void)y;
  }
  // how the quaternion of a free root is kept unit ("none" without a free joint)
  virtual std::string quaternion_handling() const = 0;

 protected:
  // steps from (t, y) to t_stop (exactly there when schedule_->exact_stops()); returns early with
  // t < t_stop on a stop request, and true at the schedule's events after at_roots acted on them
  virtual bool step_to(double t_stop, double& t, VecX& y) = 0;
  Schedule* schedule_ = nullptr;
  bool locates_events_ = false;  // set by a method with root finding

 private:
  const std::atomic<int>* stop_ = nullptr;
  std::function<void()> poll_;
};

// The one registry of integration methods: the name users write, a line about it, whether it takes
// steps of exactly `dt` (else CVODE's adaptive steps under rtol/atol), the properties claimed for a
// fixed-step method (each one a test: test_integrators), the models it refuses, and how to make one.
struct IntegratorInfo {
  Method method;    // its enum (settings.hpp): SimulationSettings::method holds this, the name its word
  std::string_view name;
  std::string_view description;
  bool fixed_step;
  int order;        // fixed-step methods: the order of convergence (0: CVODE, adaptive)
  bool symplectic;  // a symplectic map on every model it takes: no secular energy drift
  // its workspace of nv×nv size beyond Data's, in nv² doubles (Newton's Jacobians and factors,
  // the derivatives' blocks; measured on a 2000-DOF chain): check_run's memory estimate
  int dense_workspace;
  // why the method cannot integrate `model` ("": it can); nullptr: every model
  std::string (*refuses)(const Model& model);
  std::unique_ptr<Integrator> (*make)(System& system, const SimulationSettings& settings, double t0,
                                      const VecX& y0);
};
const std::vector<IntegratorInfo>& integrators();
const IntegratorInfo* find_integrator(std::string_view name);  // nullptr for an unknown name
const IntegratorInfo& find_integrator(Method method);           // every Method has its row
std::vector<std::string> integrator_names();

// Makes the integrator; throws soadyn::Error for a model the method refuses (IntegratorInfo::refuses).
std::unique_ptr<Integrator> make_integrator(Method method, System& system, const SimulationSettings& settings,
                                            double t0, const VecX& y0);

// The CVODE integrators (cvode.cpp)
std::unique_ptr<Integrator> make_cvode(bool bdf, System& system, const SimulationSettings& settings, double t0,
                                       const VecX& y0);

// Fixed steps in a span T (see the header comment): `whole` steps of dt (an integer, held as a double
// so that spans beyond a long are still counted) and, when T/dt is not a whole number, one shorter
// step after them.
constexpr double kWholeSteps = 1e-12;
struct StepCount {
  double whole = 0;
  bool partial = false;
};
StepCount count_steps(double T, double dt);

// "where it failed": the first non-finite component, or -1
int first_non_finite(const VecX& y);

}  // namespace soadyn
