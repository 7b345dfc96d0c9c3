// The articulated-body recursion: O(N) forward dynamics (the factored inverse mass matrix), whose
// factor articulated_solve reuses (algorithms.hpp).
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "dynamics_routes.hpp"
#include "multibody/articulated_inertia.hpp"
#include "articulated_factor.hpp"
#include "joint_inertial.hpp"

namespace soadyn {

namespace detail {

void aba(const Model& model, Data& data, const VecX& tau) {
  // tip to base: articulated inertias P_i and bias forces z_i
  for (int i = 0; i < model.nbodies; ++i) {
    // P_i = M_i = [I, h̃; h̃ᵀ, m e] (in place entry by entry: a tenth of this sweep's time otherwise)
    const SpatialInertia& M = data.inertia[i];
    articulated_inertia::set_inertia(data.work.articulated.P[i], M.I, M.h, M.m);
    data.work.articulated.z.col(i) = data.gyroscopic.col(i);
  }
  for (int i = model.nbodies - 1; i >= 0; --i)
    visit_joint(model, i, [&](const auto& j) { detail::aba_backward_step<std::decay_t<decltype(j)>>(model, data, tau, i); });
  // base to tip: A' = D_i A_p + a_i,  q̈_i = 𝒟⁻¹ (u_i − U_iᵀ A'),  A_i = A' + G_i q̈_i
  for (int i = 0; i < model.nbodies; ++i)
    visit_joint(model, i, [&](const auto& j) { detail::aba_forward_step<std::decay_t<decltype(j)>>(model, data, i); });
}

}  // namespace detail

}  // namespace soadyn
