// The benchmark mechanisms (so results compare with other libraries):
//   chain: N bodies in series, revolute joints; joint 1 at the origin, every later joint at
//          (0.3, 0, 0) in its parent's frame; axes cycling z, y, x; every link mass 1, centre of
//          mass (0.15, 0, 0), inertia diag(0.01, 0.02, 0.03); gravity (0, 0, −9.81).
//   binary tree: the same links, parent of body i is body ⌊(i−1)/2⌋.
//   legged: a free trunk and legs of those links (make_legged; C++ benchmarks only).
#pragma once

#include "soadyn/multibody/model.hpp"

#include <random>

namespace soadyn::bench {

inline Model make_tree(int n, bool binary) {
  std::vector<BodySpec> specs(n);
  const Vec3 axes[3] = {Vec3::UnitZ(), Vec3::UnitY(), Vec3::UnitX()};
  for (int i = 0; i < n; ++i) {
    BodySpec& b = specs[i];
    b.name = "link" + std::to_string(i + 1);
    b.joint_name = "joint" + std::to_string(i + 1);
    b.parent = i == 0 ? -1 : (binary ? (i - 1) / 2 : i - 1);
    b.joint = JointType::Revolute;
    b.axis = axes[i % 3];
    if (i > 0) b.placement.p = Vec3(0.3, 0, 0);
    b.mass = 1.0;
    b.com = Vec3(0.15, 0, 0);
    b.inertia = Vec3(0.01, 0.02, 0.03).asDiagonal();
  }
  return Model::build(specs, Vec3(0, 0, -9.81));
}

// A free-floating legged robot: a 10 kg trunk on a free joint and `legs` legs of `n` links each
// (the chain's links, hips at the trunk's corners, axes cycling x, y, y as hip and knee joints do).
inline Model make_legged(int legs, int n) {
  std::vector<BodySpec> specs;
  BodySpec trunk;
  trunk.name = "trunk";
  trunk.joint = JointType::Free;
  trunk.mass = 10.0;
  trunk.inertia = Vec3(0.1, 0.3, 0.35).asDiagonal();
  specs.push_back(trunk);
  const Vec3 axes[3] = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitY()};
  for (int l = 0; l < legs; ++l)
    for (int i = 0; i < n; ++i) {
      BodySpec b;
      b.name = "leg" + std::to_string(l) + "_" + std::to_string(i);
      b.parent = i == 0 ? 0 : int(specs.size()) - 1;
      b.axis = axes[i % 3];
      b.placement.p = i == 0 ? Vec3(l < 2 ? 0.3 : -0.3, l % 2 ? 0.1 : -0.1, 0) : Vec3(0.3, 0, 0);
      b.mass = 1.0;
      b.com = Vec3(0.15, 0, 0);
      b.inertia = Vec3(0.01, 0.02, 0.03).asDiagonal();
      specs.push_back(b);
    }
  return Model::build(specs, Vec3(0, 0, -9.81));
}

inline VecX random_vector(int n, unsigned seed, double scale = 1.0) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-scale, scale);
  VecX v(n);
  for (int k = 0; k < n; ++k) v(k) = u(gen);
  return v;
}

}  // namespace soadyn::bench
