// The spectral radius of the right-hand side's Jacobian, for the stiffness hint (stiffness.hpp).
#include "stiffness.hpp"

#include <Eigen/Eigenvalues>

#include <limits>

namespace soadyn::detail {

double spectral_radius(System& sys, double t, const VecX& y) {
  const int n = sys.size();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (n > kMaxStiffnessStates || y.size() != n) return nan;
  try {
    // J = ∂f/∂y by forward differences of the right-hand side (System::jacobian_dq: controllers and
    // springs included, which the analytic ∂f/∂y leaves out of a feedback controller)
    MatX J(n, n);
    sys.jacobian_dq(t, y.data(), J);
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
