// The fixed-step methods' common part (fixed_step.cpp): steps of exactly dt on the grid t0 + k·dt
// (integrators.hpp), the state moved on the configuration's group, and the methods made here.
//
// On the group.  A free or ball joint's q holds a unit quaternion; a step moves it by the
// exponential map, q ⊕ δ (configuration.hpp), never by adding to its four numbers, so it stays unit
// by construction and nothing renormalizes it after the step (⊕ itself rounds the product of two
// unit quaternions, exp(δ) ⊗ Q, to unit norm: a correction of a few ulps, without which rounding
// alone drifts the norm by ~1e-14 over 10⁴ steps).  A step's increment is a vector in
// the tangent layout [δ (nv); Δv (nv); ΔW …] (System::tangent_size), and
//   y ⊕ z = [q ⊕ z_δ; v + z_v; W + z_W],
// the velocities and the quadratures W, D, W_p living in vector spaces.
#pragma once

#include "soadyn/sim/integrators.hpp"

#include <memory>

namespace soadyn {

class FixedStep : public Integrator {
 public:
  FixedStep(System& s, double dt, double t0);

  bool step_to(double t_out, double& t, VecX& y) override;
  IntegratorStats stats() const override {
    IntegratorStats s = stats_;
    s.rhs_evals = sys_.rhs_evals;
    return s;
  }
  std::string quaternion_handling() const override {
    return sys_.quaternions().empty() ? "none" : "on the group (exponential map), never renormalized";
  }

 protected:
  virtual void step(double t, double h, VecX& y) = 0;
  void f(double t, const VecX& y, VecX& out) { sys_.rhs(t, y.data(), out.data()); }
  // out = y ⊕ z (z in the tangent layout); out may be y
  void move(const VecX& y, const VecX& z, VecX& out) const;
  // the tangent-layout rate of a state y_s reached as y ⊕ z from the step's start, f_s = f(y_s):
  // k = [dexp⁻¹_{z_δ}(v_s); q̈_s; Ẇ_s] (dexp⁻¹: configuration.hpp's increment_rate; v_s itself
  // where no joint holds a quaternion or z_δ = 0)
  void rate(const VecX& z, const VecX& ys, const VecX& fs, VecX& k) const;

  System& sys_;
  double dt_;
  int nq_, nv_, nw_;  // the state's q, v and quadratures: y = [q; v; W …]
  VecX k1_, k2_, k3_, k4_, tmp_, prev_;
  IntegratorStats stats_;

 private:
  void take(double t, double h, VecX& y);
  void check(double t, double h, const VecX& y) const;

  double t0_;           // the grid's origin
  long k_ = 0;          // steps taken on it
  double t_reported_;   // the t the last call returned (a caller passing another starts a new grid)
};

// euler, semi-implicit-euler, rk4 (Munthe-Kaas) and implicit-midpoint, each on the group
std::unique_ptr<Integrator> make_euler(System& sys, double dt, double t0);
std::unique_ptr<Integrator> make_semi_implicit_euler(System& sys, double dt, double t0);
std::unique_ptr<Integrator> make_rk4(System& sys, double dt, double t0);
std::unique_ptr<Integrator> make_implicit_midpoint(System& sys, const SimulationSettings& settings, double t0);
// the variational integrator of the midpoint discrete Lagrangian on the group (variational.cpp)
// (settings.newton: full, Newton's iterations; simplified, the O(N) chord iterations first)
std::unique_ptr<Integrator> make_variational(System& sys, const SimulationSettings& settings, double t0);

}  // namespace soadyn
