// The geometry of a model's configuration q, joint by joint, once: each joint's kind answers from
// its configuration space (joint_space.hpp), so no caller tests "does this joint hold a quaternion".
//
//   q ⊕ h v     integrate            the configuration reached by moving at v for h
//   q1 ⊖ q0     difference           the v with q0 ⊕ v = q1 (nv)
//   dexp⁻¹_u v  increment_rate       u̇ for q(t) = q0 ⊕ u(t) moving at v (nv): Lie-group integrators'
//                                    local coordinates (integrators.hpp)
//   T(q)        tangent_map          dδ = T dq (nv×nq, block diagonal): the tangent increment of dq
//   T̄(q)        Model::qdot          q̇ = T̄(q) v
//   ∂q̇/∂q, ∂q̇/∂v  qdot_jacobian      of q̇ = T̄(q) v (nq×nq, nq×nv, block diagonal)
//
// The increment δ is in the frame the joint's velocity is (derivatives.hpp), so ∂f/∂q =
// ∂f/∂δ · T(q) is the chain rule from the tangent to the coordinates.
#pragma once

#include "soadyn/multibody/model.hpp"

namespace soadyn {

// the offset in body i's q of its unit quaternion [w x y z], or −1 (the kind's trait)
inline int joint_quaternion(const Model& model, int i) {
  int k = -1;
  visit_joint(model, i, [&](const auto& j) { k = std::decay_t<decltype(j)>::quaternion; });
  return k;
}

// whether body i's joint has q̇ = v and T = e (no quaternion)
inline bool joint_euclidean(const Model& model, int i) { return joint_quaternion(model, i) < 0; }

// out = q ⊕ h v (out may be q)
void integrate(const Model& model, const VecX& q, const VecX& v, double h, Eigen::Ref<VecX> out);

// q1 ⊖ q0 (nv): q0 ⊕ (q1 ⊖ q0) = q1, a quaternion by its shorter turn
VecX difference(const Model& model, const VecX& q0, const VecX& q1);

// out = dexp⁻¹_u(v) joint by joint (u, v, out: nv), the increment's rate: q0 ⊕ u(t) moves at v
// when u̇ = out.  v itself where the joint has no quaternion; a quaternion's turn by the closed form
// (joint_space.hpp), valid for turns |u| < 2π
void increment_rate(const Model& model, const VecX& u, const VecX& v, Eigen::Ref<VecX> out);

// T(q), nv×nq
MatX tangent_map(const Model& model, const VecX& q);

// out = T(q) A (A: nq rows, out: nv rows), the coordinates' directions A as tangent increments
void tangent_times(const Model& model, const VecX& q, Eigen::Ref<const MatX> A, Eigen::Ref<MatX> out);

// out += T(q)ᵀ g (g: nv, out: nq), a gradient along the tangent to one along the coordinates
void add_tangent_transpose_times(const Model& model, const VecX& q, Eigen::Ref<const VecX> g, Eigen::Ref<VecX> out);

// out += A T(q) (A: nv columns, out: nq columns): ∂f/∂q = ∂f/∂δ · T
void add_times_tangent(const Model& model, const VecX& q, Eigen::Ref<const MatX> A, Eigen::Ref<MatX> out);

// P = Tᵀ (T Tᵀ)⁻¹ (nq×nv), the coordinates' change along a tangent increment: for a unit quaternion
// exactly ½ [0; δθ] ⊗ Q (free) or ½ Q ⊗ [0; δθ] (ball), orthogonal to Q
MatX tangent_to_coordinates(const Model& model, const VecX& q);

// ∂q̇/∂q into the joints' diagonal blocks of dq (nq×nq) and ∂q̇/∂v into those of dv (nq×nv);
// the rest is left as it is
void qdot_jacobian(const Model& model, const VecX& q, const VecX& v, Eigen::Ref<MatX> dq, Eigen::Ref<MatX> dv);

// out = ∂q̇/∂q Aq + ∂q̇/∂v Av (Aq: nq rows, Av: nv rows, out: nq rows)
void qdot_jacobian_times(const Model& model, const VecX& q, const VecX& v, Eigen::Ref<const MatX> Aq,
                         Eigen::Ref<const MatX> Av, Eigen::Ref<MatX> out);

// out_q += (∂q̇/∂q)ᵀ λ, out_v += (∂q̇/∂v)ᵀ λ (λ: nq)
void add_qdot_jacobian_transpose_times(const Model& model, const VecX& q, const VecX& v, Eigen::Ref<const VecX> lambda,
                                       Eigen::Ref<VecX> out_q, Eigen::Ref<VecX> out_v);

// a random configuration: each joint's coordinates uniform in [−π, π], its quaternion uniform
template <class Rng>
VecX random_configuration(const Model& model, Rng& rng) {
  VecX q(model.nq);
  for (int i = 0; i < model.nbodies; ++i)
    visit_joint(model, i, [&](const auto& j) { j.random(rng, q.data() + model.idx_q[i]); });
  return q;
}

}  // namespace soadyn
