// What the tests of a whole run's derivatives share (test_sensitivity, test_adjoint): tight CVODE
// settings, and a ball falling freely, whose derivatives have closed forms.
#pragma once

#include "soadyn/scenario.hpp"
#include "soadyn/settings.hpp"

#include <string>

namespace soadyn::test {

// CVODE at rtol 1e-11, atol 1e-13, t_end, four outputs
inline SimulationSettings tight(const std::string& method, double t_end) {
  SimulationSettings s;
  s.method = method;
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

}  // namespace soadyn::test
