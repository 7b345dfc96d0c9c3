// Tabulated signals: samples of named columns against time (read from files by
// io/table_file.hpp), and the natural cubic spline through one column (a controller's tabulated
// target).  A table's times increase, each sample at least min_table_spacing after the one before.
#pragma once

#include "soadyn/multibody/types.hpp"

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
  // the first and last knots' times: outside them the end values are held (q̇ and q̈ jump there)
  double t_first() const { return t_(0); }
  double t_last() const { return t_(t_.size() - 1); }

 private:
  // k of the interval [t_k, t_{k+1}] holding t
  int interval(double t) const;
  VecX t_, y_, m_;  // m: the second derivatives at the knots
};

}  // namespace soadyn
