// The fixed-step methods on the configuration's group (fixed_step.hpp): the grid of steps, and
// explicit Euler, semi-implicit Euler, Runge–Kutta–Munthe-Kaas 4 and the implicit midpoint rule,
// each moving free and ball joints by the exponential map.
#include "fixed_step.hpp"

#include "soadyn/sim/newton_solver.hpp"

#include <cmath>
#include <limits>
#include <sstream>

namespace soadyn {

FixedStep::FixedStep(System& s, double dt, double t0)
    : sys_(s),
      dt_(dt),
      nq_(s.nq_state()),
      nv_(s.nv_state()),
      nw_(s.nquad),
      k1_(s.size()),
      k2_(s.size()),
      k3_(s.size()),
      k4_(s.size()),
      tmp_(s.size()),
      prev_(s.size()),
      t0_(t0),
      t_reported_(t0) {}

bool FixedStep::step_to(double t_out, double& t, VecX& y) {
  // the grid t0 + k·dt goes on from where the last call left it; a caller that moved t, or a last
  // shorter step, starts a new one at t
  if (t != t_reported_) {
    t0_ = t;
    k_ = 0;
  }
  const StepCount n = count_steps(t_out - t0_, dt_);
  const long whole = long(n.whole);
  while (k_ < whole) {
    if (stop_requested()) {  // t < t_out: the run ends here
      t_reported_ = t;
      return false;
    }
    take(t0_ + double(k_) * dt_, dt_, y);  // from the grid's time (t may be the caller's t_out)
    ++k_;
    t = t0_ + double(k_) * dt_;
    check(t, dt_, y);
  }
  // t_out within rounding of the grid (count_steps): it is where the steps ended, and the time
  // reported (the grid itself goes on from t0 + k·dt)
  if (!n.partial && k_ == whole) t = t_out;
  if (n.partial && k_ == whole && t < t_out) {
    if (stop_requested()) {
      t_reported_ = t;
      return false;
    }
    const double tk = t0_ + double(k_) * dt_, h = t_out - tk;
    take(tk, h, y);
    t = t_out;
    t0_ = t_out;
    k_ = 0;
    check(t, h, y);
  }
  t_reported_ = t;
  return false;
}

// one step, as the method leaves it: no renormalization after it (the quaternions moved on the group)
void FixedStep::take(double t, double h, VecX& y) {
  prev_ = y;
  step(t, h, y);
  ++stats_.steps;
  // closed loops: q and v projected back onto their manifold (φ = 0, K v = 0) after each step
  if (sys_.has_loops() && first_non_finite(y) < 0 && !sys_.project(y)) {
    std::ostringstream os;
    os << "the closed loops could not be closed again after the step at t = " << t + h << " s (a singular configuration?)";
    throw SimulationError(os.str(), t + h);
  }
}

void FixedStep::check(double t, double h, const VecX& y) const {
  if (first_non_finite(y) < 0) return;
  // worst DOF: the largest velocity in the last finite state, the one blowing up
  Eigen::Index worst = 0;
  prev_.segment(nq_, nv_).cwiseAbs().maxCoeff(&worst);
  std::ostringstream os;
  os << "unstable at t = " << t << " s: the state is not finite after a step of " << h << " s; worst DOF "
     << sys_.component_name(nq_ + int(worst)) << " = " << prev_(nq_ + worst) << " before it";
  throw SimulationError(os.str(), t);
}

// y ⊕ z = [q ⊕ z_δ; v + z_v; W + z_W]
void FixedStep::move(const VecX& y, const VecX& z, VecX& out) const {
  sys_.integrate(y.head(nq_), z.head(nv_), 1.0, out.head(nq_));
  out.segment(nq_, nv_) = y.segment(nq_, nv_) + z.segment(nv_, nv_);
  out.tail(nw_) = y.tail(nw_) + z.tail(nw_);
}

// k = [dexp⁻¹_{z_δ}(v_s); q̈_s; Ẇ_s]
void FixedStep::rate(const VecX& z, const VecX& ys, const VecX& fs, VecX& k) const {
  sys_.increment_rate(z.head(nv_), ys.segment(nq_, nv_), k.head(nv_));
  k.segment(nv_, nv_) = fs.segment(nq_, nv_);
  k.tail(nw_) = fs.tail(nw_);
}

namespace {

// FixedStep with increments in the tangent layout: z and the stages' rates r1 … r4
class TangentStep : public FixedStep {
 public:
  TangentStep(System& s, double dt, double t0)
      : FixedStep(s, dt, t0),
        z_(VecX::Zero(s.tangent_size())),
        r1_(s.tangent_size()),
        r2_(s.tangent_size()),
        r3_(s.tangent_size()),
        r4_(s.tangent_size()) {}

 protected:
  VecX z_, r1_, r2_, r3_, r4_;
};

class Euler : public TangentStep {
  using TangentStep::TangentStep;
  // y⁺ = y ⊕ h f(t, y):  q⁺ = q ⊕ h v,  v⁺ = v + h q̈(q, v),  W⁺ = W + h Ẇ
  void step(double t, double h, VecX& y) override {
    f(t, y, k1_);
    z_.head(nv_).setZero();
    rate(z_, y, k1_, r1_);
    z_ = h * r1_;
    move(y, z_, y);
  }
};

class SemiImplicitEuler : public FixedStep {
  using FixedStep::FixedStep;
  // v⁺ = v + h q̈(q, v);  q⁺ = q ⊕ h v⁺;  quadratures W, D ← + h (P, D)(q, v) (left rectangle).
  // Symplectic when 𝓜 is constant; with 𝓜(q) the velocity is not the canonical momentum and the
  // map is not symplectic (its energy error grows secularly, test_integrators)
  void step(double t, double h, VecX& y) override {
    f(t, y, k1_);
    y.segment(nq_, nv_) += h * k1_.segment(nq_, nv_);
    y.tail(nw_) += h * k1_.tail(nw_);
    sys_.integrate(y.head(nq_), y.segment(nq_, nv_), h, y.head(nq_));
  }
};

// Runge–Kutta–Munthe-Kaas of order 4 (Munthe-Kaas, BIT 1999; Hairer, Lubich and Wanner, Geometric
// Numerical Integration, IV.8.2): the classical RK4 tableau applied to the increment z of
// y(t) = y0 ⊕ z(t), whose rate is ż = [dexp⁻¹_{z_δ}(v); q̈; Ẇ] with dexp⁻¹ in closed form (not
// truncated), so that the step is classical RK4 in these local coordinates and of order 4.
// Where no joint holds a quaternion, ⊕ is + and dexp⁻¹ the identity: the classical method itself.
class RKMK4 : public TangentStep {
  using TangentStep::TangentStep;
  void step(double t, double h, VecX& y) override {
    VecX& ys = tmp_;
    // r1 = ż(0) at y
    z_.setZero();
    f(t, y, k1_);
    rate(z_, y, k1_, r1_);
    // r2 = ż at z = (h/2) r1
    z_ = 0.5 * h * r1_;
    stage(t + 0.5 * h, y, ys, r2_);
    // r3 = ż at z = (h/2) r2
    z_ = 0.5 * h * r2_;
    stage(t + 0.5 * h, y, ys, r3_);
    // r4 = ż at z = h r3
    z_ = h * r3_;
    stage(t + h, y, ys, r4_);
    // y⁺ = y ⊕ h/6 (r1 + 2 r2 + 2 r3 + r4)
    z_ = (h / 6.0) * (r1_ + 2.0 * r2_ + 2.0 * r3_ + r4_);
    move(y, z_, y);
  }
  // r = ż at ys = y ⊕ z_, f evaluated at ts
  void stage(double ts, const VecX& y, VecX& ys, VecX& r) {
    move(y, z_, ys);
    f(ts, ys, k2_);
    rate(z_, ys, k2_, r);
  }
};

// The implicit midpoint rule on the group: with u the step's increment of q and V = v⁺,
//   q⁺ = q ⊕ u,  u = h (v + V)/2,  V = v + h q̈(t + h/2, q ⊕ u/2, (v + V)/2),  W⁺ = W + h Ẇ(…)
// the midpoint rule (order 2, symmetric: a step back by −h from (q⁺, V) has the increment −u and the
// same midpoint q⁺ ⊕ (−u/2) = q ⊕ u/2); in (q, v), so not symplectic where 𝓜 depends on q
// (test_integrators measures its energy: level on the scenes there).  Newton on the tangent-layout
// unknown X = [u; V; W⁺]:
//   G(X) = X − [0; v; W] − h g(y_m),  y_m = [q ⊕ u/2; (v + V)/2; (W + W⁺)/2],  g = [v_m; q̈_m; Ẇ_m],
// with G' = e − (h/2) ∂g/∂(δ, v, W) at y_m (System::tangent_jacobian), its δ columns chained to u by
// ∂δ_m/∂(u/2) = dexp_{u/2} (System::times_increment_jacobian), solved by its structure (NewtonSolver's
// tangent layout).  Full Newton: G' at every
// iterate, from X = [0; v; W] (its first iterate is the linearly implicit midpoint step, itself
// A-stable).  Simplified: G' once per step, at the explicit-Euler predictor's midpoint.
class ImplicitMidpoint : public TangentStep {
 public:
  ImplicitMidpoint(System& s, const SimulationSettings& settings, double t0)
      : TangentStep(s, settings.dt, t0),
        analytic_(settings.jacobian == Jacobian::Analytic),
        full_(settings.newton == Newton::Full),
        J_(s.tangent_size(), s.tangent_size()),
        newton_(s, NewtonSolver::Layout::Tangent),
        delta_(s.tangent_size()),
        half_u_(s.nv_state()) {
    if (analytic_) s.prepare_jacobian();  // sized here, so no step allocates
  }

 private:
  void step(double t, double h, VecX& y) override {
    const double tm = t + 0.5 * h;
    VecX &X = r1_, &x0 = r2_, &G = r3_;
    // x0 = [0; v; W]
    x0.head(nv_).setZero();
    x0.tail(nv_ + nw_) = y.tail(nv_ + nw_);
    X = x0;
    if (!full_) {
      // the explicit-Euler predictor X = x0 + h [v; q̈; Ẇ](y), G' at its midpoint
      f(t, y, k1_);
      z_.setZero();
      rate(z_, y, k1_, r4_);
      X += h * r4_;
      midpoint(y, X);
      factor(tm, h, X);
    }
    double previous = std::numeric_limits<double>::infinity();
    for (int it = 0; it < 50; ++it) {
      ++stats_.nonlinear_iterations;
      midpoint(y, X);
      if (full_) factor(tm, h, X);
      // −G(X) = x0 + h g(y_m) − X
      f(tm, tmp_, k3_);
      G.head(nv_) = tmp_.segment(nq_, nv_);
      G.segment(nv_, nv_) = k3_.segment(nq_, nv_);
      G.tail(nw_) = k3_.tail(nw_);
      G = x0 + h * G - X;
      if (factored_) newton_.solve(G, delta_);
      else delta_.setConstant(std::numeric_limits<double>::quiet_NaN());  // singular G': no step
      X += delta_;
      if (!delta_.allFinite()) break;
      const double size = delta_.norm(), scale = std::max(1.0, X.norm());
      if (size <= 1e-13 * scale) break;
      // full Newton converges (near-)quadratically: once it stops shrinking it has reached rounding
      if (full_ && size <= 1e-9 * scale && size >= 0.5 * previous) break;
      if (full_ && it == 49) {
        std::ostringstream os;
        os << "implicit midpoint: full Newton did not converge at t = " << t << " s with a step of " << h
           << " s (last correction " << size << ")";
        throw SimulationError(os.str(), t);
      }
      previous = size;
    }
    // y⁺ = [q ⊕ u; V; W⁺]
    sys_.integrate(y.head(nq_), X.head(nv_), 1.0, y.head(nq_));
    y.tail(nv_ + nw_) = X.tail(nv_ + nw_);
  }

  // tmp_ = y_m = [q ⊕ u/2; (v + V)/2; (W + W⁺)/2]
  void midpoint(const VecX& y, const VecX& X) {
    sys_.integrate(y.head(nq_), X.head(nv_), 0.5, tmp_.head(nq_));
    tmp_.tail(nv_ + nw_) = 0.5 * (y.tail(nv_ + nw_) + X.tail(nv_ + nw_));
  }

  // G' = e − (h/2) ∂g/∂(δ, v, W) at tmp_ (the midpoint q ⊕ u/2), the δ columns times dexp_{u/2},
  // factored by its structure (NewtonSolver: an nv×nv Schur complement, the q rows being [0 e 0])
  void factor(double tm, double h, const VecX& X) {
    if (analytic_)
      sys_.tangent_jacobian(tm, tmp_.data(), J_);
    else
      sys_.tangent_jacobian_dq(tm, tmp_.data(), J_);
    half_u_ = 0.5 * X.head(nv_);
    sys_.times_increment_jacobian(half_u_, J_.bottomLeftCorner(nv_ + nw_, nv_));
    ++stats_.jac_evals;
    newton_.set_jacobian(J_);
    factored_ = newton_.factor(0.5 * h);
  }

  bool analytic_, full_;
  MatX J_;
  NewtonSolver newton_;
  bool factored_ = false;
  VecX delta_, half_u_;
};

}  // namespace

std::unique_ptr<Integrator> make_euler(System& sys, double dt, double t0) { return std::make_unique<Euler>(sys, dt, t0); }

std::unique_ptr<Integrator> make_semi_implicit_euler(System& sys, double dt, double t0) {
  return std::make_unique<SemiImplicitEuler>(sys, dt, t0);
}

std::unique_ptr<Integrator> make_rk4(System& sys, double dt, double t0) { return std::make_unique<RKMK4>(sys, dt, t0); }

std::unique_ptr<Integrator> make_implicit_midpoint(System& sys, const SimulationSettings& settings, double t0) {
  return std::make_unique<ImplicitMidpoint>(sys, settings, t0);
}

}  // namespace soadyn
