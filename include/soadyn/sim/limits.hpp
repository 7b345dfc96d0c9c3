// Joint limits as exact events (SimulationSettings::limits).
//
// Each finite bound of a 1-DOF joint (Model::lower/upper) is a root function g = σ (q_k − bound),
// σ = +1 at a lower bound and −1 at an upper one, so g ≥ 0 inside; CVODE locates its downward
// crossing to the integrator's tolerance (CVodeRootInit) and the run stops there.  At contact:
//   impact   v_k⁻ into the bound becomes −e v_k⁻ by an impulse p e_k through 𝓜, so every other
//            joint feels it: Δv = 𝓜⁻¹ e_k p, p = −(1 + e) v_k⁻ / (𝓜⁻¹)_kk; the kinetic energy
//            lost, ½ (1 − e²) v_k⁻² / (𝓜⁻¹)_kk, is logged and kept in the energy balance.  DOFs
//            already held keep v = 0 through the same impulse (solved on all of them at once).
//   hold     e = 0, or a rebound slower than kRestSpeed (else a bouncing joint would take ever
//            shorter bounces for ever): q_k is set to the bound, v_k = 0, and the joint is held
//            by a constraint force λ on DOF k, q̈ = 𝓜⁻¹(τ + Σ e_k λ_k − bias) with q̈_k = 0.  Its
//            root function becomes σ λ, the force's push into the allowed side:
//   release  when σ λ would turn negative (the constraint would have to pull): the joint leaves.
// Then the integrator restarts (CVodeReInit).  The run's scheduler (simulate.cpp) hands the root
// functions to the integrator and calls start and on_roots; System::rhs calls constrain (Constraint,
// system.hpp).  Fixed-step methods have no root finding: check_run refuses them with limits on.
#pragma once

#include "soadyn/sim/system.hpp"

#include <string>
#include <vector>

namespace soadyn {

// a rebound slower than this (rad/s or m/s) ends in a hold
inline constexpr double kRestSpeed = 1e-6;

// LimitEvent::kind's words; a run file's /events stores each as its index here (h5log.hpp)
inline constexpr const char* kLimitEventKinds[] = {"impact", "hold", "release"};
// the index of `kind` in kLimitEventKinds, −1 for another word
int limit_event_code(const std::string& kind);

struct LimitEvent {
  double t = 0.0;
  int dof = -1;
  std::string joint;
  int side = 0;            // −1: the lower bound, +1: the upper one
  std::string kind;        // "impact", "hold" (an impact that stopped it there) or "release"
  double v_before = 0.0;   // v_k just before and after, rad/s or m/s
  double v_after = 0.0;
  double energy_lost = 0.0;  // J, kinetic energy taken by the impact
};

class JointLimits : public Constraint {
 public:
  // the limits of the 1-DOF joints not in `prescribed` (Inputs::prescribed: their motion is given,
  // and the state, whose indices the root functions read, leaves them out)
  JointLimits(const Model& model, double restitution, const std::vector<PrescribedInput>& prescribed = {});
  int count() const { return int(sides_.size()); }  // root functions, one per finite bound
  // q beyond a bound (past rounding): soadyn::Error naming the joint
  void check_inside(const VecX& q) const;
  // at the start: bounds reached with v into them (or at rest and pushed into them) as contacts
  std::vector<LimitEvent> start(System& sys, double t, VecX& y);
  // g(t, y) for the integrator: σ (q_k − bound), or σ λ while held
  void roots(System& sys, double t, const double* y, double* g);
  // the roots the integrator located at (t, y): impacts, holds, releases; y changed in place
  std::vector<LimitEvent> on_roots(System& sys, double t, VecX& y, const std::vector<int>& which);
  // System::rhs: data.qdd, computed with sys.tau, becomes that of the held DOFs' constraint
  void constrain(System& sys) override;
  double energy_lost() const { return lost_; }  // J, all impacts so far
  bool holding() const { return !held_.empty(); }

 private:
  struct Side {
    int dof, coord;  // the model's v and q index
    int sv, sq;      // the state's (System::v_index, q_index)
    int sign;        // σ: +1 lower, −1 upper
    double bound;
  };
  // an impact on side s (v into it): the impulse, the hold when slow; appends its events
  void contact(System& sys, double t, VecX& y, int s, std::vector<LimitEvent>& out);
  LimitEvent event(double t, int s, const char* kind, double before, double after, double lost) const;
  // the held set's constraint forces at (t, y) (System::rhs, which calls constrain)
  void evaluate(System& sys, double t, const VecX& y);

  const Model& model_;
  double restitution_;
  std::vector<Side> sides_;
  std::vector<int> held_;  // held sides
  VecX lambda_;            // their constraint forces at the last constrain()
  VecX qdd0_, hold0_, tau_, ydot_, y_;
  MatX W_, cols_, hold_cols_;
  double lost_ = 0.0;
};

}  // namespace soadyn
