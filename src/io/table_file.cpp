#include "soadyn/io/table_file.hpp"

#include "soadyn/io/input_file.hpp"
#include "soadyn/io/run_file.hpp"
#include "soadyn/multibody/text.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>

namespace soadyn {


namespace {

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return {};
  return s.substr(a, s.find_last_not_of(" \t\r") - a + 1);
}

// a header field as a column name: quotes, a trailing " [unit]" and export's "q." dropped
std::string column_name(std::string s) {
  s = trim(s);
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = s.substr(1, s.size() - 2);
  if (!s.empty() && s.back() == ']') {
    const size_t open = s.rfind('[');
    if (open != std::string::npos) s = trim(s.substr(0, open));
  }
  if (s.rfind("q.", 0) == 0) s = s.substr(2);
  return s;
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  size_t from = 0;
  while (true) {
    const size_t comma = line.find(',', from);
    out.push_back(line.substr(from, comma == std::string::npos ? std::string::npos : comma - from));
    if (comma == std::string::npos) return out;
    from = comma + 1;
  }
}

// the rows `keep` of t, in that order
Table rows(Table t, const std::vector<Eigen::Index>& keep) {
  Table r;
  r.path = t.path;
  r.columns = t.columns;
  r.time.resize(Eigen::Index(keep.size()));
  r.values.resize(Eigen::Index(keep.size()), t.values.cols());
  for (size_t i = 0; i < keep.size(); ++i) {
    r.time(Eigen::Index(i)) = t.time(keep[i]);
    r.values.row(Eigen::Index(i)) = t.values.row(keep[i]);
  }
  return r;
}

// Rows kept in time order, a repeated time replacing the row before it (a run's rows at an event);
// throws if time decreases.
Table ordered(Table t) {
  std::vector<Eigen::Index> keep;
  for (Eigen::Index k = 0; k < t.time.size(); ++k) {
    if (k > 0 && t.time(k) < t.time(k - 1))
      throw Error(t.path + ": /time decreases at row " + std::to_string(k) + " (" + short_number(t.time(k - 1)) + " then " +
                  short_number(t.time(k)) + ")");
    if (k > 0 && t.time(k) == t.time(k - 1)) keep.back() = k;
    else keep.push_back(k);
  }
  return rows(std::move(t), keep);
}

// A CSV table's times, checked line by line: each sample after the one before by at least the
// minimum spacing (table.hpp); the message names the file, the line and the time column.
void check_times(const Table& t, const std::string& field, const std::vector<int>& lines) {
  const Eigen::Index n = t.time.size();
  const double spacing = n > 0 ? min_table_spacing(t.time(0), t.time(n - 1)) : 0.0;
  for (Eigen::Index k = 1; k < n; ++k) {
    const double a = t.time(k - 1), b = t.time(k);
    const std::string at = t.path + ":" + std::to_string(lines[size_t(k)]) + ": column '" + field + "': ";
    const std::string before = "line " + std::to_string(lines[size_t(k - 1)]);
    if (b < a) throw Error(at + "the time decreases (" + short_number(a) + " at " + before + ", then " + short_number(b) + ")");
    if (b == a) throw Error(at + "the time " + short_number(b) + " repeats " + before + "'s: each sample needs a time of its own");
    if (b - a < spacing)
      throw Error(at + exact_number(b) + " is " + short_number(b - a) + " s after " + before + "'s " + exact_number(a) +
                  ", closer than the " + short_number(spacing) + " s samples must keep (" + short_number(kMinTableSpacing) +
                  " of the table's time scale, " + short_number(spacing / kMinTableSpacing) +
                  " s): the spline's rate and acceleration there would stall a run");
  }
}

// Every column's spline within kMaxSplineSwing of its range (table.hpp), or the two samples where
// it strays, by line (CSV) or row (run file)
void check_swing(const Table& t) {
  for (Eigen::Index c = 0; c < t.values.cols(); ++c) {
    const VecX y = t.values.col(c);
    const double range = y.maxCoeff() - y.minCoeff(), scale = y.cwiseAbs().maxCoeff();
    const CubicSpline::Swing w = CubicSpline(t.time, y).swing();
    if (!(w.beyond > kMaxSplineSwing * range + 8 * std::numeric_limits<double>::epsilon() * scale)) continue;
    // where it strays, and the narrowest interval (the jump sampled too tightly, as a rule)
    const Eigen::Index k = w.k, n = t.time.size();
    Eigen::Index narrow = 1;
    for (Eigen::Index i = 2; i < n; ++i)
      if (t.time(i) - t.time(i - 1) < t.time(narrow) - t.time(narrow - 1)) narrow = i;
    auto at = [&](Eigen::Index i) {
      return t.lines.empty() ? "row " + std::to_string(i) : "line " + std::to_string(t.lines[size_t(i)]);
    };
    throw Error(t.path + (t.lines.empty() ? "" : ":" + std::to_string(t.lines[size_t(k + 1)])) + ": column '" +
                excerpt(t.columns[size_t(c)]) + "': the spline through the samples strays " + short_number(w.beyond) +
                " beyond their range [" + short_number(y.minCoeff()) + ", " + short_number(y.maxCoeff()) + "] at t = " +
                short_number(w.t) + " s (between " + at(k) + " and " + at(k + 1) + "), more than " + short_number(kMaxSplineSwing) +
                " times that range: samples spaced this unevenly around a change (" + short_number(t.time(narrow) - t.time(narrow - 1)) +
                " s before " + at(narrow) + ", " + short_number(t.time(n - 1) - t.time(0)) +
                " s in all) make a cubic spline ring, and a run following it stall; sample the change as densely as its neighbours");
  }
}

Table read_csv(const InputFile& file) {
  file.check_size(kMaxTableBytes, "a CSV table");
  const std::string& path = file.path();
  const std::string text = file.read();
  if (text.find('\0') != std::string::npos) throw Error(path + ": a binary file, expected a table (CSV or run file)");
  Table t;
  t.path = path;
  std::vector<double> flat;  // the samples, row after row
  std::vector<int> lines;
  std::string field;         // the time column's name as the header gives it
  size_t from = 0;
  for (int n = 1; from < text.size(); ++n) {
    const size_t eol = std::min(text.find('\n', from), text.size());
    const std::string body = trim(text.substr(from, eol - from));
    from = eol + 1;
    if (body.empty() || body[0] == '#') continue;
    const std::string at = path + ":" + std::to_string(n);
    const std::vector<std::string> fields = split(body);
    if (t.columns.empty()) {
      // the header: the time first, then names no other column has
      for (const std::string& f : fields) {
        const std::string name = column_name(f);
        if (name.empty()) throw Error(at + ": a column without a name in the header");
        if (std::find(t.columns.begin(), t.columns.end(), name) != t.columns.end())
          throw Error(at + ": column '" + excerpt(name) + "' is named twice");
        t.columns.push_back(name);
      }
      if (t.columns[0] != "t" && t.columns[0] != "time")
        throw Error(at + ": the first column must be the time ('t' or 'time [s]'), got '" + excerpt(t.columns[0]) + "'");
      if (t.columns.size() < 2) throw Error(at + ": the header names no column beside the time");
      field = t.columns[0];
      continue;
    }
    if (fields.size() != t.columns.size())
      throw Error(at + ": expected " + std::to_string(t.columns.size()) + " fields as the header has, got " +
                  std::to_string(fields.size()));
    for (size_t c = 0; c < fields.size(); ++c) {
      const std::string f = trim(fields[c]);
      char* end = nullptr;
      const double x = std::strtod(f.c_str(), &end);
      if (f.empty() || end != f.c_str() + f.size() || !std::isfinite(x))
        throw Error(at + ": column '" + excerpt(t.columns[c]) + "': expected a finite number, got '" + excerpt(f, 40) + "'");
      flat.push_back(x);
    }
    lines.push_back(n);
  }
  if (t.columns.empty()) throw Error(path + ": the table is empty (expected a header line, then samples)");
  const Eigen::Index rows_n = Eigen::Index(lines.size()), cols = Eigen::Index(t.columns.size());
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> all(flat.data(), rows_n, cols);
  t.time = all.col(0);
  t.values = all.rightCols(cols - 1);
  t.columns.erase(t.columns.begin());
  check_times(t, field, lines);
  if (t.time.size() < 2) throw Error(path + ": a table needs samples at two times at least, got " + std::to_string(t.time.size()));
  t.lines = std::move(lines);
  check_swing(t);
  return t;
}

// a run file's /time and /q (read_run_file), the columns named by /model's q_names
Table run_table(const RunContents& run) {
  Table t;
  t.path = run.path;
  t.columns = run.q_names;
  t.time = run.values("/time").col(0);
  t.values = run.values("/q");
  if (t.columns.empty()) throw Error(run.path + ": /model has no q_names (not a run file from soadyn run?)");
  return t;
}

// rows of `m` kept where ordered() kept the times: by matching each kept time in order
MatX rows_at(const MatX& m, const VecX& all, const VecX& kept) {
  MatX out(kept.size(), m.cols());
  Eigen::Index k = 0;
  for (Eigen::Index r = 0; r < all.size() && k < kept.size(); ++r)
    if (all(r) == kept(k) && (r + 1 == all.size() || all(r + 1) != all(r))) out.row(k++) = m.row(r);
  return out;
}

}  // namespace

RunState read_run_state(const std::string& path) {
  const RunContents run = read_run_file(path);
  Table all = run_table(run);
  const VecX times = all.time;
  const Table t = ordered(std::move(all));  // /time and /q, ordered
  RunState s;
  s.path = path;
  s.time = t.time;
  s.q = t.values;
  s.q_names = t.columns;
  for (auto [name, out] : {std::pair{"/qd", &s.qd}, std::pair{"/qdd", &s.qdd}})
    if (const RunSeries* m = run.find(name)) *out = rows_at(m->values, times, s.time);
  return s;
}

// A run file's rows as a table: ordered, and a row closer to the next than the minimum spacing
// dropped (a run's rows at an event, or its last row just before t_end), so the spline never sees
// two knots closer than a CSV table may have them
Table spaced_run_table(const std::string& path) {
  Table t = ordered(run_table(read_run_file(path)));
  const Eigen::Index n = t.time.size();
  if (n < 2) throw Error(path + ": a table needs samples at two times at least, got " + std::to_string(n));
  const double spacing = min_table_spacing(t.time(0), t.time(n - 1));
  std::vector<Eigen::Index> keep;
  for (Eigen::Index k = 0; k < n; ++k) {
    if (!keep.empty() && t.time(k) - t.time(keep.back()) < spacing) keep.back() = k;
    else keep.push_back(k);
  }
  if (keep.size() < 2) throw Error(path + ": a table needs samples at two times at least, got " + std::to_string(keep.size()));
  Table r = rows(std::move(t), keep);
  check_swing(r);
  return r;
}

Table read_table(const std::string& path) {
  // one check for both kinds (a regular file: never a FIFO or device), then by HDF5's signature
  const InputFile file(path, "a table (CSV or run file)", kNoSizeLimit);
  return is_hdf5_file(file.name_for_library()) ? spaced_run_table(path) : read_csv(file);
}

}  // namespace soadyn
