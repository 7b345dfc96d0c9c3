// The adjoint's quadrature over its own steps (src/sim/step_quadrature.hpp): exact for the polynomials
// its rule interpolates, on uneven steps run either way in t, and accurate on a smooth integrand.
#include "../../src/sim/step_quadrature.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace soadyn;

namespace {

// uneven steps from t0 towards t1 (ratios of neighbours between 1/3 and 3, as an integrator's)
std::vector<double> uneven_grid(double t0, double t1, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ratio(1.0 / 3.0, 3.0);
  std::vector<double> h(size_t(n), 1.0);
  for (int k = 1; k < n; ++k) h[size_t(k)] = std::clamp(h[size_t(k) - 1] * ratio(rng), 0.05, 20.0);
  double total = 0;
  for (double x : h) total += x;
  std::vector<double> t{t0};
  for (double x : h) t.push_back(t.back() + (t1 - t0) * x / total);
  t.back() = t1;
  return t;
}

// two columns: p(t) = Σ c_m t^m of the given degree, and 2 p(t) + 1
VecX sample(const std::vector<double>& c, double t) {
  double p = 0, tm = 1;
  for (double cm : c) p += cm * tm, tm *= t;
  VecX f(2);
  f << p, 2 * p + 1;
  return f;
}

double integral(const std::vector<double>& c, double a, double b) {  // ∫_a^b p dt
  double s = 0;
  for (size_t m = 0; m < c.size(); ++m) s += c[m] * (std::pow(b, double(m + 1)) - std::pow(a, double(m + 1))) / double(m + 1);
  return s;
}

}  // namespace

// once six samples are in, every further interval is integrated exactly for degree ≤ 5
TEST(StepQuadrature, ExactForQuinticsOnUnevenStepsEitherWay) {
  for (unsigned seed = 0; seed < 20; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> coef(-2, 2);
    std::vector<double> c(6);
    for (double& x : c) x = coef(rng);
    for (const bool backward : {false, true}) {
      const double a = backward ? 1.5 : -0.5, b = backward ? -0.5 : 1.5;
      const std::vector<double> t = uneven_grid(a, b, 40, seed);
      StepQuadrature q(2);
      VecX after5;
      for (size_t k = 0; k < t.size(); ++k) {
        q.add(t[k], sample(c, t[k]));
        if (k == 5) after5 = q.integral();
      }
      const double exact = integral(c, t[5], b);
      const VecX got = q.integral() - after5;
      EXPECT_NEAR(got(0), exact, 1e-12 * (1 + std::abs(exact))) << "seed " << seed << (backward ? " backward" : "");
      EXPECT_NEAR(got(1), 2 * exact + (b - t[5]), 1e-12 * (1 + std::abs(exact)));
    }
  }
}

// the first intervals, with fewer samples, are exact for a line; one sample integrates nothing
TEST(StepQuadrature, LinesFromTheFirstSample) {
  const std::vector<double> c{0.7, -1.3};
  const std::vector<double> t = uneven_grid(2.0, 0.0, 12, 7);
  StepQuadrature q(2);
  q.add(t[0], sample(c, t[0]));
  EXPECT_EQ(q.integral().norm(), 0.0);
  for (size_t k = 1; k < t.size(); ++k) q.add(t[k], sample(c, t[k]));
  EXPECT_NEAR(q.integral()(0), integral(c, 2.0, 0.0), 1e-13);
  EXPECT_EQ(q.samples(), int(t.size()));
}

// a smooth integrand on steps of an integrator's size: the rule's error is far below its steps'
TEST(StepQuadrature, SmoothIntegrandToTheStepsAccuracy) {
  const std::vector<double> t = uneven_grid(0.0, 1.0, 200, 3);
  StepQuadrature q(1);
  for (double tk : t) q.add(tk, (VecX(1) << std::sin(7 * tk) * std::exp(tk)).finished());
  // ∫_0^1 e^t sin 7t dt = [e^t (sin 7t − 7 cos 7t)] / 50
  const double exact = (std::exp(1.0) * (std::sin(7.0) - 7 * std::cos(7.0)) + 7.0) / 50.0;
  EXPECT_NEAR(q.integral()(0), exact, 1e-9);
  // and a coarse grid is visibly less accurate (the test can fail for the right reason)
  const std::vector<double> coarse = uneven_grid(0.0, 1.0, 12, 3);
  StepQuadrature qc(1);
  for (double tk : coarse) qc.add(tk, (VecX(1) << std::sin(7 * tk) * std::exp(tk)).finished());
  EXPECT_GT(std::abs(qc.integral()(0) - exact), 1e-7);
}
