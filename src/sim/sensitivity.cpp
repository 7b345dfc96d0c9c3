// Forward sensitivities by CVODES (sensitivity.hpp): the CVODE integrator of cvode.hpp with
// CVodeSensInit, a sensitivity right-hand side from the analytic derivatives, and the tangent-space
// conversion at both ends.
#include "soadyn/sim/sensitivity.hpp"

#include "soadyn/sim/simulate.hpp"
#include "soadyn/multibody/text.hpp"

#include "cvode.hpp"

#include <Eigen/LU>

#include <algorithm>

namespace soadyn {

namespace {

const char* const kParameterNames[kParametersPerBody] = {"m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz"};
const char* const kParameterUnits[kParametersPerBody] = {"kg", "kg m", "kg m", "kg m", "kg m^2",
                                                         "kg m^2", "kg m^2", "kg m^2", "kg m^2", "kg m^2"};

// "rad/s" → "rad": the unit of a tangent increment of q from the unit of v
std::string without_rate(const std::string& unit) {
  const std::string s = "/s";
  return unit.size() > s.size() && unit.compare(unit.size() - s.size(), s.size(), s) == 0 ? unit.substr(0, unit.size() - s.size())
                                                                                          : unit;
}

using cvode_impl::map;

struct VectorArrayDeleter {
  int n = 0;
  void operator()(N_Vector* v) const { N_VDestroyVectorArray(v, n); }
};
using VectorArrayPtr = std::unique_ptr<N_Vector[], VectorArrayDeleter>;

// CVODE (cvode.hpp) with the sensitivities s_k = ∂y/∂p_k of its state y = [q; v; W; D], in y's own
// coordinates (the quaternions' four), converted to the tangent at the ends
class CvodeSensitivity : public cvode_impl::Cvode, public SensitivitySource {
 public:
  CvodeSensitivity(System& sys, const SimulationSettings& s, const SensitivityPlan& plan, double t0, const VecX& y0)
      // no projection: CVODES projects the state, not its sensitivities; the quaternion is normalized in
      // the dynamics and at every output instead, and its change along itself is no tangent increment
      : Cvode(s.method == Method::CvodeBdf, sys, s, t0, y0, false), plan_(plan), ns_(plan.nx0() + plan.np()) {
    const Model& m = sys.model;
    const int n = sys.size(), nv = sys.nv_state(), nq = sys.nq_state();
    if (ns_ == 0) throw Error("sensitivities: nothing to differentiate (initial_state false, no parameters)");
    if (plan.nx != 2 * nv) throw Error("sensitivities: the plan's state (" + std::to_string(plan.nx) +
                                       ") is not the system's (" + std::to_string(2 * nv) + "): plan it with the prescribed joints");
    sys.prepare_jacobian();
    S_ = MatX::Zero(n, ns_);
    // s(0): a tangent increment of q₀ moves the coordinates by P δ; one of v₀ moves v; π moves nothing
    // (the state's q and v: the free joints' when some are prescribed)
    if (plan.initial_state) {
      S_.block(0, 0, nq, nv) = sys.coordinates_of_tangent(t0, y0.data());
      S_.block(nq, nv, nv, nv).setIdentity();
    }
    S0_ = S_;
    yS_ = VectorArrayPtr(N_VCloneVectorArray(ns_, y_.get()), VectorArrayDeleter{ns_});
    if (!yS_) throw Error("CVODES: could not allocate the sensitivity vectors");
    for (int k = 0; k < ns_; ++k) map(yS_[k]) = S_.col(k);
    void* mem = mem_.get();
    check(CVodeSensInit(mem, ns_, corrector(), &CvodeSensitivity::sensitivity_rhs, yS_.get()), "CVodeSensInit");
    // error control on every sensitivity, scaled by the parameter's size: CVODES tests s_k against
    // rtol and atol / |p̄_k| (CVodeSensEEtolerances), so π_k s_k is held to the state's tolerances
    std::vector<double> pbar(size_t(ns_), 1.0);
    const VecX pi = parameters(m);
    for (size_t b = 0; b < plan.bodies.size(); ++b)
      for (int j = 0; j < kParametersPerBody; ++j) {
        const auto group = [&](int lo, int hi) {  // the largest |π| of the same kind on the body: m c's, I's
          double x = 0;
          for (int k = lo; k < hi; ++k) x = std::max(x, std::abs(pi(kParametersPerBody * plan.bodies[b] + k)));
          return x;
        };
        const double own = std::abs(pi(kParametersPerBody * plan.bodies[b] + j));
        const double scale = own > 0 ? own : j == 0 ? 1.0 : j < 4 ? group(1, 4) : group(4, 10);
        pbar[size_t(plan.nx0()) + b * kParametersPerBody + size_t(j)] = scale > 0 ? scale : 1.0;
      }
    check(CVodeSetSensParams(mem, nullptr, pbar.data(), nullptr), "CVodeSetSensParams");
    check(CVodeSensEEtolerances(mem), "CVodeSensEEtolerances");
    check(CVodeSetSensErrCon(mem, SUNTRUE), "CVodeSetSensErrCon");
    if (!bdf_) {
      // Adams: one fixed-point iteration for the state and its sensitivities together (BDF: CVODES'
      // Newton on I − γJ, the state's linear solver, for the sensitivities after the state)
      nls_sens_.reset(cvode_impl::make_fixed_point(ctx_.get()));
      if (!nls_sens_) throw Error("CVODES: could not allocate the sensitivities' fixed-point solver");
      check(CVodeSetNonlinearSolverSensSim(mem, nls_sens_.get()), "CVodeSetNonlinearSolverSensSim");
    }
    y_out_.reset(N_VClone(y_.get()));
    if (!y_out_) throw Error("CVODES: could not allocate a state vector");
  }

  // the sensitivity memory first, then the solver it uses (the base frees CVODE's memory last)
  ~CvodeSensitivity() override { CVodeSensFree(mem_.get()); }
  CvodeSensitivity(const CvodeSensitivity&) = delete;
  CvodeSensitivity& operator=(const CvodeSensitivity&) = delete;

  void sensitivities(double t, MatX& dx_dx0, MatX& dx_dpi) override {
    const int nq = sys_.nq_state(), nv = sys_.nv_state();
    void* mem = mem_.get();
    long steps = 0;
    check(CVodeGetNumSteps(mem, &steps), "CVodeGetNumSteps");
    if (steps == 0 && before_.steps == 0) {  // the start: what CVodeSensInit was given
      S_ = S0_;
      N_VScale(1.0, y_.get(), y_out_.get());
    } else {
      check(CVodeGetSensDky(mem, t, 0, yS_.get()), "CVodeGetSensDky");
      check(CVodeGetDky(mem, t, 0, y_out_.get()), "CVodeGetDky");
      for (int k = 0; k < ns_; ++k) S_.col(k) = map(yS_[k]);
    }
    // rows to the tangent: δ = T(q) s_q; v's rows as they are
    MatX X(2 * nv, ns_);
    X.bottomRows(nv) = S_.middleRows(nq, nv);
    sys_.tangent_of(t, N_VGetArrayPointer(y_out_.get()), S_.topRows(nq), X.topRows(nv));
    dx_dx0 = X.leftCols(plan_.nx0());
    dx_dpi = X.rightCols(plan_.np());
  }

  void restart(double t, const VecX& y) override {
    if (before_.steps + since_start().steps > 0) {
      check(CVodeGetSensDky(mem_.get(), t, 0, yS_.get()), "CVodeGetSensDky");
    }
    Cvode::restart(t, y);
    check(CVodeSensReInit(mem_.get(), corrector(), yS_.get()), "CVodeSensReInit");
  }

 private:
  // ṡ_k = A s_k + b_k for all k at once, A = ∂f/∂y and b_k = [0; ∂q̈/∂π_k; 0] = [0; −𝓜⁻¹ Y_k; 0]
  // never formed (System::linearize and linearized_times: the products O(N) per column, −Y_k added as
  // a generalized force before 𝓜⁻¹ is applied; Y the regressor's columns of the plan's bodies)
  static int sensitivity_rhs(int ns, double t, N_Vector y, N_Vector, N_Vector* yS, N_Vector* ySdot, void* user,
                             N_Vector, N_Vector) {
    auto* self = static_cast<CvodeSensitivity*>(static_cast<Cvode*>(user));
    try {
      System& sys = self->sys_;
      const Model& m = sys.model;
      // CVODES' vector arrays as the columns of S and Ṡ, in place where each lies in one piece (the
      // pool's clones do, nvector_pool.hpp), else through a copy
      const Eigen::Index n = self->S_.rows();
      const nvector_ops::ColumnBlock in(ns, yS, n, self->s_scratch_), out(ns, ySdot, n, self->sd_scratch_);
      in.load();
      // a call at the state of the last one (the staggered corrector's iterations) keeps its sweeps
      // and Y, and only the products are new
      const long linearization = sys.linearize(t, N_VGetArrayPointer(y));
      const bool parameters = self->plan_.np() > 0;
      if (parameters && linearization != self->y_linearization_) {
        // at the linearization's q̈ (sys.data; the listed bodies' regressor writes their A only, not q̈ or the factor)
        regressor(m, sys.data, sys.data.qdd, self->plan_.bodies, self->Y_);
        self->Y_ = -self->Y_;
        self->y_linearization_ = linearization;
      }
      Eigen::Map<MatX> sd(out.data(), n, ns);
      sys.linearized_times(Eigen::Map<const MatX>(in.data(), n, ns), sd, parameters ? &self->Y_ : nullptr);
      if (!nvector_ops::all_finite(sd.data(), sd.size())) return 1;  // recoverable: CVODES retries with a smaller step
      out.store();
      return 0;
    } catch (...) {
      self->pending_ = std::current_exception();
      return -1;
    }
  }

  // Adams: the simultaneous corrector, whose fixed-point iterations take the state and the
  // sensitivities together (on the humanoid over 1 s, one body's 10 parameters: 6276 steps and 1.58
  // state evaluations a step against the staggered corrector's 6570 and 2.24, 7 % less time); BDF:
  // the staggered one, the sensitivities' Newton iteration after the state's with its factor
  int corrector() const { return bdf_ ? CV_STAGGERED : CV_SIMULTANEOUS; }

  SensitivityPlan plan_;
  int ns_;
  MatX S_, S0_;
  std::vector<double> s_scratch_, sd_scratch_;  // S and Ṡ when CVODES' arrays do not lie in one piece
  MatX Y_;                    // −Y: the regressor's columns of the plan's bodies, negated, at linearization y_linearization_
  long y_linearization_ = 0;  // 0: none yet (linearize numbers from 1)
  VectorArrayPtr yS_;
  cvode_impl::VectorPtr y_out_;
  cvode_impl::NonlinSolPtr nls_sens_;
};

}  // namespace

SensitivityPlan plan_sensitivities(const Model& m, const SensitivitySettings& s, const std::vector<PrescribedInput>& prescribed) {
  SensitivityPlan plan;
  plan.initial_state = s.initial_state;
  // the state's DOFs: the prescribed joints' motion is given, not a state
  std::vector<char> given(size_t(m.nv), 0);
  for (const PrescribedInput& p : prescribed)
    if (p.dof >= 0 && p.dof < m.nv) given[size_t(p.dof)] = 1;
  const int nv_state = m.nv - int(std::count(given.begin(), given.end(), 1));
  plan.nx = 2 * nv_state;
  const bool all = std::find(s.parameters.begin(), s.parameters.end(), "all") != s.parameters.end();
  if (all && s.parameters.size() > 1)
    throw Error("sensitivities: parameters: expected 'all' or a list of body names, not both");
  for (const std::string& name : s.parameters) {
    if (all) break;
    const auto it = std::find(m.body_names.begin(), m.body_names.end(), name);
    if (it == m.body_names.end())
      throw Error("sensitivities: parameters: unknown body '" + excerpt(name) + "'" + did_you_mean(name, m.body_names) +
                  " (bodies after fixed joints are merged)");
    const int b = int(it - m.body_names.begin());
    if (std::find(plan.bodies.begin(), plan.bodies.end(), b) != plan.bodies.end())
      throw Error("sensitivities: parameters: body '" + excerpt(name) + "' is listed twice");
    plan.bodies.push_back(b);
  }
  if (all)
    for (int b = 0; b < m.nbodies; ++b) plan.bodies.push_back(b);
  std::sort(plan.bodies.begin(), plan.bodies.end());
  const std::vector<std::string> vn = m.v_names();
  std::vector<std::string> vu;
  for (int i = 0; i < m.nbodies; ++i)
    for (const auto& u : joint_traits(m.joint_type[i]).v_units) vu.emplace_back(u);
  for (int k = 0; k < m.nv; ++k)
    if (!given[size_t(k)]) plan.state_names.push_back("q." + vn[size_t(k)]), plan.state_units.push_back(without_rate(vu[size_t(k)]));
  for (int k = 0; k < m.nv; ++k)
    if (!given[size_t(k)]) plan.state_names.push_back("qd." + vn[size_t(k)]), plan.state_units.push_back(vu[size_t(k)]);
  for (const int b : plan.bodies)
    for (int j = 0; j < kParametersPerBody; ++j) {
      plan.parameter_names.push_back(m.body_names[size_t(b)] + "." + kParameterNames[j]);
      plan.parameter_units.push_back(kParameterUnits[j]);
    }
  return plan;
}

void check_sensitivities(const Scenario& sc, const SimulationSettings& s, bool has_controller) {
  if (!s.sensitivities.any()) return;
  // at the file's line where the scenario file asks for them, else named with the scenario
  const auto it = sc.locations.find("simulation.sensitivities");
  const std::string why = it != sc.locations.end() ? it->second + ": simulation.sensitivities: "
                          : (sc.path.empty() ? "" : sc.path + ": ") + "sensitivities: ";
  if (is_fixed_step(s.method))
    throw Error(why + "need a CVODE method (cvode-adams or cvode-bdf): " + std::string(to_string(s.method)) +
                " takes fixed steps and its variational equation is not stepped");
  if (has_controller || !sc.inputs.controllers.empty())
    throw Error(why + "a run with a controller (inputs.controllers) is not differentiated (its dtau/dx is not): remove the controller");
  if (s.limits && sc.model.has_limits())
    throw Error(why + "enforced joint limits (simulation.limits: true) are events where the state jumps, not differentiated: "
                "set limits: false");
  plan_sensitivities(sc.model, s.sensitivities, sc.inputs.prescribed);
}

SensitivityIntegrator make_sensitivity_integrator(System& system, const SimulationSettings& settings,
                                                  const SensitivityPlan& plan, double t0, const VecX& y0) {
  if (settings.method != Method::CvodeAdams && settings.method != Method::CvodeBdf)
    throw Error("sensitivities: need cvode-adams or cvode-bdf, got " + std::string(to_string(settings.method)));
  auto p = std::make_unique<CvodeSensitivity>(system, settings, plan, t0, y0);
  SensitivityIntegrator out;
  out.source = p.get();
  out.integrator = std::move(p);
  return out;
}

}  // namespace soadyn
