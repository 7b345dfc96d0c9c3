// The variational integrator's small pieces (variational.cpp): the rate map R(u) = dexp⁻¹_u of a
// turn and its derivative, and 𝓜⁻¹ as a preconditioner for Eigen's GMRES.
#pragma once

#include "soadyn/algorithm/algorithms.hpp"

#include <Eigen/Core>

#include <cmath>
#include <vector>

namespace soadyn::variational {

// c(θ) = (1 − (θ/2) cot(θ/2)) / θ² and dc/d(θ²), by their series where θ is small
inline void turn_coefficient(double t2, double& c, double& dc) {
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

inline Mat3 hat(const Vec3& u) {
  Mat3 H;
  H << 0, -u.z(), u.y(), u.z(), 0, -u.x(), -u.y(), u.x(), 0;
  return H;
}

// R(u) = e + (s/2) û + c û²
inline Mat3 turn_rate(const Vec3& u, double s) {
  double c = 0, dc = 0;
  turn_coefficient(u.squaredNorm(), c, dc);
  const Mat3 H = hat(u);
  return Mat3::Identity() + (0.5 * s) * H + c * H * H;
}

// ∂(R(u) z)/∂u = −(s/2) ẑ + 2 c' (u × (u × z)) uᵀ + c ((u·z) e + u zᵀ − 2 z uᵀ)
inline Mat3 turn_rate_derivative(const Vec3& u, const Vec3& z, double s) {
  double c = 0, dc = 0;
  turn_coefficient(u.squaredNorm(), c, dc);
  Mat3 D = (-0.5 * s) * hat(z);
  D.noalias() += (2.0 * dc) * u.cross(u.cross(z)) * u.transpose();
  D += c * (u.dot(z) * Mat3::Identity() + u * z.transpose() - 2.0 * z * u.transpose());
  return D;
}

// 𝓜⁻¹ x by the articulated-body factor forward (or hybrid) dynamics left in data (articulated_solve,
// O(N)), on the rows `index` names (the state's DOFs: 𝓜_ff⁻¹ with the prescribed joints locked):
// the preconditioner of Newton's Krylov solves (Eigen's GMRES asks for this shape)
class MassPreconditioner {
 public:
  using Scalar = double;
  using RealScalar = double;
  using StorageIndex = int;
  enum { ColsAtCompileTime = Eigen::Dynamic, MaxColsAtCompileTime = Eigen::Dynamic };
  MassPreconditioner() = default;
  void bind(const Model& model, const Data& data, const std::vector<int>& index) {
    model_ = &model;
    data_ = &data;
    index_ = &index;
    work_ = articulated_solve_work(model);
    x_ = MatX::Zero(model.nv, 1);
  }
  template <typename M>
  MassPreconditioner& analyzePattern(const M&) { return *this; }
  template <typename M>
  MassPreconditioner& factorize(const M&) { return *this; }
  template <typename M>
  MassPreconditioner& compute(const M&) { return *this; }
  // out = 𝓜⁻¹ b on the rows `index` names, without allocating (the chord iterations' step)
  template <typename Rhs>
  void apply(const Rhs& b, VecX& out) const {
    x_.setZero();
    for (size_t i = 0; i < index_->size(); ++i) x_((*index_)[i], 0) = b(Eigen::Index(i));
    articulated_solve(*model_, *data_, x_, work_);
    for (size_t i = 0; i < index_->size(); ++i) out(Eigen::Index(i)) = x_((*index_)[i], 0);
  }
  template <typename Rhs>
  VecX solve(const Rhs& b) const {
    VecX out(Eigen::Index(index_->size()));
    apply(b, out);
    return out;
  }
  Eigen::ComputationInfo info() const { return Eigen::Success; }

 private:
  const Model* model_ = nullptr;
  const Data* data_ = nullptr;
  const std::vector<int>* index_ = nullptr;
  mutable MatX work_, x_;
};

}  // namespace soadyn::variational
