// A two-link arm built in code: its mass matrix, bias and forward dynamics, checked against the
// closed form (Lagrange, θ2 relative to link 1).  Build it with find_package(soadyn) and
// soadyn::soadyn, or with `pkg-config --cflags --libs soadyn`.
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/multibody/model.hpp"

#include <cmath>
#include <cstdio>

int main() {
  // two links hinged about x, hanging along −z: the elbow l1 below the shoulder, the centres of
  // mass c1 and c2 below each hinge, J1 and J2 the moments about x through the centres of mass
  const double m1 = 2.0, m2 = 1.5, l1 = 0.8, c1 = 0.4, c2 = 0.3, J1 = 0.05, J2 = 0.03, g = 9.81;
  soadyn::BodySpec upper, lower;
  upper.name = "upper";
  upper.axis = soadyn::Vec3::UnitX();
  upper.mass = m1;
  upper.com = soadyn::Vec3(0, 0, -c1);
  upper.inertia = soadyn::Vec3(J1, 0.04, 0.02).asDiagonal();
  lower.name = "lower";
  lower.parent = 0;  // the spec list's index of the parent; −1 (the default) is the ground
  lower.axis = soadyn::Vec3::UnitX();
  lower.placement.p = soadyn::Vec3(0, 0, -l1);
  lower.mass = m2;
  lower.com = soadyn::Vec3(0, 0, -c2);
  lower.inertia = soadyn::Vec3(J2, 0.025, 0.01).asDiagonal();
  const soadyn::Model model = soadyn::Model::build({upper, lower}, soadyn::Vec3(0, 0, -g));
  soadyn::Data data(model);  // per state, sized once: the algorithms allocate nothing

  const soadyn::VecX q = Eigen::Vector2d(0.3, -0.7), v = Eigen::Vector2d(1.2, -0.4);
  const soadyn::VecX tau = Eigen::Vector2d(0.5, -0.2);
  soadyn::update_kinematics(model, data, q);   // [kin] frames, positions, inertias
  soadyn::mass_matrix(model, data);            // data.M = 𝓜(q)
  soadyn::update_velocities(model, data, v);   // [vel] v = Ψ_D G q̇
  soadyn::bias_forces(model, data);            // data.bias: Coriolis, centrifugal, gravity
  soadyn::forward_dynamics(model, data, tau, soadyn::FdMethod::ArticulatedBody);  // data.qdd, O(N)

  // the closed form
  const double c = std::cos(q[1]), h = m2 * l1 * c2 * std::sin(q[1]);
  const double g1 = (m1 * c1 + m2 * l1) * g * std::sin(q[0]), g2 = m2 * c2 * g * std::sin(q[0] + q[1]);
  Eigen::Matrix2d M;
  M(0, 0) = J1 + m1 * c1 * c1 + J2 + m2 * (l1 * l1 + c2 * c2 + 2 * l1 * c2 * c);
  M(0, 1) = M(1, 0) = J2 + m2 * (c2 * c2 + l1 * c2 * c);
  M(1, 1) = J2 + m2 * c2 * c2;
  const Eigen::Vector2d bias(-h * (2 * v[0] * v[1] + v[1] * v[1]) + g1 + g2, h * v[0] * v[0] + g2);
  const Eigen::Vector2d qdd = M.llt().solve(tau - bias);

  const double error = std::fmax((data.M - M).cwiseAbs().maxCoeff() / M.cwiseAbs().maxCoeff(),
                                 std::fmax((data.bias - bias).norm() / bias.norm(),
                                           (data.qdd - qdd).norm() / qdd.norm()));
  std::printf("M(q)   = [%.15f %.15f; %.15f %.15f]\n", data.M(0, 0), data.M(0, 1), data.M(1, 0), data.M(1, 1));
  std::printf("bias   = [%.15f %.15f]\n", data.bias[0], data.bias[1]);
  std::printf("q̈      = [%.15f %.15f]\n", data.qdd[0], data.qdd[1]);
  std::printf("largest relative difference from the closed form: %.1e\n", error);
  return error < 1e-12 ? 0 : 1;
}
