// The system's state on its manifold (system.hpp): the quaternions unit, q ⊕ h v and its rate
// dexp⁻¹ joint by joint over the state's joints, the Jacobian along the tangent (the fixed-step
// methods on the group, fixed_step.cpp), and the projection onto the closed loops' manifold (CVODE
// BDF's projection, the fixed steps, Adams' outputs) with the tangent conversions of the state.
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/multibody/configuration.hpp"
#include "soadyn/sim/system.hpp"

#include <Eigen/QR>

#include <cmath>

namespace soadyn {

void System::normalize(Eigen::Ref<VecX> q_state) const {
  ++normalizations;
  for (const int k : quaternions_) q_state.segment<4>(k).normalize();
}

// out_j = q_j ⊕ h v_j for each state joint j, by its kind
void System::integrate(const Eigen::Ref<const VecX>& q_state, const Eigen::Ref<const VecX>& v_state, double h,
                       Eigen::Ref<VecX> out) const {
  for (const StateJoint& j : state_joints_)
    visit_joint(model, j.body, [&](const auto& kind) {
      kind.integrate(q_state.data() + j.iq, v_state.data() + j.iv, h, out.data() + j.iq);
    });
}

// out_j = dexp⁻¹_{u_j}(v_j) for each state joint j, by its kind
void System::increment_rate(const Eigen::Ref<const VecX>& u, const Eigen::Ref<const VecX>& v_state,
                            Eigen::Ref<VecX> out) const {
  for (const StateJoint& j : state_joints_)
    visit_joint(model, j.body, [&](const auto& kind) {
      kind.increment_rate(u.data() + j.iv, v_state.data() + j.iv, out.data() + j.iv);
    });
}

bool System::project(Eigen::Ref<VecX> y) {
  normalize(y.head(nq_state_));
  if (!has_loops()) return true;
  linearized_ = false;  // data is about to hold the projection's states
  evaluated_ = false;
  const int nq = model.nq, nv = model.nv;
  q = y.head(nq);
  v = y.segment(nq, nv);
  // q onto φ(q) = 0: Gauss–Newton along the tangent, δ = −K⁺ φ (of minimum norm), q ← q ⊕ δ
  bool closed = false;
  for (int it = 0; it < 20 && !closed; ++it) {
    update_kinematics(model, data, q);
    update_velocities(model, data, v);
    loop_rows(model, data, inputs.loops, loops_);
    closed = loops_.phi.cwiseAbs().maxCoeff() <= kLoopClosure;
    if (closed) break;
    const VecX step = -Eigen::CompleteOrthogonalDecomposition<MatX>(loops_.K).solve(loops_.phi);
    q = model.integrate(q, step, 1.0);
    normalize(q);
  }
  if (!closed) return false;
  // v onto K v = 0: v ← v − K⁺ K v
  projector_.compute(loops_.K);
  v -= projector_.solve(VecX(loops_.K * v));
  y.head(nq) = q;
  y.segment(nq, nv) = v;
  return true;
}

void System::project_error(Eigen::Ref<VecX> err) const {
  if (!has_loops()) return;
  // the error's components across the manifold removed, K's rows at the last projection: v's
  // always, q's where q's coordinates are the tangent's (no quaternion)
  const int nq = model.nq, nv = model.nv;
  auto ev = err.segment(nq, nv);
  ev -= projector_.solve(VecX(loops_.K * ev));
  if (!model.has_quaternions()) {
    auto eq = err.head(nq);
    eq -= projector_.solve(VecX(loops_.K * eq));
  }
}

MatX System::coordinates_of_tangent(double t, const double* y) {
  expand(t, y);
  const MatX P = tangent_to_coordinates(model, q);
  if (!has_prescribed()) return P;
  return P(q_index_, v_index_);  // block diagonal by joint, and the prescribed joints' blocks are 1 × 1
}

void System::tangent_of(double t, const double* y, Eigen::Ref<const MatX> Sq, Eigen::Ref<MatX> out) {
  expand(t, y);
  if (!has_prescribed()) {
    tangent_times(model, q, Sq, out);
    return;
  }
  MatX full = MatX::Zero(model.nq, Sq.cols()), d(model.nv, Sq.cols());
  for (int k = 0; k < nq_state_; ++k) full.row(q_index_[size_t(k)]) = Sq.row(k);
  tangent_times(model, q, full, d);
  for (int k = 0; k < nv_state_; ++k) out.row(k) = d.row(v_index_[size_t(k)]);
}

// A_j ← A_j M_j⁻¹ for each state joint j holding a quaternion, M_j = dexp⁻¹_{u_j} column by column
void System::times_increment_jacobian(const Eigen::Ref<const VecX>& u, Eigen::Ref<MatX> A) const {
  for (const StateJoint& j : state_joints_)
    visit_joint(model, j.body, [&](const auto& kind) {
      using J = std::decay_t<decltype(kind)>;
      if constexpr (!J::euclidean) {
        Eigen::Matrix<double, J::nv, J::nv> M;
        for (int c = 0; c < J::nv; ++c) {
          const Eigen::Matrix<double, J::nv, 1> e = Eigen::Matrix<double, J::nv, 1>::Unit(c);
          kind.increment_rate(u.data() + j.iv, e.data(), M.col(c).data());
        }
        const Eigen::Matrix<double, J::nv, J::nv> D = M.inverse();
        for (Eigen::Index r = 0; r < A.rows(); ++r) {  // row by row: no temporary on the heap
          const Eigen::Matrix<double, 1, J::nv> a = A.row(r).template segment<J::nv>(j.iv) * D;
          A.row(r).template segment<J::nv>(j.iv) = a;
        }
      }
    });
}

void System::tangent_jacobian(double t, const double* y, Eigen::Ref<MatX> J) {
  ++jac_evals;
  const int n = nv_state_;
  prepare_jacobian();
  at_state(t, y);
  // ∂q̈/∂δ (along the tangent) and ∂q̈/∂v of the model, with the inputs' terms: O(N²)
  if (has_prescribed())
    hybrid_dynamics_derivatives(model, data, locked_, v, tau, qdd_given, *derivatives, tau_hybrid, &inputs, solve_work_);
  else
    forward_dynamics_derivatives(model, data, v, tau, *derivatives, &inputs);
  const MatX &dq = derivatives->dqdd_dq, &dv = derivatives->dqdd_dv;
  J.setZero();
  // δ̇ = v
  J.block(0, n, n, n).setIdentity();
  // the state's rows and columns of ∂q̈/∂δ and ∂q̈/∂v
  for (int c = 0; c < n; ++c) {
    const int vc = v_index_[size_t(c)];
    for (int r = 0; r < n; ++r) {
      J(n + r, c) = dq(v_index_[size_t(r)], vc);
      J(n + r, n + c) = dv(v_index_[size_t(r)], vc);
    }
  }
  // the quadratures' rows: Ẇ = P(t, v), Ḋ = D(v) (W_p's left zero, as jacobian_prescribed's)
  if (nquad > 0) {
    inputs.power_derivatives(t, v, dP_, dD_);
    if (control_work && controlled) dP_ += control;
    for (int c = 0; c < n; ++c) {
      J(2 * n, n + c) = dP_(v_index_[size_t(c)]);
      J(2 * n + 1, n + c) = dD_(v_index_[size_t(c)]);
    }
  }
}

void System::tangent_jacobian_dq(double t, const double* y, Eigen::Ref<MatX> J) {
  ++jac_evals;
  const int nqs = nq_state_, n = nv_state_, m = size();
  y_work_ = Eigen::Map<const VecX>(y, m);
  rhs(t, y_work_.data(), f0_.data());
  J.setZero();
  J.block(0, n, n, n).setIdentity();
  // column c of δ: q ⊕ ε e_c; of v and the quadratures: y + ε e
  for (int c = 0; c < n + m - nqs; ++c) {
    const bool turn = c < n;
    const int at = turn ? 0 : nqs + (c - n);
    const double e = 1e-7 * (turn ? 1.0 : std::max(1.0, std::abs(y_work_(at))));
    if (turn) {
      f1_.head(n).setZero();  // the direction e_c (f1_ then takes rhs's output)
      f1_(c) = 1.0;
      integrate(Eigen::Map<const VecX>(y, nqs), f1_.head(n), e, y_work_.head(nqs));
    } else {
      y_work_(at) += e;
    }
    rhs(t, y_work_.data(), f1_.data());
    J.col(c).tail(m - nqs) = (f1_ - f0_).tail(m - nqs) / e;
    y_work_ = Eigen::Map<const VecX>(y, m);
  }
}

}  // namespace soadyn
