// A scenario's `simulation: sensitivities: {initial_state: true, parameters: [link2, link3] | all}`
// (sensitivity.hpp, scenarios/README.md).
#include "scenario_reader.hpp"

#include <algorithm>

namespace soadyn::scenario_detail {

void read_sensitivities(const Reader& rd, const YAML::Node& n, const Model& m, SensitivitySettings& out) {
  const std::string f = "simulation.sensitivities";
  if (!n.IsMap()) rd.fail(n, f, "expected a map {initial_state: true, parameters: [body, ...] | all}, got " + Reader::show(n));
  rd.keys(n, f, {"initial_state", "parameters"});
  if (n["initial_state"]) out.initial_state = rd.boolean(n["initial_state"], f + ".initial_state");
  const YAML::Node p = n["parameters"];
  if (!p) return;
  const std::string fp = f + ".parameters";
  if (p.IsScalar()) {
    const std::string word = rd.string(p, fp);
    if (word != "all") rd.fail(p, fp, "expected a list of body names or 'all', got '" + excerpt(word) + "'");
    out.parameters = {"all"};
    return;
  }
  if (!p.IsSequence()) rd.fail(p, fp, "expected a list of body names or 'all', got " + Reader::show(p));
  for (size_t k = 0; k < p.size(); ++k) {
    const std::string fk = fp + "[" + std::to_string(k) + "]";
    const std::string name = rd.string(p[k], fk);
    if (std::find(m.body_names.begin(), m.body_names.end(), name) == m.body_names.end())
      rd.fail(p[k], fk, "no body named '" + excerpt(name) + "'" + did_you_mean(name, m.body_names) +
                            " (the bodies after fixed joints are merged)");
    if (std::find(out.parameters.begin(), out.parameters.end(), name) != out.parameters.end())
      rd.fail(p[k], fk, "body '" + excerpt(name) + "' listed twice");
    out.parameters.push_back(name);
  }
}

}  // namespace soadyn::scenario_detail
