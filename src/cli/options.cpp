// The options several commands share: lists of numbers, the model options (StateOptions) and
// the choices that answer a typo with the nearest name.
#include "cli.hpp"

#include "soadyn/io/scenario_file.hpp"
#include "soadyn/multibody/text.hpp"
#include "soadyn/multibody/configuration.hpp"
#include "soadyn/sim/scenario.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <tuple>

namespace soadyn::cli {

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

std::vector<std::string> join_negative_values(int argc, char** argv) {
  static const std::vector<std::string> list_options = {"--q", "--qd", "--tau", "--gravity"};
  std::vector<std::string> out;
  for (int k = 0; k < argc; ++k) {
    const std::string a = argv[k];
    const bool takes_list = std::find(list_options.begin(), list_options.end(), a) != list_options.end();
    if (takes_list && k + 1 < argc && argv[k + 1][0] == '-') {
      out.push_back(a + "=" + argv[k + 1]);
      ++k;
    } else {
      out.push_back(a);
    }
  }
  return out;
}

std::vector<double> parse_list(const std::string& option, const std::string& text) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  int k = 0;
  while (std::getline(ss, item, ',')) {
    const size_t b = item.find_first_not_of(" \t"), e = item.find_last_not_of(" \t");
    const std::string t = b == std::string::npos ? "" : item.substr(b, e - b + 1);
    char* end = nullptr;
    const double x = t.empty() ? 0.0 : std::strtod(t.c_str(), &end);
    if (t.empty() || *end != '\0' || !std::isfinite(x))
      throw Error(option + ": item " + std::to_string(k + 1) + ": expected a finite number, got '" + t + "'");
    out.push_back(x);
    ++k;
  }
  if (!text.empty() && text.back() == ',') throw Error(option + ": trailing comma in '" + text + "'");
  return out;
}

std::string join(const std::vector<std::string>& items, const std::string& separator) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : separator) + s;
  return out;
}

VecX vector_option(const std::string& option, const std::string& text, int size, const VecX& fallback) {
  if (text.empty()) return fallback;
  const auto v = parse_list(option, text);
  if (int(v.size()) != size)
    throw Error(option + ": expected " + std::to_string(size) + " numbers, got " + std::to_string(v.size()));
  return Eigen::Map<const VecX>(v.data(), size);
}

void add_state_options(CLI::App* c, StateOptions& o, const std::string& what) {
  c->add_option("--q", o.q, "configuration of " + what + ", comma-separated, nq numbers (free root: x,y,z,qw,qx,qy,qz first)");
  c->add_option("--qd", o.qd, "velocities of " + what + ", comma-separated, nv numbers (free root: wx,wy,wz,vx,vy,vz first)");
  c->add_option("--gravity", o.gravity, "gravity gx,gy,gz in m/s^2 (default: the scenario's; 0,0,-9.81 for a URDF)");
  c->add_flag("--free-root", o.free_root, "give a URDF's root link a free joint instead of welding it to the world");
  c->add_option("--inertia-check", o.inertia_check,
                "inertias breaking the triangle inequality: warn (load those within 5 % with a warning, "
                "refuse the rest; default), balance (make them physical), strict (refuse them)")
      ->transform(one_of({"warn", "balance", "strict"}));
}

Scenario load_with_options(const std::string& path, const StateOptions& o) {
  std::optional<Vec3> gravity;
  if (!o.gravity.empty()) gravity = Vec3(vector_option("--gravity", o.gravity, 3, Vec3::Zero()));
  const std::optional<InertiaCheck> check =
      o.inertia_check.empty() ? std::nullopt : parse_inertia_check(o.inertia_check);
  Scenario sc = load_scenario(path, o.free_root, gravity, check);
  for (const std::string& w : sc.model.warnings) std::fprintf(stderr, "soadyn: warning: %s: %s\n", path.c_str(), w.c_str());
  return sc;
}

void state_from_options(const Model& m, const StateOptions& o, VecX& q, VecX& v) {
  q = vector_option("--q", o.q, m.nq, q);
  for (int i = 0; i < m.nbodies; ++i)
    if (const int k = joint_quaternion(m, i); k >= 0) {
      const double norm = q.segment<4>(m.idx_q[i] + k).norm();
      if (std::abs(norm - 1.0) > 1e-6)
        throw Error("--q: joint '" + m.joint_names[i] + "': expected a unit quaternion, got norm " + exact_number(norm));
    }
  m.normalize(q);
  v = vector_option("--qd", o.qd, m.nv, v);
  for (const auto& [option, x, names] : {std::tuple{"--q", &q, m.q_names()}, std::tuple{"--qd", &v, m.v_names()}})
    for (Eigen::Index k = 0; k < x->size(); ++k)
      if (std::abs((*x)(k)) > kMaxStateMagnitude)
        throw Error(std::string(option) + ": " + names[size_t(k)] + " = " +
                    short_number((*x)(k)) + ": expected |value| <= " + short_number(kMaxStateMagnitude) + " (m, rad, m/s or rad/s)");
}

CLI::Validator one_of(const std::vector<std::string>& names) {
  return CLI::Validator(
      [names](std::string& value) -> std::string {
        for (const std::string& n : names)
          if (lower(n) == lower(value)) {
            value = n;
            return "";
          }
        return "expected " + join(names, " | ") + ", got '" + printable(value) + "'" + did_you_mean(value, names);
      },
      "{" + join(names, ",") + "}");
}

std::string option_suggestion(CLI::App& app, const std::vector<std::string>& args) {
  // the command the arguments name (the first that is one), else the top level
  CLI::App* command = &app;
  std::vector<std::string> commands;
  for (CLI::App* sub : app.get_subcommands({})) commands.push_back(sub->get_name());
  for (const std::string& a : args) {
    if (a.empty() || a[0] == '-') continue;
    for (CLI::App* sub : app.get_subcommands({}))
      if (sub->get_name() == a) command = sub;
    if (command == &app) {  // the first word is not a command
      const std::string hint = did_you_mean(a, commands);
      if (!hint.empty()) return "'" + printable(a) + "' is not a soadyn command" + hint;
    }
    break;
  }
  std::vector<std::string> names;
  for (const CLI::Option* opt : command->get_options()) {
    for (const std::string& l : opt->get_lnames()) names.push_back("--" + l);
    for (const std::string& s : opt->get_snames()) names.push_back("-" + s);
  }
  for (const std::string& a : args) {
    if (a.size() < 2 || a[0] != '-' || a == "--") continue;
    const std::string name = a.substr(0, a.find('='));
    if (std::find(names.begin(), names.end(), name) != names.end()) continue;
    if (std::isdigit(static_cast<unsigned char>(name[1])) || name[1] == '.') continue;  // a value: -1, -.5
    const std::string hint = did_you_mean(name, names);
    if (!hint.empty()) return "'" + printable(name) + "' is not an option of " +
                              (command == &app ? std::string("soadyn") : "soadyn " + command->get_name()) + hint;
  }
  return "";
}

}  // namespace soadyn::cli
