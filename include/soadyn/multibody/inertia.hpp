// Rigid-body spatial inertia about a reference point, in inertial coordinates.
//
// The note's M_i = S_iᵀ M̄_i S_i = [I_i − m s̃ s̃, m s̃; −m s̃, m e]; with h = m s and
// I_o = I_cm − m s̃ s̃ (the inertia about the reference point) this is [I_o, h̃; −h̃, m e].
// Composite inertias keep this form, so ten numbers carry any of them.
#pragma once

#include "soadyn/multibody/types.hpp"

namespace soadyn {

// Parallel axes: a mass m at offset c adds m (|c|² e − c cᵀ) = −m c̃ c̃ to an inertia.
inline Mat3 parallel_axis(double m, const Vec3& c) {
  return m * (c.squaredNorm() * Mat3::Identity() - c * c.transpose());
}

// C M Cᵀ for a symmetric M: the upper triangle from T = C M, mirrored (out may be M itself)
inline void rotate_symmetric(const Mat3& C, const Mat3& M, Mat3& out) {
  Mat3 T;
  T.noalias() = C * M;
  for (int a = 0; a < 3; ++a)
    for (int b = a; b < 3; ++b) out(a, b) = out(b, a) = T.row(a).dot(C.row(b));
}

struct SpatialInertia {
  double m = 0.0;           // mass
  Vec3 h = Vec3::Zero();    // first moment m c about the reference point
  Mat3 I = Mat3::Zero();    // rotational inertia about the reference point

  // M [ω; u] = [I ω + h × u; m u − h × ω]
  template <class Derived>
  [[gnu::always_inline]] Vec6 operator*(const Eigen::MatrixBase<Derived>& x) const {
    const Vec3 w = x.template head<3>(), u = x.template tail<3>();
    Vec6 y;
    y.head<3>().noalias() = I * w + h.cross(u);
    y.tail<3>() = m * u - h.cross(w);
    return y;
  }

  // M X for a 6×k block X (each column)
  template <class Derived>
  Mat6G apply(const Eigen::MatrixBase<Derived>& X) const {
    Mat6G Y(6, X.cols());
    for (Eigen::Index c = 0; c < X.cols(); ++c) Y.col(c) = (*this) * X.col(c);
    return Y;
  }

  // this += Dᵀ K D with D = [e 0; −d̃ e]: K moved from a point to the point −d from it.
  // h' = h + m d;  I' = I − d hᵀ − h dᵀ + 2 (h·d) e − m (d dᵀ − |d|² e)
  void add_transformed(const SpatialInertia& K, const Vec3& d) {
    const double hd = K.h.dot(d), dd = d.squaredNorm();
    m += K.m;
    h += K.h + K.m * d;
    // one expression: the diagonal written entry by entry and then read back whole would wait on
    // the stores
    I += K.I - d * K.h.transpose() - K.h * d.transpose() - K.m * (d * d.transpose()) +
         (2.0 * hd + K.m * dd) * Mat3::Identity();
  }

  // the 6×6 matrix [I, h̃; −h̃, m e]
  Mat6 matrix() const {
    Mat6 M;
    M << I, skew(h), -skew(h), m * Mat3::Identity();
    return M;
  }

  // body of mass m, centre of mass at c and inertia I_o about the reference point: (m, m c, I_o)
  static SpatialInertia from_origin(double mass, const Vec3& c, const Mat3& I_o) {
    SpatialInertia K;
    K.m = mass;
    K.h = mass * c;
    K.I = I_o;
    return K;
  }

  // body of mass m, inertia I_cm about its centre of mass at offset s from the reference point:
  // I_o = I_cm − m s̃ s̃  (parallel axes)
  static SpatialInertia from_body(double mass, const Vec3& s, const Mat3& I_cm) {
    SpatialInertia K;
    K.m = mass;
    K.h = mass * s;
    K.I = I_cm + parallel_axis(mass, s);
    return K;
  }
};

}  // namespace soadyn
