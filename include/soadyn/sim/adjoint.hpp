// Gradients of a whole run's cost by the adjoint method (SUNDIALS CVODES, CVodeAdjInit): one forward
// run that stores checkpoints, one backward run of the adjoint, whatever the number of parameters.
//
// The cost of a run x(t) = [q(t); v(t)] on [0, T] (T = settings.t_end):
//   G = ∫₀ᵀ ℓ(t, q, v) dt + Φ(q(T), v(T))
// and its gradient with respect to the initial state x₀ (along the tangent, as sensitivity.hpp) and
// the inertial parameters π of the bodies asked for (regressor.hpp).  With y the integrator's state
// [q; v] (quaternions' four coordinates), f its rate and λ the adjoint:
//   λ̇ = −(∂f/∂y)ᵀ λ − (∂ℓ/∂y)ᵀ,   λ(T) = (∂Φ/∂y)ᵀ               (backward, T → 0)
//   ∂G/∂y₀ = λ(0),   ∂G/∂π = ∫₀ᵀ (∂f/∂π)ᵀ λ dt                      (a quadrature of the backward run)
// (∂f/∂y)ᵀ λ is a vector–Jacobian product, never the Jacobian: with μ = 𝓜⁻¹ λ_v (the articulated-body
// factor of q̈'s recursion, articulated_solve),
//   λ_vᵀ ∂q̈/∂x = μᵀ (∂τ_in/∂x − ∂ID/∂x |_q̈)   (x = q along the tangent, or v: the inverse-dynamics
//                                              derivatives as O(N) vector products, derivatives.hpp)
//   λ_vᵀ ∂q̈/∂π = −μᵀ Y(q, v, q̈)               (the regressor; Yᵀ μ by an O(N) sweep)
// plus the q̇(q, v) rows joint by joint, and the chain rule from the tangent to the coordinates.
// ∂G/∂x₀ = [Pᵀ λ_q(0); λ_v(0)] with P = ∂q/∂δ (tangent_to_coordinates).
//
// What is differentiated and what is refused are as for forward sensitivities (sensitivity.hpp):
// CVODE methods only, no controllers, no enforced joint limits.  The backward run uses the forward
// run's method and tolerances (Adams: fixed-point iterations; BDF: Newton with −(∂f/∂y)ᵀ, analytic).
#pragma once

#include "soadyn/sim/scenario.hpp"
#include "soadyn/sim/settings.hpp"

#include <functional>
#include <string>
#include <vector>

namespace soadyn {

// G = ∫ ℓ dt + Φ.  Each part may be empty (then ≡ 0).  A part returns its value and writes its
// gradient: dq (nq, with respect to the coordinates q holds, quaternions' four included) and dv
// (nv); both arrive zeroed.
struct Cost {
  using Running = std::function<double(double t, const VecX& q, const VecX& v, Eigen::Ref<VecX> dq, Eigen::Ref<VecX> dv)>;
  using Terminal = std::function<double(const VecX& q, const VecX& v, Eigen::Ref<VecX> dq, Eigen::Ref<VecX> dv)>;
  Running running;
  Terminal terminal;
};

// Tracking of a reference motion (a logged run):
//   ℓ = ½ Σ_k wq_k (q_k − q̂_k(t))² + ½ Σ_k wv_k (v_k − v̂_k(t))²,   Φ = the same with wq_T, wv_T at T,
// q̂ and v̂ natural cubic splines through the samples (t: increasing, ≥ 2 rows; q: rows × nq; v: rows
// × nv).  Weights: one per column (nq for q, nv for v), or empty for none.  A quaternion of the
// reference is flipped to the hemisphere of the run's (Q and −Q are one attitude).  Throws
// soadyn::Error for sizes that do not match the model or times that do not increase.
struct TrackingWeights {
  VecX q, v;            // running
  VecX q_final, v_final;  // terminal
};
Cost tracking_cost(const Model& model, const VecX& t, const MatX& q, const MatX& v, const TrackingWeights& weights);

struct CostGradient {
  double cost = 0.0;  // G
  VecX d_initial_state;  // ∂G/∂x₀ (2 nv, along the tangent), empty unless asked for
  VecX d_parameters;     // ∂G/∂π (10 per body asked for, in model order)
  std::vector<std::string> state_names, parameter_names;  // as SensitivityPlan's
  long forward_steps = 0, backward_steps = 0, checkpoints = 0;
  long forward_rhs_evals = 0, backward_rhs_evals = 0;
  double cpu_seconds = 0.0;  // CPU time of the thread that ran both
};

// The gradient of `cost` over the run of sc with `settings` (t_end, method, tolerances; its own
// sensitivities are ignored) with respect to what `wrt` names (sensitivity.hpp's settings: the
// initial state, the parameters of bodies or "all").  steps_per_checkpoint: CVODES' Nd, the steps
// between checkpoints; memory holds one interpolation point per step of one interval plus one
// checkpoint per interval.  0: 50 per entry of the state y = [q; v], from 500 to 10000
// (automatic_steps_per_checkpoint); negative: refused.  Throws soadyn::Error for what forward
// sensitivities refuse, for nothing to differentiate, and SimulationError when either run fails.  The parameter quadrature has no error
// test of its own (CVodeSetQuadErrConB off): it rides on the adjoint's controlled steps.
CostGradient gradient(const Scenario& sc, const SimulationSettings& settings, const Cost& cost,
                      const SensitivitySettings& wrt, long steps_per_checkpoint = 0);
// the Nd that steps_per_checkpoint = 0 chooses for a state of n entries
long automatic_steps_per_checkpoint(int n);

}  // namespace soadyn
