// Hybrid dynamics (Featherstone, RBDA ch. 9): q̈ given at some joints (prescribed motion), τ at the
// others, both unknowns from one O(N) recursion: the articulated-body sweeps with the prescribed
// joints locked at their known acceleration.  At a prescribed joint i nothing is projected out of
// the articulated inertia (P⁺_i = P_i, the joint passes its whole inertia to its parent) and its
// known G_i q̈*_i joins the velocity-product acceleration 𝔞_i; on the way out
// A_i = D_i A_p + 𝔞_i + G_i q̈*_i and τ_i = G_iᵀ (P_i A_i + z_i), the torque that holds the motion.
#pragma once

#include "soadyn/algorithm/derivatives.hpp"
#include "soadyn/algorithm/inputs.hpp"
#include "soadyn/multibody/data.hpp"
#include "soadyn/multibody/model.hpp"

#include <vector>

namespace soadyn {

// Which joints have their motion given: locked[i] ≠ 0 for body i's joint (any kind).
struct PrescribedJoints {
  std::vector<char> locked;  // per body
  int nv_locked = 0;         // the locked joints' DOFs
  PrescribedJoints() = default;
  PrescribedJoints(const Model& model, const std::vector<int>& bodies);
  bool any() const { return nv_locked > 0; }
  bool dof_locked(const Model& model, int k) const { return locked[size_t(model.dof_body[size_t(k)])] != 0; }
};

// Needs [kin] and [vel].  tau (nv): the free joints' τ (the prescribed entries are not read);
// qdd_given (nv): the prescribed joints' q̈* (the free entries are not read).  Fills data.qdd (free
// entries solved, prescribed ones copied from qdd_given) and tau_out (nv: the free entries copied
// from tau, the prescribed ones the τ that holds q̈*).  Leaves in data.work.articulated the factor
// with the prescribed joints locked (U_i = 0, 𝒟_i⁻¹ = 0 there), so that articulated_solve then
// gives 𝓜_ff⁻¹ b on the free rows and 0 on the prescribed ones.  O(N).
void hybrid_dynamics(const Model& model, Data& data, const PrescribedJoints& prescribed, const VecX& tau,
                     const VecX& qdd_given, VecX& tau_out);

// ∂q̈/∂q (along the tangent) and ∂q̈/∂v of the hybrid dynamics at (q, v), τ the free joints'
// generalized force at this state and `inputs` (may be null) how it changes with q and v:
//   free rows:        ∂q̈_f/∂x = 𝓜_ff⁻¹ (∂τ_in/∂x − ∂ID/∂x)_f,  ID at the hybrid q̈,
//   prescribed rows:  zero (q̈* is a function of t alone),
// 𝓜_ff⁻¹ by the locked articulated-body factor (articulated_solve, O(N) per column).  Needs [kin]
// and [vel].  Fills data.qdd and tau_out (as hybrid_dynamics), dd.dtau_dq and dd.dtau_dv
// (inverse dynamics' at that q̈), dd.dqdd_dq and dd.dqdd_dv.  `work`: articulated_solve_work(model).
void hybrid_dynamics_derivatives(const Model& model, Data& data, const PrescribedJoints& prescribed, const VecX& v,
                                 const VecX& tau, const VecX& qdd_given, DerivativeData& dd, VecX& tau_out,
                                 const Inputs* inputs, MatX& work);

// The same by forming 𝓜 and bias and partitioning (a dense reference for tests): 𝓜_ff q̈_f =
// τ_f − bias_f − 𝓜_fp q̈*_p, τ_p = 𝓜_pf q̈_f + 𝓜_pp q̈*_p + bias_p.  O(N²) memory and O(nv³).
void hybrid_dynamics_dense(const Model& model, Data& data, const PrescribedJoints& prescribed, const VecX& tau,
                           const VecX& qdd_given, VecX& tau_out);

}  // namespace soadyn
