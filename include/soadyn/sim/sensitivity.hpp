// Forward sensitivities of a whole run by SUNDIALS CVODES: ∂x(t)/∂x₀ and ∂x(t)/∂π at every output,
// integrated with the state under the same error control (CVodeSetSensErrCon), from the analytic
// derivatives: ṡ = A s + b with A = [[∂q̇/∂q, ∂q̇/∂v], [∂q̈/∂q, ∂q̈/∂v]] and b = [0; ∂q̈/∂π] =
// [0; −𝓜⁻¹ Y(q, v, q̈)] (regressor.hpp), neither formed: per state the inverse-dynamics derivative
// sweeps, O(N); per column their products and 𝓜⁻¹ by the articulated-body factor, O(N) each, with −Y
// added as a generalized force before 𝓜⁻¹ (System::linearize, linearized_times; springs and dampers
// included).  No finite differences.
//
// Tangent-space convention.  x = [δq; v] has 2 nv numbers: δq the increment along the tangent,
// q ⊕ δq = Model::integrate(q, δq, 1) (derivatives.hpp), the coordinate's own increment on
// revolute, prismatic and planar joints; on a free root δq = [δθ; δp], the attitude turned about
// inertial axes, exp(δθ) ⊗ Q, and the origin moved by δp; on a ball joint δθ in the child's axes,
// Q ⊗ exp(δθ).  Column k of ∂x(t)/∂x₀ is how x(t) moves when x₀ moves along e_k in that sense, and
// its rows are x(t)'s tangent coordinates.  (CVODES integrates the quaternion's coordinates; the
// conversion is joint_tangent_map at both ends.)
//
// What is differentiated: the dynamics with the scene's torques (functions of t alone), springs and
// dampers.  Refused, one line each: fixed-step methods (CVODE's methods only), controllers (their
// ∂τ_c/∂x is not differentiated), joint limits that are enforced (events make the flow jump), and a
// parameter body that is not one of the model's.
#pragma once

#include "soadyn/sim/integrators.hpp"
#include "soadyn/algorithm/regressor.hpp"
#include "soadyn/sim/scenario.hpp"
#include "soadyn/multibody/configuration.hpp"

#include <memory>
#include <string>
#include <vector>

namespace soadyn {

// What a run's sensitivities are with respect to, resolved against a model.
struct SensitivityPlan {
  bool initial_state = false;
  std::vector<int> bodies;  // the bodies whose 10 parameters each are differentiated, in model order
  int nx = 0;               // 2 nv, the prescribed joints' DOFs left out (their motion is given)
  int nx0() const { return initial_state ? nx : 0; }
  int np() const { return kParametersPerBody * int(bodies.size()); }
  // names: x's ("q.<v name>" along the tangent, "qd.<v name>"), the parameters' ("<body>.m",
  // "<body>.mcx", …, "<body>.Izz", regressor.hpp's order), and their SI units
  std::vector<std::string> state_names, state_units, parameter_names, parameter_units;
};

// P = ∂q/∂δ (nq × nv), how the coordinates move along a tangent increment δ at q:
// tangent_to_coordinates (configuration.hpp)

// The plan for `settings` on `model` with `prescribed` joints (Inputs::prescribed: the state, and x,
// leave their DOFs out); throws soadyn::Error naming an unknown body (with the nearest name) or "all"
// mixed with names.
SensitivityPlan plan_sensitivities(const Model& model, const SensitivitySettings& settings,
                                   const std::vector<PrescribedInput>& prescribed = {});

// Throws soadyn::Error (one line) when a run of sc with settings cannot have sensitivities: a
// fixed-step method, controllers, enforced joint limits, sampled control.
void check_sensitivities(const Scenario& sc, const SimulationSettings& settings, bool has_controller);

// What carries the sensitivities along with a CVODE integrator.
class SensitivitySource {
 public:
  virtual ~SensitivitySource() = default;
  // the sensitivities at t, the time advance() last returned (or the start): dx_dx0 nx × nx0, dx_dpi nx × np
  virtual void sensitivities(double t, MatX& dx_dx0, MatX& dx_dpi) = 0;
};

// A CVODES integrator (cvode-adams or cvode-bdf, as settings say) and its sensitivities (the same object).
struct SensitivityIntegrator {
  std::unique_ptr<Integrator> integrator;
  SensitivitySource* source = nullptr;
};

// The integrator for `plan`; system.model must be the model the plan was made for.
SensitivityIntegrator make_sensitivity_integrator(System& system, const SimulationSettings& settings,
                                                  const SensitivityPlan& plan, double t0, const VecX& y0);

}  // namespace soadyn
