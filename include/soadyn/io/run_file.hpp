// A run file read back: the inverse of the layout h5log.hpp describes, the one reader behind
// `soadyn export`, `soadyn view`, read_table / read_run_state (table.hpp) and Python's read_log.
//
// Every series comes from /samples, found by its columns' names (the view "/energy/kinetic" is
// the column "energy.kinetic", "/q" the columns "q.<coordinate>") with the shape of its view, so
// every series has the same rows and each number is the double the run logged, to the bit.
// Files from before /samples (layouts 1 and 2) are read from the views' own datasets, cut to the
// rows every series has.  A running or killed run's file is read in SWMR-read mode: the rows
// flushed so far.
//
// Every failure is one soadyn::Error naming the file and the object: "run.h5: /q: expected 3
// columns (/model nq), /samples has 2 named q.*", "run.h5: cannot open the HDF5 file (corrupt or
// truncated?)".
//
// A corrupt file is refused, never a crash: HDF5 checksums these files' metadata but not the raw
// data nor its global heap, which libhdf5 1.10 follows without bounds checks.  Layout 5 keeps
// nothing there but the views' mappings: the reader refuses variable-length data before HDF5 can
// follow it and never opens a view (each series' shape comes from its columns).  A file of layout
// 4 or earlier (variable-length strings) is first read in a forked child, and refused when the
// child dies or takes more than 5 s ("run.h5: corrupt run file: the HDF5 library faults reading
// it (…)"); only then does this process read it.
#pragma once

#include "soadyn/multibody/types.hpp"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace soadyn {

// One logged series: a view of /samples (h5log.hpp), all its rows.
struct RunSeries {
  std::string path;                  // "/q", "/energy/kinetic", "/bodies/position"
  std::vector<Eigen::Index> shape;   // one row's: {} one number, {nq}, {N, 3}, {nx, np}
  std::vector<std::string> columns;  // its /samples columns' names and units, in order
  std::vector<std::string> units;
  MatX values;                       // T × (product of shape): each row in row-major order
};

// The joint limits' events (/events), one row each.
struct RunEvent {
  double t = 0.0;
  int dof = -1, side = 0, kind = 0;  // dof into v; side −1 lower, +1 upper; kind 0 impact, 1 hold, 2 release
  double v_before = 0.0, v_after = 0.0, energy_lost = 0.0;
};

struct RunContents {
  std::string path;
  // root attributes
  std::string soadyn_version, scenario_path, log_groups;
  long layout_version = 0;
  // what the run was made from: the scenario's text (a run of a .urdf or .xml file: the robot's);
  // the robot file its urdf: or model: key named, as the run read it, and that path (empty when
  // the scenario names none, or the file is from before layout 4 kept it)
  std::string scenario_text, robot_text, robot_path;
  // /model_files: every file MuJoCo's compiler was handed for an MJCF model, as handed (the main
  // text first, then its <include>s and assets; ModelFile::name as given to MuJoCo's virtual file
  // system); empty without an MJCF model and in files written before the run file stored them
  std::vector<ModelFile> model_files;
  // /model (empty lists in files without them)
  long nq = 0, nv = 0;
  std::vector<std::string> q_names, v_names, joint_names, joint_types, body_names;
  std::vector<int> parents, joint_v_index;  // per body: its parent (−1 world), its joint's first index into v
  // /solver: fixed at the start, then as the last flush left them
  struct Solver {
    std::string method, dynamics, status, quaternion_handling;
    double rtol = 0, atol = 0, output_dt = 0, t_end = 0, t_reached = 0, cpu_seconds = 0;
    double max_energy_balance_error = 0, final_energy_balance_error = 0;
    long steps = 0, rhs_evals = 0, jac_evals = 0, error_test_failures = 0, nonlinear_iterations = 0;
    long control_ticks = 0;  // layout 5 on (0 before)
    double stiffness_index = 0;   // RunSummary's (simulate.hpp); 0 and "" in files from before them
    std::string stiffness_hint;
  } solver;
  // /samples' columns, and the series logged (kViewPaths order), each with the same rows
  std::vector<std::string> column_names, column_units;
  std::vector<RunSeries> series;
  std::vector<std::string> frame_names;  // /frames/names
  // /sensitivities' attributes (empty without sensitivities)
  std::vector<std::string> state_names, state_units, parameter_names, parameter_units;
  std::vector<RunEvent> events;

  Eigen::Index rows() const;                         // T
  const RunSeries* find(const std::string& path) const;  // nullptr when the run did not log it
  const MatX& values(const std::string& path) const;     // throws soadyn::Error naming the file when not logged
};

// HDF5's signature is in the file (a run file, or another HDF5 file; read_table tells it from CSV).
// Throws soadyn::Error for a file that cannot be opened or is not a regular file (input_file.hpp).
bool is_hdf5_file(const std::string& path);

// Reads the whole file.  Throws soadyn::Error (one line naming the file and the object); a FIFO,
// device or directory is refused with its kind, never waited on (input_file.hpp).
RunContents read_run_file(const std::string& path);

// The run file open read-only, for readers of /samples in blocks (`soadyn export`): bounded
// memory for a file of any length.  Move-only; closes the file when destroyed.
class RunReader {
 public:
  explicit RunReader(const std::string& path);  // throws soadyn::Error naming the file
  ~RunReader();
  RunReader(RunReader&&) noexcept;
  RunReader& operator=(RunReader&&) noexcept;
  RunReader(const RunReader&) = delete;
  RunReader& operator=(const RunReader&) = delete;

  const std::string& path() const;
  // /samples: its attributes column_names and column_units, its rows when it was opened
  const std::vector<std::string>& column_names() const;
  const std::vector<std::string>& column_units() const;
  std::uint64_t rows() const;
  // rows [first, first + count) (within rows()), row-major, W = column_names().size() a row
  void read_rows(std::uint64_t first, std::uint64_t count, double* out) const;
  RunContents read() const;  // everything (read_run_file)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace soadyn
