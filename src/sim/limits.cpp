#include "soadyn/sim/limits.hpp"

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>

namespace soadyn {

namespace {
// q within this of a bound is at it (rounding of the initial state, of the located root)
double at_bound(double bound) { return 1e-9 * std::max(1.0, std::abs(bound)); }
}  // namespace

JointLimits::JointLimits(const Model& m, double restitution, const std::vector<PrescribedInput>& prescribed)
    : model_(m), restitution_(restitution) {
  // the state leaves the prescribed joints (1-DOF, one q each) out: a free DOF's place in it is its
  // index less the prescribed ones before it
  std::vector<char> given(size_t(m.nv), 0);
  for (const PrescribedInput& p : prescribed) given[size_t(p.dof)] = 1;
  int skipped = 0;
  for (int k = 0; k < m.nv; ++k) {
    const int i = m.dof_body[k];
    if (given[size_t(k)]) {
      ++skipped;
      continue;
    }
    if (m.nv_i[i] != 1 || m.nq_i[i] != 1) continue;
    const int sq = m.idx_q[i] - skipped, sv = k - skipped;
    if (std::isfinite(m.lower[k])) sides_.push_back({k, m.idx_q[i], sv, sq, +1, m.lower[k]});
    if (std::isfinite(m.upper[k])) sides_.push_back({k, m.idx_q[i], sv, sq, -1, m.upper[k]});
  }
  lambda_.resize(0);
}

LimitEvent JointLimits::event(double t, int s, const char* kind, double before, double after, double lost) const {
  const Side& sd = sides_[size_t(s)];
  return {t, sd.dof, model_.joint_names[size_t(model_.dof_body[size_t(sd.dof)])], sd.sign > 0 ? -1 : +1, kind,
          before, after, lost};
}

void JointLimits::check_inside(const VecX& q) const {
  for (const Side& s : sides_) {
    if (s.sign * (q(s.coord) - s.bound) >= -at_bound(s.bound)) continue;
    char buf[160];
    std::snprintf(buf, sizeof buf, "' starts at %.9g, beyond its %s limit %.9g (simulation: limits: true)",
                  q(s.coord), s.sign > 0 ? "lower" : "upper", s.bound);
    throw Error("initial state: joint '" + model_.joint_names[size_t(model_.dof_body[size_t(s.dof)])] + buf);
  }
}

void JointLimits::constrain(System& sys) {
  if (held_.empty()) return;
  // q̈ = q̈₀ + Σ_j (𝓜⁻¹ e_j) λ_j with q̈_H = 0: 𝓜⁻¹ e_j as q̈(τ + e_j) − q̈(τ), W_HH λ = −q̈₀_H (with
  // prescribed motion 𝓜_ff⁻¹ e_j by the hybrid dynamics, and the holding torques move with λ too)
  Data& d = sys.data;
  const int h = int(held_.size());
  qdd0_ = d.qdd;
  hold0_ = sys.tau_hybrid;
  cols_.resize(model_.nv, h);
  hold_cols_.resize(model_.nv, h);
  for (int j = 0; j < h; ++j) {
    tau_ = sys.tau;
    tau_(sides_[size_t(held_[size_t(j)])].dof) += 1.0;
    sys.dynamics(tau_);
    cols_.col(j) = d.qdd - qdd0_;
    hold_cols_.col(j) = sys.tau_hybrid - hold0_;
  }
  W_.resize(h, h);
  VecX rhs(h);
  for (int a = 0; a < h; ++a) {
    const int ka = sides_[size_t(held_[size_t(a)])].dof;
    W_.row(a) = cols_.row(ka);
    rhs(a) = -qdd0_(ka);
  }
  lambda_ = W_.partialPivLu().solve(rhs);
  d.qdd = qdd0_ + cols_ * lambda_;
  sys.tau_hybrid = hold0_ + hold_cols_ * lambda_;
  for (const int s : held_) d.qdd(sides_[size_t(s)].dof) = 0.0;
}

void JointLimits::evaluate(System& sys, double t, const VecX& y) {
  ydot_.resize(sys.size());
  sys.rhs(t, y.data(), ydot_.data());
}

void JointLimits::roots(System& sys, double t, const double* y, double* g) {
  if (!held_.empty()) {
    ydot_.resize(sys.size());
    sys.rhs(t, y, ydot_.data());  // λ at (t, y)
  }
  for (int s = 0; s < count(); ++s) {
    const Side& sd = sides_[size_t(s)];
    const auto it = std::find(held_.begin(), held_.end(), s);
    g[s] = it != held_.end() ? sd.sign * lambda_(it - held_.begin()) : sd.sign * (y[sd.sq] - sd.bound);
  }
}

void JointLimits::contact(System& sys, double t, VecX& y, int s, std::vector<LimitEvent>& out) {
  const Model& m = model_;
  Data& d = sys.data;
  const Side& sd = sides_[size_t(s)];
  const int nqs = sys.nq_state(), nvs = sys.nv_state();
  auto v = y.segment(nqs, nvs);
  const double before = v(sd.sv);
  // 𝓜 at q (the prescribed joints at their motion, whose velocities do not jump: the impulse moves
  // the free DOFs through 𝓜_ff), and 𝓜_ff⁻¹ E on the DOFs that take an impulse: this one and the
  // held ones
  sys.expand(t, y.data());
  const VecX v_before = sys.v;
  update_kinematics(m, d, sys.q);
  mass_matrix(m, d);
  const std::vector<int>& fv = sys.v_index();
  const Eigen::LDLT<MatX> M(d.M(fv, fv));
  std::vector<int> S{sd.sv};
  for (const int h : held_) S.push_back(sides_[size_t(h)].sv);
  const int n = int(S.size());
  MatX E = MatX::Zero(nvs, n);
  for (int j = 0; j < n; ++j) E(S[size_t(j)], j) = 1.0;
  const MatX C = M.solve(E);  // 𝓜_ff⁻¹ E
  MatX Wss(n, n);
  for (int a = 0; a < n; ++a) Wss.row(a) = C.row(S[size_t(a)]);
  // impulses p on S: v⁺_S = (−e v_k⁻, 0, …) and Δv_f = 𝓜_ff⁻¹ E p
  auto hit = [&](double after) {
    VecX target = VecX::Zero(n), now(n);
    target(0) = after;
    for (int a = 0; a < n; ++a) now(a) = v(S[size_t(a)]);
    const VecX p = Wss.partialPivLu().solve(target - now);
    v += C * p;
    for (int a = 1; a < n; ++a) v(S[size_t(a)]) = 0.0;
    v(sd.sv) = after;
  };
  double after = -restitution_ * before;
  const bool rests = std::abs(after) <= kRestSpeed;
  if (rests) after = 0.0;
  hit(after);
  // the energy lost: T⁻ − T⁺ plus the work of the prescribed joints' impulses (𝓜 Δv)_p · q̇*_p,
  // which W_p counts (the impulse on the limit does −p (v_k⁻ + v_k⁺)/2 of it)
  VecX v_after = v_before;
  for (int k = 0; k < nvs; ++k) v_after(fv[size_t(k)]) = v(k);
  const VecX impulse = d.M * (v_after - v_before);
  double held_work = 0.0;
  for (const PrescribedInput& p : sys.inputs.prescribed) held_work += impulse(p.dof) * v_before(p.dof);
  if (sys.nquad > 2) y(nqs + nvs + 2) += held_work;
  const double lost = 0.5 * v_before.dot(d.M * v_before) - 0.5 * v_after.dot(d.M * v_after) + held_work;
  lost_ += lost;
  if (!rests) {
    out.push_back(event(t, s, "impact", before, after, lost));
    return;
  }
  // at rest on the bound: held while the constraint pushes (σ λ ≥ 0), else it leaves by itself
  y(sd.sq) = sd.bound;
  held_.push_back(s);
  evaluate(sys, t, y);
  if (sd.sign * lambda_(Eigen::Index(held_.size() - 1)) < 0) {
    held_.pop_back();
    out.push_back(event(t, s, "impact", before, after, lost));
    return;
  }
  out.push_back(event(t, s, "hold", before, after, lost));
}

std::vector<LimitEvent> JointLimits::start(System& sys, double t, VecX& y) {
  sys.expand(t, y.data());
  check_inside(sys.q);
  std::vector<LimitEvent> out;
  for (int s = 0; s < count(); ++s) {
    const Side& sd = sides_[size_t(s)];
    if (std::abs(y(sd.sq) - sd.bound) > at_bound(sd.bound)) continue;
    if (sd.sign * y(sys.nq_state() + sd.sv) <= kRestSpeed) contact(sys, t, y, s, out);
  }
  return out;
}

std::vector<LimitEvent> JointLimits::on_roots(System& sys, double t, VecX& y, const std::vector<int>& which) {
  std::vector<LimitEvent> out;
  for (const int s : which) {
    const auto it = std::find(held_.begin(), held_.end(), s);
    if (it != held_.end()) {  // the constraint would pull: the joint leaves at rest
      held_.erase(it);
      out.push_back(event(t, s, "release", 0.0, 0.0, 0.0));
      continue;
    }
    const Side& sd = sides_[size_t(s)];
    if (sd.sign * y(sys.nq_state() + sd.sv) < 0) contact(sys, t, y, s, out);  // else grazing: nothing to stop
  }
  return out;
}

int limit_event_code(const std::string& kind) {
  for (int k = 0; k < int(std::size(kLimitEventKinds)); ++k)
    if (kind == kLimitEventKinds[k]) return k;
  return -1;
}

}  // namespace soadyn
