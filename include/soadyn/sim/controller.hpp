// Feedback control: a generalized force τ_c(t, q, v) added to the inputs' τ.
//
// A controller is any ControlFunction: it fills tau (nv, zeroed by the caller) from (t, q, v).
// simulate() (simulate.hpp) takes one, and adds the scenario's built-in controllers
// (`inputs: controllers:`, BuiltinControllers).  Continuous (SimulationSettings::control_dt = 0):
// evaluated at every right-hand-side evaluation and at every logged sample.  Sampled (control_dt >
// 0): evaluated at t = 0, control_dt, 2 control_dt, …, its τ held until the next tick (a zero-order
// hold, as a digital controller's); the integrator stops at every tick and restarts there.
#pragma once

#include "soadyn/multibody/data.hpp"
#include "soadyn/algorithm/inputs.hpp"
#include "soadyn/algorithm/loops.hpp"
#include "soadyn/multibody/model.hpp"

#include <functional>
#include <memory>
#include <vector>

namespace soadyn {

using ControlFunction = std::function<void(double t, const VecX& q, const VecX& v, Eigen::Ref<VecX> tau)>;

// The built-in controllers of ControllerInput, summed, each one's torque saturated.  Owns the Data
// its inverse dynamics needs (gravity compensation, computed torque), so it never touches the
// integrator's; one instance per run (not thread-safe).
//
// With closed loops (`loops`, loops.hpp) the inverse dynamics is the loops': computed torque
// actuates the DOFs its targets name (ControllerInput::actuated), their q̈ commanded, the passive
// DOFs' q̈ from the loops (K q̈ = −k̇), τ from loop_inverse_dynamics (zero on the passive DOFs);
// gravity compensation is the joint torque of least norm that holds the mechanism still,
// τ = g − Kᵀ λ with λ = argmin |g − Kᵀ λ| (gravity less what the loops carry).
class BuiltinControllers {
 public:
  BuiltinControllers(const Model& model, std::vector<ControllerInput> controllers,
                     const std::vector<LoopConstraint>& loops = {});
  void operator()(double t, const VecX& q, const VecX& v, Eigen::Ref<VecX> tau);

 private:
  const Model& model_;
  std::vector<ControllerInput> controllers_;
  std::vector<VecX> bound_;  // each controller's clamp, per DOF: max_torque, and the effort if asked
  std::vector<std::vector<char>> passive_;  // per controller, per DOF: not among its `actuated` (loops)
  Data data_;
  VecX zero_, a_, part_;
  std::vector<LoopConstraint> loops_;
  LoopData loop_data_;
};

// A function calling each of `parts` (the non-empty ones) and summing their torques; empty when all are.
ControlFunction sum_controllers(std::vector<ControlFunction> parts, int nv);

}  // namespace soadyn
