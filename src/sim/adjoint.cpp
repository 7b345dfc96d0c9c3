// Gradients of a run's cost by CVODES' adjoint (adjoint.hpp): the CVODE integrator of cvode.hpp run
// forward with checkpoints (CVodeAdjInit, CVodeF), then the adjoint backward (CVodeB) a step at a
// time, the parameter gradient integrated over its steps (step_quadrature.hpp).
#include "soadyn/sim/adjoint.hpp"

#include "soadyn/algorithm/derivatives.hpp"
#include "soadyn/sim/sensitivity.hpp"
#include "soadyn/sim/simulate.hpp"
#include "soadyn/algorithm/table.hpp"
#include "soadyn/multibody/configuration.hpp"

#include "cvode.hpp"
#include "step_quadrature.hpp"

#include <algorithm>


namespace soadyn {

namespace {

using cvode_impl::map;

// CVODE (cvode.hpp) run forward with checkpoints, then its adjoint.  The adjoint's state is
// λ = [λ_q; λ_v] (nq + nv: the quadratures W, D feed nothing back and the cost does not read them).
class CvodeAdjoint : public cvode_impl::Cvode {
 public:
  CvodeAdjoint(System& sys, const SimulationSettings& s, const SensitivityPlan& plan, const Cost& cost, const VecX& y0)
      // no projection: the quaternion is normalized in the dynamics and the adjoint differentiates
      // the coordinates CVODE integrates (as the forward sensitivities do)
      : Cvode(s.method == Method::CvodeBdf, sys, s, 0.0, y0, false),
        settings_(s),
        plan_(plan),
        cost_(cost),
        lin_(sys.model, sys.inputs, FdMethod::ArticulatedBody, sys.control_work),
        nb_(sys.model.nq + sys.model.nv),
        y0q_(y0.head(sys.model.nq)) {
    const Model& m = sys.model;
    lin_.prepare_jacobian();
    mu_ = VecX::Zero(m.nv);
    g_ = VecX::Zero(m.nv);
    dq_ = VecX::Zero(m.nq);
    dv_ = VecX::Zero(m.nv);
    ytmu_ = VecX::Zero(kParametersPerBody * m.nbodies);
  }

  // CVODES' memory (the backward problems with it: CVodeFree frees the adjoint) before the backward
  // problems' solvers, this class's members, and the base's
  ~CvodeAdjoint() override { mem_.reset(); }
  CvodeAdjoint(const CvodeAdjoint&) = delete;
  CvodeAdjoint& operator=(const CvodeAdjoint&) = delete;

  CostGradient run(long steps_per_checkpoint) {
    CostGradient out;
    forward(steps_per_checkpoint, out);
    cvode_impl::VectorPtr yb = terminal_adjoint(out);
    create_backward(yb.get());
    backward(yb.get(), out);
    // ∂G/∂x₀ = [Pᵀ λ_q(0); λ_v(0)]
    if (plan_.initial_state) {
      const Model& m = sys_.model;
      const VecX lam = map(yb.get());
      out.d_initial_state.resize(2 * m.nv);
      out.d_initial_state.head(m.nv) = tangent_to_coordinates(m, y0q_).transpose() * lam.head(m.nq);
      out.d_initial_state.tail(m.nv) = lam.tail(m.nv);
    }
    return out;
  }

 private:
  // forward: y and, when there is a running cost, the quadrature ∫ ℓ dt with error control, with
  // CVODES' checkpoints for the backward run
  void forward(long steps_per_checkpoint, CostGradient& out) {
    void* mem = mem_.get();
    const double T = settings_.t_end;
    cvode_impl::VectorPtr yq;
    if (cost_.running) {
      yq.reset(pool_.make(1, ctx_.get()));
      if (!yq) throw Error("CVODES: could not allocate the cost's quadrature");
      N_VConst(0.0, yq.get());
      check(CVodeQuadInit(mem, &CvodeAdjoint::running_cost, yq.get()), "CVodeQuadInit");
      check(CVodeSetQuadErrCon(mem, SUNTRUE), "CVodeSetQuadErrCon");
      check(CVodeQuadSStolerances(mem, settings_.rtol, settings_.atol), "CVodeQuadSStolerances");
    }
    check(CVodeAdjInit(mem, steps_per_checkpoint > 0 ? steps_per_checkpoint : automatic_steps_per_checkpoint(sys_.size()),
                       CV_HERMITE),
          "CVodeAdjInit");
    check(CVodeSetMaxNumSteps(mem, settings_.max_steps), "CVodeSetMaxNumSteps");
    double t = 0.0;
    int ncheck = 0;
    int flag = CVodeF(mem, T, y_.get(), &t, CV_NORMAL, &ncheck);
    rethrow_pending();
    if (flag < 0) fail(t, cvode_impl::flag_name(flag) + (error_message_.empty() ? "" : ": " + error_message_));
    out.checkpoints = ncheck;
    const IntegratorStats fwd = since_start();
    out.forward_steps = fwd.steps;
    out.forward_rhs_evals = fwd.rhs_evals;
    if (yq) {
      check(CVodeGetQuad(mem, &t, yq.get()), "CVodeGetQuad");
      out.cost = N_VGetArrayPointer(yq.get())[0];
    }
  }

  // λ(T) = (∂Φ/∂y)ᵀ at y(T), the terminal cost added to out.cost
  cvode_impl::VectorPtr terminal_adjoint(CostGradient& out) {
    const Model& m = sys_.model;
    const VecX yT = map(y_.get());
    cvode_impl::VectorPtr yb(pool_.make(nb_, ctx_.get()));
    if (!yb) throw Error("CVODES: could not allocate the adjoint");
    N_VConst(0.0, yb.get());
    if (cost_.terminal) {
      dq_.setZero();
      dv_.setZero();
      out.cost += cost_.terminal(yT.head(m.nq), yT.segment(m.nq, m.nv), dq_, dv_);
      map(yb.get()) << dq_, dv_;
    }
    return yb;
  }

  // the backward problem: λ̇ = −(∂f/∂y)ᵀ λ − (∂ℓ/∂y)ᵀ from T to 0, and q_B = ∫ Yᵀ μ dt so that
  // q_B(0) = ∂G/∂π; Newton with the analytic ∂f/∂y under BDF, fixed point under Adams
  void create_backward(N_Vector yb) {
    void* mem = mem_.get();
    const double T = settings_.t_end;
    check(CVodeCreateB(mem, bdf_ ? CV_BDF : CV_ADAMS, &which_), "CVodeCreateB");
    check(CVodeInitB(mem, which_, &CvodeAdjoint::adjoint_rhs, T, yb), "CVodeInitB");
    check(CVodeSStolerancesB(mem, which_, settings_.rtol, settings_.atol), "CVodeSStolerancesB");
    check(CVodeSetUserDataB(mem, which_, static_cast<Cvode*>(this)), "CVodeSetUserDataB");
    check(CVodeSetMaxNumStepsB(mem, which_, settings_.max_steps), "CVodeSetMaxNumStepsB");
    if (settings_.max_step > 0) check(CVodeSetMaxStepB(mem, which_, settings_.max_step), "CVodeSetMaxStepB");
    if (bdf_) {
      // Newton on I − γ ∂f_B/∂λ with ∂f_B/∂λ = −(∂f/∂y)ᵀ (System::jacobian), CVODE's dense LU
      AB_.reset(SUNDenseMatrix(nb_, nb_, ctx_.get()));
      if (AB_) lsB_.reset(SUNLinSol_Dense(yb, AB_.get(), ctx_.get()));
      if (!AB_ || !lsB_) throw Error("CVODES: could not allocate the adjoint's linear solver");
      check(CVodeSetLinearSolverB(mem, which_, lsB_.get(), AB_.get()), "CVodeSetLinearSolverB");
      check(CVodeSetJacFnB(mem, which_, &CvodeAdjoint::adjoint_jacobian), "CVodeSetJacFnB");
      J_ = MatX::Zero(sys_.size(), sys_.size());
    } else {
      nlsB_.reset(cvode_impl::make_fixed_point(ctx_.get()));
      if (!nlsB_) throw Error("CVODES: could not allocate the adjoint's fixed-point solver");
      check(CVodeSetNonlinearSolverB(mem, which_, nlsB_.get()), "CVodeSetNonlinearSolverB");
    }
  }

  void backward(N_Vector yb, CostGradient& out) {
    void* mem = mem_.get();
    const double T = settings_.t_end;
    double t = T;
    int flag = 0;
    // backward one step at a time, each accepted step's Yᵀμ into ∂G/∂π = ∫_T^0 Yᵀμ dt (q̇_B = Yᵀμ from
    // q_B(T) = 0): by StepQuadrature, not as a CVODES quadrature, whose 10·N numbers would ride through
    // every step's Nordsieck history.  Its rule (degree 5 through the last samples) is below the local
    // error of the λ steps it follows; measured against CVODES' own quadrature in test_adjoint
    const bool parameters = plan_.np() > 0;
    StepQuadrature quadrature(parameters ? plan_.np() : 0);
    cvode_impl::VectorPtr yf(N_VClone(y_.get()));
    if (!yf) throw Error("CVODES: could not allocate a state vector");
    VecX integrand = VecX::Zero(plan_.np());
    // (t, λ(t)) of the backward run just returned, in yb; the forward state at t from CVODES'
    // interpolation, the same the backward right-hand side was given (its derivative sweeps are reused)
    const auto sample = [&](double ts, bool at_end) {
      if (!at_end) check(CVodeGetAdjY(mem, ts, yf.get()), "CVodeGetAdjY");
      parameter_integrand(ts, N_VGetArrayPointer(at_end ? y_.get() : yf.get()), N_VGetArrayPointer(yb), integrand);
      quadrature.add(ts, integrand);
    };
    if (parameters) sample(T, true);  // y(T): CVodeF's last state (no interpolation set up before CVodeB)
    while (t > 0.0) {
      const double before = t;
      flag = CVodeB(mem, 0.0, CV_ONE_STEP);
      rethrow_pending();
      if (flag < 0)
        throw SimulationError("CVODES adjoint failed: " + cvode_impl::flag_name(flag) +
                                  (error_message_.empty() ? "" : ": " + error_message_),
                              t);
      check(CVodeGetB(mem, which_, &t, yb), "CVodeGetB");
      if (!(t < before)) throw SimulationError("CVODES adjoint: the backward run did not advance", t);
      if (parameters) sample(t, false);
    }
    if (parameters) out.d_parameters = quadrature.integral();
    if (void* memB = CVodeGetAdjCVodeBmem(mem, which_)) {
      long steps = 0, evals = 0;
      CVodeGetNumSteps(memB, &steps);
      CVodeGetNumRhsEvals(memB, &evals);
      out.backward_steps = steps;
      out.backward_rhs_evals = evals;
    }
  }

  static CvodeAdjoint& self(void* user) { return *static_cast<CvodeAdjoint*>(static_cast<Cvode*>(user)); }

  // q_Q̇ = ℓ(t, q, v)
  static int running_cost(double t, N_Vector y, N_Vector yqdot, void* user) {
    CvodeAdjoint& a = self(user);
    try {
      const Model& m = a.sys_.model;
      const auto yy = map(y);
      a.dq_.setZero();
      a.dv_.setZero();
      const double l = a.cost_.running(t, yy.head(m.nq), yy.segment(m.nq, m.nv), a.dq_, a.dv_);
      N_VGetArrayPointer(yqdot)[0] = l;
      return std::isfinite(l) ? 0 : 1;
    } catch (...) {
      a.pending_ = std::current_exception();
      return -1;
    }
  }

  // at (t, y): q̈ with the articulated-body factor and the derivative sweeps (System::linearize, kept
  // while (t, y) stays: Newton's iterations, the parameter quadrature); then μ = 𝓜⁻¹ λ_v.  A System of
  // its own: CVODES re-runs the forward problem between checkpoints, through the run's
  void solve_at(double t, const double* y, const double* lam) {
    const Model& m = sys_.model;
    lin_.linearize(t, y);
    mu_ = Eigen::Map<const VecX>(lam + m.nq, m.nv);
    lin_.linearized_solve(Eigen::Map<MatX>(mu_.data(), m.nv, 1));
  }

  // f_B = −(∂f/∂y)ᵀ λ − (∂ℓ/∂y)ᵀ, (∂f/∂y)ᵀ λ by the vector–Jacobian product of the header comment
  static int adjoint_rhs(double t, N_Vector y, N_Vector yB, N_Vector yBdot, void* user) {
    CvodeAdjoint& a = self(user);
    try {
      System& s = a.sys_;
      const Model& m = s.model;
      ++s.rhs_evals;
      const double* yy = N_VGetArrayPointer(y);
      const auto lam = map(yB);
      auto out = map(yBdot);
      a.solve_at(t, yy, N_VGetArrayPointer(yB));
      // g = (∂τ_in/∂x − ∂ID/∂x)ᵀ μ for x = δ (tangent) and x = v, by the O(N) vector products
      auto gv = out.segment(m.nq, m.nv);
      inverse_dynamics_derivatives_transpose_times(m, *a.lin_.derivatives, a.mu_, a.g_, gv);
      a.g_ = -a.g_;
      gv = -gv;
      s.inputs.add_derivatives_transpose_times(a.mu_, a.g_, gv);
      out.head(m.nq).setZero();
      // the q̇(q, v) rows, (∂q̇/∂q)ᵀ λ_q and (∂q̇/∂v)ᵀ λ_q, and the tangent's chain rule Tᵀ g to the coordinates
      add_qdot_jacobian_transpose_times(m, a.lin_.q, a.lin_.v, lam.head(m.nq), out.head(m.nq), out.segment(m.nq, m.nv));
      add_tangent_transpose_times(m, a.lin_.q, a.g_, out.head(m.nq));
      out = -out;
      if (a.cost_.running) {
        a.dq_.setZero();
        a.dv_.setZero();
        a.cost_.running(t, a.lin_.q, a.lin_.v, a.dq_, a.dv_);
        out.head(m.nq) -= a.dq_;
        out.segment(m.nq, m.nv) -= a.dv_;
      }
      return out.allFinite() ? 0 : 1;
    } catch (...) {
      a.pending_ = std::current_exception();
      return -1;
    }
  }

  // q̇_B = −(∂f/∂π)ᵀ λ = Yᵀ μ (∂q̈/∂π = −𝓜⁻¹ Y), the columns of the bodies asked for, at the forward
  // state y and the adjoint λ of time t
  void parameter_integrand(double t, const double* y, const double* lam, VecX& out) {
    solve_at(t, y, lam);
    regressor_transpose_times(sys_.model, lin_.data, lin_.data.qdd, mu_, ytmu_);  // O(N), Y never formed
    for (size_t b = 0; b < plan_.bodies.size(); ++b)
      out.segment(int(b) * kParametersPerBody, kParametersPerBody) =
          ytmu_.segment(kParametersPerBody * plan_.bodies[b], kParametersPerBody);
    if (!out.allFinite()) throw SimulationError("CVODES adjoint: the parameter gradient's integrand is not finite", t);
  }

  // ∂f_B/∂λ = −(∂f/∂y)ᵀ on [q; v] (the quadratures' rows and columns left out)
  static int adjoint_jacobian(double t, N_Vector y, N_Vector, N_Vector, SUNMatrix JB, void* user, N_Vector, N_Vector,
                              N_Vector) {
    CvodeAdjoint& a = self(user);
    try {
      a.sys_.jacobian(t, N_VGetArrayPointer(y), a.J_);
      Eigen::Map<MatX> out(SUNDenseMatrix_Data(JB), a.nb_, a.nb_);
      out = -a.J_.topLeftCorner(a.nb_, a.nb_).transpose();
      return out.allFinite() ? 0 : 1;
    } catch (...) {
      a.pending_ = std::current_exception();
      return -1;
    }
  }

  const SimulationSettings& settings_;
  const SensitivityPlan& plan_;
  const Cost& cost_;
  System lin_;  // the linearization at the forward state of the backward run (solve_at)
  int nb_;
  VecX y0q_;  // the initial coordinates (normalized), for ∂G/∂x₀ along the tangent
  int which_ = -1;
  VecX mu_, g_, dq_, dv_, ytmu_;
  MatX J_;
  cvode_impl::MatrixPtr AB_;
  cvode_impl::LinSolPtr lsB_;
  cvode_impl::NonlinSolPtr nlsB_;
};

}  // namespace

Cost tracking_cost(const Model& m, const VecX& t, const MatX& q, const MatX& v, const TrackingWeights& w) {
  const Eigen::Index n = t.size();
  if (n < 2) throw Error("tracking cost: the reference needs at least 2 samples, got " + std::to_string(n));
  for (Eigen::Index k = 1; k < n; ++k)
    if (!(t(k) > t(k - 1))) throw Error("tracking cost: the reference's times must increase (sample " + std::to_string(k) + ")");
  if (q.rows() != n || q.cols() != m.nq)
    throw Error("tracking cost: q has shape (" + std::to_string(q.rows()) + ", " + std::to_string(q.cols()) + "), expected (" +
                std::to_string(n) + ", " + std::to_string(m.nq) + ")");
  if (v.rows() != n || v.cols() != m.nv)
    throw Error("tracking cost: v has shape (" + std::to_string(v.rows()) + ", " + std::to_string(v.cols()) + "), expected (" +
                std::to_string(n) + ", " + std::to_string(m.nv) + ")");
  const auto weights = [](const VecX& x, int size, const char* what) {
    if (x.size() != 0 && x.size() != size)
      throw Error(std::string("tracking cost: ") + what + " has " + std::to_string(x.size()) + " weights, expected " +
                  std::to_string(size));
    if (!x.allFinite() || (x.size() > 0 && x.minCoeff() < 0))
      throw Error(std::string("tracking cost: ") + what + " weights must be finite and ≥ 0");
  };
  weights(w.q, m.nq, "q"), weights(w.v, m.nv, "v"), weights(w.q_final, m.nq, "q_final"), weights(w.v_final, m.nv, "v_final");
  // the reference: one natural cubic spline per column
  struct Reference {
    std::vector<CubicSpline> q, v;
    std::vector<int> quaternion;  // first coordinate of each quaternion
  };
  auto ref = std::make_shared<Reference>();
  for (int c = 0; c < m.nq; ++c) ref->q.emplace_back(t, q.col(c));
  for (int c = 0; c < m.nv; ++c) ref->v.emplace_back(t, v.col(c));
  for (int i = 0; i < m.nbodies; ++i)
    if (const int o = joint_quaternion(m, i); o >= 0) ref->quaternion.push_back(m.idx_q[i] + o);
  // Σ ½ w (x − x̂)² and its gradient w (x − x̂), x̂ = the reference at t (a quaternion's sign matched to x's)
  const auto term = [ref](double t, const VecX& x, const VecX& wx, bool is_q, Eigen::Ref<VecX> grad) {
    if (wx.size() == 0) return 0.0;
    const auto& splines = is_q ? ref->q : ref->v;
    VecX r(x.size());
    const CubicSpline::Where at = splines[0].where(t);  // every column's spline has the same knots
    for (Eigen::Index c = 0; c < x.size(); ++c) r(c) = splines[size_t(c)].value(t, at);
    if (is_q)
      for (const int k : ref->quaternion)
        if (r.segment<4>(k).dot(x.segment<4>(k)) < 0) r.segment<4>(k) = -r.segment<4>(k);
    const VecX e = x - r;
    grad += wx.cwiseProduct(e);
    return 0.5 * e.dot(wx.cwiseProduct(e));
  };
  Cost cost;
  if (w.q.size() + w.v.size() > 0)
    cost.running = [term, w](double t, const VecX& q, const VecX& v, Eigen::Ref<VecX> dq, Eigen::Ref<VecX> dv) {
      return term(t, q, w.q, true, dq) + term(t, v, w.v, false, dv);
    };
  if (w.q_final.size() + w.v_final.size() > 0) {
    const double t_last = t(n - 1);
    cost.terminal = [term, w, t_last](const VecX& q, const VecX& v, Eigen::Ref<VecX> dq, Eigen::Ref<VecX> dv) {
      return term(t_last, q, w.q_final, true, dq) + term(t_last, v, w.v_final, false, dv);
    };
  }
  return cost;
}

// 50 steps per entry of the state, from 500 to 10000.  CVODES sets up all Nd + 1 interpolation
// points of an interval before the first step (two allocations each, and two vectors from the pool:
// ~0.1 µs a point), and integrates every interval but the last forward a second time during the
// backward run.  A step costs about in proportion to the state's size, so the set-up stays a small
// share of the run's steps while a longer interval spares the second pass: a 7-DOF arm checkpoints
// every 700 steps, the 50-DOF humanoid every 5000.  Memory: at most Nd · 2n doubles per interval,
// reserved up front and touched as the steps fill it (nvector_pool.hpp)
long automatic_steps_per_checkpoint(int n) { return std::clamp(50L * n, 500L, 10000L); }

CostGradient gradient(const Scenario& sc, const SimulationSettings& settings, const Cost& cost,
                      const SensitivitySettings& wrt, long steps_per_checkpoint) {
  const Model& m = sc.model;
  if (steps_per_checkpoint < 0)
    throw Error("gradient: steps_per_checkpoint: expected a number of steps, or 0 to choose it from the state's size; got " +
                std::to_string(steps_per_checkpoint));
  SimulationSettings s = settings;
  s.sensitivities = wrt;
  check_run(sc, s);
  if (!wrt.any()) throw Error("gradient: nothing to differentiate (initial_state false, no parameters)");
  check_sensitivities(sc, s, false);
  if (!sc.inputs.prescribed.empty())
    throw Error((sc.path.empty() ? "" : sc.path + ": ") + "gradient: the adjoint does not take prescribed motion yet; "
                "use the forward sensitivities (simulation.sensitivities), which do");
  if (!cost.running && !cost.terminal) throw Error("gradient: the cost has neither a running nor a terminal part");
  const SensitivityPlan plan = plan_sensitivities(m, wrt);
  System sys(m, sc.inputs, s.dynamics);
  VecX y = sys.state(sc.q0, sc.v0);
  m.normalize(y.head(m.nq));
  const double cpu0 = thread_cpu_seconds();
  CvodeAdjoint adjoint(sys, s, plan, cost, y);
  CostGradient out = adjoint.run(steps_per_checkpoint);
  out.cpu_seconds = thread_cpu_seconds() - cpu0;
  if (plan.initial_state) out.state_names = plan.state_names;
  out.parameter_names = plan.parameter_names;
  return out;
}

}  // namespace soadyn
