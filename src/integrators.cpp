#include "soadyn/integrators.hpp"

#include "soadyn/kinematics.hpp"

#include <Eigen/LU>

#include <cmath>
#include <sstream>

namespace soadyn {

System::System(const Model& m, const Inputs& in, FdMethod fd)
    : model(m), inputs(in), method(fd), nquad(in.does_work() ? 2 : 0), data(m), q(m.nq), v(m.nv), tau(m.nv), qd(m.nq) {}

VecX System::state(const VecX& q0, const VecX& v0) const {
  VecX y = VecX::Zero(size());
  y.head(model.nq) = q0;
  y.segment(model.nq, model.nv) = v0;
  return y;
}

void System::rhs(double t, const double* y, double* ydot) {
  ++rhs_evals;
  q = Eigen::Map<const VecX>(y, model.nq);
  v = Eigen::Map<const VecX>(y + model.nq, model.nv);
  update_kinematics(model, data, q);
  update_velocities(model, data, v);
  inputs.evaluate(t, q, v, tau);
  forward_dynamics(model, data, tau, method);
  model.qdot(q, v, qd);
  Eigen::Map<VecX>(ydot, model.nq) = qd;
  Eigen::Map<VecX>(ydot + model.nq, model.nv) = data.qdd;
  if (nquad > 0) {
    // Ẇ = (τ_torques + τ_dampers) · q̇,  Ḋ = Σ c q̇²
    const Inputs::Power p = inputs.power(t, v);
    ydot[model.nq + model.nv] = p.inputs;
    ydot[model.nq + model.nv + 1] = p.dissipated;
  }
}

std::string System::component_name(int k) const {
  if (k == model.nq + model.nv && nquad > 0) return "the inputs' work W (quadrature)";
  if (k == model.nq + model.nv + 1 && nquad > 0) return "the dampers' dissipated energy D (quadrature)";
  const bool is_q = k < model.nq;
  const int idx = is_q ? k : k - model.nq;
  const std::vector<std::string> names = is_q ? model.q_names() : model.v_names();
  if (idx < 0 || idx >= int(names.size())) return "component " + std::to_string(k);
  return "joint '" + names[idx] + "' (" + (is_q ? "q" : "qd") + ")";
}

int first_non_finite(const VecX& y) {
  for (int k = 0; k < y.size(); ++k)
    if (!std::isfinite(y(k))) return k;
  return -1;
}

namespace {

// Fixed-step methods: n equal steps of h ≤ dt from t to t_out.
class FixedStep : public Integrator {
 public:
  FixedStep(System& s, double dt)
      : sys_(s), dt_(dt), k1_(s.size()), k2_(s.size()), k3_(s.size()), k4_(s.size()), tmp_(s.size()), prev_(s.size()) {}

  void advance(double t_out, double& t, VecX& y) override {
    const long n = std::max<long>(1, long(std::ceil((t_out - t) / dt_ * (1 - 1e-12))));
    const double h = (t_out - t) / double(n);
    for (long k = 0; k < n; ++k) {
      if (stop_requested()) return;  // t < t_out: the run ends here
      prev_ = y;
      step(t, h, y);
      t = k + 1 == n ? t_out : t + h;
      ++stats_.steps;
      sys_.model.normalize(y.head(sys_.model.nq));
      if (first_non_finite(y) >= 0) {
        // worst DOF: the largest velocity in the last finite state, the one blowing up
        Eigen::Index worst = 0;
        prev_.segment(sys_.model.nq, sys_.model.nv).cwiseAbs().maxCoeff(&worst);
        std::ostringstream os;
        os << "unstable at t = " << t << " s: the state is not finite after a step of " << h << " s; worst DOF "
           << sys_.component_name(sys_.model.nq + int(worst)) << " = " << prev_(sys_.model.nq + worst) << " before it";
        throw SimulationError(os.str(), t);
      }
    }
  }

  IntegratorStats stats() const override {
    IntegratorStats s = stats_;
    s.rhs_evals = sys_.rhs_evals;
    return s;
  }
  std::string quaternion_handling() const override {
    return sys_.model.has_quaternions() ? "renormalized after each step" : "none";
  }

 protected:
  virtual void step(double t, double h, VecX& y) = 0;
  void f(double t, const VecX& y, VecX& out) { sys_.rhs(t, y.data(), out.data()); }

  System& sys_;
  double dt_;
  VecX k1_, k2_, k3_, k4_, tmp_, prev_;
  IntegratorStats stats_;
};

class Euler : public FixedStep {
  using FixedStep::FixedStep;
  // y ← y + h f(t, y)
  void step(double t, double h, VecX& y) override {
    f(t, y, k1_);
    y += h * k1_;
  }
};

class SymplecticEuler : public FixedStep {
  using FixedStep::FixedStep;
  // v ← v + h q̈(q, v);  q ← q + h q̇(q, v⁺);  quadratures W, D ← + h (P, D)(q, v) (left rectangle)
  void step(double t, double h, VecX& y) override {
    const int nq = sys_.model.nq, nv = sys_.model.nv;
    f(t, y, k1_);
    y.segment(nq, nv) += h * k1_.segment(nq, nv);
    y.tail(sys_.nquad) += h * k1_.tail(sys_.nquad);
    sys_.model.qdot(y.head(nq), y.segment(nq, nv), k2_.head(nq));
    y.head(nq) += h * k2_.head(nq);
  }
};

class RK4 : public FixedStep {
  using FixedStep::FixedStep;
  // classical: y ← y + h/6 (k1 + 2 k2 + 2 k3 + k4)
  void step(double t, double h, VecX& y) override {
    f(t, y, k1_);
    tmp_ = y + 0.5 * h * k1_;
    f(t + 0.5 * h, tmp_, k2_);
    tmp_ = y + 0.5 * h * k2_;
    f(t + 0.5 * h, tmp_, k3_);
    tmp_ = y + h * k3_;
    f(t + h, tmp_, k4_);
    y += h / 6.0 * (k1_ + 2.0 * k2_ + 2.0 * k3_ + k4_);
  }
};

class ImplicitMidpoint : public FixedStep {
 public:
  ImplicitMidpoint(System& s, double dt) : FixedStep(s, dt), J_(s.size(), s.size()), lu_(s.size()) {}

 private:
  // y⁺ = y + h f(t + h/2, (y + y⁺)/2): Newton on G(Y) = Y − y − h f(t + h/2, (y + Y)/2), with the
  // Jacobian of f by forward differences once per step (simplified Newton)
  void step(double t, double h, VecX& y) override {
    const int n = sys_.size();
    const double tm = t + 0.5 * h;
    f(t, y, k1_);
    VecX& Y = k2_;
    Y = y + h * k1_;  // explicit Euler predictor
    tmp_ = 0.5 * (y + Y);
    f(tm, tmp_, k3_);
    for (int c = 0; c < n; ++c) {
      const double e = 1e-7 * std::max(1.0, std::abs(tmp_(c)));
      const double keep = tmp_(c);
      tmp_(c) += e;
      f(tm, tmp_, k4_);
      J_.col(c) = (k4_ - k3_) / e;
      tmp_(c) = keep;
    }
    ++stats_.jac_evals;
    J_ = MatX::Identity(n, n) - 0.5 * h * J_;
    lu_.compute(J_);
    for (int it = 0; it < 50; ++it) {
      ++stats_.nonlinear_iterations;
      tmp_ = 0.5 * (y + Y);
      f(tm, tmp_, k3_);
      k4_ = -(Y - y - h * k3_);
      const VecX delta = lu_.solve(k4_);
      Y += delta;
      if (!delta.allFinite()) break;
      if (delta.norm() <= 1e-13 * std::max(1.0, Y.norm())) break;
    }
    y = Y;
  }
  MatX J_;
  Eigen::PartialPivLU<MatX> lu_;
};

}  // namespace

const std::vector<IntegratorInfo>& integrators() {
  using S = const SimulationSettings&;
  static const std::vector<IntegratorInfo> table = {
      {"cvode-adams", "SUNDIALS CVODE, Adams–Moulton with fixed-point iterations (non-stiff)", false,
       [](System& sys, S s, double t0, const VecX& y0) { return make_cvode(false, sys, s, t0, y0); }},
      {"cvode-bdf", "SUNDIALS CVODE, BDF with Newton and a dense direct solver (stiff)", false,
       [](System& sys, S s, double t0, const VecX& y0) { return make_cvode(true, sys, s, t0, y0); }},
      {"euler", "explicit Euler, order 1", true,
       [](System& sys, S s, double, const VecX&) -> std::unique_ptr<Integrator> { return std::make_unique<Euler>(sys, s.dt); }},
      {"symplectic-euler", "semi-implicit Euler, order 1, symplectic", true,
       [](System& sys, S s, double, const VecX&) -> std::unique_ptr<Integrator> {
         return std::make_unique<SymplecticEuler>(sys, s.dt);
       }},
      {"rk4", "classical Runge–Kutta, order 4", true,
       [](System& sys, S s, double, const VecX&) -> std::unique_ptr<Integrator> { return std::make_unique<RK4>(sys, s.dt); }},
      {"implicit-midpoint", "implicit midpoint rule by Newton, order 2, symplectic and A-stable", true,
       [](System& sys, S s, double, const VecX&) -> std::unique_ptr<Integrator> {
         return std::make_unique<ImplicitMidpoint>(sys, s.dt);
       }},
  };
  return table;
}

const IntegratorInfo* find_integrator(std::string_view name) {
  for (const auto& info : integrators())
    if (info.name == name) return &info;
  return nullptr;
}

std::vector<std::string> integrator_names() {
  std::vector<std::string> names;
  for (const auto& info : integrators()) names.emplace_back(info.name);
  return names;
}

std::unique_ptr<Integrator> make_integrator(const std::string& method, System& system,
                                            const SimulationSettings& settings, double t0, const VecX& y0) {
  if (const IntegratorInfo* info = find_integrator(method)) return info->make(system, settings, t0, y0);
  std::string all;
  for (const auto& n : integrator_names()) all += (all.empty() ? "" : ", ") + n;
  throw Error("method: expected one of " + all + "; got '" + method + "'");
}

}  // namespace soadyn
