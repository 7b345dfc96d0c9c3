// CVODE behind the Integrator interface (cvode.cpp), and what builds on it (sensitivity.cpp: CVODES'
// forward sensitivities).  Every SUNDIALS handle has a move-only owner; no C++ exception crosses a C
// callback (it is stored and rethrown after CVode returns); SUNDIALS error messages become soadyn
// errors.  The library is SUNDIALS' CVODES, CVODE's superset with the same calls.  Internal.
#pragma once

#include "soadyn/sim/integrators.hpp"
#include "soadyn/sim/newton_solver.hpp"
#include "soadyn/multibody/configuration.hpp"

#include "fixed_point.hpp"
#include "nvector_ops.hpp"
#include "nvector_pool.hpp"

#include <cvodes/cvodes.h>
#include <cvodes/cvodes_proj.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace soadyn::cvode_impl {

// CVODE's name for a return flag
std::string flag_name(int flag);


// move-only owners of SUNDIALS handles
struct ContextDeleter {
  void operator()(SUNContext c) const { SUNContext_Free(&c); }
};
struct VectorDeleter {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
struct MatrixDeleter {
  void operator()(SUNMatrix m) const { SUNMatDestroy(m); }
};
struct LinSolDeleter {
  void operator()(SUNLinearSolver s) const { SUNLinSolFree(s); }
};
struct NonlinSolDeleter {
  void operator()(SUNNonlinearSolver s) const { SUNNonlinSolFree(s); }
};
struct CvodeDeleter {
  void operator()(void* mem) const { CVodeFree(&mem); }
};
using ContextPtr = std::unique_ptr<std::remove_pointer_t<SUNContext>, ContextDeleter>;
using VectorPtr = std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorDeleter>;
using MatrixPtr = std::unique_ptr<std::remove_pointer_t<SUNMatrix>, MatrixDeleter>;
using LinSolPtr = std::unique_ptr<std::remove_pointer_t<SUNLinearSolver>, LinSolDeleter>;
using NonlinSolPtr = std::unique_ptr<std::remove_pointer_t<SUNNonlinearSolver>, NonlinSolDeleter>;
using CvodePtr = std::unique_ptr<void, CvodeDeleter>;

inline Eigen::Map<VecX> map(N_Vector v) { return {N_VGetArrayPointer(v), N_VGetLength(v)}; }

// CVODE's linear solver for the analytic Jacobian: a direct SUNLinearSolver (SUNDIALS' generic
// API) around NewtonSolver, its content (deleted by its free).  CVODE's matrix holds J itself:
// the linear-system function (Cvode::linear_system) evaluates it when CVODE asks for a new one and
// records γ; setup factors I − γJ by its structure, solve applies the factors (cvode.cpp).
namespace linsol {
struct Content {
  NewtonSolver solver;
  double gamma = 0.0;
};
inline Content& content(SUNLinearSolver S) { return *static_cast<Content*>(S->content); }
SUNLinearSolver make(const System& sys, SUNContext ctx);
}  // namespace linsol

class Cvode : public Integrator {
 public:
  // project: keep a free root's quaternion unit by CVODE's projection where it can (BDF)
  Cvode(bool bdf, System& sys, const SimulationSettings& s, double t0, const VecX& y0, bool project = true)
      : sys_(sys), bdf_(bdf), max_steps_(s.max_steps), rtol_(s.rtol), atol_(s.atol) {
    locates_events_ = true;
    SUNContext ctx = nullptr;
    check(SUNContext_Create(nullptr, &ctx), "SUNContext_Create");
    ctx_.reset(ctx);
    // fused vector operations (one pass over memory for CVODE's linear combinations, and for all the
    // sensitivities at once in CVODES), compiled (nvector_ops.hpp); every vector cloned from y_
    // inherits them and comes from the pool (nvector_pool.hpp)
    y_.reset(pool_.make(sys.size(), ctx_.get()));
    if (!y_) throw Error("CVODE: could not allocate the state vector");
    map(y_.get()) = y0;
    mem_.reset(CVodeCreate(bdf ? CV_BDF : CV_ADAMS, ctx_.get()));
    if (!mem_) throw Error("CVODE: CVodeCreate failed");
    void* mem = mem_.get();
    check(CVodeSetErrHandlerFn(mem, &Cvode::on_error, this), "CVodeSetErrHandlerFn");
    check(CVodeInit(mem, &Cvode::rhs, t0, y_.get()), "CVodeInit");
    check(CVodeSetUserData(mem, this), "CVodeSetUserData");
    // rtol and atol (scalars, atol > 0) as CVodeSStolerances would take them, the weights in one pass
    check(CVodeWFtolerances(mem, &Cvode::error_weights), "CVodeWFtolerances");
    if (s.max_step > 0) check(CVodeSetMaxStep(mem, s.max_step), "CVodeSetMaxStep");
    if (bdf) {
      // stiff: Newton iterations with a direct solver.  Analytic: the Jacobian from System::jacobian
      // and M = I − γJ solved by its structure (NewtonSolver: an nv×nv LU).  DQ: CVODE's
      // difference-quotient Jacobian and its dense LU of M
      const bool analytic = s.jacobian == Jacobian::Analytic;
      if (analytic) sys.prepare_jacobian();
      A_.reset(SUNDenseMatrix(sys.size(), sys.size(), ctx_.get()));
      if (A_) ls_.reset(analytic ? linsol::make(sys, ctx_.get()) : SUNLinSol_Dense(y_.get(), A_.get(), ctx_.get()));
      if (!A_ || !ls_) throw Error("CVODE: could not allocate the linear solver");
      check(CVodeSetLinearSolver(mem, ls_.get(), A_.get()), "CVodeSetLinearSolver");
      if (analytic) check(CVodeSetLinSysFn(mem, &Cvode::linear_system), "CVodeSetLinSysFn");
    } else {
      // non-stiff: fixed-point (functional) iterations, no Jacobian (fixed_point.hpp)
      nls_.reset(make_fixed_point(ctx_.get()));
      if (!nls_) throw Error("CVODE: could not allocate the fixed-point solver");
      check(CVodeSetNonlinearSolver(mem, nls_.get()), "CVodeSetNonlinearSolver");
    }
    if (project && (!sys.quaternions().empty() || sys.has_loops())) {
      projection_ = CVodeSetProjFn(mem, &Cvode::project) == CV_SUCCESS;
      error_message_.clear();
    }
  }

  IntegratorStats stats() const override {
    IntegratorStats s = since_start();
    s.steps += before_.steps;
    s.rhs_evals += before_.rhs_evals;
    s.jac_evals += before_.jac_evals;
    s.error_test_failures += before_.error_test_failures;
    s.nonlinear_iterations += before_.nonlinear_iterations;
    return s;
  }

  // CVODE's counters since its last (re)initialization
  IntegratorStats since_start() const {
    IntegratorStats s;
    void* mem = mem_.get();
    // every counter read is checked: a failed read would report a stale or zero count
    auto read = [&](int (*get)(void*, long*), const char* name) {
      long v = 0;
      if (const int flag = get(mem, &v); flag < 0)
        throw Error(std::string("CVODE: ") + name + " failed (" + CVodeGetReturnFlagName(flag) + ")");
      return v;
    };
    s.steps = read(CVodeGetNumSteps, "CVodeGetNumSteps");
    s.rhs_evals = read(CVodeGetNumRhsEvals, "CVodeGetNumRhsEvals");
    s.error_test_failures = read(CVodeGetNumErrTestFails, "CVodeGetNumErrTestFails");
    s.nonlinear_iterations = read(CVodeGetNumNonlinSolvIters, "CVodeGetNumNonlinSolvIters");
    if (bdf_) {
      s.jac_evals = read(CVodeGetNumJacEvals, "CVodeGetNumJacEvals");
      // difference-quotient Jacobian evaluations of f
      s.rhs_evals += read(CVodeGetNumLinRhsEvals, "CVodeGetNumLinRhsEvals");
    }
    return s;
  }

  // CVODE anew from (t, y): order 1 and a fresh step-size search, as after a discontinuity
  void restart(double t, const VecX& y) override {
    before_ = stats();  // CVodeReInit zeroes CVODE's counters: the run's go on from here
    map(y_.get()) = y;
    check(CVodeReInit(mem_.get(), t, y_.get()), "CVodeReInit");
  }

  std::string quaternion_handling() const override {
    if (sys_.quaternions().empty()) return "none";
    return projection_ ? "CVODE projection (CVodeSetProjFn) onto the unit quaternion"
                       : "normalized in the dynamics and at every output (CVODE projection needs BDF)";
  }

 protected:
  bool step_to(double t_out, double& t, VecX& y) override {
    void* mem = mem_.get();
    // CVODE's own CV_NORMAL, one internal step at a time so that a stop request is seen before
    // every step: step until t_n ≥ t_out, then interpolate y(t_out) from the Nordsieck history.
    double tn = t;
    check(CVodeGetCurrentTime(mem, &tn), "CVodeGetCurrentTime");
    watch_roots();
    int flag = CV_SUCCESS;
    // no step past t_out when a restart follows there (a control tick) or a root may lie beyond it
    if (((schedule_ && schedule_->exact_stops()) || nroots_ > 0) && tn < t_out) check(CVodeSetStopTime(mem, t_out), "CVodeSetStopTime");
    while (tn < t_out) {
      if (stop_requested()) {  // y_ holds y(t_n), the last step's state
        take_state(tn, t, y);
        return false;
      }
      long steps = 0;  // one counter, not the whole stats() set, on every step
      check(CVodeGetNumSteps(mem, &steps), "CVodeGetNumSteps");
      steps += before_.steps;
      if (steps >= max_steps_) fail(tn, "reached the maximum number of steps (" + std::to_string(max_steps_) + ")");
      flag = CVode(mem, t_out, y_.get(), &tn, CV_ONE_STEP);
      rethrow_pending();
      if (flag < 0) break;
      if (flag == CV_ROOT_RETURN) {  // y_ holds y(t_root): the schedule acts, the caller restarts here
        take_state(tn, t, y);
        schedule_->at_roots(t, y, found_roots());
        return true;
      }
    }
    if (flag >= 0) {
      flag = CVodeGetDky(mem, t_out, 0, y_.get());
      tn = t_out;
    }
    take_state(tn, t, y);
    if (flag < 0) {
      std::string why = flag_name(flag);
      if (!error_message_.empty()) why += ": " + error_message_;
      fail(t, why);
    }
    // loops without CVODE's projection (Adams): the output projected onto the manifold, and CVODE
    // restarted there once its state has drifted from it by more than 100 atol
    if (!projection_ && sys_.has_loops() && first_non_finite(y) < 0) {
      projected_ = y;
      if (sys_.project(projected_)) {
        const bool drifted = (projected_ - y).cwiseAbs().maxCoeff() > 100 * atol_;
        y = projected_;
        if (drifted) restart(t, y);
      }
    }
    if (const int bad = first_non_finite(y); bad >= 0) {
      char at[32];
      std::snprintf(at, sizeof at, "%.9g", t);
      throw SimulationError(std::string("unstable at t = ") + at + " s: " + sys_.component_name(bad) + " is not finite", t);
    }
    return false;
  }

  // (t, y) ← (t_n, y_), the quaternions normalized where CVODE does not project them
  void take_state(double tn, double& t, VecX& y) const {
    t = tn;
    y = map(y_.get());
    if (!projection_) sys_.normalize(y.head(sys_.nq_state()));
  }

  // the schedule's root functions, registered with CVODE once (CVodeRootInit): only crossings from
  // g > 0 to g < 0
  void watch_roots() {
    if (!schedule_ || rooted_ == schedule_) return;
    rooted_ = schedule_;
    nroots_ = schedule_->root_count();
    if (nroots_ == 0) return;
    check(CVodeRootInit(mem_.get(), nroots_, &Cvode::root), "CVodeRootInit");
    std::vector<int> down(size_t(nroots_), -1);
    check(CVodeSetRootDirection(mem_.get(), down.data()), "CVodeSetRootDirection");
  }

  // the indices of the root functions CVODE found at its last return
  const std::vector<int>& found_roots() {
    std::vector<int> found(size_t(nroots_), 0);
    check(CVodeGetRootInfo(mem_.get(), found.data()), "CVodeGetRootInfo");
    roots_.clear();
    for (int i = 0; i < nroots_; ++i)
      if (found[size_t(i)] != 0) roots_.push_back(i);
    return roots_;
  }

  // the exception a callback stored (no C++ exception crosses SUNDIALS' C frames), thrown here
  void rethrow_pending() {
    if (pending_) {
      auto e = pending_;
      pending_ = nullptr;
      std::rethrow_exception(e);
    }
  }

  static int rhs(double t, N_Vector y, N_Vector ydot, void* user) {
    auto* self = static_cast<Cvode*>(user);
    try {
      self->sys_.rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
      // a non-finite derivative is recoverable: CVODE retries with a smaller step
      return nvector_ops::all_finite(N_VGetArrayPointer(ydot), N_VGetLength(ydot)) ? 0 : 1;
    } catch (...) {
      self->pending_ = std::current_exception();
      return -1;
    }
  }

  // CVODE's error weights 1/(rtol·|y| + atol) (nvector_ops::error_weights); CVODES calls it on
  // p̄_k s_k for the sensitivities too
  static int error_weights(N_Vector y, N_Vector w, void* user) {
    const auto* self = static_cast<const Cvode*>(user);
    nvector_ops::error_weights(self->rtol_, self->atol_, y, w);
    return 0;
  }

  static int root(double t, N_Vector y, double* g, void* user) {
    auto* self = static_cast<Cvode*>(user);
    try {
      self->schedule_->roots(t, N_VGetArrayPointer(y), g);
      return 0;
    } catch (...) {
      self->pending_ = std::current_exception();
      return -1;
    }
  }

  // CVODE's linear system I − γJ for the analytic Jacobian: J = ∂f/∂y (System::jacobian) into
  // CVODE's dense (column-major) matrix and the solver when CVODE asks for a new one (jok false),
  // else the one it holds; γ for the solver's setup
  static int linear_system(double t, N_Vector y, N_Vector, SUNMatrix A, sunbooleantype jok, sunbooleantype* jcur,
                           double gamma, void* user, N_Vector, N_Vector, N_Vector) {
    auto* self = static_cast<Cvode*>(user);
    try {
      linsol::Content& ls = linsol::content(self->ls_.get());
      ls.gamma = gamma;
      *jcur = jok ? SUNFALSE : SUNTRUE;
      if (jok) return 0;
      const sunindextype n = SUNDenseMatrix_Rows(A);
      Eigen::Map<MatX> J(SUNDenseMatrix_Data(A), n, n);
      self->sys_.jacobian(t, N_VGetArrayPointer(y), J);
      if (!J.allFinite()) return 1;  // recoverable: CVODE retries with a smaller step
      ls.solver.set_jacobian(J);
      return 0;
    } catch (...) {
      self->pending_ = std::current_exception();
      return -1;
    }
  }

  // unit quaternions: corr = normalized − current; the error's component along the quaternion
  // removed.  With loops, corr = System::project's − current (q onto the closure, v onto K v = 0),
  // and the error's components across the loops' manifold removed too
  static int project(double, N_Vector ycur, N_Vector corr, double, N_Vector err, void* user) {
    auto* self = static_cast<Cvode*>(user);
    auto y = map(ycur);
    auto c = map(corr);
    c.setZero();
    if (self->sys_.has_loops()) {
      self->projected_ = y;
      if (!self->sys_.project(self->projected_)) return 1;  // recoverable: CVODE retries with a smaller step
      c = self->projected_ - y;
      if (err) self->sys_.project_error(map(err));
    }
    for (const int k : self->sys_.quaternions()) {
      const Eigen::Vector4d quat = y.segment<4>(k);
      const double n = quat.norm();
      if (!(n > 0) || !std::isfinite(n)) return 1;
      if (!self->sys_.has_loops()) c.segment<4>(k) = quat / n - quat;
      if (err) {
        auto e = map(err);
        const Eigen::Vector4d u = quat / n;
        e.segment<4>(k) -= u.dot(e.segment<4>(k)) * u;
      }
    }
    return 0;
  }

  static void on_error(int code, const char* module, const char* function, char* msg, void* user) {
    auto* self = static_cast<Cvode*>(user);
    if (code < 0) self->error_message_ = std::string(module) + "::" + function + ": " + msg;
  }

  void check(int flag, const char* call) {
    if (flag < 0)
      throw Error(std::string("CVODE: ") + call + " failed (" + std::to_string(flag) + ")" +
                  (error_message_.empty() ? "" : ": " + error_message_));
  }

  // "failed at t = …: why; worst DOF: the largest weighted local error"
  [[noreturn]] void fail(double t, const std::string& why) {
    std::ostringstream os;
    os << "CVODE " << (bdf_ ? "BDF" : "Adams") << " failed at t = " << t << " s: " << why;
    VectorPtr w(N_VClone(y_.get())), e(N_VClone(y_.get()));
    if (w && e && CVodeGetErrWeights(mem_.get(), w.get()) == CV_SUCCESS &&
        CVodeGetEstLocalErrors(mem_.get(), e.get()) == CV_SUCCESS) {
      const VecX weighted = (map(w.get()).array() * map(e.get()).array()).abs();
      Eigen::Index worst = 0;
      if (weighted.allFinite() && weighted.maxCoeff(&worst) > 0)
        os << "; worst DOF: " << sys_.component_name(int(worst)) << " (weighted local error " << weighted(worst) << ")";
    }
    if (const int bad = first_non_finite(map(y_.get())); bad >= 0) os << "; " << sys_.component_name(bad) << " is not finite";
    throw SimulationError(os.str(), t);
  }

  System& sys_;
  bool bdf_;
  long max_steps_;
  double rtol_, atol_;
  bool projection_ = false;
  VecX projected_;  // project's: the state projected onto the loops' manifold
  IntegratorStats before_;  // the counters of the run before the last restart
  const Schedule* rooted_ = nullptr;  // the schedule whose roots CVODE watches (nroots_ of them)
  int nroots_ = 0;
  std::vector<int> roots_;            // those found at the last root return
  std::exception_ptr pending_;
  std::string error_message_;
  // declared in creation order, destroyed in reverse: the CVODE memory before what it uses, every
  // vector (a derived class's too) before the pool
  ContextPtr ctx_;
  nvector_ops::VectorPool pool_;
  VectorPtr y_;
  MatrixPtr A_;
  LinSolPtr ls_;
  NonlinSolPtr nls_;
  CvodePtr mem_;
};


}  // namespace soadyn::cvode_impl
