// The fixed-point corrector (src/sim/fixed_point.hpp) against SUNDIALS' SUNNonlinSol_FixedPoint on the
// same problems: a contraction g(y) = c R y + b solved to a tolerance in 1, 2 or 3 iterations, one
// that does not converge within the iterations allowed, a convergence test that gives up, and a g
// that fails; each solve's result, iteration and failure counts, the iteration index the test sees
// and the returned status agree exactly, over two solves in a row as CVODE makes them.
#include "../../src/sim/fixed_point.hpp"

#include <gtest/gtest.h>

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <vector>

namespace {

constexpr sunindextype kN = 5;

struct Problem {
  double contraction = 0.5;  // g(y) = c·R y + b, R a fixed rotation-like mixing: converges at rate c
  int fail_at_call = -1;     // the g call that fails (returns 1), counting from 0; −1: none
  int give_up_at = -1;       // the test's iteration index at which it returns a failure; −1: never
  int calls = 0;
  std::vector<int> seen_iters;  // the iteration index at each test
};

int g(N_Vector y, N_Vector gy, void* mem) {
  auto& p = *static_cast<Problem*>(mem);
  if (p.calls++ == p.fail_at_call) return 1;
  const double* x = NV_DATA_S(y);
  double* out = NV_DATA_S(gy);
  for (sunindextype i = 0; i < kN; ++i)
    out[i] = p.contraction * (0.6 * x[i] - 0.8 * x[(i + 1) % kN]) + 1.0 + 0.1 * double(i);
  return 0;
}

// converged when the change's max norm is below tol; SUN_NLS_CONTINUE otherwise
int test(SUNNonlinearSolver S, N_Vector, N_Vector delta, realtype tol, N_Vector, void* mem) {
  auto& p = *static_cast<Problem*>(mem);
  int k = -1;
  SUNNonlinSolGetCurIter(S, &k);
  p.seen_iters.push_back(k);
  if (k == p.give_up_at) return SUN_NLS_CONV_RECVR;
  return N_VMaxNorm(delta) < tol ? SUN_NLS_SUCCESS : SUN_NLS_CONTINUE;
}

struct Run {
  std::vector<double> y;
  int status = 0;
  long iters = 0, fails = 0;
  std::vector<int> seen_iters;
};

std::vector<Run> solve_all(SUNNonlinearSolver S, N_Vector tmpl, const std::vector<std::pair<Problem, double>>& cases) {
  EXPECT_EQ(SUNNonlinSolSetSysFn(S, g), SUN_NLS_SUCCESS);
  std::vector<Run> out;
  for (auto [p, tol] : cases) {
    EXPECT_EQ(SUNNonlinSolSetConvTestFn(S, test, &p), SUN_NLS_SUCCESS);
    EXPECT_EQ(SUNNonlinSolInitialize(S), SUN_NLS_SUCCESS);
    N_Vector y0 = N_VClone(tmpl), y = N_VClone(tmpl), w = N_VClone(tmpl);
    for (sunindextype i = 0; i < kN; ++i) NV_Ith_S(y0, i) = 0.3 * double(i) - 0.5, NV_Ith_S(y, i) = 20.0 - double(i);
    N_VConst(1.0, w);
    for (int repeat = 0; repeat < 2; ++repeat) {  // two solves without re-initializing, as CVODE's steps
      Run r;
      r.status = SUNNonlinSolSolve(S, y0, y, w, tol, SUNFALSE, &p);
      SUNNonlinSolGetNumIters(S, &r.iters);
      SUNNonlinSolGetNumConvFails(S, &r.fails);
      r.y.assign(NV_DATA_S(y), NV_DATA_S(y) + kN);
      r.seen_iters = p.seen_iters;
      out.push_back(r);
    }
    N_VDestroy(y0), N_VDestroy(y), N_VDestroy(w);
  }
  return out;
}

TEST(FixedPoint, EveryIterateCountAndStatusIsSundials) {
  SUNContext ctx = nullptr;
  ASSERT_EQ(SUNContext_Create(nullptr, &ctx), 0);
  N_Vector tmpl = N_VNew_Serial(kN, ctx);
  std::vector<std::pair<Problem, double>> cases;
  for (const double tol : {10.0, 1.0, 0.3}) cases.push_back({Problem{}, tol});  // 2 and 3 iterations, then too few
  Problem failing;
  failing.fail_at_call = 1;  // the second g of the first solve
  cases.push_back({failing, 1e-9});
  Problem giving_up;
  giving_up.give_up_at = 1;
  cases.push_back({giving_up, 1e-9});
  SUNNonlinearSolver theirs = SUNNonlinSol_FixedPoint(tmpl, 0, ctx);
  SUNNonlinearSolver ours = soadyn::cvode_impl::make_fixed_point(ctx);
  ASSERT_NE(ours, nullptr);
  EXPECT_EQ(SUNNonlinSolGetType(ours), SUNNonlinSolGetType(theirs));
  const auto a = solve_all(theirs, tmpl, cases), b = solve_all(ours, tmpl, cases);
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].status, b[k].status) << "solve " << k;
    EXPECT_EQ(a[k].iters, b[k].iters) << "solve " << k;
    EXPECT_EQ(a[k].fails, b[k].fails) << "solve " << k;
    EXPECT_EQ(a[k].seen_iters, b[k].seen_iters) << "solve " << k;
    for (sunindextype i = 0; i < kN; ++i) EXPECT_EQ(a[k].y[size_t(i)], b[k].y[size_t(i)]) << "solve " << k << " entry " << i;
  }
  // the cases reach every outcome: the last iterate in the caller's vector (2 iterations) or in the
  // solver's (1 or 3: copied back), the iteration limit, a failed g, a test that gives up
  EXPECT_EQ(b[0].status, SUN_NLS_SUCCESS);
  EXPECT_EQ(b[0].iters, 2);
  EXPECT_EQ(b[1].iters, 1);
  EXPECT_EQ(b[2].iters, 3);
  EXPECT_EQ(b[4].status, SUN_NLS_CONV_RECVR);
  EXPECT_EQ(b[4].iters, 3);
  EXPECT_EQ(b[6].status, SUN_NLS_CONV_RECVR);
  EXPECT_EQ(b[6].iters, 1);  // g failed at its second call
  EXPECT_EQ(b[8].status, SUN_NLS_CONV_RECVR);
  EXPECT_EQ(b[8].seen_iters.back(), 1);
  SUNNonlinSolFree(theirs);
  SUNNonlinSolFree(ours);
  N_VDestroy(tmpl);
  SUNContext_Free(&ctx);
}

}  // namespace
