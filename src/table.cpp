#include "soadyn/table.hpp"

#include "soadyn/run_file.hpp"
#include "soadyn/text.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>

namespace soadyn {

int Table::column(const std::string& name) const {
  const auto it = std::find(columns.begin(), columns.end(), name);
  return it == columns.end() ? -1 : int(it - columns.begin());
}

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

// Rows kept in time order, a repeated time replacing the row before it; throws if time decreases.
Table ordered(Table t, const std::vector<int>& lines) {
  std::vector<Eigen::Index> keep;
  for (Eigen::Index k = 0; k < t.time.size(); ++k) {
    if (k > 0 && t.time(k) < t.time(k - 1))
      throw Error(t.path + (lines.empty() ? "" : ":" + std::to_string(lines[size_t(k)])) +
                  ": time decreases (" + short_number(t.time(k - 1)) + " then " + short_number(t.time(k)) + ")");
    if (k > 0 && t.time(k) == t.time(k - 1)) keep.back() = k;
    else keep.push_back(k);
  }
  if (keep.size() < 2) throw Error(t.path + ": a table needs samples at two times at least, got " + std::to_string(keep.size()));
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

Table read_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open the table (" + std::strerror(errno) + ")");
  Table t;
  t.path = path;
  std::vector<std::vector<double>> rows;
  std::vector<int> lines;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    const std::string body = trim(line);
    if (body.empty() || body[0] == '#') continue;
    const std::string at = path + ":" + std::to_string(n);
    const std::vector<std::string> fields = split(body);
    if (t.columns.empty()) {
      // the header: the time first, then names no other column has
      for (const std::string& f : fields) {
        const std::string name = column_name(f);
        if (name.empty()) throw Error(at + ": a column without a name in the header");
        if (std::find(t.columns.begin(), t.columns.end(), name) != t.columns.end())
          throw Error(at + ": column '" + name + "' is named twice");
        t.columns.push_back(name);
      }
      if (t.columns[0] != "t" && t.columns[0] != "time")
        throw Error(at + ": the first column must be the time ('t' or 'time [s]'), got '" + t.columns[0] + "'");
      if (t.columns.size() < 2) throw Error(at + ": the header names no column beside the time");
      continue;
    }
    if (fields.size() != t.columns.size())
      throw Error(at + ": expected " + std::to_string(t.columns.size()) + " fields as the header has, got " +
                  std::to_string(fields.size()));
    std::vector<double> row;
    for (size_t c = 0; c < fields.size(); ++c) {
      const std::string f = trim(fields[c]);
      char* end = nullptr;
      const double x = std::strtod(f.c_str(), &end);
      if (f.empty() || end != f.c_str() + f.size() || !std::isfinite(x))
        throw Error(at + ": column '" + t.columns[c] + "': expected a finite number, got '" + f + "'");
      row.push_back(x);
    }
    rows.push_back(std::move(row));
    lines.push_back(n);
  }
  if (t.columns.empty()) throw Error(path + ": the table is empty (expected a header line, then samples)");
  t.time.resize(Eigen::Index(rows.size()));
  t.values.resize(Eigen::Index(rows.size()), Eigen::Index(t.columns.size() - 1));
  for (size_t k = 0; k < rows.size(); ++k) {
    t.time(Eigen::Index(k)) = rows[k][0];
    for (size_t c = 1; c < rows[k].size(); ++c) t.values(Eigen::Index(k), Eigen::Index(c - 1)) = rows[k][c];
  }
  t.columns.erase(t.columns.begin());
  return ordered(std::move(t), lines);
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
  const Table t = ordered(std::move(all), {});  // /time and /q, ordered
  RunState s;
  s.path = path;
  s.time = t.time;
  s.q = t.values;
  s.q_names = t.columns;
  for (auto [name, out] : {std::pair{"/qd", &s.qd}, std::pair{"/qdd", &s.qdd}})
    if (const RunSeries* m = run.find(name)) *out = rows_at(m->values, times, s.time);
  return s;
}

Table read_table(const std::string& path) {
  return is_hdf5_file(path) ? ordered(run_table(read_run_file(path)), {}) : read_csv(path);
}

CubicSpline::CubicSpline(VecX t, VecX y) : t_(std::move(t)), y_(std::move(y)), m_(VecX::Zero(t_.size())) {
  const Eigen::Index n = t_.size();
  if (n < 2 || y_.size() != n) throw Error("CubicSpline: needs two samples or more, as many times as values");
  for (Eigen::Index k = 1; k < n; ++k)
    if (!(t_(k) > t_(k - 1))) throw Error("CubicSpline: times must increase");
  // the second derivatives m: h_{i−1}/6 m_{i−1} + (h_{i−1} + h_i)/3 m_i + h_i/6 m_{i+1}
  //   = (y_{i+1} − y_i)/h_i − (y_i − y_{i−1})/h_{i−1}, m_0 = m_{n−1} = 0 (tridiagonal, Thomas)
  VecX c = VecX::Zero(n), d = VecX::Zero(n);
  for (Eigen::Index i = 1; i + 1 < n; ++i) {
    const double h0 = t_(i) - t_(i - 1), h1 = t_(i + 1) - t_(i);
    const double rhs = (y_(i + 1) - y_(i)) / h1 - (y_(i) - y_(i - 1)) / h0;
    const double pivot = (h0 + h1) / 3 - h0 / 6 * c(i - 1);
    c(i) = h1 / 6 / pivot;
    d(i) = (rhs - h0 / 6 * d(i - 1)) / pivot;
  }
  for (Eigen::Index i = n - 2; i >= 1; --i) m_(i) = d(i) - c(i) * m_(i + 1);
}

int CubicSpline::interval(double t) const {
  const auto it = std::upper_bound(t_.data(), t_.data() + t_.size(), t);
  return int(std::clamp<Eigen::Index>(it - t_.data() - 1, 0, t_.size() - 2));
}

// On [t_k, t_{k+1}], h = t_{k+1} − t_k, A = (t_{k+1} − t)/h, B = 1 − A:
//   y = A y_k + B y_{k+1} + ((A³ − A) m_k + (B³ − B) m_{k+1}) h²/6
//   ẏ = (y_{k+1} − y_k)/h − (3A² − 1) h m_k/6 + (3B² − 1) h m_{k+1}/6,   ÿ = A m_k + B m_{k+1}
double CubicSpline::value(double t) const { return value(t, where(t)); }

CubicSpline::Where CubicSpline::where(double t) const {
  if (t <= t_(0)) return {0, -1};
  if (t >= t_(t_.size() - 1)) return {0, 1};
  return {interval(t), 0};
}

double CubicSpline::value(double t, Where w) const {
  if (w.end < 0) return y_(0);
  if (w.end > 0) return y_(y_.size() - 1);
  const int k = w.k;
  const double h = t_(k + 1) - t_(k), A = (t_(k + 1) - t) / h, B = 1 - A;
  return A * y_(k) + B * y_(k + 1) + ((A * A * A - A) * m_(k) + (B * B * B - B) * m_(k + 1)) * h * h / 6;
}

double CubicSpline::rate(double t) const {
  if (t < t_(0) || t > t_(t_.size() - 1)) return 0.0;
  const int k = interval(t);
  const double h = t_(k + 1) - t_(k), A = (t_(k + 1) - t) / h, B = 1 - A;
  return (y_(k + 1) - y_(k)) / h - (3 * A * A - 1) * h * m_(k) / 6 + (3 * B * B - 1) * h * m_(k + 1) / 6;
}

double CubicSpline::acceleration(double t) const {
  if (t < t_(0) || t > t_(t_.size() - 1)) return 0.0;
  const int k = interval(t);
  const double h = t_(k + 1) - t_(k), A = (t_(k + 1) - t) / h;
  return A * m_(k) + (1 - A) * m_(k + 1);
}

}  // namespace soadyn
