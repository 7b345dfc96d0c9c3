// HDF5 run files.  Layout (one file per run):
//   /time (T)  /q (T×nq)  /qd (T×nv)  /qdd (T×nv)
//   /energy/kinetic, /energy/potential, /energy/total (T)
//   /momentum/linear, /momentum/angular (T×3)
//   /model: datasets joint_names, parents; attributes nq, nv
//   /solver: attributes method, rtol, atol, dt, steps, rhs_evals, jac_evals, error_test_failures,
//            nonlinear_iterations, cpu_seconds, status, t_reached, quaternion_handling
//   root attributes: scenario (the scenario's full text), soadyn_version
// Datasets are chunked and extendable.  Rows are buffered and written, then the file flushed,
// at least once per second of wall time: between flushes the file on disk is left untouched, so a
// run killed at any moment leaves a valid file holding everything up to its last flush.
#pragma once

#include "soadyn/simulate.hpp"

#include <chrono>
#include <memory>
#include <string>

namespace soadyn {

class H5Log : public RunObserver {
 public:
  // Creates (truncates) the file; throws soadyn::Error if it cannot be written.
  H5Log(const std::string& path, const Scenario& sc, const SimulationSettings& settings, const std::string& version);
  ~H5Log() override;
  H5Log(const H5Log&) = delete;
  H5Log& operator=(const H5Log&) = delete;

  void on_sample(const Sample& s) override;
  void on_progress(const RunSummary& summary) override;
  void on_finish(const RunSummary& summary) override;
  void flush(const RunSummary* summary = nullptr);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace soadyn
