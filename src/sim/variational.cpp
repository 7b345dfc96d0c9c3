// The variational integrator (fixed_step.hpp): the discrete Euler–Lagrange equations of the
// midpoint discrete Lagrangian on the configuration's group, in position–momentum form, forced by
// the discrete Lagrange–d'Alembert principle, solved by Newton.
//
// Discrete Lagrangian.  With u = h ξ the step's increment (q_k+1 = q_k ⊕ u, ξ = (q_k+1 ⊖ q_k)/h) and
// the midpoint q_m = q_k ⊕ u/2,
//   L_d(q_k, q_k+1) = h L(q_m, ξ),   L(q, v) = ½ vᵀ 𝓜(q) v − V(q).
// Its derivatives along the tangent (q ⊕ δ at either end) come from R(u) = dexp⁻¹_u, the map with
// u̇ = R(u) v for q_0 ⊕ u(t) moving at v (configuration.hpp's increment_rate; the identity on every
// coordinate but a free or ball joint's turn, where R(u) = e + (s/2) û + c(|u|) û², s = +1 for a
// ball's Q ⊗ exp(u), −1 for a free joint's exp(u) ⊗ Q, so that R(u)ᵀ = R(−u)):
//   ∂u/∂δ_k+1 = R(u),  ∂u/∂δ_k = −R(−u),  ∂δ_m/∂δ_k+1 = ½ R(u/2)⁻¹ R(u),  ∂δ_m/∂δ_k = ½ R(−u/2)⁻¹ R(−u).
// With b = ∂L/∂v = 𝓜(q_m) ξ and ā = ∂L/∂δ + τ at (q_m, ξ) — ∂L/∂δ = ½ P(ξ)ᵀ ξ − g(q_m),
// P(w) = ∂(𝓜 w)/∂δ, g the gravity's generalized force, and τ the forces the system gathers (inputs,
// springs, dampers, controllers) entering as h τ · δq_m, h/2 to each end —
//   p_k   = −D₁L_d − f_d⁻ = R(u) [b − (h/2) R(u/2)⁻¹ ā]
//   p_k+1 =  D₂L_d + f_d⁺ = R(u)ᵀ [b + (h/2) R(u/2)⁻ᵀ ā].
// Newton solves the first for ξ: its residual F(ξ) = R(u) [b − (h/2) R(u/2)⁻¹ ā] − p_k, corrections from
// G = R(u)⁻¹ F = 𝓜(q_m) ξ − (h/2) R(u/2)⁻¹ ā − R(u)⁻¹ p_k and its Jacobian; the second is explicit.
// (F, not G, is the residual: R(u)⁻¹ p_k's rounding, the same every step of a steady spin, made the
// heavy top's L_z drift by 3e-11 over 10⁶ steps, against 8e-13 with F.)  The quaternion moves by ⊕ alone (unit by construction, never renormalized).
//
// L_d is invariant under the rigid motions of the whole system where no force acts (the free
// root's exp(u) ⊗ Q and p + u_p commute with a turn and a shift of the world), so by the discrete
// Noether theorem the momenta p_k conserve the linear and angular momentum to the Newton tolerance.
// The state the run reports at step k is (q_k, v_k) with v_k = 𝓜(q_k)⁻¹ p_k, the velocity whose
// continuous momentum is the discrete one (so the momentum of the reported state is the conserved
// one); p_k is kept from the step before rather than recomputed as 𝓜 v_k when the state is the one
// the last step left.
#include "fixed_step.hpp"

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/derivatives.hpp"
#include "soadyn/algorithm/kinematics.hpp"

#include <Eigen/LU>
#include <unsupported/Eigen/IterativeSolvers>

#include <cmath>
#include <limits>
#include <sstream>
#include <type_traits>

namespace soadyn {

namespace {

// c(θ) = (1 − (θ/2) cot(θ/2)) / θ² and dc/d(θ²), by their series where θ is small
void turn_coefficient(double t2, double& c, double& dc) {
  if (t2 < 1e-2) {
    c = 1.0 / 12 + t2 * (1.0 / 720 + t2 * (1.0 / 30240 + t2 / 1209600));
    dc = 1.0 / 720 + t2 * (2.0 / 30240 + t2 * 3.0 / 1209600);
    return;
  }
  const double x = 0.5 * std::sqrt(t2), xc = x / std::tan(x), s = std::sin(x);
  c = (1.0 - xc) / t2;
  // dc/d(θ²) = (x cot x + x²/sin²x − 2) / (32 x⁴), x = θ/2
  dc = (xc + x * x / (s * s) - 2.0) / (32.0 * x * x * x * x);
}

Mat3 hat(const Vec3& u) {
  Mat3 H;
  H << 0, -u.z(), u.y(), u.z(), 0, -u.x(), -u.y(), u.x(), 0;
  return H;
}

// R(u) = e + (s/2) û + c û²
Mat3 turn_rate(const Vec3& u, double s) {
  double c = 0, dc = 0;
  turn_coefficient(u.squaredNorm(), c, dc);
  const Mat3 H = hat(u);
  return Mat3::Identity() + (0.5 * s) * H + c * H * H;
}

// ∂(R(u) z)/∂u = −(s/2) ẑ + 2 c' (u × (u × z)) uᵀ + c ((u·z) e + u zᵀ − 2 z uᵀ)
Mat3 turn_rate_derivative(const Vec3& u, const Vec3& z, double s) {
  double c = 0, dc = 0;
  turn_coefficient(u.squaredNorm(), c, dc);
  Mat3 D = (-0.5 * s) * hat(z);
  D.noalias() += (2.0 * dc) * u.cross(u.cross(z)) * u.transpose();
  D += c * (u.dot(z) * Mat3::Identity() + u * z.transpose() - 2.0 * z * u.transpose());
  return D;
}

// 𝓜(q)⁻¹ x by the articulated-body factor forward dynamics left in data (articulated_solve, O(N)):
// the preconditioner of Newton's Krylov solves (Eigen's GMRES asks for this shape)
class MassPreconditioner {
 public:
  using Scalar = double;
  using RealScalar = double;
  using StorageIndex = int;
  enum { ColsAtCompileTime = Eigen::Dynamic, MaxColsAtCompileTime = Eigen::Dynamic };
  MassPreconditioner() = default;
  void bind(const Model& model, const Data& data) {
    model_ = &model;
    data_ = &data;
    work_ = articulated_solve_work(model);
  }
  template <typename M>
  MassPreconditioner& analyzePattern(const M&) { return *this; }
  template <typename M>
  MassPreconditioner& factorize(const M&) { return *this; }
  template <typename M>
  MassPreconditioner& compute(const M&) { return *this; }
  template <typename Rhs>
  VecX solve(const Rhs& b) const {
    x_ = b;
    articulated_solve(*model_, *data_, x_, work_);
    return x_.col(0);
  }
  Eigen::ComputationInfo info() const { return Eigen::Success; }

 private:
  const Model* model_ = nullptr;
  const Data* data_ = nullptr;
  mutable MatX work_, x_;
};

// from this many DOFs on, Newton's corrections by GMRES preconditioned with 𝓜⁻¹ (O(nv²) per
// iteration: 7–8 products with the Jacobian) rather than a dense LU (O(nv³)): on the bench's chain
// (chain/step_variational) even at 128 DOFs, GMRES 1.3× faster at 256
constexpr int kKrylovFrom = 128;

class Variational : public FixedStep {
 public:
  Variational(System& s, double dt, double t0, bool chord)
      : FixedStep(s, dt, t0),
        chord_(chord),
        free_(without_gravity(s.model)),
        gravity_(!s.model.gravity.isZero(0.0)),
        dd_(s.model),
        ddg_(s.model),
        q_(s.model.nq),
        ym_(VecX::Zero(s.size())),
        xi_(s.model.nv),
        p_(s.model.nv),
        a_(s.model.nv),
        r_(s.model.nv),
        delta_(s.model.nv),
        zero_(VecX::Zero(s.model.nv)),
        J_(s.model.nv, s.model.nv),
        B_(s.model.nv, s.model.nv),
        dq_(s.model.nv, s.model.nv),
        dv_(s.model.nv, s.model.nv),
        lu_(s.model.nv),
        guess_(s.model.nv),
        gq_(s.model.nv),
        gv_(s.model.nv),
        solve_work_(articulated_solve_work(s.model)),
        cached_y_(s.size()) {
    if (s.has_prescribed() || s.has_loops())
      throw Error("variational: prescribed motion and closed loops are not available yet: use rk4 or implicit-midpoint");
    for (const System::StateJoint& j : s.state_joints())
      visit_joint(s.model, j.body, [&](const auto& kind) {
        using K = std::decay_t<decltype(kind)>;
        if constexpr (std::is_base_of_v<joints::Rotation, K>) turns_.push_back({j.iv, 1.0});
        else if constexpr (std::is_base_of_v<joints::RigidMotion, K>) turns_.push_back({j.iv, -1.0});
      });
    blocks_.resize(turns_.size());
    gmres_.preconditioner().bind(s.model, s.data);
    gmres_.setTolerance(1e-13);
    gmres_.setMaxIterations(50);
    gmres_.set_restart(50);
  }

 private:
  // a free or ball joint's turn: where it sits in v, its side s, and its blocks at the iterate
  struct Turn {
    int at;
    double s;
  };
  struct Blocks {
    Mat3 R, Rinv, Rh, Rhinv;  // R(u), R(u)⁻¹, R(u/2), R(u/2)⁻¹
  };

  static Model without_gravity(const Model& m) {
    Model f = m;
    f.gravity.setZero();
    return f;
  }

  void step(double t, double h, VecX& y) override {
    const Model& m = sys_.model;
    const int nq = m.nq, nv = m.nv;
    q_ = y.head(nq);
    // p_k: the last step's when y is the state it left, else 𝓜(q_k) v_k
    const bool cached = cached_ && y == cached_y_;
    if (!cached) {
      delta_ = y.segment(nq, nv);
      p_ = inverse_dynamics(free_, sys_.data, q_, zero_, delta_);  // 𝓜(q_k) v_k, O(N)
    } else {
      p_ = p_next_;
    }
    // ξ from v_k, or 2 v_k − ξ_k−1 (v at t_k + h/2 to O(h²)) after a step of the same h
    xi_ = y.segment(nq, nv);
    if (cached && h == last_h_) xi_ = 2.0 * xi_ - last_xi_;
    solve(t, h);
    last_xi_ = xi_;
    last_h_ = h;
    // W, D += h (P, D)(t_m, ξ) at the last evaluation (the midpoint)
    if (nw_ > 0) {
      const Inputs::Power pw = sys_.inputs.power(t + 0.5 * h, xi_);
      double controller = 0.0;
      if (sys_.control_work) controller = sys_.feedback_tau.dot(xi_) + (sys_.controlled ? sys_.control.dot(xi_) : 0.0);
      y(nq + nv) += h * (pw.inputs + controller);
      y(nq + nv + 1) += h * pw.dissipated;
    }
    // p_k+1 = R(u)ᵀ [b + (h/2) R(u/2)⁻ᵀ ā]
    r_ = a_;
    for (size_t k = 0; k < turns_.size(); ++k) r_.segment<3>(turns_[k].at) = blocks_[k].Rhinv.transpose() * a_.segment<3>(turns_[k].at);
    r_ = dd_.tau + (0.5 * h) * r_;
    for (size_t k = 0; k < turns_.size(); ++k) {
      const Vec3 w = r_.segment<3>(turns_[k].at);
      r_.segment<3>(turns_[k].at) = blocks_[k].R.transpose() * w;
    }
    p_next_ = r_;
    // q_k+1 = q_k ⊕ h ξ,  v_k+1 = 𝓜(q_k+1)⁻¹ p_k+1
    sys_.integrate(q_, xi_, h, y.head(nq));
    q_ = y.head(nq);
    y.segment(nq, nv) = forward_dynamics(free_, sys_.data, q_, zero_, r_);  // 𝓜(q_k+1)⁻¹ p_k+1, O(N)
    cached_y_ = y;
    cached_ = true;
  }

  // F(ξ) = 0 to rounding in F's own units (momentum, so that a poorly conditioned 𝓜 does not hold
  // it back): the iterations end at an iterate whose residual is within ε of F's terms, or has
  // stopped shrinking within 1000 times their rounding; that iterate's evaluation (ā, 𝓜 ξ, the
  // blocks) makes p_k+1.  (Ending at 4 ε instead saves one iteration in four but left a bias that
  // drifted a random tree's momenta by ~5e-12 over 10⁵ steps, against ~2e-13: test_variational.)
  // First the chord iterations, O(N) each; where they contract by less than half per iteration
  // (a step that barely resolves the motion), Newton's, O(nv³) each.
  void solve(double t, double h) {
    guess_ = xi_;
    if (chord_ && chord(t, h)) return;
    if (!xi_.allFinite()) xi_ = guess_;
    newton(t, h);
  }

  // F's size at the iterate, and whether it is done: within ε of its terms, or no longer shrinking
  // by half within 1000 times their rounding (𝓜 ξ is rounded by ε |𝓜| |ξ|, more than ε |𝓜 ξ| where
  // light bodies move fast or the motions cancel; |𝓜| by its largest diagonal entry S_rᵀ Y_i S_r,
  // Y_i the composite inertia the sweeps leave)
  struct Size {
    double size, scale, rounding;
  };
  Size size_of(double h) const {
    const double eps = std::numeric_limits<double>::epsilon();
    double diagonal = 0.0;
    for (int c = 0; c < sys_.model.nv; ++c) diagonal = std::max(diagonal, dd_.S.col(c).dot(dd_.row.col(c).head<6>()));
    const double scale = p_.norm() + dd_.tau.norm() + 0.5 * h * a_.norm();
    return {r_.norm(), scale, eps * (scale + diagonal * xi_.norm())};
  }
  // (the chord's linear convergence can slow to half per iteration well above rounding: it stops
  // only within 10 times the rounding, and gives way to Newton above that)
  static bool done(const Size& s, double previous, double within = 1e3) {
    const double eps = std::numeric_limits<double>::epsilon();
    return !std::isfinite(s.size) || s.size <= eps * s.scale || (s.size <= within * s.rounding && s.size >= 0.5 * previous);
  }
  [[noreturn]] void not_converged(double t, double h, const Size& s) const {
    std::ostringstream os;
    os << "variational: Newton did not converge at t = " << t << " s with a step of " << h << " s (residual "
       << s.size / s.scale << " of the momenta)";
    throw SimulationError(os.str(), t);
  }

  // G = R(u)⁻¹ F on the turns' rows (the Jacobians below are G's)
  void turn_residual() {
    for (size_t k = 0; k < turns_.size(); ++k) {
      const Vec3 f = r_.segment<3>(turns_[k].at);
      r_.segment<3>(turns_[k].at) = blocks_[k].Rinv * f;
    }
  }

  // The chord iterations: ξ ← ξ − 𝓜(q_m)⁻¹ G, 𝓜 for G's Jacobian G' = 𝓜 + O(h) (below), so that
  // they contract at a rate O(h |ξ|) (h times the speed the configuration turns), each one O(N):
  // the evaluation by sweeps (evaluate_sweeps) and 𝓜⁻¹ by the articulated-body factor at q_m (one
  // forward dynamics, then one solve).  True when they converged; false when they contracted by less
  // than half (Newton then goes on from where they stopped) or did not converge in 30.
  bool chord(double t, double h) {
    const Model& m = sys_.model;
    double previous = std::numeric_limits<double>::infinity();
    for (int it = 0; it < 30; ++it) {
      evaluate_sweeps(t + 0.5 * h, h);
      residual(h);
      const Size s = size_of(h);
      if (done(s, previous, 10.0)) return true;
      if (s.size > 0.5 * previous) return false;
      previous = s.size;
      ++stats_.nonlinear_iterations;
      turn_residual();
      forward_dynamics(free_, sys_.data, zero_, FdMethod::ArticulatedBody);  // the factor of 𝓜(q_m)
      Eigen::Map<MatX> x(r_.data(), m.nv, 1);
      articulated_solve(m, sys_.data, x, solve_work_);
      xi_ -= r_;
    }
    return false;
  }

  // Newton's iterations with G's Jacobian (jacobian: analytic but for an O(h²) term), a dense LU
  void newton(double t, double h) {
    double previous = std::numeric_limits<double>::infinity();
    for (int it = 0;; ++it) {
      evaluate(t + 0.5 * h, h);
      residual(h);
      const Size s = size_of(h);
      if (done(s, previous)) return;
      if (it == 50) {
        if (s.size <= 1e6 * s.rounding) return;
        not_converged(t, h, s);
      }
      previous = s.size;
      ++stats_.nonlinear_iterations;
      ++stats_.jac_evals;
      jacobian(h);
      turn_residual();
      correction();
      xi_ -= delta_;
    }
  }

  // δ = G'⁻¹ G: past kKrylovFrom DOFs by GMRES with 𝓜(q_m)⁻¹ (G' = 𝓜 + O(h): a few iterations, to
  // 1e-13 of |G|), its LU where GMRES does not get there in 50; else the LU
  void correction() {
    if (sys_.model.nv >= kKrylovFrom) {
      forward_dynamics(free_, sys_.data, zero_, FdMethod::ArticulatedBody);  // the factor of 𝓜(q_m)
      gmres_.compute(J_);
      delta_ = gmres_.solve(r_);
      if (gmres_.info() == Eigen::Success) return;
    }
    lu_.compute(J_);
    delta_.noalias() = lu_.solve(r_);
  }

  // the turns' blocks at the iterate: R(u), R(u/2) and their inverses, u = h ξ on the turn
  void turn_blocks(double h) {
    for (size_t k = 0; k < turns_.size(); ++k) {
      const Vec3 u = h * xi_.segment<3>(turns_[k].at);
      Blocks& b = blocks_[k];
      b.R = turn_rate(u, turns_[k].s);
      b.Rh = turn_rate(0.5 * u, turns_[k].s);
      b.Rinv = b.R.inverse();
      b.Rhinv = b.Rh.inverse();
    }
  }

  // evaluate's quantities in O(N), without the matrices: inverse dynamics' sweeps at (q_m, 0, ξ)
  // with gravity off give 𝓜 ξ (dd_.tau), then ½ P(ξ)ᵀ ξ = ½ (∂τ/∂q)ᵀ ξ by their transposed product;
  // the sweeps at (q_m, 0, 0) with gravity give g
  void evaluate_sweeps(double tm, double h) {
    const Model& m = sys_.model;
    sys_.integrate(q_, xi_, 0.5 * h, ym_.head(m.nq));
    ym_.segment(m.nq, m.nv) = xi_;
    sys_.at_state(tm, ym_.data());
    inverse_dynamics_derivative_sweeps(free_, sys_.data, zero_, xi_, dd_);
    inverse_dynamics_derivatives_transpose_times(free_, dd_, xi_, gq_, gv_);
    a_ = sys_.tau;
    a_ += 0.5 * gq_;
    if (gravity_) {
      inverse_dynamics_derivative_sweeps(m, sys_.data, zero_, zero_, ddg_);
      a_ -= ddg_.tau;
    }
    turn_blocks(h);
  }

  // at the iterate ξ: q_m = q_k ⊕ (h/2) ξ; [kin], 𝓜 and the forces τ there (System::at_state);
  // 𝓜 ξ and P(ξ) (inverse dynamics' ∂τ/∂q at (q_m, 0, ξ) with gravity off: its τ is 𝓜 ξ); g and
  // ∂g/∂δ (at (q_m, 0, 0) with gravity); ā = ½ P(ξ)ᵀ ξ − g + τ; the turns' blocks
  void evaluate(double tm, double h) {
    const Model& m = sys_.model;
    sys_.integrate(q_, xi_, 0.5 * h, ym_.head(m.nq));
    ym_.segment(m.nq, m.nv) = xi_;
    sys_.at_state(tm, ym_.data());
    mass_matrix(m, sys_.data);
    inverse_dynamics_derivatives(free_, sys_.data, zero_, xi_, dd_);
    a_ = sys_.tau;
    a_.noalias() += 0.5 * dd_.dtau_dq.transpose() * xi_;
    if (gravity_) {
      inverse_dynamics_derivatives(m, sys_.data, zero_, zero_, ddg_);
      a_ -= ddg_.tau;
    }
    turn_blocks(h);
  }

  // r = F(ξ) = R(u) [𝓜 ξ − (h/2) R(u/2)⁻¹ ā] − p_k (R = e off the turns)
  void residual(double h) {
    r_ = dd_.tau - (0.5 * h) * a_ - p_;
    for (size_t k = 0; k < turns_.size(); ++k) {
      const int at = turns_[k].at;
      const Blocks& b = blocks_[k];
      r_.segment<3>(at) = b.R * (dd_.tau.segment<3>(at) - (0.5 * h) * (b.Rhinv * a_.segment<3>(at))) - p_.segment<3>(at);
    }
  }

  // G'(ξ) = 𝓜 + (h/2) P Δ − (h/2) R(u/2)⁻¹ [(h/2) K Δ + P ᵀ + ∂τ/∂v]
  //         + (h²/4) R(u/2)⁻¹ ∂(R(u/2) z_a)/∂(u/2) + h R(u)⁻¹ ∂(R(u) z_p)/∂u,
  // Δ = R(u/2)⁻¹ (∂δ_m/∂ξ = (h/2) Δ), K = ∂τ/∂δ − ∂g/∂δ (the second derivative of ½ ξᵀ 𝓜 ξ, of
  // order h² here, is left out: Newton converges linearly at a rate O(h²|ξ|²), fast where the step
  // resolves the motion), z_a = R(u/2)⁻¹ ā, z_p = R(u)⁻¹ p_k
  void jacobian(double h) {
    dq_.setZero();
    dv_.setZero();
    sys_.inputs.add_derivatives(dq_, dv_);
    if (gravity_) dq_ -= ddg_.dtau_dq;
    J_ = dd_.dtau_dq;  // P, then P Δ
    B_ = dq_;          // K, then K Δ
    for (size_t k = 0; k < turns_.size(); ++k) {
      const int at = turns_[k].at;
      J_.middleCols<3>(at) = J_.middleCols<3>(at) * blocks_[k].Rhinv;
      B_.middleCols<3>(at) = B_.middleCols<3>(at) * blocks_[k].Rhinv;
    }
    B_ *= 0.5 * h;
    B_ += dd_.dtau_dq.transpose();
    B_ += dv_;
    for (size_t k = 0; k < turns_.size(); ++k) {
      const int at = turns_[k].at;
      B_.middleRows<3>(at) = blocks_[k].Rhinv * B_.middleRows<3>(at);
    }
    J_ = sys_.data.M + (0.5 * h) * (J_ - B_);
    for (size_t k = 0; k < turns_.size(); ++k) {
      const int at = turns_[k].at;
      const double s = turns_[k].s;
      const Blocks& b = blocks_[k];
      const Vec3 u = h * xi_.segment<3>(at);
      const Vec3 za = b.Rhinv * a_.segment<3>(at), zp = b.Rinv * p_.segment<3>(at);
      J_.block<3, 3>(at, at) += (0.25 * h * h) * b.Rhinv * turn_rate_derivative(0.5 * u, za, s);
      J_.block<3, 3>(at, at) += h * b.Rinv * turn_rate_derivative(u, zp, s);
    }
  }

  bool chord_;  // the chord iterations first (newton: simplified)
  Model free_;  // the model with gravity off: 𝓜 ξ and P(ξ) from inverse dynamics' derivatives
  bool gravity_;
  DerivativeData dd_, ddg_;
  VecX q_, ym_, xi_, p_, a_, r_, delta_, zero_, p_next_;
  MatX J_, B_, dq_, dv_;
  Eigen::PartialPivLU<MatX> lu_;
  Eigen::GMRES<MatX, MassPreconditioner> gmres_;
  VecX guess_, gq_, gv_;  // the step's first iterate; (∂τ/∂q)ᵀ ξ and (∂τ/∂v)ᵀ ξ
  MatX solve_work_;       // articulated_solve's
  std::vector<Turn> turns_;
  std::vector<Blocks> blocks_;
  VecX cached_y_;  // the state the last step left, whose momentum is p_next_
  bool cached_ = false;
  VecX last_xi_;         // the last step's ξ
  double last_h_ = 0.0;  // and its h
};

}  // namespace

std::unique_ptr<Integrator> make_variational(System& sys, const SimulationSettings& settings, double t0) {
  return std::make_unique<Variational>(sys, settings.dt, t0, settings.newton == Newton::Simplified);
}

}  // namespace soadyn
