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

#include "soadyn/types.hpp"

#include <string>
#include <vector>

namespace soadyn {

// The least time between two samples of a table: kMinTableSpacing of its time scale, the larger of
// its span and its largest |t| (1e-9 s for a table over [0, 1] s; 1e-9 is ~4.5e6 rounding units of
// the scale, so spacings are exact to ~1e-7 and the spline's derivatives stay finite)
inline constexpr double kMinTableSpacing = 1e-9;
double min_table_spacing(double first, double last);

// How far beyond a column's range its spline may stray (CubicSpline::swing), in multiples of that
// range: a step sampled 0.01 s wide beside 0.5 s intervals swings 9.5 times it; smooth samples, a
// few percent.  A column past it is refused by read_table, naming the two lines.
inline constexpr double kMaxSplineSwing = 10.0;

struct Table {
  std::string path;
  std::vector<int> lines;            // a CSV's line of each sample (empty for a run file)
  VecX time;                         // T, s, increasing
  MatX values;                       // T × columns
  std::vector<std::string> columns;  // names, without "q." and unit
  int column(const std::string& name) const;  // index, or -1
};

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

// The natural cubic spline through (t_i, y_i) (second derivative 0 at both ends): value, rate and
// acceleration continuous inside [t_0, t_{n−1}]; before and after, the end values held (rate and
// acceleration 0).  Two samples give the straight line.  O(n) to build, O(log n) to evaluate.
class CubicSpline {
 public:
  CubicSpline(VecX t, VecX y);  // n ≥ 2, t increasing
  double value(double t) const;
  double rate(double t) const;
  double acceleration(double t) const;
  // where(t), then value(t, where): for many splines on the same knots, the search done once
  struct Where {
    int k = 0;              // the interval [t_k, t_{k+1}]
    int end = 0;            // −1 before t_0, +1 after t_{n−1} (the end values held), else 0
  };
  Where where(double t) const;
  double value(double t, Where w) const;
  // How far the spline strays beyond its samples' range [min y, max y]: the largest distance over
  // every interval (0 when it stays inside), the interval and the time where it is largest.  Two
  // samples much closer than their neighbours with a step between them make the natural spline
  // ring over the whole table (1e-9 s beside 0.5 s: 5e7 times the step), and a run following it stalls.
  struct Swing {
    double beyond = 0.0;
    int k = 0;
    double t = 0.0;
  };
  Swing swing() const;

 private:
  // k of the interval [t_k, t_{k+1}] holding t
  int interval(double t) const;
  VecX t_, y_, m_;  // m: the second derivatives at the knots
};

}  // namespace soadyn
