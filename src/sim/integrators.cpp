#include "soadyn/sim/integrators.hpp"

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/sim/limits.hpp"

#include "fixed_step.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include <cmath>
#include <limits>
#include <sstream>

namespace soadyn {

int first_non_finite(const VecX& y) {
  for (int k = 0; k < y.size(); ++k)
    if (!std::isfinite(y(k))) return k;
  return -1;
}

StepCount count_steps(double T, double dt) {
  const double r = T / dt, n = std::round(r);
  if (std::abs(r - n) <= kWholeSteps * std::max(1.0, n)) return {std::max(0.0, n), false};
  return {std::floor(r), true};
}

void Integrator::set_schedule(Schedule* schedule) {
  if (schedule && schedule->root_count() > 0 && !locates_events_)
    throw Error("this integration method cannot locate events (joint limits): use cvode-adams or cvode-bdf");
  schedule_ = schedule;
}

void Integrator::advance(double t_out, double& t, VecX& y) {
  if (!schedule_) {
    step_to(t_out, t, y);
    return;
  }
  // to t_out through the schedule: each stop (a control tick) and each event ends the steps there,
  // the schedule acts, and the integrator starts afresh from the state it left
  for (;;) {
    const Schedule::Stop stop = schedule_->next_stop(t_out);
    if (step_to(stop.t, t, y)) {
      restart(t, y);
      continue;
    }
    if (t < stop.t) return;  // a stop request before a step
    if (stop.acts) {
      schedule_->at_stop(t, y);
      restart(t, y);
    }
    if (stop.t == t_out) return;
  }
}

namespace {

// Symplectic Euler for H(q, p) = ½ pᵀ 𝓜(q)⁻¹ p + V(q) in the canonical momenta p = 𝓜(q) v, V the
// gravity and spring potential, the other inputs (torques, dampers) as forcing Q(t, v).  The variant
// implicit in p, explicit in q:
//   p⁺ = p − h ∂H/∂q(q, p⁺) + h Q(t, v⁺),   q⁺ = q + h ∂H/∂p(q, p⁺) = q + h v⁺,   v⁺ = 𝓜(q)⁻¹ p⁺.
// With ∂H/∂q|_p = −∂T/∂q|_v + ∂V/∂q the unknown is v⁺, the root of
//   R(w) = 𝓜(q) w − (h/2) P(w)ᵀ w − p + h g(q) − h τ_in(t, q, w),   P(w) = ∂(𝓜(q) w)/∂q,
// since ∂T/∂q = ½ vᵀ ∂𝓜/∂q v = ½ P(v)ᵀ v; g = ∂V_gravity/∂q = bias(q, 0), the springs are in τ_in.
// P(w) is inverse dynamics' ∂τ/∂q at (q, v = 0, q̈ = w) with gravity off (its τ is 𝓜 w), and
// R'(w) = 𝓜(q) − h P(w)ᵀ − h ∂τ_in/∂v: Newton with the analytic derivatives (derivatives.hpp).
// The state stays y = [q; v], so p = 𝓜(q) v at the start of a step and v⁺⁺ = 𝓜(q⁺)⁻¹ p⁺ at its end.
// Only where q̇ = v (no quaternion: revolute, prismatic and planar joints) are (q, p) canonical.
//
// Prescribed motion: the same map for the free coordinates of the time-dependent Lagrangian
// L(q_f, q̇_f, t) = L(q_f, q*(t), q̇_f, q̇*(t)), i.e. the variational integrator of
// L_d(q_k, q_k+1) = h L(q_k, (q_k+1 − q_k)/h): w's prescribed entries are the discrete velocity
// (q*(t + h) − q*(t))/h, Newton solves the free rows R_f(w_f) = 0, p_f = (𝓜 v)_f at both ends with
// v's prescribed entries q̇*(t), q̇*(t + h) (v⁺⁺_f = 𝓜_ff⁻¹ (p⁺_f − 𝓜_fp q̇*(t + h))), and the
// prescribed rows' residual R_p(w), its discrete momentum replaced by the continuous one reached,
// is the impulse h τ_p that holds the motion, its work W_p += h τ_p · w_p.
class SymplecticEuler : public FixedStep {
 public:
  SymplecticEuler(System& s, double dt, double t0)
      : FixedStep(s, dt, t0),
        free_(without_gravity(s.model)),
        data_(s.model),
        dd_(s.model),
        q_(s.model.nq),
        w_(s.model.nv),
        p_(s.model.nv),
        g_(s.model.nv),
        r_(s.model.nv),
        tau_(s.model.nv),
        delta_(s.model.nv),
        zero_(VecX::Zero(s.model.nv)),
        J_(s.model.nv, s.model.nv),
        dq_(s.model.nv, s.model.nv),
        dv_(s.model.nv, s.model.nv),
        lu_(s.model.nv) {
    for (const PrescribedInput& p : s.inputs.prescribed) prescribed_.push_back(p.dof);
  }

  static std::string refuses(const Model& m) {
    if (!m.has_quaternions()) return "";
    return "symplectic-euler: the model has a free or ball joint, whose quaternion makes (q, 𝓜 v) "
           "non-canonical; use variational (symplectic on the group, conserves momentum), rk4 or implicit-midpoint";
  }

 private:
  static Model without_gravity(const Model& m) {
    Model f = m;
    f.gravity.setZero();
    return f;
  }

  void step(double t, double h, VecX& y) override {
    const Model& m = sys_.model;
    const int nq = sys_.nq_state(), nv = sys_.nv_state();
    // the model's q and v at t (the prescribed joints' from their motion)
    sys_.expand(t, y.data());
    q_ = sys_.q;
    // at q: kinematics, 𝓜, p = 𝓜 v, g = bias(q, 0)
    update_kinematics(m, data_, q_);
    mass_matrix(m, data_);
    p_.noalias() = data_.M * sys_.v;
    update_velocities(m, data_, zero_);
    bias_forces(m, data_);
    g_ = data_.bias;
    // Newton on R_f(w) = 0 from w = v, w_p = (q*(t + h) − q*(t))/h
    w_ = sys_.v;
    for (const PrescribedInput& p : sys_.inputs.prescribed) {
      double qn = 0, vn = 0, an = 0;
      p.at(t + h, qn, vn, an);
      w_(p.dof) = (qn - q_(p.coord)) / h;
    }
    solve(t, h);
    // quadratures at v⁺ (right rectangle, as the damping in the momentum update)
    if (sys_.nquad > 0) {
      const Inputs::Power pw = sys_.inputs.power(t, w_);
      y(nq + nv) += h * pw.inputs;
      y(nq + nv + 1) += h * pw.dissipated;
    }
    // p⁺ = 𝓜(q) v⁺, q⁺ = q + h v⁺ (q̇ = v on these joints), v⁺⁺ = 𝓜(q⁺)⁻¹ p⁺
    p_.noalias() = data_.M * w_;
    const std::vector<int>& fv = sys_.v_index();
    for (int k = 0; k < nv; ++k) y(k) += h * w_(fv[size_t(k)]);
    sys_.expand(t + h, y.data());
    update_kinematics(m, data_, sys_.q);
    mass_matrix(m, data_);
    if (prescribed_.empty()) {
      ltdl_factor(m, data_);
      ltdl_solve(m, data_, p_);
      y.segment(nq, nv) = p_;
      return;
    }
    // v⁺⁺_f = 𝓜_ff⁻¹ (p⁺_f − 𝓜_fp q̇*(t + h))
    VecX& b = delta_;
    b = p_;
    for (const int k : prescribed_) b.noalias() -= data_.M.col(k) * sys_.v(k);
    y.segment(nq, nv) = data_.M(fv, fv).llt().solve(b(fv));
    // W_p += h τ_p · w_p, the holding impulse h τ_p = p_p(t + h) − p_p(t) − h (∂L/∂q_p + τ_in,p)(q, w):
    // R_p(w) with (𝓜(q) w)_p, the discrete momentum (p⁺'s free rows alone are the state's), replaced
    // by the momentum p_p(t + h) = (𝓜(q⁺) v⁺⁺)_p of the state reached
    if (sys_.nquad > 2) {
      for (int k = 0; k < nv; ++k) sys_.v(fv[size_t(k)]) = y(nq + k);
      double held = 0;
      for (const int k : prescribed_) held += (r_(k) - p_(k) + data_.M.row(k).dot(sys_.v)) * w_(k);
      y(nq + nv + 2) += held;
    }
  }

  // Newton on R(w) = 0, the free rows (all rows when nothing is prescribed); leaves R(w) at the
  // last iterate in r_
  void solve(double t, double h) {
    const std::vector<int>& fv = sys_.v_index();
    double previous = std::numeric_limits<double>::infinity();
    for (int it = 0;; ++it) {
      ++stats_.nonlinear_iterations;
      ++stats_.jac_evals;
      inverse_dynamics_derivatives(free_, data_, zero_, w_, dd_);  // τ = 𝓜 w, ∂τ/∂q = P(w)
      sys_.inputs.evaluate(t, q_, w_, tau_);
      if (sys_.controlled) tau_ += sys_.control;
      // R(w) = 𝓜 w − (h/2) P(w)ᵀ w − p + h (g − τ_in)
      r_ = dd_.tau - p_ + h * (g_ - tau_);
      r_.noalias() -= (0.5 * h) * dd_.dtau_dq.transpose() * w_;
      dq_.setZero();
      dv_.setZero();
      sys_.inputs.add_derivatives(dq_, dv_);
      // R'(w) = 𝓜 − h P(w)ᵀ − h ∂τ_in/∂v, its free rows and columns
      J_ = data_.M - h * dd_.dtau_dq.transpose() - h * dv_;
      double size = 0, scale = 1;
      if (prescribed_.empty()) {
        lu_.compute(J_);
        delta_.noalias() = lu_.solve(r_);
        w_ -= delta_;
        size = delta_.norm();
      } else {
        const VecX d = J_(fv, fv).partialPivLu().solve(r_(fv));
        w_(fv) -= d;
        size = d.norm();
      }
      scale = std::max(1.0, w_.norm());
      if (!std::isfinite(size)) break;  // the state check reports it
      if (size <= 1e-14 * scale) break;
      // quadratic convergence: once a correction stops shrinking it has reached rounding
      if (size <= 1e-10 * scale && size >= 0.5 * previous) break;
      if (it == 49) {
        std::ostringstream os;
        os << "symplectic-euler: Newton did not converge at t = " << t << " s with a step of " << h
           << " s (last correction " << size << ")";
        throw SimulationError(os.str(), t);
      }
      previous = size;
    }
  }

  Model free_;  // the model with gravity off: P(w) from inverse dynamics' derivatives
  Data data_;
  DerivativeData dd_;
  VecX q_, w_, p_, g_, r_, tau_, delta_, zero_;
  MatX J_, dq_, dv_;
  Eigen::PartialPivLU<MatX> lu_;
  std::vector<int> prescribed_;  // the prescribed joints' DOFs
};

}  // namespace

const std::vector<IntegratorInfo>& integrators() {
  using S = const SimulationSettings&;
  using P = std::unique_ptr<Integrator>;
  static const std::vector<IntegratorInfo> table = {
      {Method::CvodeAdams, to_string(Method::CvodeAdams),
       "SUNDIALS CVODE, Adams–Moulton with fixed-point iterations (non-stiff)", false, 0, false, 0, nullptr,
       [](System& sys, S s, double t0, const VecX& y0) { return make_cvode(false, sys, s, t0, y0); }},
      {Method::CvodeBdf, to_string(Method::CvodeBdf),
       "SUNDIALS CVODE, BDF with Newton and a direct solver (stiff)", false, 0, false, 24, nullptr,
       [](System& sys, S s, double t0, const VecX& y0) { return make_cvode(true, sys, s, t0, y0); }},
      {Method::Euler, to_string(Method::Euler),
       "explicit Euler, order 1; free and ball joints on the group (q ⊕ h v)", true, 1, false, 0, nullptr,
       [](System& sys, S s, double t0, const VecX&) -> P { return make_euler(sys, s.dt, t0); }},
      {Method::SemiImplicitEuler, to_string(Method::SemiImplicitEuler),
       "v then q ⊕ h v, order 1; not symplectic where the mass matrix depends on q", true, 1, false, 0,
       nullptr, [](System& sys, S s, double t0, const VecX&) -> P { return make_semi_implicit_euler(sys, s.dt, t0); }},
      {Method::SymplecticEuler, to_string(Method::SymplecticEuler),
       "symplectic Euler in the momenta p = M(q) v by Newton, order 1, symplectic (no free or ball joints)",
       true, 1, true, 12, &SymplecticEuler::refuses,
       [](System& sys, S s, double t0, const VecX&) -> P { return std::make_unique<SymplecticEuler>(sys, s.dt, t0); }},
      {Method::Rk4, to_string(Method::Rk4),
       "Runge–Kutta–Munthe-Kaas: classical Runge–Kutta on the group, order 4", true, 4, false, 0, nullptr,
       [](System& sys, S s, double t0, const VecX&) -> P { return make_rk4(sys, s.dt, t0); }},
      {Method::ImplicitMidpoint, to_string(Method::ImplicitMidpoint),
       "implicit midpoint rule, q ⊕ h v on the group, by Newton, order 2, symmetric and A-stable", true, 2, false, 24,
       nullptr, [](System& sys, S s, double t0, const VecX&) -> P { return make_implicit_midpoint(sys, s, t0); }},
      {Method::Variational, to_string(Method::Variational),
       "variational (midpoint discrete Lagrangian) on the group by Newton, order 2, symplectic, symmetric, "
       "conserves momentum", true, 2, true, 16, nullptr,
       [](System& sys, S s, double t0, const VecX&) -> P { return make_variational(sys, s, t0); }},
  };
  return table;
}

const IntegratorInfo* find_integrator(std::string_view name) {
  for (const auto& info : integrators())
    if (info.name == name) return &info;
  return nullptr;
}

std::vector<std::string> integrator_names() {
  std::vector<std::string> names;
  for (const auto& info : integrators()) names.emplace_back(info.name);
  return names;
}

const IntegratorInfo& find_integrator(Method method) {
  for (const auto& info : integrators())
    if (info.method == method) return info;
  throw Error("method: not an integration method (" + std::to_string(int(method)) + ")");
}

std::unique_ptr<Integrator> make_integrator(Method method, System& system, const SimulationSettings& settings,
                                            double t0, const VecX& y0) {
  const IntegratorInfo& info = find_integrator(method);
  if (info.refuses)
    if (const std::string why = info.refuses(system.model); !why.empty()) throw Error(why);
  return info.make(system, settings, t0, y0);
}

}  // namespace soadyn
