// 𝓜⁻¹ about the inertial origin (minverse.cpp), for minverse and forward_dynamics_derivatives,
// which has S already.
#pragma once

#include "soadyn/multibody/data.hpp"
#include "soadyn/multibody/model.hpp"

namespace soadyn::detail {

// 𝓜⁻¹ into Minv (nv×nv, full) from S (6×nv: each G_k moved to the inertial origin, [a; b + η × a]).
// Needs [kin]; works in data.work.origin.
void minverse_origin(const Model& model, Data& data, const Mat6X& S, MatX& Minv);

}  // namespace soadyn::detail
