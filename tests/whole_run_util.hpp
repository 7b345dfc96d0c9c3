// What the tests of a whole run's derivatives share (test_sensitivity, test_adjoint): tight CVODE
// settings, a ball falling freely (its derivatives have closed forms) and two seeded random scenes.
#pragma once

#include "soadyn/sim/scenario.hpp"
#include "soadyn/sim/settings.hpp"
#include "test_util.hpp"

#include <string>

namespace soadyn::test {

// CVODE at rtol 1e-11, atol 1e-13, t_end, four outputs
inline SimulationSettings tight(const std::string& method, double t_end) {
  SimulationSettings s;
  s.method = parse_method(method);
  s.t_end = t_end;
  s.output_dt = t_end / 4;
  s.rtol = 1e-11;
  s.atol = 1e-13;
  return s;
}

// a 2 kg ball on a free joint, its centre of mass at the frame's origin, gravity −9.81 e_z, from
// (0.5, −1, 3) m at (1, 0, 2) m/s, no spin
inline Scenario falling_ball() {
  BodySpec b;
  b.name = "ball";
  b.joint = JointType::Free;
  b.mass = 2.0;
  b.inertia = Vec3(0.1, 0.1, 0.1).asDiagonal();
  Scenario sc;
  sc.path = "ball";
  sc.model = Model::build({b}, Vec3(0, 0, -9.81));
  sc.q0 = sc.model.neutral_configuration();
  sc.q0.head(3) = Vec3(0.5, -1.0, 3.0);
  sc.v0 = VecX::Zero(6);
  sc.v0.tail(3) = Vec3(1.0, 0.0, 2.0);
  return sc;
}

// a seeded random chain of 4 (a quarter prismatic) with a spring and a damper on its first joints
// and a sinusoidal torque on the last, so that ∂τ/∂x comes from Inputs too
inline Scenario random_chain_with_inputs() {
  Rng rng(7);
  Scenario sc;
  sc.path = "random chain";
  sc.model = random_model(rng, {.n = 4, .branching = 0.0, .prismatic = 0.25});
  sc.q0 = random_q(rng, sc.model);
  sc.v0 = random_v(rng, sc.model);
  sc.inputs.springs.push_back({"", 0, 0, 3.0, 0.2});
  sc.inputs.dampers.push_back({"", 1, 0.4});
  sc.inputs.torques.push_back({"", 3, 0.3, 0.5, 1.5, 0.2});
  return sc;
}

// a seeded random tree of 3 on a free root, a third of its joints ball joints
inline Scenario random_free_tree() {
  Rng rng(11);
  Scenario sc;
  sc.path = "random free tree";
  sc.model = random_model(rng, {.n = 3, .branching = 0.5, .ball = 0.34, .free_root = true});
  sc.q0 = random_q(rng, sc.model);
  sc.v0 = random_v(rng, sc.model);
  return sc;
}

}  // namespace soadyn::test
