// Tabulated signals: samples of named columns against time, read from a CSV file or a soadyn run
// file, and the natural cubic spline through one column (a controller's tabulated target).
//
// CSV: a header line naming the columns, the first of them the time ("t" or "time", with or
// without a unit: "time [s]"), then one line of numbers per sample; blank lines and lines starting
// with '#' are skipped.  A column may be named as `soadyn export --csv` names it ("q.elbow [rad]"):
// the "q." and the unit are dropped, so an exported run is a table of its joints.
// Run file (HDF5, read by read_run_file: run_file.hpp): /time and /q, the columns named by
// /model's q_names.
// Only a regular file is read (input_file.hpp: a FIFO, device or directory is refused with its
// kind), a CSV of at most kMaxTableBytes.  A CSV's times must increase, each sample at least
// min_table_spacing after the one before (a repeated or a closer time is refused with its line:
// the spline's rate through two samples 1e-16 s apart is 10¹⁶ times their difference, and a run
// stalls there); a run file's rows at a repeated time (an event) or closer than that keep the last.
#pragma once

#include "soadyn/algorithm/table.hpp"

#include <string>

namespace soadyn {

// Reads a CSV file or a run file (told apart by HDF5's signature); throws soadyn::Error naming
// file, line and column: `traj.csv:7: column 'elbow': expected a number, got 'x'`.
Table read_table(const std::string& path);

// A run file's /time and state: /q (columns named by /model's q_names), /qd and /qdd, each rows
// as read_table keeps them (time increasing, a repeated time's last row); /qd or /qdd absent from
// the file (a run logged without them) is left empty.  Throws soadyn::Error naming the file for a
// file that is not a run, a missing /time or /q, or datasets whose sizes disagree.
struct RunState {
  std::string path;
  VecX time;                         // T, s
  MatX q, qd, qdd;                   // T × nq, T × nv, T × nv (qd, qdd: 0 × 0 when not logged)
  std::vector<std::string> q_names;  // /model's
};
RunState read_run_state(const std::string& path);

}  // namespace soadyn
