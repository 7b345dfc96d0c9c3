// The O(N) articulated-body route, for forward_dynamics (dynamics.cpp) to call: it lives with the
// factor it shares with minverse (articulated.cpp).
#pragma once

#include "soadyn/data.hpp"
#include "soadyn/model.hpp"

namespace soadyn::detail {

// q̈ = 𝓜⁻¹ (τ − bias) into data.qdd, leaving the articulated-body factor in Data (articulated_solve.cpp reuses it)
void aba(const Model& model, Data& data, const VecX& tau);

}  // namespace soadyn::detail
