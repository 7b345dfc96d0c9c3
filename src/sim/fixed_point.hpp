// CVODE's fixed-point corrector (Adams) as a SUNNonlinearSolver of soadyn's own: SUNDIALS'
// SUNNonlinSol_FixedPoint without Anderson acceleration, iterate for iterate, with its iterates
// alternating between the caller's vector and one of the solver's instead of copied.
//
// SUNDIALS' iteration copies the iterate aside (yprev), evaluates g into gy, copies gy back, and
// forms the change from the copy: three passes over every vector per iteration besides g, on ns + 1
// vectors under CVODES' simultaneous corrector.  Here iteration k evaluates g from one buffer into
// the other and forms the change (one pass); the last iterate is copied into the caller's vector
// only when it lies in the solver's.  Each iterate, change, convergence test, iteration count and
// failure is SUNDIALS' own (tests/sim/test_fixed_point.cpp runs both on the same problems).
#pragma once

#include <sundials/sundials_context.h>
#include <sundials/sundials_nonlinearsolver.h>

namespace soadyn::cvode_impl {

// A fixed-point solver (SUNNONLINEARSOLVER_FIXEDPOINT, at most 3 iterations unless set): for
// CVodeSetNonlinearSolver, and CVodeSetNonlinearSolverSensSim whatever the vectors it is given
// (its two work vectors are clones of the first correction it solves for); nullptr if out of memory.
// SUNNonlinSolFree frees it.
SUNNonlinearSolver make_fixed_point(SUNContext ctx);

}  // namespace soadyn::cvode_impl
