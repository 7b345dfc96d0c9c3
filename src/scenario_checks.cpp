// The combinations of a scenario's sections a run refuses, refused where the file says them
// (file:line:column: field): limits: true with a fixed-step method, a start beyond a joint's
// limit, sensitivities with a fixed-step method, a controller or enforced limits.  check_run
// (simulate.cpp) checks the same again before any run, for settings given elsewhere (the command
// line, Python).
#include "scenario_reader.hpp"

#include "soadyn/integrators.hpp"
#include "soadyn/limits.hpp"
#include "soadyn/scenario.hpp"

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

// where a joint's start is given: initial.q.J, else limits.J, else simulation.limits
std::pair<YAML::Node, std::string> start_of(const YAML::Node& root, const std::string& joint) {
  if (const YAML::Node n = find(root, {"initial", "q", joint}); n.IsDefined()) return {n, "initial.q." + joint};
  if (const YAML::Node n = find(root, {"limits", joint}); n.IsDefined()) return {n, "limits." + joint};
  const YAML::Node n = find(root, {"simulation", "limits"});
  return {n.IsDefined() ? n : root, "simulation.limits"};
}

}  // namespace

void check_combinations(const Reader& rd, const YAML::Node& root, const Scenario& sc) {
  const YAML::Node sim = find(root, {"simulation"});
  if (!sim.IsDefined()) return;  // the defaults: no limits enforced, no sensitivities
  const SimulationSettings& s = sc.simulation;
  const Model& m = sc.model;
  const bool fixed = find_integrator(s.method).fixed_step;
  const std::string method(to_string(s.method));
  if (s.limits && m.has_limits()) {
    YAML::Node at = find(sim, {"limits"});
    if (!at.IsDefined()) at = sim;
    if (fixed)
      rd.fail(at, "simulation.limits", "true needs an integrator that locates events (cvode-adams or cvode-bdf); " +
                                           method + " (simulation.method) takes fixed steps");
    try {
      JointLimits(m, s.restitution).check_inside(sc.q0);
    } catch (const Error& e) {
      // the first 1-DOF joint outside its range (the one check_inside names, past its rounding)
      for (int i = 0; i < m.nbodies; ++i) {
        if (m.nv_i[size_t(i)] != 1 || m.nq_i[size_t(i)] != 1) continue;
        const double q = sc.q0(m.idx_q[size_t(i)]);
        const int k = m.idx_v[size_t(i)];
        if (q >= m.lower[size_t(k)] && q <= m.upper[size_t(k)]) continue;
        const auto [node, field] = start_of(root, m.joint_names[size_t(i)]);
        rd.fail(node, field, e.what());
      }
      rd.fail(at, "simulation.limits", e.what());
    }
  }
  if (s.sensitivities.any()) {
    YAML::Node at = find(sim, {"sensitivities"});
    if (!at.IsDefined()) at = sim;
    const std::string f = "simulation.sensitivities";
    if (fixed)
      rd.fail(at, f, "need a CVODE method (cvode-adams or cvode-bdf): " + method +
                         " (simulation.method) takes fixed steps and its variational equation is not stepped");
    if (!sc.inputs.controllers.empty())
      rd.fail(at, f, "a run with a controller (inputs.controllers) is not differentiated (its dtau/dx is not): remove the controller");
    if (s.limits && m.has_limits())
      rd.fail(at, f, "enforced joint limits (simulation.limits: true) are events where the state jumps, not differentiated: "
                     "set limits: false");
  }
}

}  // namespace soadyn::scenario_detail
