// Inertial-parameter identification (identify.hpp): the stacked regressor's least squares, or
// Gauss–Newton on the trajectory with CVODES sensitivities; both solved by the same rank-revealing,
// column-scaled SVD step.
#include "soadyn/sim/identify.hpp"

#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/algorithm/regressor.hpp"
#include "soadyn/sim/sensitivity.hpp"
#include "soadyn/sim/simulate.hpp"
#include "soadyn/multibody/text.hpp"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace soadyn {

namespace {

// One minimum-norm step of A δ = b, column-scaled, rank-truncated (identify.hpp)
struct Step {
  VecX delta, standard_error, singular_values;
  MatX null_space;  // π coordinates, one direction per column
  int rank = 0;
  double sigma2 = 0.0, rms_before = 0.0, rms_after = 0.0;
};

// rows of the null-space basis brought to reduced row-echelon form (pivot on the largest entry),
// so a parameter the data cannot see alone is its own direction
MatX echelon(MatX N) {
  const Eigen::Index k = N.cols(), n = N.rows();
  MatX B = N.transpose();  // k × n
  Eigen::Index row = 0;
  for (Eigen::Index col = 0; col < n && row < k; ++col) {
    Eigen::Index piv;
    const double big = B.col(col).tail(k - row).cwiseAbs().maxCoeff(&piv);
    if (big < 1e-10) continue;
    B.row(row).swap(B.row(row + piv));
    B.row(row) /= B(row, col);
    for (Eigen::Index r = 0; r < k; ++r)
      if (r != row) B.row(r) -= B(r, col) * B.row(row);
    ++row;
  }
  return B.transpose();
}

// mu > 0: the Levenberg–Marquardt step (AᵀA + mu σ_max² D²)⁻¹ Aᵀ b instead (Gauss–Newton's damping)
Step solve(const MatX& A, const VecX& b, double tolerance, double mu = 0.0) {
  Step s;
  const Eigen::Index n = A.cols(), m = A.rows();
  // D: the columns' norms, so that kg and kg m² weigh alike; a column below 1e-12 of the largest
  // is round-off of a parameter that does not act (its exact value is 0): zero, with D = 1
  VecX D = A.colwise().norm().transpose();
  const double floor = 1e-12 * (n > 0 ? D.maxCoeff() : 0.0);
  MatX As = A;
  for (Eigen::Index j = 0; j < n; ++j) {
    if (D(j) > floor && D(j) > 0) continue;
    D(j) = 1.0;
    As.col(j).setZero();
  }
  As = As * D.cwiseInverse().asDiagonal();
  const Eigen::JacobiSVD<MatX> svd(As, Eigen::ComputeThinU | Eigen::ComputeThinV);
  s.singular_values = svd.singularValues();
  const double top = n > 0 ? s.singular_values(0) : 0.0;
  while (s.rank < n && s.singular_values(s.rank) > tolerance * top) ++s.rank;
  const int r = s.rank;
  const auto U = svd.matrixU().leftCols(r);
  const auto V = svd.matrixV().leftCols(r);
  const VecX inv = s.singular_values.head(r).cwiseInverse();
  // δ = D⁻¹ V_r Σ_r⁻¹ U_rᵀ b: no component along the null space, held at the prior (damped:
  // σ_k / (σ_k² + mu σ_max²) for 1 / σ_k)
  const VecX gain = mu > 0 ? VecX(s.singular_values.head(r).array() /
                                  (s.singular_values.head(r).array().square() + mu * top * top))
                           : inv;
  s.delta = D.cwiseInverse().asDiagonal() * (V * (gain.asDiagonal() * (U.transpose() * b)));
  const VecX res = b - As * (D.asDiagonal() * s.delta);
  s.rms_before = m ? std::sqrt(b.squaredNorm() / double(m)) : 0.0;
  s.rms_after = m ? std::sqrt(res.squaredNorm() / double(m)) : 0.0;
  // σ̂² = |b − A δ|² / (m − r), cov = σ̂² D⁻¹ V_r Σ_r⁻² V_rᵀ D⁻¹
  s.sigma2 = m > r ? res.squaredNorm() / double(m - r) : 0.0;
  const MatX W = D.cwiseInverse().asDiagonal() * (V * inv.asDiagonal());
  s.standard_error = (s.sigma2 * W.rowwise().squaredNorm()).cwiseSqrt();
  // A x = 0 ⇔ (A D⁻¹)(D x) = 0: the null space in π's coordinates, largest entry 1
  MatX N = echelon(svd.matrixV().rightCols(n - r));
  N = D.cwiseInverse().asDiagonal() * N;
  for (Eigen::Index c = 0; c < N.cols(); ++c) {
    Eigen::Index at;
    N.col(c).cwiseAbs().maxCoeff(&at);
    N.col(c) /= N(at, c);
    for (Eigen::Index j = 0; j < n; ++j)
      if (std::abs(N(j, c)) < 1e-12) N(j, c) = 0.0;
  }
  s.null_space = N;
  return s;
}

// π⁰ with the fitted bodies' entries replaced by x
VecX full_parameters(const VecX& prior, const std::vector<int>& bodies, const VecX& x) {
  VecX pi = prior;
  for (size_t k = 0; k < bodies.size(); ++k)
    pi.segment<kParametersPerBody>(kParametersPerBody * bodies[k]) = x.segment<kParametersPerBody>(kParametersPerBody * Eigen::Index(k));
  return pi;
}

// A δ = b of least squares: A the fitted bodies' columns of Y, b = τ − Y π⁰
void stack_regressor(const Scenario& sc, const Measurements& d, const std::vector<int>& bodies, MatX& A, VecX& b) {
  const Model& m = sc.model;
  const Eigen::Index T = d.t.size(), np = kParametersPerBody * Eigen::Index(bodies.size());
  const VecX pi = parameters(m);
  A.resize(T * m.nv, np);
  b.resize(T * m.nv);
  Data data(m);
  MatX Y;
  VecX q(m.nq), v(m.nv), qdd(m.nv), tau(m.nv);
  for (Eigen::Index k = 0; k < T; ++k) {
    q = d.q.row(k).transpose();
    v = d.v.row(k).transpose();
    qdd = d.qdd.row(k).transpose();
    update_kinematics(m, data, q);
    update_velocities(m, data, v);
    regressor(m, data, qdd, Y);
    if (d.tau.size()) tau = d.tau.row(k).transpose();
    else sc.inputs.evaluate(d.t(k), q, v, tau);
    for (size_t j = 0; j < bodies.size(); ++j)
      A.block(k * m.nv, kParametersPerBody * Eigen::Index(j), m.nv, kParametersPerBody) =
          Y.middleCols(kParametersPerBody * bodies[j], kParametersPerBody);
    b.segment(k * m.nv, m.nv) = tau - Y * pi;
  }
}

// the scene run over each window of W samples from the data's state at the window's start (the
// inputs' sines shifted to its time), with parameters π: the residual [q_k − q(t_k); v_k − v(t_k)]
// of every sample after a window's first, and its Jacobian ∂x(t_k)/∂π_S
void trajectory_residual(const Scenario& sc, const Measurements& d, const std::vector<std::string>& names,
                         const VecX& pi, Eigen::Index W, VecX& r, MatX& J) {
  Scenario run = sc;
  run.model = with_parameters(sc.model, pi);
  SimulationSettings settings = sc.simulation;
  const Eigen::Index T = d.t.size();
  const double dt = d.t(1) - d.t(0);
  settings.output_dt = dt;
  settings.sensitivities = {false, names};
  const int nv = sc.model.nv, nx = 2 * nv;
  const Eigen::Index rows = (T - 1) * nx;
  r.resize(rows);
  J.resize(rows, kParametersPerBody * Eigen::Index(names.size()));
  std::vector<Sample> samples;
  for (Eigen::Index k0 = 0; k0 + 1 < T; k0 += W) {
    const Eigen::Index n = std::min(W, T - 1 - k0);  // samples after the window's first
    run.q0 = d.q.row(k0).transpose();
    run.v0 = d.v.row(k0).transpose();
    for (size_t u = 0; u < run.inputs.torques.size(); ++u)  // sin(2π f (t0 + s) + φ)
      run.inputs.torques[u].phase = sc.inputs.torques[u].phase + 2.0 * std::numbers::pi * sc.inputs.torques[u].frequency * d.t(k0);
    settings.t_end = double(n) * dt;
    samples.clear();
    const RunSummary summary = simulate(run, settings, nullptr, &samples);
    if (!summary.completed || Eigen::Index(samples.size()) < n + 1)
      throw Error("identify: gauss-newton: the scene with the current parameters did not run from t = " + short_number(d.t(k0)) +
                  " to " + short_number(d.t(k0 + n)) + " (" + summary.status + ")");
    for (Eigen::Index j = 1; j <= n; ++j) {
      const Sample& s = samples[size_t(j)];
      const Eigen::Index k = k0 + j, at = (k - 1) * nx;
      r.segment(at, nv) = d.q.row(k).transpose() - s.q;
      r.segment(at + nv, nv) = d.v.row(k).transpose() - s.qd;
      J.middleRows(at, nx) = s.sensitivity_parameters;
    }
  }
}

void check_measurements(const Model& m, const Measurements& d) {
  const std::string w = "identify: " + d.path + ": ";
  const Eigen::Index T = d.t.size();
  if (T < 2) throw Error(w + "expected samples at two times at least, got " + std::to_string(T));
  const auto shape = [&](const MatX& x, int cols, const char* what, bool optional) {
    if (optional && x.size() == 0) return;
    if (x.rows() != T || x.cols() != cols)
      throw Error(w + what + ": expected " + std::to_string(T) + " × " + std::to_string(cols) + " samples, got " +
                  std::to_string(x.rows()) + " × " + std::to_string(x.cols()));
    if (!x.allFinite()) throw Error(w + what + ": expected finite numbers");
  };
  shape(d.q, m.nq, "q", false);
  shape(d.v, m.nv, "qd", false);
  shape(d.qdd, m.nv, "qdd", true);
  shape(d.tau, m.nv, "tau", true);
  if (!d.t.allFinite()) throw Error(w + "t: expected finite times");
}

}  // namespace

std::optional<IdentifyMethod> parse_identify_method(const std::string& s) {
  if (s == "auto") return IdentifyMethod::Auto;
  if (s == "least-squares") return IdentifyMethod::LeastSquares;
  if (s == "gauss-newton") return IdentifyMethod::GaussNewton;
  return std::nullopt;
}

namespace {

// The bodies to fit, as named (`all`: every body with a mass), after the options and the
// measurements are checked against the scene
std::vector<std::string> bodies_to_fit(const Scenario& sc, const Measurements& d, const IdentifyOptions& o) {
  const Model& m = sc.model;
  if (o.bodies.empty()) throw Error("identify: parameters: expected the bodies to fit (names, or all)");
  for (const std::string& name : o.bodies)
    if (name != "all" && m.body_index(name) < 0)
      throw Error("identify: parameters: no body named '" + printable(name) + "'" + did_you_mean(name, m.body_names) +
                  " (the bodies after fixed joints are merged)");
  if (!(o.window > 0) || !std::isfinite(o.window))
    throw Error("identify: window: expected a positive number of seconds, got " + short_number(o.window));
  if (!(o.rank_tolerance > 0 && o.rank_tolerance < 1))
    throw Error("identify: rank tolerance: expected a number in (0, 1), got " + short_number(o.rank_tolerance));
  if (!sc.inputs.controllers.empty() && !d.tau.size())
    throw Error("identify: " + sc.path + ": the scene has controllers, whose torques the run file does not give; remove "
                "them (the torques then come from the inputs) or give the measured torques");
  // a massless body (an MJCF body's frame for each joint but its last, a massless URDF link) has no
  // parameters of its own to fit: named, it is refused; `all` is every body with a mass
  std::vector<std::string> bodies;
  for (const std::string& name : o.bodies) {
    if (name == "all") {
      for (int b = 0; b < m.nbodies; ++b)
        if (m.mass[size_t(b)] > 0.0) bodies.push_back(m.body_names[size_t(b)]);
      continue;
    }
    if (const int b = m.body_index(name); !(m.mass[size_t(b)] > 0.0))
      throw Error("identify: parameters: body '" + excerpt(name) + "' is massless in the scene (a frame between joints: an MJCF "
                  "body with several joints has one per joint but its last, which carries the mass); fit the body that has the mass");
  }
  if (std::find(o.bodies.begin(), o.bodies.end(), "all") == o.bodies.end() || o.bodies.size() > 1)
    bodies = o.bodies;  // names, or `all` with names (refused by the plan)
  check_measurements(m, d);
  return bodies;
}

// Least squares on the stacked regressor: Y π = τ at every logged sample (q̈ measured)
Step fit_least_squares(const Scenario& sc, const Measurements& d, const SensitivityPlan& plan, const IdentifyOptions& o,
                       IdentifyResult& res) {
  if (!d.qdd.size())
    throw Error("identify: " + d.path + ": least squares needs the accelerations (/qdd), which the data does not have");
  // a joint held at its limit takes a constraint force that τ = Y π does not have: a biased fit
  if (sc.simulation.limits && sc.model.has_limits())
    throw Error("identify: least-squares: " + sc.path + ": the scene enforces joint limits (simulation: limits: true), "
                "whose impacts and holding forces the regressor does not model (the fit would be biased): set limits: false");
  res.method = "least-squares";
  MatX A;
  VecX b;
  stack_regressor(sc, d, plan.bodies, A, b);
  const Step step = solve(A, b, o.rank_tolerance);
  res.fitted = res.prior + step.delta;
  res.rows = int(A.rows());
  res.rms_prior = step.rms_before;
  res.rms_fitted = step.rms_after;
  return step;
}

// Gauss–Newton on the trajectory residual over windows of W samples, its Jacobian from the CVODES
// sensitivities, damped as Levenberg–Marquardt: a step that leaves the rigid bodies or raises the
// residual is retried with 10 times the damping; one that lowers it is taken and the damping cut by 10
Step fit_gauss_newton(const Scenario& sc, const Measurements& d, const SensitivityPlan& plan, const IdentifyOptions& o,
                      IdentifyResult& res) {
  const Model& m = sc.model;
  res.method = "gauss-newton";
  if (m.has_quaternions())
    throw Error("identify: gauss-newton: the model has free or ball joints, whose residual identify does not form yet; "
                "use least squares (a run file with /qdd)");
  const Eigen::Index T = d.t.size();
  const double dt = d.t(1) - d.t(0);
  for (Eigen::Index k = 0; k < T; ++k)
    if (!(dt > 0) || std::abs(d.t(k) - d.t(0) - double(k) * dt) > 1e-9 * std::max(1.0, std::abs(d.t(k))))
      throw Error("identify: gauss-newton: " + d.path + ": expected samples at t_0 + k·" + short_number(dt) +
                  " (a run's output grid), got t = " + short_number(d.t(k)) + " at sample " + std::to_string(k));
  const Eigen::Index W = std::max<Eigen::Index>(1, Eigen::Index(std::llround(o.window / dt)));
  std::vector<std::string> names;
  for (int b : plan.bodies) names.push_back(m.body_names[size_t(b)]);
  const VecX pi0 = parameters(m);
  VecX x = res.prior, r, r_try;
  MatX J, J_try;
  trajectory_residual(sc, d, names, full_parameters(pi0, plan.bodies, x), W, r, J);
  res.rms_prior = std::sqrt(r.squaredNorm() / double(r.size()));
  double mu = 1e-4;
  for (res.iterations = 1; res.iterations <= o.max_iterations; ++res.iterations) {
    bool taken = false;
    VecX delta;
    for (int tries = 0; tries < 16 && !taken; ++tries, mu *= 10.0) {
      delta = solve(J, r, o.rank_tolerance, mu).delta;
      try {
        trajectory_residual(sc, d, names, full_parameters(pi0, plan.bodies, x + delta), W, r_try, J_try);
        taken = r_try.squaredNorm() <= r.squaredNorm();
      } catch (const Error&) {  // no rigid body there: a shorter step
      }
    }
    if (!taken) break;  // no step lowers the residual: at its minimum to round-off
    mu = std::max(1e-12, mu / 100.0);  // the loop's last × 10 undone, then ÷ 10
    x += delta;
    r.swap(r_try);
    J.swap(J_try);
    if (delta.cwiseAbs().maxCoeff() <= 1e-10 * std::max(1.0, x.cwiseAbs().maxCoeff())) break;
  }
  res.iterations = std::min(res.iterations, o.max_iterations);
  res.fitted = x;
  res.rows = int(J.rows());
  res.rms_fitted = std::sqrt(r.squaredNorm() / double(r.size()));
  return solve(J, r, o.rank_tolerance);  // the rank, null space and errors at the fit
}

}  // namespace

IdentifyResult identify(const Scenario& sc, const Measurements& d, const IdentifyOptions& o) {
  const Model& m = sc.model;
  const SensitivityPlan plan = plan_sensitivities(m, {false, bodies_to_fit(sc, d, o)});
  IdentifyResult res;
  res.bodies = plan.bodies;
  res.names = plan.parameter_names;
  res.units = plan.parameter_units;
  const VecX pi0 = parameters(m);
  res.prior.resize(plan.np());
  for (size_t k = 0; k < plan.bodies.size(); ++k)
    res.prior.segment<kParametersPerBody>(kParametersPerBody * Eigen::Index(k)) =
        pi0.segment<kParametersPerBody>(kParametersPerBody * plan.bodies[k]);

  const bool least_squares = o.method == IdentifyMethod::LeastSquares || (o.method == IdentifyMethod::Auto && d.qdd.size());
  const Step step = least_squares ? fit_least_squares(sc, d, plan, o, res) : fit_gauss_newton(sc, d, plan, o, res);
  res.rank = step.rank;
  res.singular_values = step.singular_values;
  res.unidentifiable = step.null_space;
  res.sigma2 = step.sigma2;
  res.standard_error = step.standard_error;
  try {
    res.model = with_parameters(m, full_parameters(pi0, plan.bodies, res.fitted));
  } catch (const Error& e) {
    throw Error(std::string("identify: the fit is no rigid body: ") + (e.what() + std::string("with_parameters: ").size()));
  }
  return res;
}

}  // namespace soadyn
