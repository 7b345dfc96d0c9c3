// A run's samples as columns, as Python's soadyn.Trajectory: one row per output time.
#pragma once

#include "soadyn/sim/simulate.hpp"

#include <string>
#include <vector>

namespace soadyn {

// Row-major T × k: row k is sample k, contiguous (numpy's (T, k) without a copy).
using SampleRows = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// T samples at the output times.  Per-body series hold a row of 3N (or 4N) numbers per sample,
// body after body: body i of sample k is body_position.row(k).segment<3>(3 i) (numpy's (T, N, 3)).
// A sensitivity row holds sample k's matrix row after row (numpy's (T, nx, ·)).
struct Trajectory {
  VecX t;                                    // (T) s
  SampleRows q, v, qdd;                      // (T × nq), (T × nv): v the note's q̇ (free joint: [ω; ṗ], inertial)
  VecX kinetic_energy, potential_energy, total_energy;  // (T) J; potential includes joint springs
  VecX work_inputs, dissipated, impact_loss; // (T) J: W(t), the dampers' D(t) ≥ 0, the impacts' L(t)
  VecX work_prescribed;                      // (T) J: W_p(t), the prescribed joints' torques' work (zeros without)
  SampleRows prescribed_torque;              // (T × prescribed joints) N m or N: the torques holding their motion
  std::vector<std::string> prescribed_joints;  // their names, in prescribed_torque's column order
  SampleRows loop_force;                     // (T × loop rows) N or N m: the loops' multipliers λ (0 columns without loops)
  VecX loop_closure;                         // (T) the largest closure error |φ| (zeros without loops)
  std::vector<std::string> loop_rows;        // loop_force's columns, "<loop>.<part>" (loop_row_names)
  SampleRows control;                        // (T × nv) the controllers' τ_c, zeros without one
  SampleRows linear_momentum, angular_momentum;  // (T × 3), about the inertial origin
  SampleRows body_position, body_com;        // (T × 3N) inertial, m
  SampleRows body_orientation;               // (T × 4N) unit quaternions [w x y z], body → inertial
  SampleRows sensitivity_initial_state;      // (T × nx·nx) ∂x(t)/∂x₀, nx = 2 nv, 0 columns without them
  SampleRows sensitivity_parameters;         // (T × nx·np) ∂x(t)/∂π, 0 columns without them
  RunSummary summary;                        // how the run ended, its statistics and events
  std::vector<std::string> warnings;         // the settings' (check_run), then the run's (summary.warnings)
  std::vector<std::string> joint_names;      // the model's
  std::vector<int> parents;                  // the model's body parents (−1: the base)

  Eigen::Index size() const { return t.size(); }
  // sample k as simulate() observed it
  Sample sample(Eigen::Index k) const;
  // (E(t) − E(0)) / max(|E(0)|, peak T over the run), (T): the energy's drift
  VecX energy_error() const;
  // (E(t) − E(0) − W(t) − W_p(t) + L(t)) / max(|E(0)|, peak T, peak |W|, peak |W_p|) over the run, (T):
  // what the summary's figures take
  VecX balance_error() const;
};

// Keeps every sample it receives (and forwards all it receives to `next`, if any); take() then
// hands them over as a Trajectory of a model with nq, nv and nbodies.
class TrajectoryRecorder : public RunObserver {
 public:
  explicit TrajectoryRecorder(RunObserver* next = nullptr) : next_(next) {}
  void on_sample(const Sample& s) override;
  void on_event(const LimitEvent& e) override;
  void on_progress(const RunSummary& r) override;
  void on_finish(const RunSummary& r) override;
  // the samples so far as columns (the recorder is left empty); `prescribed` names the prescribed
  // joints' columns (Inputs::prescribed)
  Trajectory take(const Model& model, const std::vector<PrescribedInput>& prescribed = {},
                  const std::vector<LoopConstraint>& loops = {});

 private:
  RunObserver* next_;
  std::vector<double> t_, q_, v_, qdd_, kinetic_, potential_, total_, work_, dissipated_, impact_loss_, control_,
      work_prescribed_, prescribed_torque_, loop_force_, loop_closure_,
      linear_, angular_, position_, orientation_, com_, dx_dx0_, dx_dpi_;
};

}  // namespace soadyn
