// Inertial-parameter identification: the parameters π (regressor.hpp, 10 per body) of some bodies
// fitted to a logged motion, the other bodies' held at the scene's values.
//
// Least squares (the data has q̈): each sample k gives τ_k = Y(q_k, v_k, q̈_k) π, τ_k the scene's
// inputs at (t_k, q_k, v_k) (torques, springs, dampers) or the measured torques when given.  The
// columns of the bodies not fitted move to the right-hand side:
//   A δ = b,   A = [Y_k,S]_k,   b = [τ_k − Y_k π⁰]_k,   π = π⁰ + δ   (S: the fitted columns).
// Gauss–Newton (no q̈, or asked): the scene simulated with the current π over windows of `window`
// seconds, each from the data's state at its start (the inputs' sines shifted to its time), the
// residual r = [q_k − q(t_k); v_k − v(t_k)]_k (q along the tangent; revolute, prismatic and planar
// joints only) and its Jacobian ∂x(t_k)/∂π_S by CVODES (sensitivity.hpp); A δ = r each iteration,
// damped (Levenberg–Marquardt) until the residual falls, until the step is below 1e-10 of π or
// max_iterations.  Short windows keep the residual near linear in π: one run over a whole
// excited motion drifts off the data (chaotically, for a double pendulum) and single shooting
// then finds no descent from 30 % off.
//
// Each step is the minimum-norm solution of the column-scaled problem (A D⁻¹)(D δ) = b, D the
// columns' norms (a column below 1e-12 of the largest is round-off of a parameter that does not act:
// zero), by an SVD: singular values below rank_tolerance · σ_max count as zero.  So the
// directions the data cannot see (A's null space) are held at the scene's values, not fitted to
// noise, and reported (IdentifyResult::unidentifiable).  Covariance of the fit:
//   σ̂² D⁻¹ V_r Σ_r⁻² V_rᵀ D⁻¹,  σ̂² = |b − A δ|² / (rows − rank),
// the standard errors its diagonal's roots (those of unidentifiable parameters cover only what the
// data saw of them).  A fitted π that is no rigid body is refused by with_parameters, naming it.
#pragma once

#include "soadyn/sim/scenario.hpp"
#include "soadyn/algorithm/table.hpp"

#include <optional>
#include <string>
#include <vector>

namespace soadyn {

enum class IdentifyMethod { Auto, LeastSquares, GaussNewton };  // Auto: least squares when q̈ is there
// "auto", "least-squares", "gauss-newton"; nullopt otherwise
std::optional<IdentifyMethod> parse_identify_method(const std::string& s);

struct IdentifyOptions {
  std::vector<std::string> bodies;  // the bodies whose 10 parameters are fitted ({"all"}: every body)
  IdentifyMethod method = IdentifyMethod::Auto;
  double rank_tolerance = 1e-8;     // σ_k ≤ this · σ_max counts as zero (column-scaled A)
  int max_iterations = 20;          // Gauss–Newton
  double window = 0.1;              // Gauss–Newton: s simulated from each logged state
};

// The samples fitted: a run file's (read_run_state), checked against a model, or arrays.
struct Measurements {
  std::string path;  // named in messages
  VecX t;            // T
  MatX q, v, qdd;    // T × nq, T × nv, T × nv (qdd empty: not measured)
  MatX tau;          // T × nv measured generalized forces (empty: the scene's inputs give them);
                     // least squares only: Gauss–Newton simulates the scene's inputs
};
// The run file's samples; refuses (soadyn::Error naming the file) a run whose joints (/q's names)
// are not the model's, or one without /qd.
Measurements read_measurements(const std::string& path, const Model& model);

struct IdentifyResult {
  std::string method;                       // "least-squares" or "gauss-newton"
  std::vector<int> bodies;                  // fitted bodies, model order
  std::vector<std::string> names, units;    // "<body>.m", "<body>.mcx", …, "<body>.Izz" (regressor.hpp's order)
  VecX prior, fitted, standard_error;       // the fitted bodies' parameters, 10 each
  int rows = 0, rank = 0, iterations = 0;   // equations stacked, rank of A, Gauss–Newton iterations
  VecX singular_values;                     // of the column-scaled A, largest first
  MatX unidentifiable;                      // columns: unit directions in π_S that the data cannot see
  double sigma2 = 0.0;                      // σ̂²
  double rms_prior = 0.0, rms_fitted = 0.0;  // RMS of the residual before and after
  Model model;                              // the scene's model with the fitted parameters
};

// Throws soadyn::Error (one line) for an unknown body, measurements of the wrong size, a method
// the data cannot have (least squares without q̈), a scene with controllers and no measured
// torques (the run file does not log theirs), Gauss–Newton on quaternion joints or on samples that are not the output grid
// t_k = t_0 + k Δt, and a fit that is no rigid body (with_parameters's message).
IdentifyResult identify(const Scenario& sc, const Measurements& data, const IdentifyOptions& options);

// "0.7071 link2.Ixx - 0.7071 link2.Iyy": direction k of result.unidentifiable, entries below 1e-6
// of its largest left out
std::string describe_direction(const IdentifyResult& result, int k);

// The scene's text with the fitted bodies' mass properties as its `inertial:` map (scenarios/
// README.md), kFittedScenarioHeader first; a relative robot file (urdf:, model:) rewritten
// relative to the directory of `output` so the fitted scene loads from there.
std::string fitted_scenario_text(const Scenario& sc, const IdentifyResult& result, const std::string& output);

}  // namespace soadyn
