// CVODE behind the Integrator interface: the linear solver and the factory (the class: cvode.hpp).
#include "cvode.hpp"

namespace soadyn {

namespace cvode_impl {

// CVODE's name for a return flag (it allocates the string with malloc: freed here)
std::string flag_name(int flag) {
  char* name = CVodeGetReturnFlagName(flag);
  std::string out = name ? name : "flag " + std::to_string(flag);
  std::free(name);
  return out;
}

namespace linsol {
namespace {
SUNLinearSolver_Type type(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
SUNLinearSolver_ID id(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }
int setup(SUNLinearSolver S, SUNMatrix) {
  // a singular I − γJ is recoverable: CVODE retries with a smaller step
  return content(S).solver.factor(content(S).gamma) ? SUNLS_SUCCESS : SUNLS_LUFACT_FAIL;
}
int solve(SUNLinearSolver S, SUNMatrix, N_Vector x, N_Vector b, realtype) {
  content(S).solver.solve(map(b), map(x));
  return SUNLS_SUCCESS;
}
int free(SUNLinearSolver S) {
  if (!S) return SUNLS_SUCCESS;
  delete static_cast<Content*>(S->content);
  S->content = nullptr;
  SUNLinSolFreeEmpty(S);
  return SUNLS_SUCCESS;
}
}  // namespace

SUNLinearSolver make(const System& sys, SUNContext ctx) {
  auto c = std::make_unique<Content>(Content{NewtonSolver(sys)});
  SUNLinearSolver S = SUNLinSolNewEmpty(ctx);
  if (!S) return nullptr;
  S->ops->gettype = type;
  S->ops->getid = id;
  S->ops->setup = setup;
  S->ops->solve = solve;
  S->ops->free = free;
  S->content = c.release();
  return S;
}
}  // namespace linsol

}  // namespace cvode_impl

std::unique_ptr<Integrator> make_cvode(bool bdf, System& system, const SimulationSettings& settings, double t0,
                                       const VecX& y0) {
  return std::make_unique<cvode_impl::Cvode>(bdf, system, settings, t0, y0);
}

}  // namespace soadyn
