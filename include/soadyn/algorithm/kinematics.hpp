// Kinematics at a state: every quantity the note needs, in inertial coordinates.
#pragma once

#include "soadyn/multibody/data.hpp"
#include "soadyn/multibody/model.hpp"

namespace soadyn {

// [kin] R_i, η_i, d_i, s_i, r_i, G_i, I_i and M_i at configuration q (size nq).
// Joints along a unit axis of their frame take a specialized path (one sincos, no 3×3 product).
void update_kinematics(const Model& model, Data& data, const VecX& q);
// The frames alone: R_i, η_i, d_i and G_i of [kin] (not s_i, r_i, M_i), for the 𝓜 route that keeps
// its inertias in body axes (mass_matrix_local.cpp)
void update_frames(const Model& model, Data& data, const VecX& q);
// The frames of one body and its ancestors only (R, η, d, G of those, as update_frames gives
// them; the other bodies' are left as they were): O(depth) for a frame's pose or Jacobian.
// body = −1 (the world) does nothing.
void update_frames_to(const Model& model, Data& data, const VecX& q, int body);
// The same by the generic joint interface (joint_motion, joint_subspace) for every joint: the
// reference the specialized path is tested against.
void update_kinematics_reference(const Model& model, Data& data, const VecX& q);

// (cos θ, sin θ) into column i of turn for every revolute joint along a unit axis (Model::angles),
// the one trigonometry update_kinematics and the local-frame 𝓜 route need; roots = false leaves
// out the joints that hang from the ground (the local route never turns a root's inertia)
void joint_turns(const Model& model, const VecX& q, Eigen::Matrix2Xd& turn, bool roots = true);

// [vel] v = Ψ_D G q̇ (eq. 4), v̄ = S v (eq. 5), and the velocity-product terms a_i, b_i used by the
// dynamics.  Needs [kin].  v has size nv.
void update_velocities(const Model& model, Data& data, const VecX& v);

// The note's 6×6 blocks of body i at the current [kin] state.
Mat6 D_matrix(const Data& data, int i);  // D_i = [e 0; −d̃_i e]   (0 at a root: the note's D_1)
Mat6 S_matrix(const Data& data, int i);  // S_i = [e 0; −s̃_i e]
Mat6 M_matrix(const Data& data, int i);  // M_i = S_iᵀ M̄_i S_i   (eq. 12)
Mat6G G_matrix(const Model& model, const Data& data, int i);  // G_i, 6×nv_i
Mat3 inertia_cm(const Data& data, int i);  // I_i about the cm, inertial: I_η + m s̃_i s̃_i

// A rotation (body → inertial, C_i) as the unit quaternion [w x y z] with w ≥ 0, as logs and
// `soadyn inspect` report a body's attitude.
Eigen::Vector4d attitude_quaternion(const Mat3& R);

// J = S Ψ_D G (eq. 7): 6N×nv, rows 6i..6i+5 give v̄_i = [ω_i; ṙ_i].  Needs [kin].
void jacobian(const Model& model, const Data& data, MatX& J);

}  // namespace soadyn
