// ∫ f dt of a vector integrand sampled where an integrator steps, accumulated one sample at a time.
// The adjoint's parameter gradient (adjoint.cpp): its integrand Yᵀμ has 10 numbers per body, and
// handing it to CVODES as a quadrature carries that many numbers through every step's Nordsieck
// history (prediction, correction, rescaling), most of the backward run's vector work on big trees.
//
// Each new interval [t_{n−1}, t_n] is integrated exactly for the polynomial through the last
// k ≤ kMaxPoints samples (the step's own two and the ones before it): with s = (t − t_n)/h,
// h = t_n − t_{n−1},
//   ∫_{t_{n−1}}^{t_n} f dt ≈ h Σ_j w_j f_j,   Σ_j w_j s_j^m = ∫_{−1}^{0} s^m ds = (−1)^m/(m + 1), m < k
// (a k×k Vandermonde system in the scaled nodes s_j ∈ [s_min, 0], solved per sample: O(k³) scalars,
// then O(k·n) for the sum).  The samples may run either way in t (the adjoint runs from T to 0).
#pragma once

#include "soadyn/multibody/types.hpp"

#include <Eigen/LU>

#include <algorithm>

namespace soadyn {

class StepQuadrature {
 public:
  static constexpr int kMaxPoints = 6;  // degree 5: below the error of the steps it follows

  explicit StepQuadrature(int n) : F_(n, kMaxPoints), sum_(VecX::Zero(n)) {}

  // the integrand f at t, t beyond every earlier sample (in the run's direction)
  template <class Vec>
  void add(double t, const Vec& f) {
    const int slot = count_ % kMaxPoints;
    F_.col(slot) = f;
    t_[slot] = t;
    ++count_;
    const int k = std::min(count_, kMaxPoints);
    if (k < 2) return;
    const double h = t - t_[(count_ - 2) % kMaxPoints];
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxPoints, kMaxPoints> V(k, k);
    Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxPoints, 1> rhs(k);
    for (int j = 0; j < k; ++j) {
      const double s = (t_[(count_ - 1 - j) % kMaxPoints] - t) / h;
      double p = 1.0;
      for (int m = 0; m < k; ++m, p *= s) V(m, j) = p;
    }
    for (int m = 0; m < k; ++m) rhs(m) = (m % 2 == 0 ? 1.0 : -1.0) / (m + 1);
    const auto w = V.partialPivLu().solve(rhs).eval();
    for (int j = 0; j < k; ++j) sum_.noalias() += (h * w(j)) * F_.col((count_ - 1 - j) % kMaxPoints);
  }

  // ∫ f dt from the first sample's t to the last's (signed: negative steps give the integral
  // from the last back to the first with a minus sign, as an integrator running backward has it)
  const VecX& integral() const { return sum_; }
  int samples() const { return count_; }

 private:
  MatX F_;                     // n × kMaxPoints ring of the last samples
  double t_[kMaxPoints] = {};  // their times
  int count_ = 0;
  VecX sum_;
};

}  // namespace soadyn
