// Joint inputs: the generalized forces a scene applies (torques, springs, dampers), evaluated on
// every right-hand-side call.  Plain numerics: no file format is involved here.
#pragma once

#include "soadyn/algorithm/loops.hpp"
#include "soadyn/multibody/types.hpp"

#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace soadyn {

class CubicSpline;

// Joint inputs a scene may need, and no more.  Each acts on one 1-DOF joint (index into v).
struct TorqueInput {
  std::string joint;
  int dof = -1;
  double constant = 0.0;   // N·m or N
  double amplitude = 0.0;  // + amplitude · sin(2π frequency t + phase)
  double frequency = 0.0;  // Hz
  double phase = 0.0;      // rad
};
struct SpringInput {
  std::string joint;
  int dof = -1;
  int coord = -1;          // index into q
  double stiffness = 0.0;  // τ = −k (q − rest)
  double rest = 0.0;
};
struct DamperInput {
  std::string joint;
  int dof = -1;
  double damping = 0.0;    // τ = −c q̇
};

// A joint's reference q_d(t) = constant + amplitude · sin(2π frequency t + phase), with its rate
// and acceleration (a controller's target, a prescribed joint's motion); or, when `table` is set,
// the cubic spline through a tabulated column (table.hpp); or, when `slew` is set, a rest-to-rest
// move from `from` to `to` over [start, start + duration], the quintic
//   q_d = from + (to − from) (10 s³ − 15 s⁴ + 6 s⁵),  s = (t − start) / duration clamped to [0, 1],
// whose rate and acceleration are zero at both ends (the other fields then unused).
struct JointSlew {
  double from = 0.0, to = 0.0, start = 0.0, duration = 1.0;
};
struct JointTarget {
  double constant = 0.0, amplitude = 0.0, frequency = 0.0, phase = 0.0;
  std::shared_ptr<const CubicSpline> table;
  std::shared_ptr<const JointSlew> slew;
  double value(double t) const;
  double rate(double t) const;
  double acceleration(double t) const;
  // the times where the motion's q̈ or its rate of change jumps (a slew's start and end, a
  // table's first and last rows): an integrator's steps should end there
  std::vector<double> corners() const;
};

// A joint whose motion is given (hybrid dynamics, hybrid.hpp): a 1-DOF joint following `target`,
// or, when `function` is set, the caller's (q*, q̇*, q̈*)(t) (Python's prescribed=).  Its τ is
// whatever holds that motion; the system (system.hpp) leaves its q and v out of the state.
struct PrescribedInput {
  std::string joint;
  int body = -1, dof = -1, coord = -1;  // its body, its index into v and into q
  JointTarget target;
  std::function<void(double t, double& q, double& qd, double& qdd)> function;
  // q*, q̇*, q̈* at t
  void at(double t, double& q, double& qd, double& qdd) const;
};

// A built-in controller (controller.hpp computes it), each DOF's torque clamped to ±max_torque and,
// with at_effort, to ±Model::effort (a URDF's <limit effort>; DOFs without one unclamped by it):
//   pd                    τ_k = K_p (q_d − q_k) + K_d (q̇_d − q̇_k) on one joint
//   gravity_compensation  τ = g(q), the generalized gravity force, on every DOF
//   computed_torque       τ = 𝓜(q) (q̈_d + K_d ė + K_p e) + bias(q, q̇), e = q_d − q, on every DOF
//                         (a model of 1-DOF joints; a joint without a target keeps its initial q)
struct ControllerInput {
  enum class Kind { Pd, GravityCompensation, ComputedTorque } kind = Kind::Pd;
  std::vector<int> dofs, coords;    // pd: its joint; computed_torque: every DOF (coords: into q)
  std::vector<JointTarget> targets; // one per dof (pd, computed_torque)
  std::vector<int> actuated;        // computed_torque: the DOFs its targets name; with closed loops the
                                    // actuators (the rest passive, moved by the loops)
  double kp = 0.0, kd = 0.0;        // 1/s², 1/s for computed_torque; N·m/rad, N·m·s/rad for pd
  double max_torque = std::numeric_limits<double>::infinity();
  bool at_effort = false;
};

struct Inputs {
  std::vector<TorqueInput> torques;
  std::vector<SpringInput> springs;
  std::vector<DamperInput> dampers;
  std::vector<ControllerInput> controllers;  // evaluated by controller.hpp, not by evaluate()
  std::vector<PrescribedInput> prescribed;   // joints whose motion is given (system.hpp), not by evaluate()
  std::vector<LoopConstraint> loops;         // closed loops on the tree (loops.hpp, system.hpp), not by evaluate()
  bool empty() const { return torques.empty() && springs.empty() && dampers.empty(); }
  // τ(t, q, v): the generalized force the inputs apply
  void evaluate(double t, const VecX& q, const VecX& v, Eigen::Ref<VecX> tau) const;
  // dq += ∂τ/∂q (along the tangent, derivatives.hpp; springs act on 1-DOF joints, where the
  // coordinate is the tangent) and dv += ∂τ/∂v: both nv×nv, constant (torques depend on t only)
  void add_derivatives(Eigen::Ref<MatX> dq, Eigen::Ref<MatX> dv) const;
  // dq += A ∂τ/∂q and dv += A ∂τ/∂v for an nv×nv A (forward_dynamics_derivatives' 𝓜⁻¹): column by column
  void add_derivatives_times(const MatX& A, Eigen::Ref<MatX> dq, Eigen::Ref<MatX> dv) const;
  // out += (∂τ/∂q) xq + (∂τ/∂v) xv for directions as columns (nv × k each; the forward sensitivities')
  void add_derivatives_directions(const Eigen::Ref<const MatX>& xq, const Eigen::Ref<const MatX>& xv,
                                  Eigen::Ref<MatX> out) const;
  // gq += (∂τ/∂q)ᵀ μ and gv += (∂τ/∂v)ᵀ μ, the same derivatives as vector products (the adjoint's)
  void add_derivatives_transpose_times(const VecX& mu, Eigen::Ref<VecX> gq, Eigen::Ref<VecX> gv) const;
  // ∂P/∂v and ∂D/∂v of power(t, v) (the quadratures' rates; neither depends on q): nv each
  void power_derivatives(double t, const VecX& v, Eigen::Ref<VecX> dP, Eigen::Ref<VecX> dD) const;
  // the inputs' potential energy (springs), so E = T + V_gravity + V_springs is conserved
  double spring_energy(const VecX& q) const;
  // The power of the inputs that are not in the potential: P = (τ_torques + τ_dampers) · q̇ (each
  // input acts on a 1-DOF joint, where q̇ = v), and the dampers' share of it as the power they
  // dissipate, D = Σ c q̇² ≥ 0.  Along a run, dE/dt = P: E(t) − E(0) = W(t) = ∫ P dt.
  struct Power {
    double inputs = 0.0, dissipated = 0.0;
  };
  Power power(double t, const VecX& v) const;
  // torques or dampers: the energy balance has a work term
  bool does_work() const { return !torques.empty() || !dampers.empty(); }
};

}  // namespace soadyn
