// Frames and task space: where a point of the robot is, how fast it moves, and what it takes to
// push it.  Pinocchio's frames, computeFrameJacobian, getFrame(Classical)Acceleration,
// jacobianCenterOfMass, ccrba and computeCoriolisMatrix; MuJoCo's mj_jacSite and mj_subtreeCom.
//
// A frame (model.hpp: frame_names, frame_body, frame_placement) is fixed on body b by a placement
// X; at a state it sits at R = C_b X.R (frame → inertial), p = η_b + C_b X.p.  Its motion in three
// references (Pinocchio's names; soadyn's order, angular first):
//   world                 [ω; v_O], v_O = ṗ − ω × p: the velocity of the body's point at the
//                         inertial origin, inertial axes (a spatial velocity)
//   local                 [Rᵀ ω; Rᵀ ṗ]: the frame's own axes, about its origin
//   local_world_aligned   [ω; ṗ]: inertial axes, about the frame's origin
// A frame Jacobian is body b's row block of the note's Ψ_D G (eq. 7 without S), moved from η_b to
// p: [Ψ_D G]_b = Σ_{j ≤ b} D_{b:j} G_j with D_{b:j} = D_b ⋯ D_{j+1} = [e 0; −(η_b − η_j)~ e] (the
// D's telescope), so column k of DOF k on body j is [g; u + g × (p − η_j)] for G_k = [g; u]: one
// walk up b's ancestors, O(depth), nothing else touched.  Accelerations are the same walk over
// v̇ = Ψ_D (G q̈ + 𝔞) (Data::coriolis, without gravity's base acceleration).
//
// Stages (data.hpp): [kin] update_kinematics(q), [vel] update_velocities(v); frame_placement,
// frame_jacobian and point_jacobian read only R, η and G, so update_frames(q) is enough for them.  Nothing here allocates
// once its outputs have their size, except where a function says so (test_no_alloc).
// Elsewhere: a scenario's frames: adds frames and log: {frames: [...]} logs their poses (h5log.hpp,
// /frames); `soadyn inspect --frame NAME` prints a frame's pose and Jacobian; Python has every call
// under the same name (src/python/frames.cpp).
#pragma once

#include "soadyn/multibody/data.hpp"
#include "soadyn/multibody/model.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace soadyn {

enum class Reference { World, Local, LocalWorldAligned };

// The one registry of references: the word users write for each, and a line about it.
struct ReferenceInfo {
  Reference reference;
  std::string_view name;
  std::string_view description;
};
const std::vector<ReferenceInfo>& references();
std::string_view to_string(Reference r);
Reference parse_reference(std::string_view s);  // a name of references(); throws soadyn::Error

// [kin] (R, p) of the frame: R frame → inertial, p its origin, inertial
Placement frame_placement(const Model& model, const Data& data, int frame);

// [kin][vel] the frame's velocity in `reference`
Vec6 frame_velocity(const Model& model, const Data& data, int frame, Reference reference);

// [kin][vel] the frame's acceleration for joint accelerations qdd (nv), in `reference`.
// Spatial (classical = false): world [α; v̇_O] and local [Rᵀ α; Rᵀ (p̈ − ω × ṗ)] are the time
// derivatives of those velocities; local_world_aligned is local's turned to inertial axes,
// [α; p̈ − ω × ṗ] (Pinocchio's convention).  Classical: [α; the acceleration of the body's point
// at the reference point] in the reference's axes: local [Rᵀ α; Rᵀ p̈], local_world_aligned
// [α; p̈], world [α; p̈ − α × p − ω × (ω × p)].
Vec6 frame_acceleration(const Model& model, const Data& data, int frame, const VecX& qdd, Reference reference,
                        bool classical = false);

// [kin] J, 6×nv (resized when it is not): the frame's velocity in `reference` is J v
void frame_jacobian(const Model& model, const Data& data, int frame, Reference reference, MatX& J);
// The same from q alone, as Pinocchio's computeFrameJacobian(q): the frames of the frame's body
// and its ancestors (update_frames_to), then the walk above, O(depth) in all; the other bodies'
// [kin] fields are left as they were.
void frame_jacobian(const Model& model, Data& data, const VecX& q, int frame, Reference reference, MatX& J);

// [kin][vel] J̇ v = d/dt (J(q) v) at fixed v, the frame's acceleration at q̈ = 0 in the sense of
// each reference's velocity: world and local as frame_acceleration's spatial ones,
// local_world_aligned [α; p̈] (the classical one), so that J q̈ + J̇ v is the derivative of J v
void frame_jacobian_dot_times_v(const Model& model, const Data& data, int frame, Reference reference, Vec6& out);

// The same for a frame given by its body (−1: the world, where it stays put) and its placement on
// it rather than by a frame index (a loop constraint's frames, loops.hpp)
Placement body_frame_placement(const Model& model, const Data& data, int body, const Placement& on_body);
Vec6 body_frame_velocity(const Model& model, const Data& data, int body, const Placement& on_body, Reference reference);
void body_frame_jacobian(const Model& model, const Data& data, int body, const Placement& on_body, Reference reference,
                         MatX& J);
void body_frame_jacobian_dot_times_v(const Model& model, const Data& data, int body, const Placement& on_body,
                                     Reference reference, Vec6& out);
// [kin] J, 3×nv: ṗ = J v for the point at `point` of body `body` (body frame coordinates)
void point_jacobian(const Model& model, const Data& data, int body, const Vec3& point, MatX& J);

// Centre of mass of the moving bodies (as Pinocchio's: bodies welded to the world are not in it;
// they do not move).  [kin] c = Σ m_i r_i / m
Vec3 com(const Model& model, const Data& data);
// [kin][vel] ċ = Σ m_i ṙ_i / m
Vec3 com_velocity(const Model& model, const Data& data);
// [kin] J_c, 3×nv, ċ = J_c v: column k of DOF k on body j is f_k / m, with K_j G_k = [n_k; f_k]
// (K_j the composite inertia of j's subtree about η_j).  Fills data.work.composite.K.
void com_jacobian(const Model& model, Data& data, MatX& J);
// The same from q alone, as Pinocchio's jacobianCenterOfMass(q): the frames (update_frames, [kin]
// without the inertias), then each subtree's mass and first moment only; fills data.work.composite.K's m and h
// (not its rotational inertia) and leaves [kin]'s inertias and r as they were.
void com_jacobian(const Model& model, Data& data, const VecX& q, MatX& J);

// Centroidal momentum h_G = [k_G; l] (angular first): l = Σ m_i ṙ_i and k_G = Σ I_i ω_i +
// (r_i − c) × m_i ṙ_i, the angular momentum about the centre of mass c.
// [kin] A_G, 6×nv, h_G = A_G v: column k = [n_k + (η_j − c) × f_k; f_k].  Fills data.work.composite.K.
void centroidal_momentum_matrix(const Model& model, Data& data, MatX& AG);
// [kin][vel] h_G = A_G v, from the bodies' velocities
Vec6 centroidal_momentum(const Model& model, const Data& data);
// [kin][vel] Ȧ_G v = ḣ_G at q̈ = 0: Σ_i of the bodies' M_i a_i + 𝔟_i (data.gyroscopic) about c,
// a = Ψ_D 𝔞 the bodies' accelerations at q̈ = 0 without gravity.  Overwrites data.A (the
// [rne]/[fd] scratch).
Vec6 centroidal_momentum_matrix_dot_times_v(const Model& model, Data& data);
// [kin] the composite inertia of every moving body about the centre of mass, inertial axes
// (h = 0 up to rounding): h_G = K_G [ω_G; ċ] defines the average angular velocity ω_G.  Fills data.work.composite.K.
SpatialInertia centroidal_inertia(const Model& model, Data& data);

// [kin] Λ = (J 𝓜⁻¹ Jᵀ)⁻¹ for a task Jacobian J (k×nv, e.g. frame_jacobian's or its 3 linear
// rows), by 𝓜 = L Lᵀ (data.work.factor.llt) and Y = L⁻¹ Jᵀ, J 𝓜⁻¹ Jᵀ = Yᵀ Y: 𝓜⁻¹ is never formed.  Fills
// data.work.factor.llt; leaves data.M as mass_matrix left it (𝓜 is formed there and put back);
// allocates Y (nv×k) and a copy of 𝓜.  Throws soadyn::Error when J 𝓜⁻¹ Jᵀ is singular
// (a smallest eigenvalue below 1e-10 of the largest): more rows than the joints can move
// independently at this configuration.
void operational_space_inertia(const Model& model, Data& data, const MatX& J, MatX& Lambda);

// [kin][vel] C(q, v), nv×nv, with C v = bias − gravity's part (bias at v = 0) and 𝓜̇ − 2C
// skew-symmetric: C = Σ_i J_iᵀ (M̄_i J̇_i + [ω̃_i I_i 0; 0 0] J_i), J_i body i's rows of
// J = S Ψ_D G (eq. 7, about the centre of mass) and M̄_i = diag(I_i, m_i e).  O(N·nv²);
// allocates two 6×nv blocks.
void coriolis_matrix(const Model& model, const Data& data, MatX& C);

}  // namespace soadyn
