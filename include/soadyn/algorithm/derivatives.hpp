// Analytic partial derivatives of inverse and forward dynamics, O(N·depth), in the spirit of
// Carpentier & Mansard, "Analytical derivatives of rigid body dynamics algorithms" (RSS 2018),
// written in the note's inertial frame.
//
// Frame.  Every spatial vector here is [ω; u] in inertial coordinates with its moment point at the
// inertial origin (the note's v_i = [ω_i; η̇_i] moved there by D_{i:0}: u = η̇_i + η_i × ω_i), so a
// perturbation of joint j moves every quantity of the subtree below j rigidly, by the twist
// ξ = S_j δ_j, and the derivative of anything rigidly attached is a cross product with ξ.
//   S_i      G_i moved to the origin: [a; b + η_i × a] for G_i's column [a; b]
//   v_i      v_p + S_i q̇_i,    a_i = a_p + S_i q̈_i + Σ_c q̇_c μ_c × S_c   (a at the ground: [0; −g])
//   f_i      Y_i a_i + v_i ×* Y_i v_i,   F_i = Σ_{k ⪰ i} f_k,   τ_i = S_iᵀ F_i
// with m × m' = [ω × ω'; ω × u' + u × ω'] and m ×* f = [ω × n + u × f; ω × f].
//
// Tangent-space convention (free and ball joints).  ∂/∂q means the derivative along the increment
// δ (nv numbers) with q ⊕ δ = Model::integrate(q, δ, 1) (joint_integrate): the increment lives in the
// frame the joint's velocity does.
//   free  [x y z, Q]: δ = [δθ; δp]; p + δp, and Q turned about inertial axes: exp(δθ) ⊗ Q
//   ball  Q:          δ = δθ in the child's frame: Q ⊗ exp(δθ)
//   planar, revolute, prismatic: δ is the coordinate's own increment.
// So ∂q̈/∂q is nv×nv; joint_tangent_map (joint.hpp) gives the chain rule to the coordinates.
//
// Forward dynamics: ∂q̈/∂x = 𝓜⁻¹ (∂τ_in/∂x − ∂ID/∂x |_q̈) at the q̈ of the state, without forming
// ∂ID/∂x: 𝓜⁻¹ by the articulated-body recursion about the origin (minverse), then its products with
// the ∂ID columns made of the sweeps' vectors directly, O(N²) on every tree (forward_derivatives.cpp).
// ∂q̈/∂τ = 𝓜⁻¹ comes with them.
#pragma once

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/multibody/data.hpp"
#include "soadyn/algorithm/inputs.hpp"
#include "soadyn/multibody/model.hpp"

#include <vector>

namespace soadyn {

// B_i of the derivative sweeps (derivatives.cpp): B β = Y (β × v) + β ×* Y v + v ×* Y β for a body
// of inertia Y and velocity v, and the sum of these over a subtree.  Its right half is zero, so it is
// held as B = [T 0; −2 f̃ 0] (f: the linear momentum Y v, summed with the bodies).
struct CoriolisBlock {
  Mat3 T = Mat3::Zero();
  Vec3 f = Vec3::Zero();

  // B x = [T x_ω; −2 f × x_ω]
  Vec6 operator*(const Vec6& x) const {
    const Vec3 xw = x.head<3>();
    Vec6 y;
    y.head<3>().noalias() = T * xw;
    y.tail<3>() = -2.0 * f.cross(xw);
    return y;
  }
  // the top half of Bᵀ s (the bottom half is zero): Tᵀ s_ω + 2 f × s_u
  Vec3 transpose_times(const Vec6& s) const {
    Vec3 y = 2.0 * f.cross(Vec3(s.tail<3>()));
    y.noalias() += T.transpose() * s.head<3>();
    return y;
  }
  CoriolisBlock& operator+=(const CoriolisBlock& o) {
    T += o.T;
    f += o.f;
    return *this;
  }
};

// Per-state arrays of the derivative algorithms, sized once from a Model (Data holds the rest).
// No derivative algorithm allocates once a DerivativeData exists.
struct DerivativeData {
  explicit DerivativeData(const Model& model);

  // world-frame sweep (see the header comment), all about the inertial origin
  Mat6X S;                          // 6×nv: S_i, column per DOF
  Mat6X v, a;                       // 6×N: v_i, a_i (a includes −g)
  Mat6X F;                          // 6×N: F_i, subtree sums of f_i
  std::vector<SpatialInertia> Y;    // composite inertia of the subtree of i, about the origin
  std::vector<CoriolisBlock> B;     // composite of B_k β = Y_k (β × v_k) + β ×* Y_k v_k + v_k ×* Y_k β
  VecX tau;                         // τ = S_iᵀ F_i (equals inverse_dynamics)
  // per DOF column c (joint j): the vectors its derivative column is made of (see derivatives.cpp)
  // (B's zero right half drops the last three of Bᵀ S_r and so of β_c and S_c: 9 numbers each)
  Eigen::Matrix<double, 9, Eigen::Dynamic> row;    // [Y_i S_r; (B_iᵀ S_r)_ω] for row r of body i
  Eigen::Matrix<double, 9, Eigen::Dynamic> colq;   // [κ_c; β_c,ω]
  Eigen::Matrix<double, 9, Eigen::Dynamic> colv;   // [−λ_c; S_c,ω]
  Mat6X psi, rho, phi;                             // ψ_c, ρ_c (rows of ancestors), φ_c = ξ ×* F_j

  // results
  MatX dtau_dq, dtau_dv;            // ∂τ/∂q (tangent), ∂τ/∂v of inverse dynamics, nv×nv
  MatX dqdd_dq, dqdd_dv;            // ∂q̈/∂q (tangent), ∂q̈/∂v of forward dynamics, nv×nv
  MatX Minv;                        // ∂q̈/∂τ = 𝓜⁻¹
  MatX blocks;                      // nv × 9·Model::npaths: 𝓜⁻¹'s sums over ancestors and subtrees, per path
  std::vector<char> leaf;           // body i has no child
  Mat6X w, T1;                      // 6×N: the vector products' sums (…_transpose_times)
  Mat3X T2;                         // 3×N: the same for the top half of Bᵀ (its bottom half is zero)
  // inverse_dynamics_derivatives_times: its directions go kDirections at a time, as rows; its
  // per-body blocks (9 + 6 columns of kDirections rows each) and the rows of xq, xv and out
  static constexpr int kDirections = 16;  // row_blocks.hpp's kMaxRows
  MatX directions;                  // kDirections × (15 N + 3 nv)
};

// ∂τ/∂q and ∂τ/∂v of τ = 𝓜(q) q̈ + bias(q, v) at (q, v, q̈), q̈ held fixed.  Needs [kin] at q; v and
// q̈ have size nv.  Fills dd.dtau_dq, dd.dtau_dv and dd.tau.  O(N·depth).
void inverse_dynamics_derivatives(const Model& model, const Data& data, const VecX& v, const VecX& qdd,
                                  DerivativeData& dd);

// gq = (∂τ/∂q)ᵀ μ and gv = (∂τ/∂v)ᵀ μ (nv each) for vectors μ, without the matrices, in two steps so
// that many μ at one state share the first: the O(N) sweeps inverse_dynamics_derivatives begins
// with (at (q, v, q̈); needs [kin]; fills dd.tau), then per μ one more pair of O(N) sweeps in place of
// its O(N·depth) fill (derivatives.cpp).  The adjoint's vector–Jacobian products (adjoint.hpp).
void inverse_dynamics_derivative_sweeps(const Model& model, const Data& data, const VecX& v, const VecX& qdd,
                                        DerivativeData& dd);
void inverse_dynamics_derivatives_transpose_times(const Model& model, DerivativeData& dd, const VecX& mu,
                                                  Eigen::Ref<VecX> gq, Eigen::Ref<VecX> gv);
// out = (∂τ/∂q) xq + (∂τ/∂v) xv for the columns of xq and xv (nv × k each; out nv × k), after the
// same sweeps, without the matrices: per column one O(N) base-to-tip and one tip-to-base sum in place
// of the O(N·depth) fill, kDirections columns at a time (derivative_products.cpp).  The forward
// sensitivities' products (sensitivity.hpp).
void inverse_dynamics_derivatives_times(const Model& model, DerivativeData& dd, const Eigen::Ref<const MatX>& xq,
                                        const Eigen::Ref<const MatX>& xv, Eigen::Ref<MatX> out);

// ∂q̈/∂q and ∂q̈/∂v of q̈ = 𝓜⁻¹ (τ − bias) at (q, v), where τ is the generalized force at this state
// and `inputs` (may be null) says how it changes with q and v (springs, dampers).  Needs [kin] and
// [vel] at (q, v).  Fills data.qdd (by the articulated-body route), dd.dqdd_dq, dd.dqdd_dv and
// dd.Minv = 𝓜⁻¹ = ∂q̈/∂τ, which they are made from (`minv` is kept for callers of the time when it
// was optional; it changes nothing); not dd.dtau_dq, dd.dtau_dv (inverse_dynamics_derivatives).
// O(N²) on every tree.
void forward_dynamics_derivatives(const Model& model, Data& data, const VecX& v, const VecX& tau, DerivativeData& dd,
                                  const Inputs* inputs = nullptr, bool minv = false);

}  // namespace soadyn
