// Where a scenario file gives the fields a run may refuse in combination (limits: true with a
// fixed-step method, a start beyond a joint's limit, sensitivities a run cannot differentiate):
// Scenario::locations, so that check_run (simulate.cpp) refuses them naming the file, the line and
// the field, whatever gave the other half (the file, --method on the command line, Python).
#include "scenario_reader.hpp"

#include "soadyn/sim/scenario.hpp"

namespace soadyn::scenario_detail {

namespace {

// root[a][b]…, or an undefined node where a key is missing (reset, not =: a YAML::Node's = writes
// into the node it refers to)
YAML::Node find(const YAML::Node& root, std::initializer_list<std::string> keys) {
  YAML::Node n;
  n.reset(root);
  for (const std::string& k : keys) {
    const YAML::Node& here = n;  // the const operator[]: a missing key is not added
    if (!here.IsDefined() || !here.IsMap() || !here[k]) return YAML::Node(YAML::NodeType::Undefined);
    const YAML::Node next = here[k];
    n.reset(next);
  }
  return n;
}

}  // namespace

void record_locations(const Reader& rd, const YAML::Node& root, Scenario& sc) {
  auto put = [&](const std::string& field, const YAML::Node& n) {
    const YAML::Mark m = n.Mark();
    if (n.IsDefined() && m.line >= 0)
      sc.locations[field] = rd.file + ":" + std::to_string(m.line + 1) + ":" + std::to_string(m.column + 1);
  };
  put("simulation.limits", find(root, {"simulation", "limits"}));
  put("simulation.sensitivities", find(root, {"simulation", "sensitivities"}));
  put("loops", find(root, {"loops"}));
  for (const std::string& joint : sc.model.joint_names) {
    put("initial.q." + joint, find(root, {"initial", "q", joint}));
    put("limits." + joint, find(root, {"limits", joint}));
    put("prescribed." + joint, find(root, {"prescribed", joint}));
  }
}

}  // namespace soadyn::scenario_detail
