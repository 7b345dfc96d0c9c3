// Shared test helpers: seeded random trees and states, tolerance checks, dense references.
#pragma once

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/multibody/model.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <string>
#include <numeric>
#include <random>

namespace soadyn::test {

// |a − b| ≤ tol · max(1, |b|) elementwise-max sense: ‖a − b‖_max ≤ tol · max(1, ‖b‖_max)
// what f throws as soadyn::Error, or "(no error)"
inline std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

inline ::testing::AssertionResult near_rel(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double tol) {
  if (a.rows() != b.rows() || a.cols() != b.cols())
    return ::testing::AssertionFailure() << "shape " << a.rows() << "x" << a.cols() << " vs " << b.rows() << "x"
                                         << b.cols();
  const double scale = std::max(1.0, b.cwiseAbs().maxCoeff());
  const double err = (a - b).cwiseAbs().maxCoeff();
  if (err <= tol * scale) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "max abs error " << err << " > " << tol << " * " << scale << "\n"
                                       << "got:\n" << a << "\nexpected:\n" << b;
}

struct Rng {
  std::mt19937_64 gen;
  explicit Rng(std::uint64_t seed) : gen(seed) {}
  double uniform(double lo = -1.0, double hi = 1.0) { return std::uniform_real_distribution<double>(lo, hi)(gen); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(gen); }
  Vec3 vec3(double lo = -1.0, double hi = 1.0) { return {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)}; }
  Mat3 rotation() {
    Eigen::Quaterniond q(uniform(), uniform(), uniform(), uniform());
    return q.normalized().toRotationMatrix();
  }
  // a physically valid inertia: principal moments from a random mass distribution, random axes
  Mat3 inertia() {
    const Vec3 sq = vec3(0.05, 1.0);  // second moments Σ m x², Σ m y², Σ m z²
    const Vec3 l(sq.y() + sq.z(), sq.x() + sq.z(), sq.x() + sq.y());
    const Mat3 R = rotation();
    return R * l.asDiagonal() * R.transpose();
  }
};

struct TreeOptions {
  int n = 10;
  double branching = 0.5;        // 0: a chain; 1: parents drawn uniformly from all earlier bodies
  double prismatic = 0.0;        // fraction of prismatic joints
  double ball = 0.0;             // fraction of ball joints
  double planar = 0.0;           // fraction of planar joints
  double helical = 0.0;          // fraction of helical joints (pitch uniform in [−0.3, 0.3] m/rad)
  bool free_root = false;
  int fixed = 0;                 // extra bodies attached by fixed joints
  double unit_axis = 0.0;        // fraction of axes along ±x, ±y or ±z (half of them with an
                                 // unturned placement): the specialized kinematics' path
  Vec3 gravity = Vec3(0, 0, -9.81);
};

// a named set of tree options: one case of a parameterized test over random trees
struct TreeCase {
  const char* name;
  TreeOptions options;
  friend void PrintTo(const TreeCase& c, std::ostream* os) { *os << c.name; }
};

inline std::vector<BodySpec> random_specs(Rng& rng, const TreeOptions& o) {
  std::vector<BodySpec> specs;
  const int total = o.n + o.fixed;
  std::vector<int> fixed_slots(std::max(total - 1, 0));  // distinct bodies 1..total−1
  std::iota(fixed_slots.begin(), fixed_slots.end(), 1);
  std::shuffle(fixed_slots.begin(), fixed_slots.end(), rng.gen);
  fixed_slots.resize(std::min<size_t>(o.fixed, fixed_slots.size()));
  for (int i = 0; i < total; ++i) {
    BodySpec b;
    b.name = std::string("b").append(std::to_string(i));
    b.parent = i == 0 ? -1 : (rng.uniform(0, 1) < o.branching ? rng.integer(0, i - 1) : i - 1);
    const bool is_fixed = i > 0 && std::find(fixed_slots.begin(), fixed_slots.end(), i) != fixed_slots.end();
    if (i == 0 && o.free_root) b.joint = JointType::Free;
    else if (is_fixed) b.joint = JointType::Fixed;
    else {
      const double u = rng.uniform(0, 1);
      b.joint = u < o.prismatic                        ? JointType::Prismatic
                : u < o.prismatic + o.ball             ? JointType::Ball
                : u < o.prismatic + o.ball + o.planar ? JointType::Planar
                : u < o.prismatic + o.ball + o.planar + o.helical ? JointType::Helical
                                                       : JointType::Revolute;
      if (b.joint == JointType::Helical) b.pitch = rng.uniform(-0.3, 0.3);
    }
    b.axis = rng.vec3().normalized() * rng.uniform(0.5, 2.0);
    if (b.joint != JointType::Free) b.placement = {rng.rotation(), rng.vec3(-0.6, 0.6)};
    if (o.unit_axis > 0.0 && rng.uniform(0, 1) < o.unit_axis) {
      b.axis = (rng.uniform(0, 1) < 0.5 ? 1.0 : -1.0) * rng.uniform(0.5, 2.0) * Vec3::Unit(rng.integer(0, 2));
      if (b.joint != JointType::Free && rng.uniform(0, 1) < 0.5) b.placement.R.setIdentity();
    }
    b.mass = rng.uniform(0.2, 3.0);
    b.com = rng.vec3(-0.4, 0.4);
    b.inertia = rng.inertia();
    specs.push_back(b);
  }
  return specs;
}

inline Model random_model(Rng& rng, const TreeOptions& o) { return Model::build(random_specs(rng, o), o.gravity); }

inline VecX random_q(Rng& rng, const Model& m) {
  VecX q(m.nq);
  for (int i = 0; i < m.nq; ++i) q(i) = rng.uniform(-2.0, 2.0);
  m.normalize(q);
  return q;
}

// 𝓜 at q by the note's literal procedure and by the composite sweep, after update_kinematics
struct Computed {
  MatX literal, composite;
};

inline Computed both(const Model& model, Data& data, const VecX& q) {
  update_kinematics(model, data, q);
  Computed c;
  mass_matrix_literal(model, data, c.literal);
  mass_matrix(model, data);
  c.composite = data.M;
  return c;
}

// bias(q, q̇) by the staged inertial route: update_kinematics, update_velocities, bias_forces
inline VecX bias_at(const Model& model, const VecX& q, const VecX& v) {
  Data d(model);
  update_kinematics(model, d, q);
  update_velocities(model, d, v);
  bias_forces(model, d);
  return d.bias;
}

inline VecX random_v(Rng& rng, const Model& m, double scale = 1.0) {
  VecX v(m.nv);
  for (int i = 0; i < m.nv; ++i) v(i) = scale * rng.uniform();
  return v;
}

}  // namespace soadyn::test
