// Inertial parameters: the joint-torque regressor τ = Y(q, v, q̈) π, the parameters of a model and
// a model with other parameters, and ∂q̈/∂π.
//
// π holds 10 numbers per body, body after body in the model's order (Pinocchio's convention):
//   m, m c_x, m c_y, m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz
// with c the centre of mass and I the inertia about the body frame's origin (its joint point η_i),
// both in the body's own axes (Model::com, Model::inertia_origin); a body is everything welded to
// it.  τ = Y π is inverse dynamics, gravity included.
#pragma once

#include <vector>

#include "soadyn/multibody/data.hpp"
#include "soadyn/multibody/model.hpp"

namespace soadyn {

inline constexpr int kParametersPerBody = 10;

VecX parameters(const Model& model);
// The model with parameters π (10 N).  Refuses (soadyn::Error naming the body and what is wrong) a
// physically inconsistent π: a mass ≤ 0, or an inertia about the centre of mass, I − m(|c|² e − c cᵀ),
// that is not positive semidefinite or breaks the triangle inequality.
Model with_parameters(const Model& model, const VecX& pi);

// Y (nv × 10 N) with τ = Y π at (q, v, q̈).  Needs [kin] and [vel] (update_kinematics,
// update_velocities); leaves data.A, data.F and data.tau as inverse_dynamics does.
void regressor(const Model& model, Data& data, const VecX& qdd, MatX& Y);
// The columns of the listed bodies only (nv × 10·bodies.size(), in the order listed): the same
// numbers as regressor's, in O(Σ depth of the listed bodies) instead of O(N·depth): each body's
// acceleration along its own chain, or the whole tree's by inverse dynamics when the chains
// together are longer than the tree.  Needs [kin] and [vel]; writes data.A of the listed bodies
// (and then data.A, data.F and data.tau as inverse_dynamics does)
void regressor(const Model& model, Data& data, const VecX& qdd, const std::vector<int>& bodies, MatX& Y);

// Yᵀ μ (10 N) at (q, v, q̈) for a vector μ (nv), in O(N) without forming Y: one base-to-tip sweep of
// w_i = D_i w_parent + G_i μ_i, then each body's 6×10 block (the adjoint's ∂G/∂π, adjoint.hpp).  Needs
// [kin] and [vel]; leaves data.A, data.F and data.tau as inverse_dynamics does, and overwrites data.work.local.V.
void regressor_transpose_times(const Model& model, Data& data, const VecX& qdd, const VecX& mu, Eigen::Ref<VecX> out);

// ∂q̈/∂π (nv × 10 N) of forward dynamics at (q, v, τ): −𝓜⁻¹ Y(q, v, q̈), 𝓜⁻¹ applied by the tree's
// LᵀDL factor, never formed.  Needs [kin] and [vel]; leaves data.qdd = q̈ and data.M = 𝓜.
void forward_dynamics_parameter_derivative(const Model& model, Data& data, const VecX& tau, MatX& dqdd_dpi);

}  // namespace soadyn
