// The system the integrators step: ẏ = f(t, y) for a model with its inputs and controllers, and its
// Jacobian ∂f/∂y (system.cpp).  The integrators (integrators.hpp) and the events (limits.hpp) use it.
#pragma once

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/sim/controller.hpp"
#include "soadyn/algorithm/derivatives.hpp"
#include "soadyn/algorithm/hybrid.hpp"
#include "soadyn/algorithm/inputs.hpp"

#include <Eigen/QR>

#include <optional>
#include <string>

namespace soadyn {

class System;

// Forces that hold DOFs where the run's events put them (joint limits at a bound, limits.hpp).
// System::rhs hands them data.qdd, computed with sys.tau, and they make it the constrained q̈.
class Constraint {
 public:
  virtual ~Constraint() = default;
  virtual void constrain(System& sys) = 0;
};

// ẏ = f(t, y) for the model with its inputs.  The state is y = [q; v], followed, when the inputs
// do work (torques or dampers), by two quadratures the integrator advances with the rest:
// W = ∫ P dt, the work of the inputs, and D = ∫ Σ c q̇² dt ≥ 0, the part the dampers dissipated
// (Inputs::power).  Nothing feeds back from them into q and v.
//
// Prescribed motion (inputs.prescribed): those joints' q, q̇, q̈ are functions of t, so the state
// holds the free joints' q and v alone (nq_state, nv_state: the model's q and v with the prescribed
// joints' entries left out, in the model's order), q̈_f and the prescribed joints' τ come from the
// hybrid dynamics (hybrid.hpp, O(N)), and a third quadrature W_p = ∫ τ_p · q̇* dt counts the work of
// the torques τ_p that hold the prescribed motion (beyond the joints' own inputs), so that
// E(t) − E(0) = W + W_p − D.
class System {
 public:
  // control_work: a controller acts (feedback or control), so W has the quadratures and counts it
  System(const Model& model, const Inputs& inputs, FdMethod method, bool control_work = false);
  int size() const { return nq_state_ + nv_state_ + nquad; }
  // the state's q and v sizes: the model's, less the prescribed joints'
  int nq_state() const { return nq_state_; }
  int nv_state() const { return nv_state_; }
  bool has_prescribed() const { return locked_.any(); }
  // the joints whose motion is given (hybrid_dynamics' locked set)
  const PrescribedJoints& prescribed_joints() const { return locked_; }
  // closed loops (inputs.loops): q̈ by loop_forward_dynamics, their multipliers and rows at the
  // last evaluation in loop_data()
  bool has_loops() const { return loops_.m > 0; }
  const LoopData& loop_data() const { return loops_; }
  // the loops' dependent rows at the first evaluation (m − rank of A; a planar four-bar closed by
  // a hinge: 3): λ is of minimum norm along them.  -1 before the first evaluation.
  int loop_dependent_rows() const { return loop_first_rank_ < 0 ? -1 : loops_.m - loop_first_rank_; }
  // y onto the manifold the state lives on: the quaternions unit and, with loops, q onto φ(q) = 0
  // (Gauss–Newton along the tangent, steps of minimum norm, to kLoopClosure) and v onto K v = 0
  // (v − K⁺ K v).  False when the closure is not reached in 20 iterations (a singular or
  // unreachable configuration).  project_error removes from an error estimate (CVODE's) its
  // components across the manifold, with K at the last projection.
  bool project(Eigen::Ref<VecX> y);
  void project_error(Eigen::Ref<VecX> err) const;
  // the state's q and v entries as indices into the model's q and v
  const std::vector<int>& q_index() const { return q_index_; }
  const std::vector<int>& v_index() const { return v_index_; }
  // where each quaternion starts in the state (free and ball joints)
  const std::vector<int>& quaternions() const { return quaternions_; }
  // one joint's entries in the state: its q (iq, mq) and v (iv, nv); the free joints' in the tree's order
  struct StateJoint {
    int iq, mq, iv, nv;
    int body;  // its body in the model
  };
  const std::vector<StateJoint>& state_joints() const { return state_joints_; }
  // the state's quaternions made unit (q_state: the state's nq_state q entries); counts its calls
  void normalize(Eigen::Ref<VecX> q_state) const;
  mutable long normalizations = 0;
  // out = q_state ⊕ h v_state joint by joint (configuration.hpp's ⊕ for each state joint: a free or
  // ball joint's quaternion turned by the exponential map, unit by construction); out may be q_state
  void integrate(const Eigen::Ref<const VecX>& q_state, const Eigen::Ref<const VecX>& v_state, double h,
                 Eigen::Ref<VecX> out) const;
  // out = dexp⁻¹_u(v_state) joint by joint (u, out: nv_state): the rate of the increment u for which
  // q0 ⊕ u moves at v_state (configuration.hpp's increment_rate)
  void increment_rate(const Eigen::Ref<const VecX>& u, const Eigen::Ref<const VecX>& v_state, Eigen::Ref<VecX> out) const;
  // A ← A dexp_u joint by joint (A: nv_state columns along the tangent at q0 ⊕ u): the columns
  // along the increment u instead, dexp_u being the inverse of increment_rate's map (a joint
  // without a quaternion's columns unchanged)
  void times_increment_jacobian(const Eigen::Ref<const VecX>& u, Eigen::Ref<MatX> A) const;
  // q̇ = T̄(q) v for the state's q and v (nq_state, nv_state) into out (nq_state)
  void qdot(const Eigen::Ref<const VecX>& q_state, const Eigen::Ref<const VecX>& v_state, Eigen::Ref<VecX> out);
  // [q; v; 0 …]: the state at the start of a run from the model's q0, v0 (the prescribed joints'
  // entries left out; the quadratures start at zero)
  VecX state(const VecX& q0, const VecX& v0) const;
  // the model's q and v at (t, y) into q, v (the prescribed joints' from their motion at t, their q̈*
  // into qdd_given); with nothing prescribed, y's
  void expand(double t, const double* y);
  // ẏ = [q̇(q, v); q̈; P; D]; counts evaluations
  void rhs(double t, const double* y, double* ydot);
  // q, v and [kin], [vel] at y, and τ: the inputs', the held control's and the feedback controller's
  // (rhs, jacobian and jacobian_times begin with it)
  void at_state(double t, const double* y);
  // data.qdd for the generalized force tau_in at the state at_state left: the hybrid dynamics' with
  // prescribed motion (tau_hybrid then its τ, the holding one on the prescribed DOFs), forward
  // dynamics by `method` otherwise (Constraint's columns, limits.cpp)
  void dynamics(const VecX& tau_in);
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
  // With prescribed motion, S and out are in the state's layout, q̈_f's rows 𝓜_ff⁻¹ (…)_f by the
  // hybrid dynamics' locked factor, and W_p's row zero (it feeds nothing back).
  long linearize(double t, const double* y);
  void linearized_times(const MatX& S, MatX& out, const MatX* forces = nullptr);
  void linearized_times(Eigen::Ref<const MatX> S, Eigen::Ref<MatX> out, const MatX* forces = nullptr);
  // X ← 𝓜⁻¹ X (nv rows) by the articulated-body factor linearize left in data (O(N) per column;
  // with prescribed motion 𝓜_ff⁻¹ on the free rows, 0 on the prescribed ones)
  void linearized_solve(Eigen::Ref<MatX> X);
  // the state's coordinates along the tangent at (t, y): ∂q_state/∂δ (nq_state × nv_state,
  // tangent_to_coordinates of the free joints), and δ = T(q) S_q for columns S_q of the state's
  // q rows (nq_state × k) into out (nv_state × k).  Both set q and v to (t, y)'s (expand)
  MatX coordinates_of_tangent(double t, const double* y);
  void tangent_of(double t, const double* y, Eigen::Ref<const MatX> Sq, Eigen::Ref<MatX> out);
  void prepare_jacobian();
  // ∂f/∂y by forward differences of rhs (size() extra evaluations, counted as RHS evaluations)
  void jacobian_dq(double t, const double* y, Eigen::Ref<MatX> J);
  // ∂f/∂(δ, v, W…) on the tangent (tangent_size() square): f's rows [δ̇; q̈; P…] with δ̇ = v, the
  // columns along a tangent increment δ of q (q ⊕ δ) rather than along the coordinates, so that
  // the q rows are [0 e 0] and J_vq = ∂q̈/∂δ.  Analytic (the derivatives' ∂q̈/∂δ and ∂q̈/∂v, as
  // jacobian) or by forward differences of rhs along q ⊕ ε e_c and v + ε e_c (tangent_jacobian_dq)
  int tangent_size() const { return 2 * nv_state_ + nquad; }
  void tangent_jacobian(double t, const double* y, Eigen::Ref<MatX> J);
  void tangent_jacobian_dq(double t, const double* y, Eigen::Ref<MatX> J);
  // the name of component k of y ("theta2 (q)", "bus.wz (v)", "the inputs' work W")
  std::string component_name(int k) const;

  const Model& model;
  const Inputs& inputs;
  FdMethod method;
  int nquad;  // 2 (W, D) when the inputs do work, 3 (W, D, W_p) with prescribed motion, else 0
  Data data;
  std::optional<DerivativeData> derivatives;  // jacobian's workspace, made on first use
  VecX q, v, tau, qd;
  // prescribed motion: q̈* (nv, the prescribed entries set by expand), the hybrid dynamics' τ (nv:
  // the inputs' on free DOFs, the holding one on prescribed), and τ_p, the prescribed joints' τ
  // beyond their inputs (one per inputs.prescribed), at the last evaluation
  VecX qdd_given, tau_hybrid, prescribed_tau;
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
  // forces holding DOFs where events put them (joint limits at a bound, limits.hpp): rhs applies them
  Constraint* constraint = nullptr;
  long rhs_evals = 0;
  long jac_evals = 0;

 private:
  // linearized_times' q̇ rows and δ = T(q) S_q when a joint holds a quaternion
  void linearized_tangent_rows(const Eigen::Ref<const MatX>& S, Eigen::Ref<MatX>& out);
  void rhs_prescribed(double t, double* ydot);
  // after each loop solve: the loops' rank and margin against the first evaluation's; a
  // SimulationError naming t and the loop at a singular configuration (kLoopSingular)
  void check_loop_rank(double t);
  void jacobian_prescribed(double t, Eigen::Ref<MatX> J);
  void model_times(Eigen::Ref<const MatX> S, Eigen::Ref<MatX> out, const MatX* forces);
  PrescribedJoints locked_;
  LoopData loops_;
  int loop_first_rank_ = -1;            // A's rank at the first evaluation
  std::vector<int> loop_block_rank_;    // each loop's own rank there (singular_loops)
  Eigen::CompleteOrthogonalDecomposition<MatX> projector_;  // K's at the last projection
  int nq_state_, nv_state_;
  std::vector<int> q_index_, v_index_, quaternions_;
  std::vector<StateJoint> state_joints_;
  MatX Jqq_, Jqv_, Jvq_;            // jacobian_prescribed: the model's q̇ and q̈ blocks before the state's are taken
  bool evaluated_ = false;         // rhs's state (eval_t_, eval_y_) is still data's
  double eval_t_ = 0.0;
  VecX eval_y_;
  bool linearized_ = false;        // linearize's state (lin_t_, lin_y_) is still data's
  long linearizations_ = 0;        // how many linearize has made: the current one's number
  double lin_t_ = 0.0;
  VecX lin_y_;
  // scratch, each the workspace of the method named
  VecX y_work_, f0_, f1_;          // jacobian_dq
  MatX delta_, W_;                 // linearized_times: S's q rows on the tangent; the forces
  MatX Sm_, Om_;                   // linearized_times with prescribed motion: S and out in the model's layout
  MatX solve_work_;                // articulated_solve's (prepare_jacobian)
  VecX dP_, dD_;                   // jacobian, linearized_times: ∂Ẇ/∂v, ∂Ḋ/∂v (the quadratures' rows)
};

}  // namespace soadyn
