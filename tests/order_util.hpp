// What the order tests of the fixed-step methods share (test_lie_group_steps, test_variational,
// test_variational_prescribed): a method's errors at T at h, h/2 and h/4 against CVODE at rtol 1e-12.
#pragma once

#include "soadyn/multibody/configuration.hpp"
#include "soadyn/sim/simulate.hpp"
#include "test_util.hpp"

#include <functional>
#include <vector>

namespace soadyn::test {

// Into ref the last sample of CVODE Adams at rtol 1e-12, atol 1e-14 over [0, T]; into err the
// errors at T of the runs settings(h), h = dt, dt/2, dt/4, each ‖[q_ref ⊖ q; v − v_ref; booked(x) −
// booked(ref)]‖ on the group (booked: a quantity the run books, W or W_p; none when empty).  A run
// that does not complete is a fatal failure (callers: ASSERT_NO_FATAL_FAILURE, or HasFatalFailure).
inline void halving_errors(const Scenario& sc, double dt, double T,
                           const std::function<SimulationSettings(double h)>& settings, Sample& ref,
                           std::vector<double>& err, const std::function<double(const Sample&)>& booked = {}) {
  SimulationSettings s = sc.simulation;
  s.method = Method::CvodeAdams;
  s.rtol = 1e-12;
  s.atol = 1e-14;
  s.t_end = T;
  s.output_dt = T;
  std::vector<Sample> r;
  const RunSummary rs = simulate(sc, s, nullptr, &r);
  ASSERT_TRUE(rs.completed) << "the reference: " << rs.status;
  ref = r.back();
  err.clear();
  const int nv = sc.model.nv;
  for (const double h : {dt, dt / 2, dt / 4}) {
    std::vector<Sample> x;
    const RunSummary sum = simulate(sc, settings(h), nullptr, &x);
    ASSERT_TRUE(sum.completed) << "h = " << h << ": " << sum.status;
    VecX e(2 * nv + (booked ? 1 : 0));
    e.head(nv) = difference(sc.model, ref.q, x.back().q);
    e.segment(nv, nv) = x.back().qd - ref.qd;
    if (booked) e(2 * nv) = booked(x.back()) - booked(ref);
    err.push_back(e.norm());
  }
}

}  // namespace soadyn::test
