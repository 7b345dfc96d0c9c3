// A planar four-bar closed by a hinge, at a closed configuration and moving on its loop: shared by
// the loop tests of the algorithm (test_loops) and of a run (test_loops_run); and two closed scenes
// run side by side (test_loop_mechanisms, test_mjcf_loops).
#pragma once

#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/algorithm/loops.hpp"
#include "soadyn/multibody/model.hpp"
#include "soadyn/sim/simulate.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>

#include <algorithm>

#include <cmath>
#include <vector>

namespace soadyn::test {

// a planar four-bar in the xy plane: crank (ground pivot O, length a), coupler (b), rocker (ground
// pivot at x = g, length c), the coupler's end hinged to the rocker's about z; link i of mass
// 1 + i/2 with its centre of mass halfway, Izz = m L²/12; closed at crank angle θ (the open
// branch), moving at crank rate ω.  The default shape is a crank-rocker.
struct FourBarShape {
  double a = 0.3, b = 1.0, c = 0.8, g = 0.9;
  Vec3 gravity = Vec3(0, -9.81, 0);
};
struct FourBar {
  Model model;
  std::vector<LoopConstraint> loops;
  VecX q, v;
};

inline FourBar four_bar(double theta, double omega, const FourBarShape& shape = {}) {
  const double a = shape.a, b = shape.b, c = shape.c, g = shape.g;
  std::vector<BodySpec> s(3);
  const char* names[] = {"crank", "coupler", "rocker"};
  const double len[] = {a, b, c};
  for (int i = 0; i < 3; ++i) {
    s[size_t(i)].name = names[i];
    s[size_t(i)].mass = 1.0 + 0.5 * i;
    s[size_t(i)].com = Vec3(len[i] / 2, 0, 0);
    s[size_t(i)].inertia = Vec3(0.001, s[size_t(i)].mass * len[i] * len[i] / 12, s[size_t(i)].mass * len[i] * len[i] / 12).asDiagonal();
  }
  s[1].parent = 0, s[1].placement.p = Vec3(a, 0, 0);
  s[2].placement.p = Vec3(g, 0, 0);
  FourBar f;
  f.model = Model::build(s, shape.gravity);
  LoopConstraint hinge;
  hinge.name = "closing";
  hinge.type = LoopType::Hinge;
  hinge.body_a = 1, hinge.at_a.p = Vec3(b, 0, 0);
  hinge.body_b = 2, hinge.at_b.p = Vec3(c, 0, 0);
  f.loops.push_back(hinge);
  // the joint C where |C − B| = b and |C − D| = c, B the crank's end, D the rocker's pivot
  const Eigen::Vector2d B(a * std::cos(theta), a * std::sin(theta)), D(g, 0);
  const double r = (D - B).norm(), x = (b * b - c * c + r * r) / (2 * r), y = std::sqrt(b * b - x * x);
  const Eigen::Vector2d u = (D - B) / r, C = B + x * u + y * Eigen::Vector2d(-u.y(), u.x());
  const double coupler = std::atan2(C.y() - B.y(), C.x() - B.x()), rocker = std::atan2(C.y(), C.x() - g);
  f.q = Eigen::Vector3d(theta, coupler - theta, rocker);
  // v in K's null space with the crank at ω
  Data d(f.model);
  update_kinematics(f.model, d, f.q);
  update_velocities(f.model, d, VecX::Zero(3));
  LoopData ld(f.model, f.loops);
  loop_rows(f.model, d, f.loops, ld);
  Eigen::FullPivLU<MatX> lu(ld.K);
  lu.setThreshold(1e-10);
  const MatX kernel = lu.kernel();
  f.v = kernel.col(0) * (omega / kernel(0, 0));
  return f;
}

// Two scenes, each run with its own settings, compared sample by sample: the largest |q_a − q_b|,
// how far a's q moved from its first sample, and a's run (a fatal failure where either run does not
// complete or their samples differ in number)
struct MotionGap {
  double gap = 0.0, moved = 0.0;
  size_t samples = 0;
  double t_end = 0.0;
  RunSummary run_a;
};
inline void motion_gap(const Scenario& a, const Scenario& b, MotionGap& out) {
  std::vector<Sample> sa, sb;
  out.run_a = simulate(a, a.simulation, nullptr, &sa);
  const RunSummary rb = simulate(b, b.simulation, nullptr, &sb);
  ASSERT_TRUE(out.run_a.completed) << out.run_a.status;
  ASSERT_TRUE(rb.completed) << rb.status;
  ASSERT_EQ(sa.size(), sb.size());
  for (size_t k = 0; k < sa.size(); ++k) {
    out.gap = std::max(out.gap, (sa[k].q - sb[k].q).cwiseAbs().maxCoeff());
    out.moved = std::max(out.moved, (sa[k].q - sa[0].q).cwiseAbs().maxCoeff());
  }
  out.samples = sa.size();
  out.t_end = sa.back().t;
}

}  // namespace soadyn::test
