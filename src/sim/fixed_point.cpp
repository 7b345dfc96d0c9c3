// The fixed-point corrector (fixed_point.hpp).
#include "fixed_point.hpp"

#include <sundials/sundials_nvector.h>

#include <memory>
#include <new>
#include <type_traits>
#include <utility>

namespace soadyn::cvode_impl {

namespace {

// the solver's own vectors, destroyed with its content
struct VectorDeleter {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
using VectorPtr = std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorDeleter>;

struct Content {
  SUNNonlinSolSysFn sys = nullptr;
  SUNNonlinSolConvTestFn ctest = nullptr;
  void* ctest_data = nullptr;
  int maxiters = 3;  // SUNDIALS' default
  int curiter = 0;
  long niters = 0;      // in the last solve, as SUNDIALS counts them (CVODES adds them up)
  long nconvfails = 0;  // likewise
  VectorPtr other;  // the second buffer for the iterates
  VectorPtr delta;  // the change of the last iteration
  N_Vector cloned_from = nullptr;  // the correction vector `other` and `delta` were cloned from
};

Content& content(SUNNonlinearSolver S) { return *static_cast<Content*>(S->content); }

SUNNonlinearSolver_Type get_type(SUNNonlinearSolver) { return SUNNONLINEARSOLVER_FIXEDPOINT; }

int initialize(SUNNonlinearSolver S) {
  Content& c = content(S);
  if (!c.sys || !c.ctest) return SUN_NLS_MEM_NULL;
  c.niters = 0, c.nconvfails = 0;
  return SUN_NLS_SUCCESS;
}

// ycor: the initial iterate on entry (as SUNDIALS 6.4's solver takes it: CVODE sets it, and the
// prediction y0 is not read), the solution on return; w the weights for the test
int solve(SUNNonlinearSolver S, N_Vector, N_Vector ycor, N_Vector w, realtype tol, booleantype, void* mem) {
  Content& c = content(S);
  if (ycor != c.cloned_from) {  // the first solve, or CVODE hands over other vectors: buffers like them
    c.other.reset(N_VClone(ycor));
    c.delta.reset(N_VClone(ycor));
    c.cloned_from = c.other && c.delta ? ycor : nullptr;
    if (!c.cloned_from) return SUN_NLS_MEM_FAIL;
  }
  c.niters = 0, c.nconvfails = 0;
  // iterate k in `cur`, g(cur) into `next`; SUNDIALS' ycor is `next` after each iteration
  N_Vector cur = ycor, next = c.other.get();
  const auto finish = [&](N_Vector last, int status) {
    if (last != ycor) N_VScale(1.0, last, ycor);
    return status;
  };
  for (c.curiter = 0; c.curiter < c.maxiters; ++c.curiter) {
    if (c.sys(cur, next, mem) != 0) break;  // as SUNDIALS: a failed g ends the solve as a convergence failure
    ++c.niters;
    N_VLinearSum(1.0, next, -1.0, cur, c.delta.get());
    const int status = c.ctest(S, next, c.delta.get(), tol, w, c.ctest_data);
    if (status == SUN_NLS_SUCCESS) return finish(next, SUN_NLS_SUCCESS);
    if (status != SUN_NLS_CONTINUE) {
      ++c.nconvfails;
      return finish(next, status);
    }
    std::swap(cur, next);
  }
  ++c.nconvfails;
  return finish(cur, SUN_NLS_CONV_RECVR);
}

int free_solver(SUNNonlinearSolver S) {
  if (!S) return SUN_NLS_SUCCESS;
  delete static_cast<Content*>(S->content);  // its vectors with it
  S->content = nullptr;
  SUNNonlinSolFreeEmpty(S);
  return SUN_NLS_SUCCESS;
}

int set_sys(SUNNonlinearSolver S, SUNNonlinSolSysFn f) {
  if (!f) return SUN_NLS_ILL_INPUT;
  content(S).sys = f;
  return SUN_NLS_SUCCESS;
}

int set_ctest(SUNNonlinearSolver S, SUNNonlinSolConvTestFn f, void* data) {
  if (!f) return SUN_NLS_ILL_INPUT;
  content(S).ctest = f;
  content(S).ctest_data = data;
  return SUN_NLS_SUCCESS;
}

int set_max_iters(SUNNonlinearSolver S, int n) {
  if (n < 1) return SUN_NLS_ILL_INPUT;
  content(S).maxiters = n;
  return SUN_NLS_SUCCESS;
}

int get_num_iters(SUNNonlinearSolver S, long* n) {
  *n = content(S).niters;
  return SUN_NLS_SUCCESS;
}

int get_cur_iter(SUNNonlinearSolver S, int* k) {
  *k = content(S).curiter;
  return SUN_NLS_SUCCESS;
}

int get_num_conv_fails(SUNNonlinearSolver S, long* n) {
  *n = content(S).nconvfails;
  return SUN_NLS_SUCCESS;
}

}  // namespace

SUNNonlinearSolver make_fixed_point(SUNContext ctx) {
  SUNNonlinearSolver S = SUNNonlinSolNewEmpty(ctx);
  if (!S) return nullptr;
  S->content = new (std::nothrow) Content;
  if (!S->content) {
    SUNNonlinSolFreeEmpty(S);
    return nullptr;
  }
  S->ops->gettype = get_type;
  S->ops->initialize = initialize;
  S->ops->solve = solve;
  S->ops->free = free_solver;
  S->ops->setsysfn = set_sys;
  S->ops->setctestfn = set_ctest;
  S->ops->setmaxiters = set_max_iters;
  S->ops->getnumiters = get_num_iters;
  S->ops->getcuriter = get_cur_iter;
  S->ops->getnumconvfails = get_num_conv_fails;
  return S;
}

}  // namespace soadyn::cvode_impl
