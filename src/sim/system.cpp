// The system the integrators step (system.hpp): ẏ = f(t, y) for a model with its inputs and
// controllers, its Jacobian ∂f/∂y by the analytic derivatives (and by forward differences), and the
// Jacobian applied to columns without forming it.
#include "soadyn/sim/integrators.hpp"
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/sim/limits.hpp"
#include "soadyn/multibody/configuration.hpp"
#include "soadyn/sim/system.hpp"

#include <cmath>
#include <string>

namespace soadyn {

System::System(const Model& m, const Inputs& in, FdMethod fd, bool control_work)
    : model(m),
      inputs(in),
      method(fd),
      nquad(in.does_work() || control_work ? 2 : 0),
      data(m),
      q(m.nq),
      v(m.nv),
      tau(m.nv),
      qd(m.nq),
      control(VecX::Zero(m.nv)),
      feedback_tau(VecX::Zero(m.nv)),
      control_work(control_work),
      eval_y_(VecX::Zero(m.nq + m.nv + nquad)),
      y_work_(m.nq + m.nv + nquad),
      f0_(m.nq + m.nv + nquad),
      f1_(m.nq + m.nv + nquad),
      dP_(m.nv),
      dD_(m.nv) {}

VecX System::state(const VecX& q0, const VecX& v0) const {
  VecX y = VecX::Zero(size());
  y.head(model.nq) = q0;
  y.segment(model.nq, model.nv) = v0;
  return y;
}

void System::at_state(double t, const double* y) {
  linearized_ = false;  // data is about to hold another evaluation
  evaluated_ = false;
  q = Eigen::Map<const VecX>(y, model.nq);
  v = Eigen::Map<const VecX>(y + model.nq, model.nv);
  update_kinematics(model, data, q);
  update_velocities(model, data, v);
  inputs.evaluate(t, q, v, tau);
  if (controlled) tau += control;
  if (feedback) {
    feedback_tau.setZero();
    feedback(t, q, v, feedback_tau);
    tau += feedback_tau;
  }
}

void System::rhs(double t, const double* y, double* ydot) {
  ++rhs_evals;
  at_state(t, y);
  forward_dynamics(model, data, tau, method);
  if (constraint) constraint->constrain(*this);  // held DOFs: their constraint forces
  model.qdot(q, v, qd);
  Eigen::Map<VecX>(ydot, model.nq) = qd;
  Eigen::Map<VecX>(ydot + model.nq, model.nv) = data.qdd;
  if (nquad > 0) {
    // Ẇ = (τ_torques + τ_dampers) · q̇,  Ḋ = Σ c q̇²
    const Inputs::Power p = inputs.power(t, v);
    double controller = 0.0;  // (control + τ_c) · v, the controllers' power (v · τ is power on every joint)
    if (control_work) controller = feedback_tau.dot(v) + (controlled ? control.dot(v) : 0.0);
    ydot[model.nq + model.nv] = p.inputs + controller;
    ydot[model.nq + model.nv + 1] = p.dissipated;
  }
  evaluated_ = true;
  eval_t_ = t;
  eval_y_ = Eigen::Map<const VecX>(y, size());
}

bool System::holds_rhs_at(double t, const double* y) const {
  return evaluated_ && t == eval_t_ && Eigen::Map<const VecX>(y, size()) == eval_y_;
}

void System::prepare_jacobian() {
  if (!derivatives) derivatives.emplace(model);
  if (lin_y_.size() != size()) lin_y_ = VecX::Zero(size());  // linearize's record of its state
  if (solve_work_.size() == 0) solve_work_ = articulated_solve_work(model);
}

void System::jacobian(double t, const double* y, Eigen::Ref<MatX> J) {
  ++jac_evals;
  const int nq = model.nq, nv = model.nv;
  prepare_jacobian();
  at_state(t, y);
  // q̈, ∂q̈/∂q (along the tangent), ∂q̈/∂v with the inputs' terms, and 𝓜⁻¹: O(N²)
  forward_dynamics_derivatives(model, data, v, tau, *derivatives, &inputs);
  const MatX& dq = derivatives->dqdd_dq;
  J.setZero();
  // ∂q̇/∂q and ∂q̇/∂v: block diagonal, joint by joint
  qdot_jacobian(model, q, v, J.topLeftCorner(nq, nq), J.block(0, nq, nq, nv));
  // ∂q̈/∂q_coords = ∂q̈/∂δ · T(q)
  add_times_tangent(model, q, dq, J.block(nq, 0, nv, nq));
  J.block(nq, nq, nv, nv) = derivatives->dqdd_dv;
  // the quadratures' rows: Ẇ = P(t, v), Ḋ = D(v); nothing depends on W or D
  if (nquad > 0) {
    inputs.power_derivatives(t, v, dP_, dD_);
    if (control_work && controlled) dP_ += control;  // ∂(control · v)/∂v
    J.row(nq + nv).segment(nq, nv) = dP_.transpose();
    J.row(nq + nv + 1).segment(nq, nv) = dD_.transpose();
  }
}

long System::linearize(double t, const double* y) {
  prepare_jacobian();
  const int n = size();
  if (linearized_ && t == lin_t_ && Eigen::Map<const VecX>(y, n) == lin_y_) return linearizations_;
  // [kin], [vel], τ, q̈ and the articulated-body factor: rhs's when it has just evaluated this very
  // (t, y) by that route without constraints (CVODES evaluates f at each iterate before the
  // sensitivities' right-hand side there, and at the state it has converged before the staggered
  // corrector), else evaluated here
  if (!(method == FdMethod::ArticulatedBody && !constraint && holds_rhs_at(t, y))) {
    at_state(t, y);
    forward_dynamics(model, data, tau, FdMethod::ArticulatedBody);
  }
  // the sweeps ∂ID/∂x is made of, at that q̈: O(N)
  inverse_dynamics_derivative_sweeps(model, data, v, data.qdd, *derivatives);
  lin_t_ = t;
  lin_y_ = Eigen::Map<const VecX>(y, n);
  linearized_ = true;
  return ++linearizations_;
}

void System::jacobian_times(double t, const double* y, const MatX& S, MatX& out) {
  linearize(t, y);
  linearized_times(S, out);
}

void System::linearized_times(const MatX& S, MatX& out, const MatX* forces) {
  if (out.rows() != size() || out.cols() != S.cols()) out.resize(size(), S.cols());
  linearized_times(Eigen::Ref<const MatX>(S), Eigen::Ref<MatX>(out), forces);
}

void System::linearized_times(Eigen::Ref<const MatX> S, Eigen::Ref<MatX> out, const MatX* forces) {
  if (!linearized_) throw Error("System::linearized_times: no state linearized since the last evaluation");
  const double t = lin_t_;
  const int nq = model.nq, nv = model.nv;
  const Eigen::Index ns = S.cols();
  if (forces && (forces->rows() != nv || forces->cols() > ns))
    throw Error("System::linearized_times: forces: expected " + std::to_string(nv) + " rows and at most as many columns as S");
  if (S.rows() != size() || out.rows() != size() || out.cols() != ns)
    throw Error("System::linearized_times: expected S and out of " + std::to_string(size()) + " rows and the same columns");
  if (delta_.rows() != nv || delta_.cols() != ns) delta_.resize(nv, ns), W_.resize(nv, ns);
  const auto s_v = S.middleRows(nq, nv);
  // q̇'s rows, and S's q rows on the tangent: δ = T(q) s_q (q itself when no joint holds a quaternion)
  const bool tangent = model.has_quaternions();
  if (tangent)
    linearized_tangent_rows(S, out);
  else
    out.topRows(nq) = s_v;
  const auto dq = tangent ? Eigen::Ref<const MatX>(delta_) : Eigen::Ref<const MatX>(S.topRows(nq));
  // q̈'s rows: 𝓜⁻¹ ((∂τ_in/∂q − ∂ID/∂q) δ + (∂τ_in/∂v − ∂ID/∂v) s_v + F): the products O(N) per
  // column, then 𝓜⁻¹ by the articulated-body factor, O(N) per column
  inverse_dynamics_derivatives_times(model, *derivatives, dq, s_v, W_);
  W_ = -W_;
  inputs.add_derivatives_directions(dq, s_v, W_);
  if (forces) W_.rightCols(forces->cols()) += *forces;
  articulated_solve(model, data, W_, solve_work_);
  out.middleRows(nq, nv) = W_;
  // the quadratures' rows: Ẇ = P(t, v), Ḋ = D(v)
  if (nquad > 0) {
    inputs.power_derivatives(t, v, dP_, dD_);
    if (control_work && controlled) dP_ += control;
    out.row(nq + nv).noalias() = dP_.transpose() * s_v;
    out.row(nq + nv + 1).noalias() = dD_.transpose() * s_v;
  }
}

void System::linearized_solve(Eigen::Ref<MatX> X) {
  if (!linearized_) throw Error("System::linearized_solve: no state linearized since the last evaluation");
  articulated_solve(model, data, X, solve_work_);
}

void System::linearized_tangent_rows(const Eigen::Ref<const MatX>& S, Eigen::Ref<MatX>& out) {
  const int nq = model.nq, nv = model.nv;
  // q̇'s rows ∂q̇/∂q s_q + ∂q̇/∂v s_v, and δ = T(q) s_q
  qdot_jacobian_times(model, q, v, S.topRows(nq), S.middleRows(nq, nv), out.topRows(nq));
  tangent_times(model, q, S.topRows(nq), delta_);
}

void System::jacobian_dq(double t, const double* y, Eigen::Ref<MatX> J) {
  ++jac_evals;
  const int n = size();
  y_work_ = Eigen::Map<const VecX>(y, n);
  rhs(t, y_work_.data(), f0_.data());
  for (int c = 0; c < n; ++c) {
    const double e = 1e-7 * std::max(1.0, std::abs(y_work_(c)));
    const double keep = y_work_(c);
    y_work_(c) += e;
    rhs(t, y_work_.data(), f1_.data());
    J.col(c) = (f1_ - f0_) / e;
    y_work_(c) = keep;
  }
}

std::string System::component_name(int k) const {
  if (k == model.nq + model.nv && nquad > 0) return "the inputs' work W (quadrature)";
  if (k == model.nq + model.nv + 1 && nquad > 0) return "the dampers' dissipated energy D (quadrature)";
  const bool is_q = k < model.nq;
  const int idx = is_q ? k : k - model.nq;
  const std::vector<std::string> names = is_q ? model.q_names() : model.v_names();
  if (idx < 0 || idx >= int(names.size())) return "component " + std::to_string(k);
  return "joint '" + names[idx] + "' (" + (is_q ? "q" : "qd") + ")";
}

}  // namespace soadyn
