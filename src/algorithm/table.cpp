#include "soadyn/algorithm/table.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace soadyn {

int Table::column(const std::string& name) const {
  const auto it = std::find(columns.begin(), columns.end(), name);
  return it == columns.end() ? -1 : int(it - columns.begin());
}

double min_table_spacing(double first, double last) {
  return kMinTableSpacing * std::max({last - first, std::abs(first), std::abs(last)});
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

CubicSpline::Swing CubicSpline::swing() const {
  const double lo = y_.minCoeff(), hi = y_.maxCoeff();
  Swing out;
  for (Eigen::Index k = 0; k + 1 < t_.size(); ++k) {
    // y(B) on B = (t − t_k)/h in [0, 1]: its extremes where dy/dB = a B² + b B + c = 0
    const double h = t_(k + 1) - t_(k), m0 = m_(k), m1 = m_(k + 1);
    const double a = (m1 - m0) / 2 * h * h, b = m0 * h * h, c = (y_(k + 1) - y_(k)) - h * h * (2 * m0 + m1) / 6;
    std::vector<double> at = {0.5};
    if (std::abs(a) > 1e-300) {
      const double d = b * b - 4 * a * c;
      if (d >= 0) at.insert(at.end(), {(-b + std::sqrt(d)) / (2 * a), (-b - std::sqrt(d)) / (2 * a)});
    } else if (std::abs(b) > 1e-300) {
      at.push_back(-c / b);
    }
    for (double B : at) {
      if (!(B > 0 && B < 1)) continue;
      const double t = t_(k) + B * h, y = value(t, Where{int(k), 0});
      const double beyond = std::max({y - hi, lo - y, 0.0});
      if (beyond > out.beyond) out = {beyond, int(k), t};
    }
  }
  return out;
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
