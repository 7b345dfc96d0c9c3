#include "soadyn/sim/controller.hpp"

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"

#include <Eigen/QR>

#include <algorithm>

namespace soadyn {

BuiltinControllers::BuiltinControllers(const Model& model, std::vector<ControllerInput> controllers,
                                       const std::vector<LoopConstraint>& loops)
    : model_(model),
      controllers_(std::move(controllers)),
      data_(model),
      zero_(VecX::Zero(model.nv)),
      a_(VecX::Zero(model.nv)),
      part_(VecX::Zero(model.nv)),
      loops_(loops),
      loop_data_(model, loops) {
  for (const ControllerInput& c : controllers_) {
    VecX b = VecX::Constant(model.nv, c.max_torque);
    if (c.at_effort)
      for (int k = 0; k < model.nv; ++k) b(k) = std::min(b(k), model.effort[size_t(k)]);
    bound_.push_back(std::move(b));
    std::vector<char> passive(size_t(model.nv), 1);
    for (const int k : c.actuated)
      if (k >= 0 && k < model.nv) passive[size_t(k)] = 0;
    passive_.push_back(std::move(passive));
  }
}

void BuiltinControllers::operator()(double t, const VecX& q, const VecX& v, Eigen::Ref<VecX> tau) {
  using Kind = ControllerInput::Kind;
  for (size_t i = 0; i < controllers_.size(); ++i) {
    const ControllerInput& c = controllers_[i];
    part_.setZero();
    switch (c.kind) {
      case Kind::Pd: {
        // τ_k = K_p (q_d − q_k) + K_d (q̇_d − q̇_k)
        const int k = c.dofs[0];
        part_(k) = c.kp * (c.targets[0].value(t) - q(c.coords[0])) + c.kd * (c.targets[0].rate(t) - v(k));
        break;
      }
      case Kind::GravityCompensation:
        // τ = 𝓜·0 + bias(q, 0): the generalized gravity force
        update_kinematics(model_, data_, q);
        update_velocities(model_, data_, zero_);
        inverse_dynamics(model_, data_, zero_);
        part_ = data_.tau;
        if (!loops_.empty()) {
          // less what the loops carry: τ = g − Kᵀ λ, λ of least squares
          loop_rows(model_, data_, loops_, loop_data_);
          const MatX Kt = loop_data_.K.transpose();
          Eigen::CompleteOrthogonalDecomposition<MatX> cod(Kt);
          cod.setThreshold(kLoopRankTolerance);
          part_ -= Kt * cod.solve(part_);
        }
        break;
      case Kind::ComputedTorque: {
        // τ = 𝓜(q) (q̈_d + K_d ė + K_p e) + bias(q, q̇) by inverse dynamics at the commanded q̈
        for (size_t j = 0; j < c.dofs.size(); ++j) {
          const int k = c.dofs[j];
          const JointTarget& r = c.targets[j];
          a_(k) = r.acceleration(t) + c.kd * (r.rate(t) - v(k)) + c.kp * (r.value(t) - q(c.coords[j]));
        }
        update_kinematics(model_, data_, q);
        update_velocities(model_, data_, v);
        if (loops_.empty()) {
          inverse_dynamics(model_, data_, a_);
          part_ = data_.tau;
        } else {
          // the actuators' q̈ commanded, the passive DOFs' from the loops: τ on the actuators
          for (int k = 0; k < model_.nv; ++k)
            if (passive_[i][size_t(k)]) a_(k) = 0.0;
          part_ = loop_inverse_dynamics(model_, data_, loops_, c.actuated, a_, loop_data_);
        }
        break;
      }
    }
    tau += part_.cwiseMax(-bound_[i]).cwiseMin(bound_[i]);
  }
}

ControlFunction sum_controllers(std::vector<ControlFunction> parts, int nv) {
  parts.erase(std::remove_if(parts.begin(), parts.end(), [](const ControlFunction& f) { return !f; }), parts.end());
  if (parts.empty()) return {};
  if (parts.size() == 1) return parts[0];
  return [parts = std::move(parts), part = VecX(nv)](double t, const VecX& q, const VecX& v,
                                                     Eigen::Ref<VecX> tau) mutable {
    for (auto& f : parts) {
      part.setZero();
      f(t, q, v, part);
      tau += part;
    }
  };
}

}  // namespace soadyn
