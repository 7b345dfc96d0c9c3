// The system mass matrix and the equations of motion 𝓜(q) q̈ = τ − bias(q, q̇).
//
// Pipeline: update_kinematics(q) → [mass_matrix] → update_velocities(v) → bias / inverse /
// forward dynamics.  Each stage reads what the earlier ones cached in Data, and a call whose stage
// does not hold (a fresh Data; [vel] after update_kinematics at a new q) throws soadyn::Error
// (Data::stages).  One call from the state, as Pinocchio's crba / nonLinearEffects / rnea / aba:
// mass_matrix(model, data, q), bias_forces(model, data, q, v), inverse_dynamics(model, data, q, v,
// q̈), forward_dynamics(model, data, q, v, τ).
#pragma once

#include "soadyn/multibody/data.hpp"
#include "soadyn/multibody/model.hpp"
#include "soadyn/algorithm/fd_method.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace soadyn {

// 𝓜 by the note's three-step procedure: J = Ψ_D G column by column, Q = M J, 𝓜 = Jᵀ Q.
// O(N²) and kept as the readable reference.  Needs [kin].
void mass_matrix_literal(const Model& model, const Data& data, MatX& M_out);

// 𝓜 = Gᵀ Ψ_Dᵀ M Ψ_D G (eq. 14) from composite inertias: one tip-to-base sweep
// K_p += D_iᵀ K_i D_i and, per body, a walk up its ancestors.  O(N·depth).  Needs [kin];
// fills data.M (both triangles).
void mass_matrix(const Model& model, Data& data);

// 𝓜(q) straight from q (size nq), as Pinocchio's crba(q): the same composite algorithm with every
// quantity in body axes (mass_matrix_local.cpp), so no inertial kinematics is formed.  Needs
// nothing; fills data.M, the same 𝓜 as update_kinematics + mass_matrix to rounding, and leaves
// every other result as it was (past 22 bodies the frames it needs are formed in its workspace).
void mass_matrix(const Model& model, Data& data, const VecX& q);

// bias(q, q̇) = Gᵀ Ψ_Dᵀ (M Ψ_D 𝔞 + 𝔟) with 𝔞 = Data::coriolis, 𝔟 = Data::gyroscopic: Coriolis, centrifugal, gyroscopic and gravity.
// Needs [kin] and [vel]; fills data.bias, and data.A and data.F at q̈ = 0.
void bias_forces(const Model& model, Data& data);

// bias(q, q̇) straight from q (nq) and v (nv), as Pinocchio's nonLinearEffects: the same two
// sweeps with every quantity in body axes (bias_local.cpp), so no inertial kinematics is formed.
// Needs nothing; fills data.bias, the same bias as update_kinematics + update_velocities +
// bias_forces to rounding, and leaves every other result as it was.
void bias_forces(const Model& model, Data& data, const VecX& q, const VecX& v);

// τ = 𝓜 q̈ + bias with the same two sweeps.  Needs [kin] and [vel]; fills data.tau, data.A and data.F.
void inverse_dynamics(const Model& model, Data& data, const VecX& qdd);

// The same in one call, as Pinocchio's rnea(q, v, a): update_kinematics(q), update_velocities(v),
// then the sweeps.  Needs nothing; leaves [kin] and [vel] at (q, v); returns data.tau.
const VecX& inverse_dynamics(const Model& model, Data& data, const VecX& q, const VecX& v, const VecX& qdd);

// FdMethod and its words: fd_method.hpp

// q̈ = 𝓜⁻¹ (τ − bias).  Needs [kin] and [vel]; fills data.qdd (Dense and Sparse also fill
// data.M and data.bias).
void forward_dynamics(const Model& model, Data& data, const VecX& tau, FdMethod method);

// The same in one call, as Pinocchio's aba(q, v, τ): update_kinematics(q), update_velocities(v),
// then the route (the O(N) one unless told).  Needs nothing; leaves [kin] and [vel] at (q, v);
// returns data.qdd.
const VecX& forward_dynamics(const Model& model, Data& data, const VecX& q, const VecX& v, const VecX& tau,
                             FdMethod method = FdMethod::ArticulatedBody);

// 𝓜⁻¹ (nv×nv) without forming 𝓜, as Pinocchio's computeMinverse: the articulated-body recursion
// for every unit force at once, O(N·depth) tip to base and O(N) per column base to tip (O(N²) on a
// chain).  Needs [kin]; fills Minv (nv×nv, full, symmetric to rounding; allocates only when Minv has
// another size); fills no result of Data (the articulated-body factor it leaves in the workspace is
// the one articulated_solve reads).
void minverse(const Model& model, Data& data, MatX& Minv);

// X ← 𝓜⁻¹ X for the columns of X (nv×k), with the articulated-body factor that
// forward_dynamics(…, ArticulatedBody) or minverse leaves in data.work.articulated: one
// tip-to-base and one base-to-tip sweep per column, O(N) each whatever the tree, several columns at
// a time (articulated_solve.cpp).  `work` is articulated_solve_work(model); nothing allocates.
void articulated_solve(const Model& model, const Data& data, Eigen::Ref<MatX> X, MatX& work);
MatX articulated_solve_work(const Model& model);

// The tree-sparse route in two parts, for reuse: factor data.M into data.work.factor.L, then solve in place.
void ltdl_factor(const Model& model, Data& data);
void ltdl_solve(const Model& model, const Data& data, Eigen::Ref<VecX> x);

// T = ½ Σ (ω_iᵀ I_i ω_i + m_i ṙ_iᵀ ṙ_i)   (eq. 9).  Needs [vel].
double kinetic_energy(const Model& model, const Data& data);
// V = −Σ m_i g·r_i over every body with mass, the world-welded ones included.  Needs [kin].
double potential_energy(const Model& model, const Data& data);

struct Momentum {
  Vec3 linear = Vec3::Zero();   // Σ m_i ṙ_i
  Vec3 angular = Vec3::Zero();  // Σ I_i ω_i + r_i × m_i ṙ_i, about the inertial origin
};
Momentum momentum(const Model& model, const Data& data);

}  // namespace soadyn
