// The table of simulation settings (settings.hpp): each one's name, kind, unit, range, words and
// help, said once; the readers and writers at the edges loop over it.
#include "soadyn/sim/settings.hpp"

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/multibody/text.hpp"
#include "soadyn/multibody/types.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <utility>

namespace soadyn {

namespace {

using S = SimulationSettings;
using K = SettingKind;
using R = SettingRange;

// the words of the enums whose registry is elsewhere or nowhere: each value once, in the enum's order
// (integrators() describes each method and makes its integrator; it takes its name from here)
constexpr std::pair<Method, std::string_view> kMethodWords[] = {
    {Method::CvodeAdams, "cvode-adams"}, {Method::CvodeBdf, "cvode-bdf"}, {Method::Euler, "euler"},
    {Method::SemiImplicitEuler, "semi-implicit-euler"}, {Method::SymplecticEuler, "symplectic-euler"},
    {Method::Rk4, "rk4"}, {Method::ImplicitMidpoint, "implicit-midpoint"},
    {Method::Variational, "variational"}};
constexpr std::pair<Jacobian, std::string_view> kJacobianWords[] = {{Jacobian::Analytic, "analytic"}, {Jacobian::Dq, "dq"}};
constexpr std::pair<Newton, std::string_view> kNewtonWords[] = {{Newton::Full, "full"}, {Newton::Simplified, "simplified"}};

template <class E, size_t N>
std::string_view word_in(const std::pair<E, std::string_view> (&table)[N], E e) {
  for (const auto& [value, word] : table)
    if (value == e) return word;
  throw Error("not a value of the enum: " + std::to_string(int(e)));
}
template <class E, size_t N>
std::optional<E> value_in(const std::pair<E, std::string_view> (&table)[N], std::string_view w) {
  for (const auto& [value, word] : table)
    if (word == w) return value;
  return std::nullopt;
}
template <class E, size_t N>
std::vector<std::string> words_in(const std::pair<E, std::string_view> (&table)[N]) {
  std::vector<std::string> out;
  for (const auto& entry : table) out.emplace_back(entry.second);
  return out;
}

std::vector<std::string> method_words() { return words_in(kMethodWords); }
std::vector<std::string> jacobian_words() { return words_in(kJacobianWords); }
std::vector<std::string> newton_words() { return words_in(kNewtonWords); }

// word → enum (nullopt: none of its words)
std::optional<Method> method_of(std::string_view w) { return value_in(kMethodWords, w); }
std::optional<FdMethod> route_of(std::string_view w) {
  for (const FdMethodInfo& info : fd_methods())
    if (info.name == w) return info.method;
  return std::nullopt;
}
std::optional<Jacobian> jacobian_of(std::string_view w) { return value_in(kJacobianWords, w); }
std::optional<Newton> newton_of(std::string_view w) { return value_in(kNewtonWords, w); }

// the WordField of an enum member of S, read by to_string and set by `of`
template <auto field, auto of>
WordField word_field() {
  return {[](const S& s) { return to_string(s.*field); },
          [](S& s, std::string_view w) {
            const auto value = of(w);
            if (value) s.*field = *value;
            return value.has_value();
          }};
}

SettingInfo real(std::string_view name, double S::*field, std::string_view unit, R range, std::string_view help) {
  return {name, K::Real, field, unit, help, range, nullptr, "", "", "", false};
}
SettingInfo word(std::string_view name, WordField field, std::vector<std::string> (*words)(), std::string_view noun,
                 std::string_view help, std::string_view old_word = "", std::string_view new_word = "") {
  return {name, K::Word, field, "", help, R::Any, words, noun, old_word, new_word, false};
}
// a setting of IntegrationSettings
SettingInfo integration(SettingInfo info) {
  info.integration = true;
  return info;
}

}  // namespace

std::string_view to_string(Method m) { return word_in(kMethodWords, m); }
std::string_view to_string(Jacobian j) { return word_in(kJacobianWords, j); }
std::string_view to_string(Newton n) { return word_in(kNewtonWords, n); }

namespace {

template <class E>
E parse_word(std::string_view name, std::string_view word, std::optional<E> (*of)(std::string_view)) {
  if (const std::optional<E> value = of(word)) return *value;
  const SettingInfo& info = *find_setting(name);
  throw Error(std::string(info.name) + ": " + setting_problem(info, std::string(word)));
}

}  // namespace

Method parse_method(std::string_view word) { return parse_word("method", word, method_of); }
Jacobian parse_jacobian(std::string_view word) { return parse_word("jacobian", word, jacobian_of); }
Newton parse_newton(std::string_view word) { return parse_word("newton", word, newton_of); }

const std::vector<SettingInfo>& setting_table() {
  static const std::vector<SettingInfo> table = {
      real("t_end", &S::t_end, "s", R::Positive, "end time"),
      real("output_dt", &S::output_dt, "s", R::Positive, "time between logged samples"),
      integration(word("method", word_field<&S::method, method_of>(), method_words, "method", "the integrator")),
      integration(real("rtol", &S::rtol, "1", R::Positive, "CVODE relative tolerance, in (0, 1)")),
      integration(real("atol", &S::atol, "1", R::Positive, "CVODE absolute tolerance (in the state's own units)")),
      integration(real("dt", &S::dt, "s", R::Positive, "fixed-step methods' step")),
      integration(real("max_step", &S::max_step, "s", R::NonNegative, "CVODE's largest step (0: none)")),
      {"max_steps", K::Count, &S::max_steps, "1", "CVODE steps allowed in the whole run", R::Positive, nullptr, "", "", "", true},
      integration(word("dynamics", word_field<&S::dynamics, route_of>(), fd_method_names, "route",
                       "forward-dynamics route (on, the old word for aba, is taken)", kFdMethodAliasOn,
                       to_string(FdMethod::ArticulatedBody))),
      integration(word("jacobian", word_field<&S::jacobian, jacobian_of>(), jacobian_words, "",
                       "cvode-bdf and implicit-midpoint: analytic derivatives or difference quotients (dq)")),
      integration(word("newton", word_field<&S::newton, newton_of>(), newton_words, "",
                       "implicit-midpoint: the Jacobian at every iterate, or once per step; variational: Newton, or O(N) chord iterations with M")),
      {"limits", K::Flag, &S::limits, "", "joint limits as events (CVODE): impact, hold, release", R::Any, nullptr, "", "", "", false},
      real("restitution", &S::restitution, "1", R::UnitInterval, "coefficient of restitution at a limit"),
      real("control_dt", &S::control_dt, "s", R::NonNegative, "time between controller samples, zero-order hold (0: continuous)"),
  };
  return table;
}

const SettingInfo* find_setting(std::string_view name) {
  for (const SettingInfo& info : setting_table())
    if (info.name == name) return &info;
  return nullptr;
}

std::string setting_problem(const SettingInfo& info, double x) {
  if (info.kind != K::Real && info.kind != K::Count) return "expected " + std::string(info.kind == K::Flag ? "true or false" : "a name");
  if (!std::isfinite(x)) return "expected a finite number";
  switch (info.range) {
    case R::Any: break;
    case R::Positive:
      if (!(x > 0)) return "expected a positive number";
      break;
    case R::NonNegative:
      if (!(x >= 0)) return "expected 0 or a positive number";
      break;
    case R::UnitInterval:
      if (!(x >= 0 && x <= 1)) return "expected a coefficient in [0, 1]";
      break;
  }
  if (info.kind == K::Count && (x != std::floor(x) || x > 1e15)) return "expected a whole number";
  return "";
}

std::string setting_problem(const SettingInfo& info, const std::string& word) {
  if (info.kind != K::Word) return "expected a number";
  if (!info.old_word.empty() && word == info.old_word) return "";
  const std::vector<std::string> words = info.words();
  if (std::find(words.begin(), words.end(), word) != words.end()) return "";
  if (!info.noun.empty()) return "unknown " + std::string(info.noun) + " '" + excerpt(word) + "'" + did_you_mean(word, words);
  std::string alternatives;
  for (size_t k = 0; k < words.size(); ++k) alternatives += (k == 0 ? "" : k + 1 == words.size() ? " or " : ", ") + words[k];
  return "expected " + alternatives + ", got '" + excerpt(word) + "'" + did_you_mean(word, words);
}

namespace {

[[noreturn]] void refuse(const SettingInfo& info, const std::string& problem) {
  throw Error(std::string(info.name) + ": " + problem);
}

}  // namespace

void set_setting(SimulationSettings& s, const SettingInfo& info, double x) {
  if (const std::string p = setting_problem(info, x); !p.empty()) refuse(info, p + ", got " + short_number(x));
  if (const auto* f = std::get_if<double S::*>(&info.field)) s.**f = x;
  else s.*std::get<long S::*>(info.field) = long(x);
}

void set_setting(SimulationSettings& s, const SettingInfo& info, const std::string& word) {
  if (const std::string p = setting_problem(info, word); !p.empty()) refuse(info, p);
  const std::string_view w = !info.old_word.empty() && word == info.old_word ? info.new_word : std::string_view(word);
  if (!std::get<WordField>(info.field).set(s, w)) refuse(info, "'" + excerpt(std::string(w)) + "' names none of its values");
}

void set_setting(SimulationSettings& s, const SettingInfo& info, bool flag) {
  if (info.kind != K::Flag) refuse(info, setting_problem(info, 0.0));
  s.*std::get<bool S::*>(info.field) = flag;
}

std::string setting_text(const SimulationSettings& s, const SettingInfo& info) {
  return std::visit(
      [&](auto field) -> std::string {
        using F = decltype(field);
        if constexpr (std::is_same_v<F, WordField>) return std::string(field.get(s));
        else if constexpr (std::is_same_v<F, bool S::*>) return s.*field ? "true" : "false";
        else {
          char buf[32];
          std::snprintf(buf, sizeof buf, "%.17g", double(s.*field));
          return buf;
        }
      },
      info.field);
}

double setting_number(const SimulationSettings& s, const SettingInfo& info) {
  if (const auto* f = std::get_if<double S::*>(&info.field)) return s.**f;
  if (const auto* f = std::get_if<long S::*>(&info.field)) return double(s.**f);
  throw Error(std::string(info.name) + ": not a number setting");
}

std::string control_ticks_problem(double t_end, double control_dt) {
  if (!(control_dt > 0) || !(t_end > 0)) return "";
  const double ticks = t_end / control_dt;
  if (ticks <= kMaxControlTicks) return "";
  return "control_dt " + short_number(control_dt) + " s over t_end " + short_number(t_end) + " s is " + short_number(ticks) +
         " controller ticks, more than the " + short_number(kMaxControlTicks) +
         " a run may take (each one restarts the integrator): raise control_dt or lower t_end";
}

}  // namespace soadyn
