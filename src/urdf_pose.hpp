// A urdfdom pose as a soadyn Placement (the library's URDF import and the viewer's visuals).
// Internal: it names urdfdom's types, which the public headers do not.
#pragma once

#include "soadyn/model.hpp"

#include <urdf_model/pose.h>

namespace soadyn {

// X.p = the pose's position, X.R = its rotation (the quaternion normalized)
inline Placement to_placement(const urdf::Pose& p) {
  Placement X;
  X.p = Vec3(p.position.x, p.position.y, p.position.z);
  X.R = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).normalized().toRotationMatrix();
  return X;
}

}  // namespace soadyn
