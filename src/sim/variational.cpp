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
#include "variational_blocks.hpp"

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/derivatives.hpp"
#include "soadyn/algorithm/hybrid.hpp"
#include "soadyn/algorithm/kinematics.hpp"

#include <Eigen/LU>
#include <unsupported/Eigen/IterativeSolvers>

#include <cmath>
#include <limits>
#include <sstream>
#include <type_traits>

namespace soadyn {

namespace {

using namespace variational;

// from this many DOFs on, Newton's corrections by GMRES preconditioned with 𝓜⁻¹ (O(nv²) per
// iteration: 7–8 products with the Jacobian) rather than a dense LU (O(nv³)): on the bench's chain
// (chain/step_variational) even at 128 DOFs, GMRES 1.3× faster at 256
constexpr int kKrylovFrom = 128;

class Variational : public FixedStep {
 public:
  Variational(System& s, double dt, double t0, bool chord)
      : FixedStep(s, dt, t0),
        chord_(chord),
        prescribed_(s.has_prescribed()),
        free_(without_gravity(s.model)),
        gravity_(!s.model.gravity.isZero(0.0)),
        vi_(s.v_index()),
        dd_(s.model),
        ddg_(s.model),
        qk_(s.nq_state()),
        ym_(VecX::Zero(s.size())),
        xf_(s.nv_state()),
        xi_(s.model.nv),
        p_(s.model.nv),
        a_(s.model.nv),
        r_(s.model.nv),
        rf_(s.nv_state()),
        delta_(s.nv_state()),
        zero_(VecX::Zero(s.model.nv)),
        x_(s.model.nv),
        vp_(VecX::Zero(s.model.nv)),
        J_(s.model.nv, s.model.nv),
        B_(s.model.nv, s.model.nv),
        dq_(s.model.nv, s.model.nv),
        dv_(s.model.nv, s.model.nv),
        lu_(s.nv_state()),
        guess_(s.nv_state()),
        gq_(s.model.nv),
        gv_(s.model.nv),
        held_(s.model.nv),
        cached_y_(s.size()) {
    if (s.has_loops()) throw Error("variational: closed loops are not available yet: use rk4 or implicit-midpoint");
    for (const System::StateJoint& j : s.state_joints())
      visit_joint(s.model, j.body, [&](const auto& kind) {
        using K = std::decay_t<decltype(kind)>;
        const int at = s.model.idx_v[size_t(j.body)];
        if constexpr (std::is_base_of_v<joints::Rotation, K>) turns_.push_back({at, 1.0});
        else if constexpr (std::is_base_of_v<joints::RigidMotion, K>) turns_.push_back({at, -1.0});
      });
    blocks_.resize(turns_.size());
    gmres_.preconditioner().bind(s.model, s.data, vi_);
    gmres_.setTolerance(1e-13);
    gmres_.setMaxIterations(50);
    gmres_.set_restart(50);
  }

 private:
  // a free or ball joint's turn: where it sits in the model's v, its side s
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

  // the model's v at t with only the prescribed joints' q̇*(t) (into vp_)
  void prescribed_velocity(double t) {
    double q = 0, qdd = 0;
    for (const PrescribedInput& pi : sys_.inputs.prescribed) pi.at(t, q, vp_(pi.dof), qdd);
  }
  // W_p += Σ (impulse on prescribed joint j) · q̇*_j(t)
  double prescribed_work(const VecX& impulse, double t) {
    prescribed_velocity(t);
    double w = 0.0;
    for (const PrescribedInput& pi : sys_.inputs.prescribed) w += impulse(pi.dof) * vp_(pi.dof);
    return w;
  }

  // One step (the free joints' q and v in y; the model's at t from System::expand).  With prescribed
  // motion, only the free rows of the DEL equations hold: the prescribed joints' q and q̇ at t_m are
  // their given motion's, ξ_f is the unknown, and the impulses the prescribed rows miss are what held
  // the motion: at node k, p⁻_k − p_k on the way out (p⁻_k = b − (h/2) ā of the step from it, p_k =
  // 𝓜(q_k) v_k the continuous momentum) and p_k+1 − p⁺_k+1 on the way in, each ≈ ∫ τ_p over its half
  // step, their work counted in W_p at the half step's midpoint velocity q̇*(t_k + h/4), q̇*(t_k+1 − h/4)
  void step(double t, double h, VecX& y) override {
    const int nqs = sys_.nq_state(), nvs = sys_.nv_state();
    qk_ = y.head(nqs);
    // p_k: the last step's when y is the state it left, else 𝓜(q_k) v_k
    const bool cached = cached_ && y == cached_y_;
    if (!cached) {
      sys_.expand(t, y.data());
      p_ = inverse_dynamics(free_, sys_.data, sys_.q, zero_, sys_.v);  // 𝓜(q_k) v_k, O(N)
      held_ = p_;  // the continuous momentum at t_k (its prescribed rows)
    } else {
      p_ = p_next_;
    }
    // ξ from v_k, or 2 v_k − ξ_k−1 (v at t_k + h/2 to O(h²)) after a step of the same h
    xf_ = y.segment(nqs, nvs);
    if (cached && h == last_h_) xf_ = 2.0 * xf_ - last_xf_;
    solve(t, h);
    last_xf_ = xf_;
    last_h_ = h;
    // W, D += h (P, D)(t_m, ξ) at the last evaluation (the midpoint)
    const int w = nqs + nvs;
    if (nw_ > 0) {
      const Inputs::Power pw = sys_.inputs.power(t + 0.5 * h, xi_);
      double controller = 0.0;
      if (sys_.control_work) controller = sys_.feedback_tau.dot(xi_) + (sys_.controlled ? sys_.control.dot(xi_) : 0.0);
      y(w) += h * (pw.inputs + controller);
      y(w + 1) += h * pw.dissipated;
    }
    if (prescribed_) {  // the holding impulse out of node k: p⁻_k − p_k
      r_ = dd_.tau - (0.5 * h) * a_ - held_;
      y(w + 2) += prescribed_work(r_, t + 0.25 * h);
    }
    // p_k+1 = R(u)ᵀ [b + (h/2) R(u/2)⁻ᵀ ā]
    r_ = a_;
    for (size_t k = 0; k < turns_.size(); ++k) r_.segment<3>(turns_[k].at) = blocks_[k].Rhinv.transpose() * a_.segment<3>(turns_[k].at);
    r_ = dd_.tau + (0.5 * h) * r_;
    for (size_t k = 0; k < turns_.size(); ++k) {
      const Vec3 u = r_.segment<3>(turns_[k].at);
      r_.segment<3>(turns_[k].at) = blocks_[k].R.transpose() * u;
    }
    p_next_ = r_;
    // q_k+1 = q_k ⊕ h ξ,  v_k+1 from p_k+1
    sys_.integrate(qk_, xf_, h, y.head(nqs));
    if (!prescribed_) {
      y.segment(nqs, nvs) = forward_dynamics(free_, sys_.data, y.head(nqs), zero_, r_);  // 𝓜⁻¹ p_k+1, O(N)
    } else {
      // v_f = 𝓜_ff⁻¹ (p_f − 𝓜_fp q̇*_p): the hybrid dynamics at (q_k+1, 0) with gravity off, τ_f = p_f
      // and q̈*_p = q̇*_p(t_k+1); then p_k+1 = 𝓜(q_k+1) v_k+1 and the impulse into node k+1
      // (System::expand puts q̇*(t_k+1) on the prescribed rows of sys_.v, the only ones read there)
      sys_.expand(t + h, y.data());
      update_kinematics(free_, sys_.data, sys_.q);
      update_velocities(free_, sys_.data, zero_);
      hybrid_dynamics(free_, sys_.data, sys_.prescribed_joints(), r_, sys_.v, x_);
      for (int i = 0; i < nvs; ++i) y(nqs + i) = sys_.data.qdd(vi_[size_t(i)]);
      sys_.expand(t + h, y.data());  // v_k+1 whole; [kin] at q_k+1 and v = 0 still hold
      inverse_dynamics(free_, sys_.data, sys_.v);
      held_ = sys_.data.tau;
      r_ = held_ - p_next_;
      y(w + 2) += prescribed_work(r_, t + 0.75 * h);
    }
    cached_y_ = y;
    cached_ = true;
  }

  // F(ξ) = 0 to rounding in F's own units (momentum, so that a poorly conditioned 𝓜 does not hold
  // it back): the iterations end at an iterate whose residual is within ε of F's terms, or has
  // stopped shrinking within 1000 times their rounding; that iterate's evaluation (ā, 𝓜 ξ, the
  // blocks) makes p_k+1.  (Ending at 4 ε instead saves one iteration in four but left a bias that
  // drifted a random tree's momenta by ~5e-12 over 10⁵ steps, against ~2e-13: test_variational.)
  // First the chord iterations, O(N) each, when asked for (newton: simplified); where they
  // contract by less than half per iteration (a step that barely resolves the motion), Newton's.
  // With prescribed motion F and ξ are their free rows.
  void solve(double t, double h) {
    guess_ = xf_;
    if (chord_ && chord(t, h)) return;
    if (!xf_.allFinite()) xf_ = guess_;
    newton(t, h);
  }

  // F's size at the iterate (its free rows), and whether it is done: within ε of its terms, or no
  // longer shrinking by half within `within` times their rounding (𝓜 ξ is rounded by ε |𝓜| |ξ|, more
  // than ε |𝓜 ξ| where light bodies move fast or the motions cancel; |𝓜| by its largest diagonal
  // entry S_rᵀ Y_i S_r, Y_i the composite inertia the sweeps leave)
  struct Size {
    double size, scale, rounding;
  };
  Size size_of(double h) const {
    const double eps = std::numeric_limits<double>::epsilon();
    double diagonal = 0.0;
    for (int c = 0; c < sys_.model.nv; ++c) diagonal = std::max(diagonal, dd_.S.col(c).dot(dd_.row.col(c).head<6>()));
    const double scale = p_.norm() + dd_.tau.norm() + 0.5 * h * a_.norm();
    return {rf_.norm(), scale, eps * (scale + diagonal * xi_.norm())};
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

  // G = R(u)⁻¹ F on the turns' rows (the Jacobians below are G's), into rf_ (the free rows)
  void turn_residual() {
    for (size_t k = 0; k < turns_.size(); ++k) {
      const Vec3 f = r_.segment<3>(turns_[k].at);
      r_.segment<3>(turns_[k].at) = blocks_[k].Rinv * f;
    }
    gather(r_, rf_);
  }
  void gather(const VecX& model, VecX& state) const {
    for (size_t i = 0; i < vi_.size(); ++i) state(Eigen::Index(i)) = model(vi_[i]);
  }
  // the articulated-body factor of 𝓜(q_m) in data (MassPreconditioner then applies 𝓜⁻¹) (the hybrid dynamics', prescribed joints locked,
  // with prescribed motion), with gravity off (the factor does not depend on it)
  void mass_factor() {
    if (prescribed_) hybrid_dynamics(free_, sys_.data, sys_.prescribed_joints(), zero_, zero_, x_);
    else forward_dynamics(free_, sys_.data, zero_, FdMethod::ArticulatedBody);
  }

  // The chord iterations: ξ ← ξ − 𝓜(q_m)⁻¹ G (𝓜_ff with prescribed motion), 𝓜 for G's Jacobian
  // G' = 𝓜 + O(h) (below), so that they contract at a rate O(h |ξ|) (h times the speed the
  // configuration turns), each one O(N): the evaluation by sweeps (evaluate_sweeps) and 𝓜⁻¹ by the
  // articulated-body factor at q_m (one forward dynamics, then one solve).  True when they
  // converged; false when they contracted by less than half (Newton then goes on from where they
  // stopped) or did not converge in 30.
  bool chord(double t, double h) {
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
      mass_factor();
      gmres_.preconditioner().apply(rf_, delta_);  // 𝓜⁻¹ G on the free rows
      xf_ -= delta_;
    }
    return false;
  }

  // Newton's iterations with G's Jacobian (jacobian: analytic but for an O(h²) term)
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
      xf_ -= delta_;
    }
  }

  // δ = G'_ff⁻¹ G_f: past kKrylovFrom DOFs by GMRES with 𝓜_ff(q_m)⁻¹ (G' = 𝓜 + O(h): a few
  // iterations, to 1e-13 of |G|), its LU where GMRES does not get there in 50; else the LU
  void correction() {
    if (prescribed_) Jf_ = J_(vi_, vi_);
    const MatX& J = prescribed_ ? Jf_ : J_;
    if (sys_.nv_state() >= kKrylovFrom) {
      mass_factor();
      gmres_.compute(J);
      delta_ = gmres_.solve(rf_);
      if (gmres_.info() == Eigen::Success) return;
    }
    lu_.compute(J);
    delta_.noalias() = lu_.solve(rf_);
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

  // q_m = q_k ⊕ (h/2) ξ, the state there ([kin], [vel] at the model's (q_m, ξ), the prescribed
  // joints' at their motion's t_m) and τ (System::at_state); ξ the model's v there
  void midpoint(double tm, double h) {
    const int nqs = sys_.nq_state(), nvs = sys_.nv_state();
    sys_.integrate(qk_, xf_, 0.5 * h, ym_.head(nqs));
    ym_.segment(nqs, nvs) = xf_;
    sys_.at_state(tm, ym_.data());
    xi_ = sys_.v;
  }

  // evaluate's quantities in O(N), without the matrices: inverse dynamics' sweeps at (q_m, 0, ξ)
  // with gravity off give 𝓜 ξ (dd_.tau), then ½ P(ξ)ᵀ ξ = ½ (∂τ/∂q)ᵀ ξ by their transposed product;
  // the sweeps at (q_m, 0, 0) with gravity give g
  void evaluate_sweeps(double tm, double h) {
    const Model& m = sys_.model;
    midpoint(tm, h);
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

  // at the iterate: the midpoint, 𝓜 and the forces τ there; 𝓜 ξ and P(ξ) (inverse dynamics' ∂τ/∂q
  // at (q_m, 0, ξ) with gravity off: its τ is 𝓜 ξ); g and ∂g/∂δ (at (q_m, 0, 0) with gravity);
  // ā = ½ P(ξ)ᵀ ξ − g + τ; the turns' blocks
  void evaluate(double tm, double h) {
    const Model& m = sys_.model;
    midpoint(tm, h);
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

  // r = F(ξ) = R(u) [𝓜 ξ − (h/2) R(u/2)⁻¹ ā] − p_k (R = e off the turns; every row of the model),
  // its free rows in rf_
  void residual(double h) {
    r_ = dd_.tau - (0.5 * h) * a_ - p_;
    for (size_t k = 0; k < turns_.size(); ++k) {
      const int at = turns_[k].at;
      const Blocks& b = blocks_[k];
      r_.segment<3>(at) = b.R * (dd_.tau.segment<3>(at) - (0.5 * h) * (b.Rhinv * a_.segment<3>(at))) - p_.segment<3>(at);
    }
    gather(r_, rf_);
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

  bool chord_;       // the chord iterations first (newton: simplified)
  bool prescribed_;  // the state holds the free joints alone
  Model free_;       // the model with gravity off: 𝓜 ξ and P(ξ) from inverse dynamics' derivatives
  bool gravity_;
  const std::vector<int>& vi_;  // the state's v entries in the model's v
  DerivativeData dd_, ddg_;
  VecX qk_, ym_, xf_;                        // q_k and the unknown ξ (the state's)
  VecX xi_, p_, a_, r_, rf_, delta_, zero_;  // the model's ξ, p_k, ā, F; F's free rows, the correction
  VecX x_, vp_, p_next_;
  MatX J_, B_, dq_, dv_, Jf_;
  Eigen::PartialPivLU<MatX> lu_;
  Eigen::GMRES<MatX, MassPreconditioner> gmres_;
  VecX guess_, gq_, gv_;  // the step's first iterate; (∂τ/∂q)ᵀ ξ and (∂τ/∂v)ᵀ ξ
  VecX held_;             // with prescribed motion, 𝓜(q_k) v_k (the continuous momentum at the node)
  std::vector<Turn> turns_;
  std::vector<Blocks> blocks_;
  VecX cached_y_;  // the state the last step left, whose momentum is p_next_
  bool cached_ = false;
  VecX last_xf_;         // the last step's ξ
  double last_h_ = 0.0;  // and its h
};

}  // namespace

std::unique_ptr<Integrator> make_variational(System& sys, const SimulationSettings& settings, double t0) {
  return std::make_unique<Variational>(sys, settings.dt, t0, settings.newton == Newton::Simplified);
}

}  // namespace soadyn
