// Time integration of 𝓜(q) q̈ = τ(t, q, q̇) − bias(q, q̇) with state y = [q; v].
//
// One interface, several methods:
//   cvode-adams          SUNDIALS CVODE, Adams–Moulton, fixed-point iteration (non-stiff)
//   cvode-bdf            SUNDIALS CVODE, BDF, Newton with a direct solver (stiff): the Jacobian of f
//                        analytic (System::jacobian) with I − γJ solved by its structure through an
//                        nv×nv Schur complement (NewtonSolver), or CVODE's difference quotients and
//                        its dense LU
//   euler                explicit Euler (order 1)
//   semi-implicit-euler  v ← v + h q̈(q, v), then q ← q ⊕ h v (order 1).  Symplectic only where 𝓜 is
//                        constant: with 𝓜(q) the update in velocities is not a symplectic map
//   symplectic-euler     symplectic Euler in the canonical momenta p = 𝓜(q) v (order 1, symplectic):
//                        p⁺ = p − h ∂H/∂q(q, p⁺) by Newton, then q⁺ = q + h 𝓜(q)⁻¹ p⁺.  Models
//                        without quaternions (revolute, prismatic, planar joints), where q̇ = v
//   rk4                  classical Runge–Kutta (order 4)
//   implicit-midpoint    y ← y + h f((y + y⁺)/2), Newton iterations (order 2, symmetric, A-stable; in
//                        (q, v), so not symplectic where 𝓜 depends on q): the one fixed-step baseline
//                        that stays stable on stiff scenes.  Full Newton (the Jacobian at every
//                        iterate, from y) or simplified (once per step, at the explicit-Euler predictor)
// Free roots keep a unit quaternion: CVODE projects it (CVodeSetProjFn); fixed-step methods
// renormalize after each step.
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

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace soadyn {

class JointLimits;

// A run that went unstable or that the integrator could not continue.
class SimulationError : public Error {
 public:
  SimulationError(const std::string& what, double t) : Error(what), t(t) {}
  double t;
};

// ẏ = f(t, y) for the model with its inputs.  The state is y = [q; v], followed, when the inputs
// do work (torques or dampers), by two quadratures the integrator advances with the rest:
// W = ∫ P dt, the work of the inputs, and D = ∫ Σ c q̇² dt ≥ 0, the part the dampers dissipated
// (Inputs::power).  Nothing feeds back from them into q and v.
class System {
 public:
  // control_work: a controller acts (feedback or control), so W has the quadratures and counts it
  System(const Model& model, const Inputs& inputs, FdMethod method, bool control_work = false);
  int size() const { return model.nq + model.nv + nquad; }
  // [q; v; 0 …]: the state at the start of a run (the quadratures start at zero)
  VecX state(const VecX& q0, const VecX& v0) const;
  // ẏ = [q̇(q, v); q̈; P; D]; counts evaluations
  void rhs(double t, const double* y, double* ydot);
  // q, v and [kin], [vel] at y, and τ: the inputs', the held control's and the feedback controller's
  // (rhs, jacobian and jacobian_times begin with it)
  void at_state(double t, const double* y);
  // whether data holds rhs's evaluation at exactly (t, y), nothing evaluated since: [kin], [vel], τ,
  // q̈ and the factor of `method` (the forward sensitivities start from it at the state CVODES has
  // just converged, sensitivity.cpp)
  bool holds_rhs_at(double t, const double* y) const;
  // ∂f/∂y (size()×size()) by the analytic derivatives: ∂q̈/∂q along the tangent, chained to the
  // coordinates y holds (add_times_tangent, configuration.hpp), ∂q̈/∂v, and the Jacobian of q̇(q, v) (qdot_jacobian);
  // the inputs' springs and dampers included.  Counts evaluations.  The first call (or
  // prepare_jacobian) allocates the derivatives' workspace, 7 nv² doubles: a run that never asks for
  // ∂f/∂y (CVODE Adams, the explicit methods) keeps memory linear in nv beyond Data's 𝓜
  void jacobian(double t, const double* y, Eigen::Ref<MatX> J);
  // out = (∂f/∂y) S for the columns of S (size() rows) without forming ∂f/∂y: the q̇ rows joint by
  // joint, and q̈'s = 𝓜⁻¹ ((∂τ_in/∂q − ∂ID/∂q) T S_q + (∂τ_in/∂v − ∂ID/∂v) S_v) by the inverse-dynamics
  // derivatives' products (O(N) per column after O(N) sweeps, derivatives.hpp) and the articulated-body
  // factor (O(N) per column, articulated_solve); springs and dampers included (forward sensitivities,
  // sensitivity.hpp).  Allocates out and its scratch on the first call of a width.
  void jacobian_times(double t, const double* y, const MatX& S, MatX& out);
  // jacobian_times in two halves, for many products at one state (CVODES' BDF, with the staggered
  // corrector, iterates on the sensitivities at the state it has converged): linearize leaves data (q̈ and the
  // articulated-body factor; τ, A, F free for the caller) and the sweeps at (t, y), doing nothing when
  // they already hold for this very (t, y) (no evaluation since), and starting from rhs's evaluation
  // when it has just made one there; it returns the number of that linearization (a new number for
  // each one it makes, so that a caller keeping more at the state knows when to redo it).
  // linearized_times applies it to S; with `forces` (nv × m, m ≤ S's columns), the last m columns
  // also move along τ by them: their q̈ rows gain ∂q̈/∂τ F = 𝓜⁻¹ F (∂q̈/∂π = −𝓜⁻¹ Y, sensitivity.cpp).
  // The MatX form sizes out; the Ref form writes into out as it is (size() × S's columns), so
  // that CVODES' own vectors can be S and out without a copy
  long linearize(double t, const double* y);
  void linearized_times(const MatX& S, MatX& out, const MatX* forces = nullptr);
  void linearized_times(Eigen::Ref<const MatX> S, Eigen::Ref<MatX> out, const MatX* forces = nullptr);
  void prepare_jacobian();
  // ∂f/∂y by forward differences of rhs (size() extra evaluations, counted as RHS evaluations)
  void jacobian_dq(double t, const double* y, Eigen::Ref<MatX> J);
  // the name of component k of y ("theta2 (q)", "bus.wz (v)", "the inputs' work W")
  std::string component_name(int k) const;

  const Model& model;
  const Inputs& inputs;
  FdMethod method;
  int nquad;  // 2 (W, D) when the inputs do work, else 0
  Data data;
  std::optional<DerivativeData> derivatives;  // jacobian's workspace, made on first use
  VecX q, v, tau, qd;
  // an external generalized force added to the inputs' τ while `controlled` (rollout.hpp: a
  // control held over each step); it depends on neither q nor v, so ∂f/∂y is unchanged
  VecX control;
  bool controlled = false;
  // a feedback controller τ_c(t, q, v) added on every evaluation (controller.hpp; continuous
  // control: sampled control holds its τ in `control`), feedback_tau its last value.  With
  // control_work, W also counts (control + τ_c) · q̇.  ∂f/∂y leaves out ∂τ_c/∂y (Newton then
  // converges on an approximate Jacobian)
  ControlFunction feedback;
  VecX feedback_tau;
  bool control_work = false;
  // joint limits holding DOFs at a bound (limits.hpp): rhs applies their constraint forces
  JointLimits* limits = nullptr;
  VecX y_work, f0, f1;             // jacobian_dq's scratch
  MatX delta, W;                   // jacobian_times: S's q rows on the tangent; the forces
  MatX solve_work;                 // articulated_solve's (prepare_jacobian)
  VecX dP, dD;                     // ∂Ẇ/∂v, ∂Ḋ/∂v (the quadratures' rows)
  long rhs_evals = 0;
  long jac_evals = 0;

 private:
  // linearized_times' q̇ rows and δ = T(q) S_q when a joint holds a quaternion
  void linearized_tangent_rows(const Eigen::Ref<const MatX>& S, Eigen::Ref<MatX>& out);
  bool evaluated_ = false;         // rhs's state (eval_t_, eval_y_) is still data's
  double eval_t_ = 0.0;
  VecX eval_y_;
  bool linearized_ = false;        // linearize's state (lin_t_, lin_y_) is still data's
  long linearizations_ = 0;        // how many linearize has made: the current one's number
  double lin_t_ = 0.0;
  VecX lin_y_;
};

struct IntegratorStats {
  long steps = 0;
  long rhs_evals = 0;
  long jac_evals = 0;
  long error_test_failures = 0;
  long nonlinear_iterations = 0;
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  // advance (t, y) to t_out; throws SimulationError when the run cannot continue.  Returns early,
  // with t < t_out and y the state at t, when a stop was requested (set_stop) before a step.
  virtual void advance(double t_out, double& t, VecX& y) = 0;
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
  // right-hand side (a new control), which a multistep method must not step across.  Fixed-step
  // methods keep no history between steps: nothing to do
  virtual void restart(double t, const VecX& y) {
    (void)t;
    (void)y;
  }
  // how the quaternion of a free root is kept unit ("none" without a free joint)
  virtual std::string quaternion_handling() const = 0;
  // n root functions g(t, y) → g[0 … n) (limits.hpp), each located where it crosses zero going
  // down: advance() then returns at the root, t < t_out possibly, with roots() the indices found
  // (empty otherwise); the caller restarts there.  Methods without root finding throw soadyn::Error
  using RootFunction = std::function<void(double t, const double* y, double* g)>;
  virtual void set_roots(int n, RootFunction g) {
    (void)n;
    (void)g;
    throw Error("this integration method cannot locate events (joint limits): use cvode-adams or cvode-bdf");
  }
  const std::vector<int>& roots() const { return roots_; }
  // never step past an advance()'s t_out (a restart follows there: a control tick).  Fixed-step
  // methods end their steps there already
  virtual void set_exact_stops(bool) {}

 protected:
  std::vector<int> roots_;

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
