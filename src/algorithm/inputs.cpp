#include "soadyn/algorithm/inputs.hpp"

#include "soadyn/algorithm/table.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace soadyn {

namespace {
// the quintic rest-to-rest profile's s ∈ [0, 1] and its derivatives' factors (JointSlew)
struct SlewAt {
  double s, span, T;
};
SlewAt slew_at(const JointSlew& w, double t) {
  const double s = w.duration > 0 ? std::clamp((t - w.start) / w.duration, 0.0, 1.0) : (t < w.start ? 0.0 : 1.0);
  return {s, w.to - w.from, w.duration};
}
}  // namespace

// q_d = from + Δ (10 s³ − 15 s⁴ + 6 s⁵),  q̇_d = Δ/T · 30 s² (1 − s)²,  q̈_d = Δ/T² · 60 s (1 − s)(1 − 2s)
double JointTarget::value(double t) const {
  if (slew) {
    const SlewAt a = slew_at(*slew, t);
    return slew->from + a.span * a.s * a.s * a.s * (10 - 15 * a.s + 6 * a.s * a.s);
  }
  if (table) return table->value(t);
  return constant + amplitude * std::sin(2 * std::numbers::pi * frequency * t + phase);
}
double JointTarget::rate(double t) const {
  if (slew) {
    const SlewAt a = slew_at(*slew, t);
    return a.T > 0 ? a.span / a.T * 30 * a.s * a.s * (1 - a.s) * (1 - a.s) : 0.0;
  }
  if (table) return table->rate(t);
  const double w = 2 * std::numbers::pi * frequency;
  return amplitude * w * std::cos(w * t + phase);
}
double JointTarget::acceleration(double t) const {
  if (slew) {
    const SlewAt a = slew_at(*slew, t);
    return a.T > 0 ? a.span / (a.T * a.T) * 60 * a.s * (1 - a.s) * (1 - 2 * a.s) : 0.0;
  }
  if (table) return table->acceleration(t);
  const double w = 2 * std::numbers::pi * frequency;
  return -amplitude * w * w * std::sin(w * t + phase);
}

std::vector<double> JointTarget::corners() const {
  if (slew) return {slew->start, slew->start + slew->duration};
  if (table) return {table->t_first(), table->t_last()};
  return {};
}

void PrescribedInput::at(double t, double& q, double& qd, double& qdd) const {
  if (function) {
    function(t, q, qd, qdd);
    return;
  }
  q = target.value(t), qd = target.rate(t), qdd = target.acceleration(t);
}

void Inputs::evaluate(double t, const VecX& q, const VecX& v, Eigen::Ref<VecX> tau) const {
  tau.setZero();
  for (const auto& u : torques)
    tau(u.dof) += u.constant + u.amplitude * std::sin(2 * std::numbers::pi * u.frequency * t + u.phase);
  for (const auto& s : springs) tau(s.dof) -= s.stiffness * (q(s.coord) - s.rest);
  for (const auto& d : dampers) tau(d.dof) -= d.damping * v(d.dof);
}

Inputs::Power Inputs::power(double t, const VecX& v) const {
  // P = Σ τ_k q̇_k over torques and dampers; D = Σ c q̇²
  Power p;
  for (const auto& u : torques)
    p.inputs += (u.constant + u.amplitude * std::sin(2 * std::numbers::pi * u.frequency * t + u.phase)) * v(u.dof);
  for (const auto& d : dampers) p.dissipated += d.damping * v(d.dof) * v(d.dof);
  p.inputs -= p.dissipated;
  return p;
}

void Inputs::add_derivatives(Eigen::Ref<MatX> dq, Eigen::Ref<MatX> dv) const {
  // τ = −k (q − rest) − c q̇
  for (const auto& s : springs) dq(s.dof, s.dof) -= s.stiffness;
  for (const auto& d : dampers) dv(d.dof, d.dof) -= d.damping;
}

void Inputs::add_derivatives_times(const MatX& A, Eigen::Ref<MatX> dq, Eigen::Ref<MatX> dv) const {
  // add_derivatives' diagonal entries, each scaling a column of A
  for (const auto& s : springs) dq.col(s.dof) -= s.stiffness * A.col(s.dof);
  for (const auto& d : dampers) dv.col(d.dof) -= d.damping * A.col(d.dof);
}

void Inputs::add_derivatives_directions(const Eigen::Ref<const MatX>& xq, const Eigen::Ref<const MatX>& xv,
                                        Eigen::Ref<MatX> out) const {
  // the diagonal of add_derivatives, each entry scaling a row of the directions
  for (const auto& s : springs) out.row(s.dof) -= s.stiffness * xq.row(s.dof);
  for (const auto& d : dampers) out.row(d.dof) -= d.damping * xv.row(d.dof);
}

void Inputs::add_derivatives_transpose_times(const VecX& mu, Eigen::Ref<VecX> gq, Eigen::Ref<VecX> gv) const {
  // the diagonal of add_derivatives: (∂τ/∂q)ᵀ μ and (∂τ/∂v)ᵀ μ
  for (const auto& s : springs) gq(s.dof) -= s.stiffness * mu(s.dof);
  for (const auto& d : dampers) gv(d.dof) -= d.damping * mu(d.dof);
}

void Inputs::power_derivatives(double t, const VecX& v, Eigen::Ref<VecX> dP, Eigen::Ref<VecX> dD) const {
  // P = Σ τ_u(t) q̇_u − Σ c q̇²,  D = Σ c q̇²
  dP.setZero();
  dD.setZero();
  for (const auto& u : torques)
    dP(u.dof) += u.constant + u.amplitude * std::sin(2 * std::numbers::pi * u.frequency * t + u.phase);
  for (const auto& d : dampers) {
    dP(d.dof) -= 2.0 * d.damping * v(d.dof);
    dD(d.dof) += 2.0 * d.damping * v(d.dof);
  }
}

double Inputs::spring_energy(const VecX& q) const {
  double V = 0.0;
  for (const auto& s : springs) V += 0.5 * s.stiffness * (q(s.coord) - s.rest) * (q(s.coord) - s.rest);
  return V;
}

}  // namespace soadyn
