// Inside the library: the last step of the composite 𝓜, shared by the inertial sweep
// (mass_matrix.cpp) and the body-axes one (mass_matrix_local.cpp).
#pragma once

#include "soadyn/multibody/data.hpp"
#include "soadyn/multibody/model.hpp"

namespace soadyn {

// 𝓜_jk = S0_jᵀ F0_k for every DOF j on the chain of DOF k, both triangles, from Data::S0 and
// Data::F0 (each DOF's G and K G moved once to the inertial origin)
void mass_matrix_entries(const Model& model, Data& data);

}  // namespace soadyn
