// Routes inside the library: the O(N) articulated-body route, for forward_dynamics (dynamics.cpp) to
// call (it lives with the factor it shares with minverse, articulated.cpp); and the frames of q
// written into the body-axes workspace, for the 𝓜 route that must leave [kin] as it was.
#pragma once

#include "soadyn/multibody/data.hpp"
#include "soadyn/multibody/model.hpp"

namespace soadyn::detail {

// q̈ = 𝓜⁻¹ (τ − bias) into data.qdd, leaving the articulated-body factor in Data (articulated_solve.cpp reuses it)
void aba(const Model& model, Data& data, const VecX& tau);

// update_frames(q) into out.R, out.eta, out.d, out.G instead of [kin] (kinematics.cpp)
void update_frames(const Model& model, Data& data, const VecX& q, Workspace::BodyAxes& out);

}  // namespace soadyn::detail
