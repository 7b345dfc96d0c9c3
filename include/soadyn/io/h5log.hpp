// HDF5 run files.  Layout (one file per run, layout_version 5; run_file.hpp reads it back):
//   /samples (T×W)   every logged number, one row per output time; attributes column_names and
//                    column_units (W strings each: "time", "q.bus.x", "qd.left", "energy.total",
//                    "momentum.linear.x", "bodies.position.bus.x", …; "s", "m", "rad", "1", …)
//   views (HDF5 virtual datasets) of /samples' columns, so every series has one length at every
//   instant, each with a `units` attribute (one string, or one per column when they differ):
//     /time (T)                                                    always
//     /q (T×nq)  /qd (T×nv)  /qdd (T×nv)                           group "state"
//     /energy/kinetic, potential, total, work_inputs, dissipated (T)  group "energy"
//     /momentum/linear, /momentum/angular (T×3)                    group "momentum"
//     /bodies/position, /bodies/com (T×N×3), /bodies/orientation (T×N×4, w x y z)  group "bodies"
//     /frames/position (T×F×3), /frames/orientation (T×F×4)        a scenario's log: frames: [...]
//   /frames/names    those F frames (frames.hpp), a string dataset, when there are any
//     /sensitivities/initial_state (T×nx×nx), ∂x(t)/∂x₀      simulation: sensitivities: (sensitivity.hpp),
//     /sensitivities/parameters (T×nx×np), ∂x(t)/∂π          x = [q along the tangent; v], nx = 2 nv;
//                    `units` one per element (row-major) when they differ; the group's attributes
//                    state_names, state_units (nx), parameter_names, parameter_units (np), convention
//     /energy/impact_loss (T), L(t) (J)                            with joint limits on (limits.hpp)
//     /control (T×nv), the controllers' τ, columns control.<v name>  with a controller
//   /events (E×7): t, dof (into v), side (−1 lower, +1 upper), kind (0 impact, 1 hold, 2 release),
//                  v_before, v_after, energy_lost; attribute column_names; with joint limits on
//   /bodies/names    the N bodies (after fixed joints are merged), a string dataset
//   /scenario        the scenario's full text (a string dataset: any size)
//   /robot           the URDF or MJCF text the scenario's urdf: or model: key named, as the run read
//                    it (attribute path: where it was); absent when it names none, and in files
//                    before layout 4 (a run of a .urdf or .xml file itself: /scenario holds it)
//   /model_files     an MJCF model's files as MuJoCo's compiler was handed them (the main text, its
//                    <include>s and assets): attributes count, description; datasets 0..count-1, one
//                    file's bytes each (uint8, 1-D) with a fixed-length string attribute name (its
//                    name in MuJoCo's VFS); soadyn view compiles the model from these alone.  Absent
//                    without an MJCF model and in files written before it was added
//   /model: attributes nq, nv, q_names, v_names, q_units, v_units, joint_names, joint_types,
//           body_names, gravity, units, free_joint, ball_joint, planar_joint, helical_joint
//           (conventions), joint_pitches (m/rad, 0 but on helical joints);
//           datasets parents, joint_q_index, joint_v_index (ints, −1 = world)
//   /solver: attributes method, rtol, atol, dt, output_dt, t_end, dynamics, jacobian, newton (fixed
//            at the start);
//            scalar datasets status, t_reached, steps, rhs_evals, jac_evals, error_test_failures,
//            nonlinear_iterations, cpu_seconds, quaternion_handling, max_energy_balance_error,
//            final_energy_balance_error, control_ticks (layout 5; rewritten at every flush)
//   root attributes: scenario_path, soadyn_version, layout_version, log_groups
// Strings: every string is fixed-length UTF-8, null-padded (layout 5; earlier layouts wrote
// attributes and /bodies/names, /frames/names variable-length): h5py returns attributes as bytes
// (.decode()), datasets (/scenario, /bodies/names, /solver/status, …) as str with .asstr().
//
// Consistency: the file uses HDF5's single-writer/multiple-reader mode (SWMR, latest format).
// Everything is created before SWMR writing starts; afterwards the writer only appends rows to
// /samples (one extent for all series) and overwrites the fixed-size /solver datasets, and the
// library orders its writes so that the file on disk is valid at every instant.  The file is built
// under a temporary name and renamed onto the output path at the first flush, so a run killed or
// refused before then leaves an existing file untouched.  Readers of a running or killed run's
// file open it in SWMR-read mode (h5py: File(path, "r", swmr=True); read_run_file does so by
// itself); a finished run's file opens plainly.  New series are added as new columns of /samples and new views.
#pragma once

#include "soadyn/io/output_file.hpp"
#include "soadyn/sim/sensitivity.hpp"
#include "soadyn/sim/simulate.hpp"

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace soadyn {

// Writing the output file failed (a full disk, a quota, an I/O error).  The message is one line
// naming the cause, the file, the time reached and what the file keeps; it starts in lower case
// (strerror's "No space left on device" reads "no space left on device" after "soadyn: error:").
class IoError : public Error {
 public:
  explicit IoError(std::string message) : Error(lower_first(std::move(message))) {}

 private:
  static std::string lower_first(std::string s) {
    if (!s.empty() && s[0] >= 'A' && s[0] <= 'Z') s[0] = char(s[0] - 'A' + 'a');
    return s;
  }
};

// The groups of series a run logs (`soadyn run --log state,energy`); /time is always logged.
struct LogGroups {
  bool state = true, energy = true, momentum = true, bodies = true;
  // frames whose poses are logged after everything else (indices of Model::frame_names; H5Log
  // adds a scenario's log: frames: to those given); not part of parse() and str()
  std::vector<int> frames;
  // set by H5Log from the run (not part of parse() and str()): the limits' events and L(t)
  // (simulation: limits: true on a model with limits), the controllers' τ (built-in ones, or a
  // caller's controller when it says so)
  bool impacts = false, control = false;
  // set by H5Log from settings.sensitivities (not part of parse() and str()): what /sensitivities holds
  std::shared_ptr<const SensitivityPlan> sensitivities = nullptr;
  // set by H5Log from the scenario's prescribed joints (not part of parse() and str()): their DOFs,
  // whose holding torques /prescribed logs (and, with energy, their work /energy/work_prescribed)
  std::vector<int> prescribed = {};
  // set by H5Log from the scenario's loops (not part of parse() and str()): /loops/force's columns
  // (loop_row_names, loop_row_units) and /loops/closure; empty without loops
  std::vector<std::string> loop_rows = {}, loop_units = {};
  // "state,energy,momentum,bodies" (any subset, any order; "all"); throws soadyn::Error naming
  // the bad item
  static LogGroups parse(const std::string& text);
  std::string str() const;  // "state,energy,momentum,bodies"
};

// The layout's version, the root attribute layout_version: 4 added /robot; 5 writes every string
// fixed-length (no variable-length data, nothing in HDF5's unchecksummed global heap but the views'
// mappings, which soadyn's reader never opens).
inline constexpr int kLayoutVersion = 5;

// Bytes one logged row takes (W doubles), for the projected size of a run.
std::uint64_t row_bytes(const Model& model, const LogGroups& groups = {});

// The groups a run of `sc` with `settings` logs, given the caller's: `groups` completed as H5Log
// completes them (the limits' impacts, the controllers' τ, the sensitivities, the scenario's log:
// frames), so row_bytes(sc.model, logged_groups(...)) is the row a run file will hold.
LogGroups logged_groups(const Scenario& sc, const SimulationSettings& settings, const LogGroups& groups);

class H5Log : public RunObserver {
 public:
  // Builds the whole file under a temporary name next to `path`; throws soadyn::Error (IoError for
  // a write failure) and then leaves nothing behind.
  H5Log(const std::string& path, const Scenario& sc, const SimulationSettings& settings, const std::string& version,
        const LogGroups& groups = {});
  // A log that never reached its first flush removes its temporary file.
  ~H5Log() override;
  H5Log(const H5Log&) = delete;
  H5Log& operator=(const H5Log&) = delete;

  void on_sample(const Sample& s) override;
  void on_event(const LimitEvent& e) override;  // written with the next flush
  void on_progress(const RunSummary& summary) override;  // flushes at the first step, then every flush interval
  void set_flush_interval(double seconds);                // wall time between flushes, default 0.5 s
  // flushes and closes the file; a run interrupted before its first step (only the initial state
  // logged) writes nothing and leaves an existing file untouched
  void on_finish(const RunSummary& summary) override;
  // Writes the buffered rows (and the summary), then has the library write everything out; the
  // first flush renames the file onto its path.  Throws IoError when a write fails: the file keeps
  // its last flushed rows and is not touched again.
  void flush(const RunSummary* summary = nullptr);

  // the name the file is built under: "<path>.<pid>.tmp"
  static std::string temporary_path(const std::string& path);
  // the file being written until the first flush (for a signal handler to remove), then the path
  const std::string& current_path() const;
  bool published() const;
  // the flushes so far and the wall time they took, s
  long flushes() const;
  double flush_seconds() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace soadyn
