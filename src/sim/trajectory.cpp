// Trajectory: a run's samples as columns, and the observer that gathers them.
#include "soadyn/sim/trajectory.hpp"

#include <algorithm>
#include <cmath>

namespace soadyn {

namespace {

void append(std::vector<double>& to, const double* from, Eigen::Index n) { to.insert(to.end(), from, from + n); }

// T rows of k numbers each from a flat vector (emptied)
SampleRows rows(std::vector<double>& flat, Eigen::Index T, Eigen::Index k) {
  SampleRows out = Eigen::Map<const SampleRows>(flat.data(), T, k);
  std::vector<double>().swap(flat);
  return out;
}

VecX column(std::vector<double>& flat) {
  VecX out = Eigen::Map<const VecX>(flat.data(), Eigen::Index(flat.size()));
  std::vector<double>().swap(flat);
  return out;
}

// the run's energy scale: max(|E(0)|, peak T, peak |W|, peak |W_p|) over all of it (a run from rest
// with E(0) = 0 is measured against the energy its inputs and given motions bring in)
double energy_scale(const VecX& E, const VecX& T, const VecX& W, const VecX& Wp) {
  double scale = std::max(std::abs(E(0)), T.maxCoeff());
  if (W.size() > 0) scale = std::max(scale, W.cwiseAbs().maxCoeff());
  if (Wp.size() > 0) scale = std::max(scale, Wp.cwiseAbs().maxCoeff());
  return std::max(scale, 1e-300);
}

}  // namespace

void TrajectoryRecorder::on_sample(const Sample& s) {
  t_.push_back(s.t);
  append(q_, s.q.data(), s.q.size());
  append(v_, s.qd.data(), s.qd.size());
  append(qdd_, s.qdd.data(), s.qdd.size());
  kinetic_.push_back(s.kinetic);
  potential_.push_back(s.potential);
  total_.push_back(s.total);
  work_.push_back(s.work_inputs);
  dissipated_.push_back(s.dissipated);
  impact_loss_.push_back(s.impact_loss);
  work_prescribed_.push_back(s.work_prescribed);
  append(prescribed_torque_, s.prescribed_torque.data(), s.prescribed_torque.size());
  append(loop_force_, s.loop_force.data(), s.loop_force.size());
  loop_closure_.push_back(s.loop_closure);
  append(control_, s.control.data(), s.control.size());
  append(linear_, s.linear.data(), 3);
  append(angular_, s.angular.data(), 3);
  // column-major 3×N and 4×N: body after body, as the rows want them
  append(position_, s.body_position.data(), s.body_position.size());
  append(orientation_, s.body_orientation.data(), s.body_orientation.size());
  append(com_, s.body_com.data(), s.body_com.size());
  // each sensitivity matrix row after row
  const MatX x0 = s.sensitivity_initial_state.transpose(), pi = s.sensitivity_parameters.transpose();
  append(dx_dx0_, x0.data(), x0.size());
  append(dx_dpi_, pi.data(), pi.size());
  if (next_) next_->on_sample(s);
}

void TrajectoryRecorder::on_event(const LimitEvent& e) {
  if (next_) next_->on_event(e);
}

void TrajectoryRecorder::on_progress(const RunSummary& r) {
  if (next_) next_->on_progress(r);
}

void TrajectoryRecorder::on_finish(const RunSummary& r) {
  if (next_) next_->on_finish(r);
}

Trajectory TrajectoryRecorder::take(const Model& m, const std::vector<PrescribedInput>& prescribed,
                                    const std::vector<LoopConstraint>& loops) {
  Trajectory tr;
  const Eigen::Index T = Eigen::Index(t_.size()), N = m.nbodies;
  const Eigen::Index nx0 = T > 0 ? Eigen::Index(dx_dx0_.size()) / T : 0, nxp = T > 0 ? Eigen::Index(dx_dpi_.size()) / T : 0;
  tr.t = column(t_);
  tr.q = rows(q_, T, m.nq);
  tr.v = rows(v_, T, m.nv);
  tr.qdd = rows(qdd_, T, m.nv);
  tr.kinetic_energy = column(kinetic_);
  tr.potential_energy = column(potential_);
  tr.total_energy = column(total_);
  tr.work_inputs = column(work_);
  tr.dissipated = column(dissipated_);
  tr.impact_loss = column(impact_loss_);
  tr.work_prescribed = column(work_prescribed_);
  tr.prescribed_torque = rows(prescribed_torque_, T, Eigen::Index(prescribed.size()));
  for (const PrescribedInput& p : prescribed) tr.prescribed_joints.push_back(p.joint);
  tr.loop_rows = loop_row_names(loops);
  tr.loop_force = rows(loop_force_, T, Eigen::Index(tr.loop_rows.size()));
  tr.loop_closure = column(loop_closure_);
  tr.control = rows(control_, T, T > 0 ? Eigen::Index(control_.size()) / T : m.nv);
  tr.linear_momentum = rows(linear_, T, 3);
  tr.angular_momentum = rows(angular_, T, 3);
  tr.body_position = rows(position_, T, 3 * N);
  tr.body_orientation = rows(orientation_, T, 4 * N);
  tr.body_com = rows(com_, T, 3 * N);
  tr.sensitivity_initial_state = rows(dx_dx0_, T, nx0);
  tr.sensitivity_parameters = rows(dx_dpi_, T, nxp);
  tr.joint_names = m.joint_names;
  tr.parents = m.parent;
  return tr;
}

Sample Trajectory::sample(Eigen::Index k) const {
  Sample s;
  s.t = t(k);
  s.q = q.row(k).transpose();
  s.qd = v.row(k).transpose();
  s.qdd = qdd.row(k).transpose();
  s.kinetic = kinetic_energy(k), s.potential = potential_energy(k), s.total = total_energy(k);
  s.work_inputs = work_inputs(k), s.dissipated = dissipated(k), s.impact_loss = impact_loss(k);
  if (work_prescribed.size() == t.size()) s.work_prescribed = work_prescribed(k);
  if (prescribed_torque.cols() > 0) s.prescribed_torque = prescribed_torque.row(k).transpose();
  if (loop_force.cols() > 0) s.loop_force = loop_force.row(k).transpose();
  if (loop_closure.size() == t.size()) s.loop_closure = loop_closure(k);
  s.control = control.row(k).transpose();
  s.linear = linear_momentum.row(k).transpose();
  s.angular = angular_momentum.row(k).transpose();
  const Eigen::Index N = body_position.cols() / 3;
  s.body_position = Eigen::Map<const Mat3X>(body_position.row(k).data(), 3, N);
  s.body_com = Eigen::Map<const Mat3X>(body_com.row(k).data(), 3, N);
  s.body_orientation = Eigen::Map<const Eigen::Matrix<double, 4, Eigen::Dynamic>>(body_orientation.row(k).data(), 4, N);
  // the sensitivities, stored row after row, nx = 2 nv rows each
  const Eigen::Index nx = 2 * v.cols();
  if (sensitivity_initial_state.cols() > 0)
    s.sensitivity_initial_state = Eigen::Map<const SampleRows>(sensitivity_initial_state.row(k).data(), nx, nx);
  if (sensitivity_parameters.cols() > 0)
    s.sensitivity_parameters =
        Eigen::Map<const SampleRows>(sensitivity_parameters.row(k).data(), nx, sensitivity_parameters.cols() / nx);
  return s;
}

VecX Trajectory::energy_error() const {
  if (size() == 0) return VecX();
  // (E − E(0)) / max(|E(0)|, peak T)
  return (total_energy.array() - total_energy(0)) / energy_scale(total_energy, kinetic_energy, VecX(), VecX());
}

VecX Trajectory::balance_error() const {
  if (size() == 0) return VecX();
  // (E − E(0) − W − W_p + L) / max(|E(0)|, peak T, peak |W|, peak |W_p|)
  const VecX wp = work_prescribed.size() == size() ? work_prescribed : VecX::Zero(size());
  return (total_energy.array() - total_energy(0) - work_inputs.array() - wp.array() + impact_loss.array()) /
         energy_scale(total_energy, kinetic_energy, work_inputs, wp);
}

}  // namespace soadyn
