// How a run is integrated and logged: the `simulation` section of a scenario, overridable from the
// command line.  Plain numerics: no file format is involved here.
#pragma once

#include <string>
#include <vector>

namespace soadyn {

// Forward sensitivities of a run (sensitivity.hpp): ∂x(t)/∂x₀ and ∂x(t)/∂π at every output, x = [q; v]
// along the tangent (2 nv numbers), π the inertial parameters (regressor.hpp) of the bodies named.
struct SensitivitySettings {
  bool initial_state = false;          // ∂x(t)/∂x₀, 2nv × 2nv
  std::vector<std::string> parameters; // body names (Model::body_names), or {"all"}: ∂x(t)/∂π, 2nv × 10·bodies
  bool any() const { return initial_state || !parameters.empty(); }
};

struct SimulationSettings {
  double t_end = 10.0;                 // s
  double output_dt = 0.01;             // s between logged samples
  std::string method = "cvode-adams";  // a name of integrators() (integrators.hpp): cvode-adams | cvode-bdf |
                                       //   euler | semi-implicit-euler | symplectic-euler | rk4 | implicit-midpoint
  double rtol = 1e-8;                  // CVODE relative tolerance
  double atol = 1e-10;                 // CVODE absolute tolerance
  double dt = 1e-3;                    // fixed-step methods' step, s: exactly (count_steps, integrators.hpp)
  double max_step = 0.0;               // CVODE maximum step, s (0: none)
  long max_steps = 100000000;          // CVODE steps allowed in the whole run
  std::string dynamics = "aba";        // forward-dynamics route: dense | sparse | aba ("on" taken too)
  std::string jacobian = "analytic";   // ∂f/∂y for cvode-bdf and implicit-midpoint: analytic | dq
                                       //   (analytic derivatives, derivatives.hpp; or difference quotients)
  std::string newton = "full";         // implicit-midpoint: full (the Jacobian at every iterate) | simplified
                                       //   (once per step, at the explicit-Euler predictor)
  // joint limits (limits.hpp): off by default, so a model's limits change nothing unless asked
  bool limits = false;                 // each DOF's lower/upper an event: impact, hold, release (CVODE only)
  double restitution = 0.0;            // coefficient of restitution e at a limit, 0 ≤ e ≤ 1 (0: held there)
  double control_dt = 0.0;             // s between controller samples, zero-order hold (0: continuous)
  SensitivitySettings sensitivities;   // none by default (CVODE methods only)
};

}  // namespace soadyn
