// The O(N) sweeps the derivatives of inverse and forward dynamics are made of (derivatives.cpp):
// S, v, a, f, the composites Y and B, τ, the rows [Y_i S_r; B_iᵀ S_r] and per column κ, β, λ, φ,
// ψ, ρ, all into a DerivativeData; `where` names the caller in its errors.
#pragma once

#include "soadyn/algorithm/derivatives.hpp"

namespace soadyn::detail {

void derivative_sweeps(const Model& model, const Data& data, const VecX& qd, const VecX& qdd, DerivativeData& dd,
                       const char* where);

}  // namespace soadyn::detail
