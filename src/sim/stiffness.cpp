// The spectral radius of the right-hand side's Jacobian, for the stiffness hint (stiffness.hpp).
#include "stiffness.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <limits>

namespace soadyn::detail {

double spectral_radius(System& sys, double t, const VecX& y) {
  const int n = sys.size();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (n > kMaxStiffnessStates || y.size() != n) return nan;
  try {
    // J(:, j) ≈ (f(y + δ_j e_j) − f(y)) / δ_j,  δ_j = √ε · max(1, |y_j|)
    VecX f0(n), f1(n), yj = y;
    MatX J(n, n);
    sys.rhs(t, y.data(), f0.data());
    for (int j = 0; j < n; ++j) {
      const double d = std::sqrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::abs(y(j)));
      yj(j) = y(j) + d;
      sys.rhs(t, yj.data(), f1.data());
      yj(j) = y(j);
      J.col(j) = (f1 - f0) / d;
    }
    if (!J.allFinite()) return nan;
    // max |λ| over J's eigenvalues (complex pairs for oscillating modes)
    const Eigen::EigenSolver<MatX> es(J, false);
    if (es.info() != Eigen::Success) return nan;
    return es.eigenvalues().cwiseAbs().maxCoeff();
  } catch (...) {
    return nan;  // a controller that throws, a state the model refuses: no estimate, no hint
  }
}

}  // namespace soadyn::detail
