// The system the integrators step (system.hpp): ẏ = f(t, y) for a model with its inputs and
// controllers, its Jacobian ∂f/∂y by the analytic derivatives (and by forward differences), and the
// Jacobian applied to columns without forming it.
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/multibody/configuration.hpp"
#include "soadyn/sim/system.hpp"
#include "soadyn/sim/integrators.hpp"

#include <cmath>
#include <sstream>
#include <string>

namespace soadyn {

namespace {
std::vector<int> prescribed_bodies(const Model& m, const Inputs& in) {
  std::vector<int> bodies;
  for (const PrescribedInput& p : in.prescribed) {
    if (p.body < 0 || p.body >= m.nbodies || m.nv_i[p.body] != 1 || m.nq_i[p.body] != 1)
      throw Error("prescribed motion: joint '" + p.joint + "' is not a 1-DOF joint of the model");
    bodies.push_back(p.body);
  }
  return bodies;
}
}  // namespace

System::System(const Model& m, const Inputs& in, FdMethod fd, bool control_work)
    : model(m),
      inputs(in),
      method(fd),
      nquad(!in.prescribed.empty() ? 3 : in.does_work() || control_work ? 2 : 0),
      data(m),
      q(m.nq),
      v(m.nv),
      tau(m.nv),
      qd(m.nq),
      qdd_given(VecX::Zero(m.nv)),
      tau_hybrid(VecX::Zero(m.nv)),
      prescribed_tau(VecX::Zero(Eigen::Index(in.prescribed.size()))),
      control(VecX::Zero(m.nv)),
      feedback_tau(VecX::Zero(m.nv)),
      control_work(control_work),
      locked_(m, prescribed_bodies(m, in)),
      loops_(m, in.loops),
      nq_state_(m.nq - locked_.nv_locked),
      nv_state_(m.nv - locked_.nv_locked),
      eval_y_(VecX::Zero(size())),
      y_work_(size()),
      f0_(size()),
      f1_(size()),
      dP_(m.nv),
      dD_(m.nv) {
  if (!in.loops.empty() && !in.prescribed.empty())
    throw Error("closed loops and prescribed motion together are not available yet: drop one of them");
  // the state's layout: every joint not prescribed, in the tree's order
  for (int i = 0; i < m.nbodies; ++i) {
    if (locked_.locked[size_t(i)]) continue;
    const StateJoint sj{int(q_index_.size()), m.nq_i[i], int(v_index_.size()), m.nv_i[i], i};
    if (const int k = joint_quaternion(m, i); k >= 0) quaternions_.push_back(sj.iq + k);
    for (int c = 0; c < m.nq_i[i]; ++c) q_index_.push_back(m.idx_q[i] + c);
    for (int c = 0; c < m.nv_i[i]; ++c) v_index_.push_back(m.idx_v[i] + c);
    state_joints_.push_back(sj);
  }
}

VecX System::state(const VecX& q0, const VecX& v0) const {
  VecX y = VecX::Zero(size());
  for (int k = 0; k < nq_state_; ++k) y(k) = q0(q_index_[size_t(k)]);
  for (int k = 0; k < nv_state_; ++k) y(nq_state_ + k) = v0(v_index_[size_t(k)]);
  return y;
}

void System::qdot(const Eigen::Ref<const VecX>& q_state, const Eigen::Ref<const VecX>& v_state, Eigen::Ref<VecX> out) {
  if (!has_prescribed()) {
    model.qdot(q_state, v_state, out);
    return;
  }
  // joint by joint: the prescribed ones' entries (1-DOF: q̇ = v) play no part in the others'
  for (int k = 0; k < nq_state_; ++k) q(q_index_[size_t(k)]) = q_state(k);
  for (int k = 0; k < nv_state_; ++k) v(v_index_[size_t(k)]) = v_state(k);
  model.qdot(q, v, qd);
  for (int k = 0; k < nq_state_; ++k) out(k) = qd(q_index_[size_t(k)]);
}

void System::expand(double t, const double* y) {
  linearized_ = false;  // q and v no longer those of data's evaluation
  evaluated_ = false;
  if (!has_prescribed()) {
    q = Eigen::Map<const VecX>(y, model.nq);
    v = Eigen::Map<const VecX>(y + model.nq, model.nv);
    return;
  }
  for (int k = 0; k < nq_state_; ++k) q(q_index_[size_t(k)]) = y[k];
  for (int k = 0; k < nv_state_; ++k) v(v_index_[size_t(k)]) = y[nq_state_ + k];
  // q*, q̇*, q̈* at t
  for (const PrescribedInput& p : inputs.prescribed) p.at(t, q(p.coord), v(p.dof), qdd_given(p.dof));
}

void System::at_state(double t, const double* y) {
  linearized_ = false;  // data is about to hold another evaluation
  evaluated_ = false;
  expand(t, y);
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
  if (has_prescribed()) {
    rhs_prescribed(t, ydot);
    evaluated_ = true;
    eval_t_ = t;
    eval_y_ = Eigen::Map<const VecX>(y, size());
    return;
  }
  if (has_loops()) {
    loop_forward_dynamics(model, data, inputs.loops, v, tau, loops_);  // the loops' multipliers with q̈
    check_loop_rank(t);
  } else
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

// ẏ = [q̇_f; q̈_f; P; D; P_p]: q̈_f and τ_p by the hybrid dynamics; P_p = Σ τ_p q̇*, τ_p the
// holding τ less the joint's own inputs (the motor's torque)
void System::rhs_prescribed(double t, double* ydot) {
  hybrid_dynamics(model, data, locked_, tau, qdd_given, tau_hybrid);
  if (constraint) constraint->constrain(*this);  // held DOFs: their constraint forces (and the holding τ's share)
  model.qdot(q, v, qd);
  for (int k = 0; k < nq_state_; ++k) ydot[k] = qd(q_index_[size_t(k)]);
  for (int k = 0; k < nv_state_; ++k) ydot[nq_state_ + k] = data.qdd(v_index_[size_t(k)]);
  const Inputs::Power p = inputs.power(t, v);
  double controller = 0.0, held = 0.0;
  if (control_work) controller = feedback_tau.dot(v) + (controlled ? control.dot(v) : 0.0);
  for (size_t j = 0; j < inputs.prescribed.size(); ++j) {
    const int k = inputs.prescribed[j].dof;
    prescribed_tau(Eigen::Index(j)) = tau_hybrid(k) - tau(k);
    held += prescribed_tau(Eigen::Index(j)) * v(k);
  }
  const int w = nq_state_ + nv_state_;
  ydot[w] = p.inputs + controller;
  ydot[w + 1] = p.dissipated;
  ydot[w + 2] = held;
}

void System::check_loop_rank(double t) {
  if (loop_first_rank_ < 0) {
    loop_first_rank_ = loops_.rank;
    loop_block_rank_ = loop_ranks(loops_, int(inputs.loops.size()));
  }
  if (loops_.rank >= loop_first_rank_ && loops_.margin >= kLoopSingular) return;
  // a dead point: the rows that held the motion no longer determine it
  std::string names;
  const std::vector<int> which = singular_loops(loops_, loop_block_rank_);
  for (size_t k = 0; k < which.size(); ++k)
    names += std::string(k == 0 ? "" : k + 1 == which.size() ? " and " : ", ") + "'" + inputs.loops[size_t(which[k])].name + "'";
  std::ostringstream os;
  os << "closed loop" << (which.size() > 1 ? "s " : " ") << names << " at a singular configuration (a dead point) at t = "
     << t << " s: " << (which.size() > 1 ? "their" : "its") << " constraint rows lose rank (" << loop_first_rank_
     << " at the start, ";
  if (loops_.rank < loop_first_rank_)
    os << loops_.rank << " here";
  else
    os << "here the smallest pivot " << loops_.margin << " of the largest";
  os << "), so the loops no longer determine the motion";
  throw SimulationError(os.str(), t);
}

void System::dynamics(const VecX& tau_in) {
  if (has_loops())
    loop_forward_dynamics(model, data, inputs.loops, v, tau_in, loops_);
  else if (has_prescribed())
    hybrid_dynamics(model, data, locked_, tau_in, qdd_given, tau_hybrid);
  else
    forward_dynamics(model, data, tau_in, method);
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
  if (has_loops()) {  // the loops' multipliers are not differentiated: ∂f/∂y by differences
    --jac_evals;
    jacobian_dq(t, y, J);
    return;
  }
  at_state(t, y);
  if (has_prescribed()) {
    jacobian_prescribed(t, J);
    return;
  }
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

// ∂f/∂y of the free joints' state: the model's blocks (q̇'s joint by joint, the hybrid dynamics'
// ∂q̈/∂q chained to the coordinates, ∂q̈/∂v), then the state's rows and columns of them.  W_p's row is
// left zero: it feeds nothing back, and Newton converges on it with the rest
void System::jacobian_prescribed(double t, Eigen::Ref<MatX> J) {
  const int nq = model.nq, nv = model.nv, nqs = nq_state_, nvs = nv_state_;
  if (Jqq_.rows() != nq) Jqq_.resize(nq, nq), Jqv_.resize(nq, nv), Jvq_.resize(nv, nq);
  hybrid_dynamics_derivatives(model, data, locked_, v, tau, qdd_given, *derivatives, tau_hybrid, &inputs, solve_work_);
  Jqq_.setZero(), Jqv_.setZero(), Jvq_.setZero();
  qdot_jacobian(model, q, v, Jqq_, Jqv_);
  add_times_tangent(model, q, derivatives->dqdd_dq, Jvq_);
  const MatX& dv = derivatives->dqdd_dv;
  J.setZero();
  for (int c = 0; c < nqs; ++c) {
    const int qc = q_index_[size_t(c)];
    for (int r = 0; r < nqs; ++r) J(r, c) = Jqq_(q_index_[size_t(r)], qc);
    for (int r = 0; r < nvs; ++r) J(nqs + r, c) = Jvq_(v_index_[size_t(r)], qc);
  }
  for (int c = 0; c < nvs; ++c) {
    const int vc = v_index_[size_t(c)];
    for (int r = 0; r < nqs; ++r) J(r, nqs + c) = Jqv_(q_index_[size_t(r)], vc);
    for (int r = 0; r < nvs; ++r) J(nqs + r, nqs + c) = dv(v_index_[size_t(r)], vc);
  }
  // the quadratures' rows: Ẇ = P(t, v), Ḋ = D(v) on the free DOFs' columns
  inputs.power_derivatives(t, v, dP_, dD_);
  if (control_work && controlled) dP_ += control;
  for (int c = 0; c < nvs; ++c) {
    J(nqs + nvs, nqs + c) = dP_(v_index_[size_t(c)]);
    J(nqs + nvs + 1, nqs + c) = dD_(v_index_[size_t(c)]);
  }
}

long System::linearize(double t, const double* y) {
  if (has_loops()) throw Error("the forward sensitivities are not available with closed loops yet");
  prepare_jacobian();
  const int n = size();
  if (linearized_ && t == lin_t_ && Eigen::Map<const VecX>(y, n) == lin_y_) return linearizations_;
  // [kin], [vel], τ, q̈ and the articulated-body factor: rhs's when it has just evaluated this very
  // (t, y) by that route without constraints (CVODES evaluates f at each iterate before the
  // sensitivities' right-hand side there, and at the state it has converged before the staggered
  // corrector), else evaluated here.  With prescribed motion the hybrid dynamics' q̈ and its factor
  // with those joints locked (rhs's own route)
  if (has_prescribed()) {
    if (!holds_rhs_at(t, y)) {
      at_state(t, y);
      hybrid_dynamics(model, data, locked_, tau, qdd_given, tau_hybrid);
    }
  } else if (!(method == FdMethod::ArticulatedBody && !constraint && holds_rhs_at(t, y))) {
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
  const int nq = model.nq, nv = model.nv, w = nq_state_ + nv_state_;
  const Eigen::Index ns = S.cols();
  if (forces && (forces->rows() != nv || forces->cols() > ns))
    throw Error("System::linearized_times: forces: expected " + std::to_string(nv) + " rows and at most as many columns as S");
  if (S.rows() != size() || out.rows() != size() || out.cols() != ns)
    throw Error("System::linearized_times: expected S and out of " + std::to_string(size()) + " rows and the same columns");
  if (!has_prescribed()) {
    model_times(S.topRows(nq + nv), out.topRows(nq + nv), forces);
  } else {
    // S's rows in the model's layout, the prescribed joints' zero (their q and v are functions of t
    // alone), the model's products, and the free joints' rows of them: the locked factor gives
    // q̈_f's rows 𝓜_ff⁻¹ (…)_f
    if (Sm_.rows() != nq + nv || Sm_.cols() != ns) Sm_.resize(nq + nv, ns), Om_.resize(nq + nv, ns);
    Sm_.setZero();
    for (int k = 0; k < nq_state_; ++k) Sm_.row(q_index_[size_t(k)]) = S.row(k);
    for (int k = 0; k < nv_state_; ++k) Sm_.row(nq + v_index_[size_t(k)]) = S.row(nq_state_ + k);
    model_times(Sm_, Om_, forces);
    for (int k = 0; k < nq_state_; ++k) out.row(k) = Om_.row(q_index_[size_t(k)]);
    for (int k = 0; k < nv_state_; ++k) out.row(nq_state_ + k) = Om_.row(nq + v_index_[size_t(k)]);
  }
  // the quadratures' rows: Ẇ = P(t, v), Ḋ = D(v); W_p's row left zero, as in jacobian (it feeds
  // nothing back, and the sensitivities reported are q's and v's)
  if (nquad > 0) {
    const auto s_v = has_prescribed() ? Eigen::Ref<const MatX>(Sm_.bottomRows(nv)) : Eigen::Ref<const MatX>(S.middleRows(nq, nv));
    inputs.power_derivatives(lin_t_, v, dP_, dD_);
    if (control_work && controlled) dP_ += control;
    out.row(w).noalias() = dP_.transpose() * s_v;
    out.row(w + 1).noalias() = dD_.transpose() * s_v;
    if (nquad > 2) out.row(w + 2).setZero();
  }
}

// out = (∂[q̇; q̈]/∂[q; v]) S in the model's layout (nq + nv rows each)
void System::model_times(Eigen::Ref<const MatX> S, Eigen::Ref<MatX> out, const MatX* forces) {
  const int nq = model.nq, nv = model.nv;
  const Eigen::Index ns = S.cols();
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
  const int w = nq_state_ + nv_state_;
  if (k == w && nquad > 0) return "the inputs' work W (quadrature)";
  if (k == w + 1 && nquad > 0) return "the dampers' dissipated energy D (quadrature)";
  if (k == w + 2 && nquad > 2) return "the prescribed joints' work W_p (quadrature)";
  const bool is_q = k < nq_state_;
  const int at = is_q ? k : k - nq_state_;
  if (at < 0 || at >= (is_q ? nq_state_ : nv_state_)) return "component " + std::to_string(k);
  const int idx = is_q ? q_index_[size_t(at)] : v_index_[size_t(at)];
  const std::vector<std::string> names = is_q ? model.q_names() : model.v_names();
  if (idx < 0 || idx >= int(names.size())) return "component " + std::to_string(k);
  return "joint '" + names[idx] + "' (" + (is_q ? "q" : "qd") + ")";
}

}  // namespace soadyn
