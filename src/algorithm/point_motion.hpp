// A body point's acceleration from the joints' along its chain alone (kinematics.cpp), for the
// frames' accelerations and the listed bodies' regressor columns, O(depth) each.
#pragma once

#include "soadyn/multibody/data.hpp"
#include "soadyn/multibody/model.hpp"

namespace soadyn::detail {

// α and p̈ of body b's point p for joint accelerations qdd (nullptr: q̈ = 0), gravity not included
// (b = −1, the world: zero).  Needs [kin] and [vel].
void point_acceleration(const Model& model, const Data& data, int b, const Vec3& p, const VecX* qdd, Vec3& alpha,
                        Vec3& pdd);

}  // namespace soadyn::detail
