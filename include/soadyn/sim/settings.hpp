// How a run is integrated and logged: the `simulation` section of a scenario, overridable from the
// command line, and the table that says each setting once.  No file format is involved here.
#pragma once

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/fd_method.hpp"

#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace soadyn {

// Forward sensitivities of a run (sensitivity.hpp): ∂x(t)/∂x₀ and ∂x(t)/∂π at every output, x = [q; v]
// along the tangent (2 nv numbers), π the inertial parameters (regressor.hpp) of the bodies named.
struct SensitivitySettings {
  bool initial_state = false;          // ∂x(t)/∂x₀, 2nv × 2nv
  std::vector<std::string> parameters; // body names (Model::body_names), or {"all"}: ∂x(t)/∂π, 2nv × 10·bodies
  bool any() const { return initial_state || !parameters.empty(); }
};

// The integration method: its word (in parentheses) is said in settings.cpp with the other enums'
// words; each one is a row of integrators() (integrators.hpp), the registry that says what it does
// and makes it.
enum class Method {
  CvodeAdams,         // "cvode-adams": SUNDIALS CVODE, Adams–Moulton (non-stiff), adaptive steps
  CvodeBdf,           // "cvode-bdf": SUNDIALS CVODE, BDF with Newton (stiff), adaptive steps
  Euler,              // "euler": explicit Euler, fixed steps
  SemiImplicitEuler,  // "semi-implicit-euler": v, then q, fixed steps
  SymplecticEuler,    // "symplectic-euler": symplectic Euler in the momenta, fixed steps
  Rk4,                // "rk4": classical Runge–Kutta on the group (Munthe-Kaas), fixed steps
  ImplicitMidpoint,   // "implicit-midpoint": implicit midpoint rule by Newton, fixed steps
  Variational         // "variational": the midpoint discrete Lagrangian's DEL equations on the group, fixed steps
};
// ∂f/∂y for cvode-bdf and implicit-midpoint
enum class Jacobian {
  Analytic,  // "analytic": the analytic derivatives (derivatives.hpp)
  Dq         // "dq": difference quotients
};
// implicit-midpoint's and variational's Newton iteration (variational's simplified: the chord iterations with 𝓜)
enum class Newton {
  Full,       // "full": the Jacobian at every iterate
  Simplified  // "simplified": once per step, at the explicit-Euler predictor (variational: 𝓜(q_m), O(N))
};
// Each one's word (the scenario's, the command line's, Python's, the run file's): Method's from
// kMethodWords (settings.cpp; integrators() describes each), FdMethod's (fd_method.hpp) from fd_methods()
std::string_view to_string(Method m);
std::string_view to_string(Jacobian j);
std::string_view to_string(Newton n);
// The enum named by a word, as a scenario takes it; throws Error("method: unknown method 'rk5'; did
// you mean 'rk4'?") for another
Method parse_method(std::string_view word);
Jacobian parse_jacobian(std::string_view word);
Newton parse_newton(std::string_view word);

// How the equations of motion are integrated, declared once: a run's (SimulationSettings) and a
// batch of rollouts' (RolloutSettings, rollout.hpp)
struct IntegrationSettings {
  Method method = Method::CvodeAdams;  // the integrator (integrators.hpp)
  double rtol = 1e-8;                  // CVODE relative tolerance
  double atol = 1e-10;                 // CVODE absolute tolerance
  double dt = 1e-3;                    // fixed-step methods' step, s: exactly (count_steps, integrators.hpp)
  double max_step = 0.0;               // CVODE maximum step, s (0: none)
  long max_steps = 100000000;          // CVODE steps allowed in the whole run (in each rollout)
  FdMethod dynamics = FdMethod::ArticulatedBody;  // forward-dynamics route: dense | sparse | aba ("on" taken too)
  Jacobian jacobian = Jacobian::Analytic;        // ∂f/∂y for cvode-bdf and implicit-midpoint
  Newton newton = Newton::Full;                  // implicit-midpoint's and variational's Newton iteration
};

struct SimulationSettings : IntegrationSettings {
  double t_end = 10.0;                 // s
  double output_dt = 0.01;             // s between logged samples
  // joint limits (limits.hpp): off by default, so a model's limits change nothing unless asked
  bool limits = false;                 // each DOF's lower/upper an event: impact, hold, release (CVODE only)
  double restitution = 0.0;            // coefficient of restitution e at a limit, 0 ≤ e ≤ 1 (0: held there)
  double control_dt = 0.0;             // s between controller samples, zero-order hold (0: continuous)
  SensitivitySettings sensitivities;   // none by default (CVODE methods only)
};

// Each scalar setting above, declared once (settings.cpp).  Its name is the key under a scenario's
// simulation:, soadyn run's option (--t-end for t_end), the Python SimulationSettings attribute and
// simulate() keyword, a sweep's vary: path simulation.<name> and the run file's /solver attribute;
// the YAML reader, the CLI, Python and the log loop over this table instead of listing the fields.
// (sensitivities, a structured setting, has its own reader: scenario_sensitivity.cpp.)
enum class SettingKind { Real, Count, Word, Flag };
enum class SettingRange { Any, Positive, NonNegative, UnitInterval };  // of a Real or Count

// A Word setting's field: an enum, read as its word and set from one (a word of words(), the old
// word already replaced by its successor); set returns false for a word that names none of its values
struct WordField {
  std::string_view (*get)(const SimulationSettings& s);
  bool (*set)(SimulationSettings& s, std::string_view word);
};

struct SettingInfo {
  using Field =
      std::variant<double SimulationSettings::*, long SimulationSettings::*, WordField, bool SimulationSettings::*>;
  std::string_view name;
  SettingKind kind;
  Field field;
  std::string_view unit;  // of a Real or Count ("s", "1"); empty for words and flags
  std::string_view help;
  SettingRange range = SettingRange::Any;  // a Count is also whole
  // Word: the words it takes (integrators, forward-dynamics routes, …) and what one is called in an
  // error ("method": "unknown method 'rk5'"); empty noun: "expected analytic or dq, got 'x'"
  std::vector<std::string> (*words)() = nullptr;
  std::string_view noun;
  // Word: an older word still taken (not among words()), stored as its successor: dynamics' on → aba
  std::string_view old_word, new_word;
  // a field of IntegrationSettings (how the equations are integrated): what a sweep's reference run
  // may set (Python: SimulationSettings.integration_names)
  bool integration = false;
};

const std::vector<SettingInfo>& setting_table();
const SettingInfo* find_setting(std::string_view name);

// What is wrong with a value for the setting ("" when nothing): "expected a positive number",
// "unknown method 'rk5'; did you mean 'rk4'?".  A number's text is added by the caller (", got -1").
std::string setting_problem(const SettingInfo& info, double x);
std::string setting_problem(const SettingInfo& info, const std::string& word);

// Set one setting; a Word is stored as the enum its word names (the O(N) route's old word on → aba).
// Throws Error("<name>: <problem>") on a value setting_problem refuses.
void set_setting(SimulationSettings& s, const SettingInfo& info, double x);
void set_setting(SimulationSettings& s, const SettingInfo& info, const std::string& word);
void set_setting(SimulationSettings& s, const SettingInfo& info, bool flag);

// The setting's value as text (words as their word, numbers with %.17g, flags true/false), and a Real's or Count's as a
// number (the run file's /solver)
std::string setting_text(const SimulationSettings& s, const SettingInfo& info);
double setting_number(const SimulationSettings& s, const SettingInfo& info);

// The most controller ticks a run may take, t_end / control_dt with control_dt > 0: each tick
// stops the integrator and restarts it there, so ticks cost what steps cost and more; as many as
// CVODE's default step budget (max_steps, 10⁸).  control_dt 1e-9 over 10 s (10¹⁰ ticks) would run
// for hours, 1e-300 could not advance time at all.
inline constexpr double kMaxControlTicks = 1e8;

// What is wrong with control_dt for a run to t_end ("" when nothing): more ticks than
// kMaxControlTicks, said with the numbers ("control_dt 1e-09 s over t_end 10 s is 1e+10 ticks, …")
std::string control_ticks_problem(double t_end, double control_dt);

}  // namespace soadyn
