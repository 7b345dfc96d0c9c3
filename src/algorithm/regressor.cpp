// The joint-torque regressor and the inertial parameters (regressor.hpp).
//
// Inverse dynamics (rnea.cpp's sweeps) gives each body's joint-point acceleration pair
// A_i = [α_i; a_i] (a_i the classical acceleration of η_i, gravity folded in at the roots) and
// velocity ω_i.  Newton–Euler about the moving point η_i, in body i's axes (R_i: body → inertial),
// with h = m c:
//   f = m a + α × h + ω × (ω × h),     n = I α + ω × (I ω) + h × a,
// linear in π_i = (m, h, I): so W_i (6×10) with [n; f] = W_i π_i, moved to inertial axes by R_i.
// τ_k collects G_kᵀ of the force pairs of k's subtree carried to η_k (F_p += D_iᵀ F_i, as the
// backward sweep does): Y's block (DOFs of j, parameters of i) = G_jᵀ D_{i:j}ᵀ R_i W_i for every
// ancestor j of i, and zero elsewhere.
#include "soadyn/algorithm/regressor.hpp"

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/multibody/inertia.hpp"
#include "soadyn/multibody/text.hpp"

#include "point_motion.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <string>

namespace soadyn {

namespace {

using Mat610 = Eigen::Matrix<double, 6, kParametersPerBody>;

// I's six entries (row, column) in π's order xx, xy, yy, xz, yz, zz
constexpr int kInertiaEntry[6][2] = {{0, 0}, {0, 1}, {1, 1}, {0, 2}, {1, 2}, {2, 2}};

// the symmetric basis of those entries
Mat3 inertia_basis(int k) {
  Mat3 E = Mat3::Zero();
  E(kInertiaEntry[k][0], kInertiaEntry[k][1]) = E(kInertiaEntry[k][1], kInertiaEntry[k][0]) = 1.0;
  return E;
}

std::string body_label(const Model& m, int i) { return "body '" + printable(m.body_names[size_t(i)]) + "'"; }

}  // namespace

VecX parameters(const Model& model) {
  VecX pi(kParametersPerBody * model.nbodies);
  for (int i = 0; i < model.nbodies; ++i) {
    const double m = model.mass[i];
    const Vec3 h = m * model.com[i];
    const Mat3& I = model.inertia_origin[i];
    pi.segment<kParametersPerBody>(kParametersPerBody * i) << m, h.x(), h.y(), h.z(), I(0, 0), I(0, 1), I(1, 1),
        I(0, 2), I(1, 2), I(2, 2);
  }
  return pi;
}

Model with_parameters(const Model& model, const VecX& pi) {
  if (pi.size() != kParametersPerBody * model.nbodies)
    throw Error("with_parameters: pi: expected " + std::to_string(kParametersPerBody * model.nbodies) +
                " numbers (10 per body), got " + std::to_string(pi.size()));
  Model out = model;
  for (int i = 0; i < model.nbodies; ++i) {
    const auto p = pi.segment<kParametersPerBody>(kParametersPerBody * i);
    if (!p.allFinite()) throw Error("with_parameters: " + body_label(model, i) + ": expected finite parameters");
    if ((p.array() == 0.0).all()) {  // all ten zero: a massless body (a frame between joints), as Model has them
      out.mass[i] = 0.0;
      out.com[i].setZero();
      out.inertia[i].setZero();
      out.inertia_origin[i].setZero();
      continue;
    }
    const double m = p(0);
    if (!(m > 0.0)) throw Error("with_parameters: " + body_label(model, i) + ": mass: expected > 0, got " + std::to_string(m));
    const Vec3 c = Vec3(p(1), p(2), p(3)) / m;
    Mat3 Io;
    Io << p(4), p(5), p(7), p(5), p(6), p(8), p(7), p(8), p(9);
    const Mat3 Icm = Io - parallel_axis(m, c);  // about the centre of mass
    const Vec3 l = Eigen::SelfAdjointEigenSolver<Mat3>(Icm, Eigen::EigenvaluesOnly).eigenvalues();
    const double tol = 1e-12 * std::max(1.0, Io.cwiseAbs().maxCoeff());
    if (l(0) < -tol)
      throw Error("with_parameters: " + body_label(model, i) +
                  ": inertia about the centre of mass: expected positive semidefinite, got principal moments " +
                  std::to_string(l(0)) + ", " + std::to_string(l(1)) + ", " + std::to_string(l(2)));
    if (l(2) > l(0) + l(1) + tol)
      throw Error("with_parameters: " + body_label(model, i) +
                  ": inertia about the centre of mass: expected principal moments obeying the triangle inequality, got " +
                  std::to_string(l(0)) + ", " + std::to_string(l(1)) + ", " + std::to_string(l(2)));
    out.mass[i] = m;
    out.com[i] = c;
    out.inertia[i] = Icm;
    out.inertia_origin[i] = Io;
  }
  return out;
}

namespace {

// W_i (6×10) in body i's axes with [n; f] = W_i π_i (the header comment), from [kin], [vel] and data.A
Mat610 body_regressor(const Data& data, int i) {
  const Mat3& R = data.R[i];
  const Vec3 w = R.transpose() * data.V.col(i).head<3>();
  const Vec3 al = R.transpose() * data.A.col(i).head<3>(), a = R.transpose() * data.A.col(i).tail<3>();
  // columns m, h (3), I (6); rows [n; f]
  Mat610 W = Mat610::Zero();
  W.block<3, 1>(3, 0) = a;
  for (int k = 0; k < 3; ++k) {
    const Vec3 e = Vec3::Unit(k);
    W.block<3, 1>(0, 1 + k) = e.cross(a);
    W.block<3, 1>(3, 1 + k) = al.cross(e) + w.cross(w.cross(e));
  }
  for (int k = 0; k < 6; ++k) {
    const Mat3 E = inertia_basis(k);
    W.block<3, 1>(0, 4 + k) = E * al + w.cross(E * w);
  }
  return W;
}

// body i's ten columns of Y into Y's columns from `at`: W_i to inertial axes, then up the chain of
// ancestors, G_jᵀ B, B ← D_jᵀ B = [n + d_j × f; f] (rows of non-ancestors left as they are)
void body_columns(const Model& model, const Data& data, int i, MatX& Y, int at) {
  const Mat3& R = data.R[i];
  const Mat610 W = body_regressor(data, i);
  Mat610 B;
  B.topRows<3>() = R * W.topRows<3>();
  B.bottomRows<3>() = R * W.bottomRows<3>();
  for (int j = i; j >= 0; j = model.parent[j]) {
    const int iv = model.idx_v[j], n = model.nv_i[j];
    Y.block(iv, at, n, kParametersPerBody).noalias() = data.G.middleCols(iv, n).transpose() * B;
    const Vec3 d = data.d.col(j);
    for (int c = 0; c < kParametersPerBody; ++c) B.block<3, 1>(0, c) += d.cross(Vec3(B.block<3, 1>(3, c)));
  }
}

// W_iᵀ [x; y] for [x; y] = R_iᵀ w (w in inertial axes) without forming W_i, column by column of
// body_regressor: m: y·a;  h: a × x + y × α + (y·ω) ω − |ω|² y;  I's entry (r, c): xᵀ E α + zᵀ E ω
// with z = x × ω and E the symmetric basis (u_r v_c + u_c v_r, or u_r v_r on the diagonal)
Eigen::Matrix<double, kParametersPerBody, 1> body_regressor_transpose_times(const Data& data, int i, const Vec6& wi) {
  const Mat3& R = data.R[i];
  const Vec3 x = R.transpose() * wi.head<3>(), y = R.transpose() * wi.tail<3>();
  const Vec3 w = R.transpose() * data.V.col(i).head<3>();
  const Vec3 al = R.transpose() * data.A.col(i).head<3>(), a = R.transpose() * data.A.col(i).tail<3>();
  const Vec3 z = x.cross(w);
  Eigen::Matrix<double, kParametersPerBody, 1> out;
  out(0) = y.dot(a);
  out.segment<3>(1) = a.cross(x) + y.cross(al) + y.dot(w) * w - w.squaredNorm() * y;
  for (int k = 0; k < 6; ++k) {
    const int r = kInertiaEntry[k][0], c = kInertiaEntry[k][1];
    out(4 + k) = r == c ? x(r) * al(r) + z(r) * w(r) : x(r) * al(c) + x(c) * al(r) + z(r) * w(c) + z(c) * w(r);
  }
  return out;
}

}  // namespace

void regressor(const Model& model, Data& data, const VecX& qdd, MatX& Y) {
  inverse_dynamics(model, data, qdd);  // data.A: [α_i; a_i] of every body, inertial axes
  Y.setZero(model.nv, kParametersPerBody * model.nbodies);
  for (int i = 0; i < model.nbodies; ++i) body_columns(model, data, i, Y, kParametersPerBody * i);
}

void regressor(const Model& model, Data& data, const VecX& qdd, const std::vector<int>& bodies, MatX& Y) {
  for (const int b : bodies)
    if (b < 0 || b >= model.nbodies)
      throw Error("regressor: body index " + std::to_string(b) + " out of range 0.." + std::to_string(model.nbodies - 1));
  // A_b = [α_b; η̈_b − g], inverse dynamics' pair: along each listed body's chain alone (O(depth)),
  // or for the whole tree by inverse dynamics (O(N)) when the chains together are longer
  long chains = 0;
  for (const int b : bodies)
    for (int j = b; j >= 0; j = model.parent[j]) ++chains;
  const bool whole_tree = chains > model.nbodies;
  if (whole_tree) inverse_dynamics(model, data, qdd);
  Y.setZero(model.nv, kParametersPerBody * Eigen::Index(bodies.size()));
  for (size_t k = 0; k < bodies.size(); ++k) {
    const int b = bodies[k];
    if (!whole_tree) {
      Vec3 alpha, eta_dd;
      detail::point_acceleration(model, data, b, data.eta.col(b), &qdd, alpha, eta_dd);
      data.A.col(b).head<3>() = alpha;
      data.A.col(b).tail<3>() = eta_dd - model.gravity;
    }
    body_columns(model, data, b, Y, kParametersPerBody * int(k));
  }
}

void regressor_transpose_times(const Model& model, Data& data, const VecX& qdd, const VecX& mu, Eigen::Ref<VecX> out) {
  data.check(model, "regressor_transpose_times", "mu", mu.size(), model.nv);
  data.check(model, "regressor_transpose_times", "out", out.size(), kParametersPerBody * model.nbodies);
  inverse_dynamics(model, data, qdd);  // data.A
  // (Yᵀ μ)_i = Σ_{j ⪯ i} (G_j μ_j)ᵀ D_{i:j}ᵀ R_i W_i = w_iᵀ R_i W_i with w_i = D_i w_p + G_i μ_i, the
  // dual of carrying B up the ancestors: D [ω; u] = [ω; u + ω × d_i].  Base to tip, in data.work.local.V's columns
  Mat6X& w = data.work.local.V;
  for (int i = 0; i < model.nbodies; ++i) {
    const int p = model.parent[i], iv = model.idx_v[i], n = model.nv_i[i];
    Vec6 wi = data.G.middleCols(iv, n) * mu.segment(iv, n);
    if (p >= 0) {
      const Vec3 om = w.col(p).head<3>();
      wi.head<3>() += om;
      wi.tail<3>() += w.col(p).tail<3>() + om.cross(Vec3(data.d.col(i)));
    }
    w.col(i) = wi;
    out.segment<kParametersPerBody>(kParametersPerBody * i) = body_regressor_transpose_times(data, i, wi);
  }
}

void forward_dynamics_parameter_derivative(const Model& model, Data& data, const VecX& tau, MatX& dqdd_dpi) {
  data.check(model, "forward_dynamics_parameter_derivative", "tau", tau.size(), model.nv);
  forward_dynamics(model, data, tau, FdMethod::Sparse);  // data.qdd; 𝓜 factored into data.work.factor.L
  regressor(model, data, data.qdd, dqdd_dpi);  // inverse dynamics at q̈ writes tau, A, F, never qdd
  // ∂q̈/∂π = −𝓜⁻¹ Y: one LᵀDL solve per column
  for (Eigen::Index c = 0; c < dqdd_dpi.cols(); ++c) {
    auto col = dqdd_dpi.col(c);
    col = -col;
    ltdl_solve(model, data, col);
  }
}

}  // namespace soadyn
