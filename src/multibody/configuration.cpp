// The configuration's geometry joint by joint (configuration.hpp): one dispatch per body to its
// kind, whose configuration space (joint_space.hpp) holds the formulas.
#include "soadyn/multibody/configuration.hpp"

namespace soadyn {

namespace {

// f(kind, iq, iv) for every body: its kind J and the first q and v of its joint
template <class F>
void for_each_joint(const Model& model, F&& f) {
  for (int i = 0; i < model.nbodies; ++i)
    visit_joint(model, i, [&](const auto& j) { f(j, model.idx_q[i], model.idx_v[i]); });
}

template <class J>
using TangentOf = Eigen::Matrix<double, J::nv, J::nq>;

}  // namespace

// out_i = q_i ⊕ h v_i
void integrate(const Model& model, const VecX& q, const VecX& v, double h, Eigen::Ref<VecX> out) {
  for_each_joint(model, [&](const auto& j, int iq, int iv) { j.integrate(q.data() + iq, v.data() + iv, h, out.data() + iq); });
}

// v_i = q1_i ⊖ q0_i
VecX difference(const Model& model, const VecX& q0, const VecX& q1) {
  VecX v(model.nv);
  for_each_joint(model, [&](const auto& j, int iq, int iv) { j.difference(q0.data() + iq, q1.data() + iq, v.data() + iv); });
  return v;
}

// r_i = dexp⁻¹_{u_i}(v_i)
void increment_rate(const Model& model, const VecX& u, const VecX& v, Eigen::Ref<VecX> out) {
  for_each_joint(model, [&](const auto& j, int, int iv) { j.increment_rate(u.data() + iv, v.data() + iv, out.data() + iv); });
}

// T = diag(T_i(q_i))
MatX tangent_map(const Model& model, const VecX& q) {
  MatX T = MatX::Zero(model.nv, model.nq);
  for_each_joint(model, [&](const auto& j, int iq, int iv) {
    using J = std::decay_t<decltype(j)>;
    T.block<J::nv, J::nq>(iv, iq) = j.tangent(q.data() + iq);
  });
  return T;
}

// δ_i = T_i A_i (A_i itself where T_i = e)
void tangent_times(const Model& model, const VecX& q, Eigen::Ref<const MatX> A, Eigen::Ref<MatX> out) {
  for_each_joint(model, [&](const auto& j, int iq, int iv) {
    using J = std::decay_t<decltype(j)>;
    if constexpr (J::euclidean) out.middleRows<J::nv>(iv) = A.middleRows<J::nq>(iq);
    else out.middleRows<J::nv>(iv).noalias() = j.tangent(q.data() + iq) * A.middleRows<J::nq>(iq);
  });
}

// out_i += T_iᵀ g_i
void add_tangent_transpose_times(const Model& model, const VecX& q, Eigen::Ref<const VecX> g, Eigen::Ref<VecX> out) {
  for_each_joint(model, [&](const auto& j, int iq, int iv) {
    using J = std::decay_t<decltype(j)>;
    if constexpr (J::euclidean) out.segment<J::nq>(iq) += g.segment<J::nv>(iv);
    else out.segment<J::nq>(iq).noalias() += j.tangent(q.data() + iq).transpose() * g.segment<J::nv>(iv);
  });
}

// out_{:, i} += A_{:, i} T_i, column by column (no temporary)
void add_times_tangent(const Model& model, const VecX& q, Eigen::Ref<const MatX> A, Eigen::Ref<MatX> out) {
  for_each_joint(model, [&](const auto& j, int iq, int iv) {
    using J = std::decay_t<decltype(j)>;
    if constexpr (J::euclidean) {
      out.middleCols<J::nq>(iq) += A.middleCols<J::nv>(iv);
    } else {
      const TangentOf<J> T = j.tangent(q.data() + iq);
      for (int c = 0; c < J::nq; ++c)
        for (int k = 0; k < J::nv; ++k)
          if (T(k, c) != 0.0) out.col(iq + c) += T(k, c) * A.col(iv + k);
    }
  });
}

// P_i = T_iᵀ (T_i T_iᵀ)⁻¹
MatX tangent_to_coordinates(const Model& model, const VecX& q) {
  MatX P = MatX::Zero(model.nq, model.nv);
  for_each_joint(model, [&](const auto& j, int iq, int iv) {
    using J = std::decay_t<decltype(j)>;
    const TangentOf<J> T = j.tangent(q.data() + iq);
    if constexpr (J::euclidean) P.block<J::nq, J::nv>(iq, iv).setIdentity();
    else P.block<J::nq, J::nv>(iq, iv) = T.transpose() * (T * T.transpose()).inverse();
  });
  return P;
}

void qdot_jacobian(const Model& model, const VecX& q, const VecX& v, Eigen::Ref<MatX> dq, Eigen::Ref<MatX> dv) {
  for_each_joint(model, [&](const auto& j, int iq, int iv) {
    using J = std::decay_t<decltype(j)>;
    Eigen::Matrix<double, J::nq, J::nq> a;
    Eigen::Matrix<double, J::nq, J::nv> b;
    j.qdot_jacobian(q.data() + iq, v.data() + iv, a, b);
    dq.block<J::nq, J::nq>(iq, iq) = a;
    dv.block<J::nq, J::nv>(iq, iv) = b;
  });
}

// q̇'s rows: ∂q̇/∂q Aq + ∂q̇/∂v Av joint by joint (Av's rows where q̇ = v)
void qdot_jacobian_times(const Model& model, const VecX& q, const VecX& v, Eigen::Ref<const MatX> Aq,
                         Eigen::Ref<const MatX> Av, Eigen::Ref<MatX> out) {
  for_each_joint(model, [&](const auto& j, int iq, int iv) {
    using J = std::decay_t<decltype(j)>;
    if constexpr (J::euclidean) {
      out.middleRows<J::nq>(iq) = Av.middleRows<J::nv>(iv);
    } else {
      Eigen::Matrix<double, J::nq, J::nq> a;
      Eigen::Matrix<double, J::nq, J::nv> b;
      j.qdot_jacobian(q.data() + iq, v.data() + iv, a, b);
      out.middleRows<J::nq>(iq).noalias() = a * Aq.middleRows<J::nq>(iq);
      out.middleRows<J::nq>(iq).noalias() += b * Av.middleRows<J::nv>(iv);
    }
  });
}

void add_qdot_jacobian_transpose_times(const Model& model, const VecX& q, const VecX& v, Eigen::Ref<const VecX> lambda,
                                       Eigen::Ref<VecX> out_q, Eigen::Ref<VecX> out_v) {
  for_each_joint(model, [&](const auto& j, int iq, int iv) {
    using J = std::decay_t<decltype(j)>;
    if constexpr (J::euclidean) {
      out_v.segment<J::nv>(iv) += lambda.segment<J::nq>(iq);
    } else {
      Eigen::Matrix<double, J::nq, J::nq> a;
      Eigen::Matrix<double, J::nq, J::nv> b;
      j.qdot_jacobian(q.data() + iq, v.data() + iv, a, b);
      out_q.segment<J::nq>(iq).noalias() += a.transpose() * lambda.segment<J::nq>(iq);
      out_v.segment<J::nv>(iv).noalias() += b.transpose() * lambda.segment<J::nq>(iq);
    }
  });
}

}  // namespace soadyn
