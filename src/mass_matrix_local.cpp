// 𝓜(q) from q alone, in body frames: the fast path beside mass_matrix's inertial sweep
// (mass_matrix.cpp), which stays the reference it is tested against.
//
// The same composite-inertia algorithm, 𝓜_jk = G_jᵀ D_{i:j}ᵀ K_i G_k (eq. 14 by composites),
// with each quantity in the axes of the body the sweep is at instead of inertial ones, so no
// inertial frame is ever formed:
//   K̂_i = M̂_i + Σ_children X_c K̂_c X_cᵀ        body i's axes, about η_i; M̂_i is the model's
//                                              constant inertia, never turned per call
//   F̂_k = K̂_i Ĝ_k for each DOF k of body i, then carried to each ancestor's axes and point
//   𝓜_jk = Ĝ_jᵀ F̂_k                            in the axes of the body owning DOF j
// where Ĝ_i is G_i in body i's axes and X_c moves a force from the child's axes and point to its
// parent's: f' = R f, n' = R n + p × f' with (R, p) the child's placement ∘ joint motion.
// A revolute joint along a unit axis e_k of a placement that does not turn the frame makes R a
// turn by θ about e_k: it mixes two components only (cos θ, sin θ: no 3×3 product).
//
// A DOF's F̂ is moved once per ancestor: O(N·depth) 6-vector moves, against the inertial sweep's
// O(N·depth) dot products of vectors moved once.  Past kLocalDepth the dot products win, and the
// entry point keeps the composites in body axes but moves each K̂ Ĝ once to the inertial origin,
// with the entries as the inertial sweep's dot products (mass_matrix_frames).  Columns are kept in
// depth-first order so that a subtree's are one run whatever the body order.
#include "soadyn/algorithms.hpp"
#include "soadyn/kinematics.hpp"

#include "mass_matrix_entries.hpp"

#include <cmath>

namespace soadyn {

namespace {

// deepest model the local route takes (one run, chains, local against mixed: N = 16 0.57–0.59
// against 0.63–0.65 µs, 20 0.80–0.86 against 0.88, 24 1.13–1.15 against 1.03–1.06, 32 1.70–1.75
// against 1.54–1.63)
constexpr int kLocalDepth = 22;

// K̂_i = M̂_i for every body: its own inertia, constant in its axes
void body_inertias(const Model& model, Data& data) {
  for (int i = 0; i < model.nbodies; ++i)
    data.Kl[i] = SpatialInertia::from_origin(model.mass[i], model.com[i], model.inertia_origin[i]);
}

// Kp += X K Xᵀ for X = (Rot_k(θ), d): K turned by θ about e_k (Rot taking e_a → c e_a + s e_b,
// e_b → −s e_a + c e_b, a = k + 1, b = k + 2; its 2×2 block by double angles), then moved by d:
//   h' = Rot h,  I' = Rot I Rotᵀ,  w = h' + m d / 2,
//   Kp.m += m,  Kp.h += h' + m d,  Kp.I += I' + 2 (d·w) e − (d wᵀ + w dᵀ)
// All in scalars: Kp is read back as soon as the sweep reaches the parent, and a load wider than
// the stores it reads stalls the CPU
template <int k>
inline void add_turned(const SpatialInertia& K, double c, double s, const Vec3& d, SpatialInertia& Kp) {
  constexpr int a = (k + 1) % 3, b = (k + 2) % 3;
  const double m = K.m, c2 = c * c - s * s, s2 = 2.0 * c * s;
  const double avg = 0.5 * (K.I(a, a) + K.I(b, b)), dif = 0.5 * (K.I(a, a) - K.I(b, b)), iab = K.I(a, b);
  double h[3], I[3][3];
  h[k] = K.h(k);
  h[a] = c * K.h(a) - s * K.h(b);
  h[b] = s * K.h(a) + c * K.h(b);
  I[k][k] = K.I(k, k);
  I[k][a] = c * K.I(k, a) - s * K.I(k, b);
  I[k][b] = s * K.I(k, a) + c * K.I(k, b);
  I[a][a] = avg + dif * c2 - iab * s2;
  I[b][b] = avg - dif * c2 + iab * s2;
  I[a][b] = dif * s2 + iab * c2;
  I[a][k] = I[k][a], I[b][k] = I[k][b], I[b][a] = I[a][b];
  const double w[3] = {h[0] + 0.5 * m * d[0], h[1] + 0.5 * m * d[1], h[2] + 0.5 * m * d[2]};
  const double dw2 = 2.0 * (d[0] * w[0] + d[1] * w[1] + d[2] * w[2]);
  Kp.m += m;
  for (int r = 0; r < 3; ++r) {
    Kp.h(r) += h[r] + m * d[r];
    for (int col = 0; col < 3; ++col) Kp.I(r, col) += I[r][col] - d[r] * w[col] - w[r] * d[col];
    Kp.I(r, r) += dw2;
  }
}

// columns [c0, c1) of F moved to the parent: f' = Rot f, n' = Rot n + p × f' (Rot as above).
// Each column is read and written as six scalars, so a column written by one body's move is read
// back by the next at the same width (a wider read of narrower stores stalls the CPU).
template <int k>
inline void turn_columns(Mat6X& F, int c0, int c1, double c, double s, const Vec3& p) {
  constexpr int a = (k + 1) % 3, b = (k + 2) % 3;
  for (int j = c0; j < c1; ++j) {
    double* x = F.col(j).data();
    double n[3], f[3];
    n[k] = x[k], f[k] = x[3 + k];
    n[a] = c * x[a] - s * x[b], n[b] = s * x[a] + c * x[b];
    f[a] = c * x[3 + a] - s * x[3 + b], f[b] = s * x[3 + a] + c * x[3 + b];
    x[0] = n[0] + p.y() * f[2] - p.z() * f[1];
    x[1] = n[1] + p.z() * f[0] - p.x() * f[2];
    x[2] = n[2] + p.x() * f[1] - p.y() * f[0];
    x[3] = f[0], x[4] = f[1], x[5] = f[2];
  }
}

// the same for any (R, p)
inline void move_columns(Mat6X& F, int c0, int c1, const Mat3& R, const Vec3& p) {
  for (int j = c0; j < c1; ++j) {
    double* x = F.col(j).data();
    const Vec3 f = R * Vec3(x[3], x[4], x[5]);
    const Vec3 n = R * Vec3(x[0], x[1], x[2]) + p.cross(f);
    x[0] = n[0], x[1] = n[1], x[2] = n[2];
    x[3] = f[0], x[4] = f[1], x[5] = f[2];
  }
}

// one body with a revolute joint along ±e_k of a placement that does not turn the frame
// (every index known at compile time, so K stays in registers)
template <int k>
void revolute_step(const Model& model, Data& data, int i, double sign) {
  constexpr int a = (k + 1) % 3, b = (k + 2) % 3;
  const SpatialInertia& K = data.Kl[i];
  Mat6X& F = data.Fl;
  const int p = model.parent[i], iv = model.idx_v[i], begin = model.dfs_begin[i], end = model.dfs_end[i];
  // F̂_i = K̂_i Ĝ_i with Ĝ_i = ±[e_k; 0]: ±[I e_k; −h × e_k]
  double* x = F.col(begin).data();
  x[0] = sign * K.I(0, k), x[1] = sign * K.I(1, k), x[2] = sign * K.I(2, k);
  x[3 + k] = 0.0, x[3 + a] = -sign * K.h(b), x[3 + b] = sign * K.h(a);
  // 𝓜_ij = Ĝ_iᵀ F̂_j = ±(F̂_j)_k for every DOF j of the subtree (both triangles)
  const Eigen::Index nv = data.Mass.rows();
  double* M = data.Mass.data();
  M[iv + iv * nv] = sign * x[k];
  for (int pos = begin + 1; pos < end; ++pos) {
    const int j = model.dfs_dof[pos];
    M[iv + j * nv] = M[j + iv * nv] = sign * F(k, pos);
  }
  if (p < 0) return;
  // X_i = (Rot_k(θ), placement offset)
  const double c = data.turn(0, i), s = sign * data.turn(1, i);
  const Vec3& offset = model.placement[i].p;
  turn_columns<k>(F, begin, end, c, s, offset);
  add_turned<k>(K, c, s, offset, data.Kl[p]);
}

// Deeper models: the composites in body axes as above, but each K̂_i Ĝ_k moved once to the
// inertial origin, F0_k = [R n̂ + η_i × R f̂; R f̂], and the entries as dot products with
// S0_j = [a; b + η × a] (mass_matrix_entries), from the frames alone (update_frames: no inertia
// turned into inertial axes)
void mass_matrix_frames(const Model& model, Data& data, const VecX& q) {
  update_frames(model, data, q);
  const int N = model.nbodies;
  body_inertias(model, data);
  for (int i = N - 1; i >= 0; --i) {
    const SpatialInertia& K = data.Kl[i];
    const Mat3& R = data.R[i];
    const Vec3 eta = data.eta.col(i);
    const JointType type = model.joint_type[i];
    const int p = model.parent[i], unit = model.unit_axis[i];
    const int k = std::abs(unit) - 1;
    const double sign = unit > 0 ? 1.0 : -1.0;
    const bool turn_only = unit != 0 && type == JointType::Revolute && !model.placement_turns[i];
    const Vec3 hw = R * K.h;  // h in inertial axes
    for (int c = model.idx_v[i]; c < model.idx_v[i] + model.nv_i[i]; ++c) {
      const Vec3 ga = data.G.col(c).head<3>(), gb = data.G.col(c).tail<3>();
      // R K̂ Ĝ = R K̂ Rᵀ G: [R I Rᵀ a + h_w × b; m b − h_w × a], with R I Rᵀ a = ±R I e_k along a unit axis
      Vec3 nw, fw;
      if (unit != 0 && type == JointType::Revolute) {
        nw.noalias() = sign * (R * K.I.col(k));
        fw = ga.cross(hw);
      } else {
        nw.noalias() = R * (K.I * (R.transpose() * ga));
        nw += hw.cross(gb);
        fw = K.m * gb - hw.cross(ga);
      }
      nw += eta.cross(fw);
      data.F0.col(c).head<3>() = nw;
      data.F0.col(c).tail<3>() = fw;
      data.S0.col(c).head<3>() = ga;
      data.S0.col(c).tail<3>() = gb + eta.cross(ga);
    }
    if (p < 0) continue;
    // K̂_p += X_i K̂_i X_iᵀ
    if (turn_only) {
      const double c = data.turn(0, i), s = sign * data.turn(1, i);
      const Vec3& offset = model.placement[i].p;
      switch (k) {
        case 0: add_turned<0>(K, c, s, offset, data.Kl[p]); break;
        case 1: add_turned<1>(K, c, s, offset, data.Kl[p]); break;
        default: add_turned<2>(K, c, s, offset, data.Kl[p]); break;
      }
      continue;
    }
    const Mat3 Rrel = data.R[p].transpose() * R;
    SpatialInertia Kr = K;
    rotate_symmetric(Rrel, Kr.I, Kr.I);
    Kr.h = Rrel * K.h;
    data.Kl[p].add_transformed(Kr, data.R[p].transpose() * data.d.col(i));
  }
  mass_matrix_entries(model, data);
}

}  // namespace

void mass_matrix(const Model& model, Data& data, const VecX& q) {
  data.check(model, "mass_matrix", "q", q.size(), model.nq);
  if (model.depth > kLocalDepth) {
    mass_matrix_frames(model, data, q);
    return;
  }
  joint_turns(model, q, data.turn, false);
  const int N = model.nbodies;
  const Eigen::Index nv = data.Mass.rows();
  double* M = data.Mass.data();
  Mat6X& F = data.Fl;
  body_inertias(model, data);
  for (int i = N - 1; i >= 0; --i) {
    SpatialInertia& K = data.Kl[i];
    const JointType type = model.joint_type[i];
    const Placement& X = model.placement[i];
    const int p = model.parent[i], unit = model.unit_axis[i], iv = model.idx_v[i], ni = model.nv_i[i];
    const int begin = model.dfs_begin[i], end = model.dfs_end[i];
    const int k = std::abs(unit) - 1;
    const double sign = unit > 0 ? 1.0 : -1.0;
    if (unit != 0 && type == JointType::Revolute && !model.placement_turns[i]) {
      switch (k) {
        case 0: revolute_step<0>(model, data, i, sign); break;
        case 1: revolute_step<1>(model, data, i, sign); break;
        default: revolute_step<2>(model, data, i, sign); break;
      }
      continue;
    }
    if (unit != 0) {
      // Ĝ_i = ±[e_k; 0] (revolute) or ±[0; e_k] (prismatic): F̂_i = K̂_i Ĝ_i is a column of K̂_i,
      // and 𝓜_ij = Ĝ_iᵀ F̂_j one component of F̂_j
      const bool revolute = type == JointType::Revolute;
      Vec3 n = Vec3::Zero(), f = Vec3::Zero();
      if (revolute) n = sign * K.I.col(k), f = -sign * K.h.cross(Vec3::Unit(k));
      else n = sign * K.h.cross(Vec3::Unit(k)), f(k) = sign * K.m;
      double* x = F.col(begin).data();
      x[0] = n[0], x[1] = n[1], x[2] = n[2], x[3] = f[0], x[4] = f[1], x[5] = f[2];
      const int row = revolute ? k : 3 + k;
      for (int pos = begin; pos < end; ++pos) {
        const int j = model.dfs_dof[pos];
        M[iv + j * nv] = M[j + iv * nv] = sign * F(row, pos);
      }
      if (p < 0) continue;
    } else {
      // any other joint: Ĝ_i = G_i as seen from the body (joint frame turned by R(q)ᵀ), and
      // the free joint's G = e in inertial axes is [Rᵀ 0; 0 Rᵀ] in its own
      Mat3 Rm;
      Vec3 pm;
      joint_motion(type, model.axis[i], q.data() + model.idx_q[i], Rm, pm);
      Mat6G S(6, ni);
      if (type == JointType::Free) {
        const Mat3 Rt = (X.R * Rm).transpose();
        S.setZero();
        S.topLeftCorner<3, 3>() = Rt;
        S.bottomRightCorner<3, 3>() = Rt;
      } else {
        joint_subspace(type, model.axis[i], Rm.transpose(), Mat3::Identity(), S);
      }
      for (int m = 0; m < ni; ++m) F.col(begin + m) = K * S.col(m);
      for (int m = 0; m < ni; ++m)
        for (int pos = begin; pos < end; ++pos) {
          const int j = model.dfs_dof[pos];
          M[iv + m + j * nv] = M[j + (iv + m) * nv] = S.col(m).dot(F.col(pos));
        }
      if (p < 0) continue;
      // X_i = placement ∘ joint motion
      const Mat3 R = X.R * Rm;
      const Vec3 pr = X.p + X.R * pm;
      rotate_symmetric(R, K.I, K.I);
      K.h = R * K.h;
      move_columns(F, begin, end, R, pr);
      data.Kl[p].add_transformed(K, pr);
      continue;
    }
    // a unit-axis joint whose placement turns the frame, or a prismatic one: X_i = (X.R Rot, X.p + X.R x e_k)
    Mat3 R = X.R;
    Vec3 pr = X.p;
    if (type == JointType::Revolute) {
      turn_frame(X.R, k, data.turn(0, i), sign * data.turn(1, i), R);
    } else {
      pr += (sign * q(model.idx_q[i])) * X.R.col(k);
    }
    if (model.placement_turns[i] || type == JointType::Revolute) {
      rotate_symmetric(R, K.I, K.I);
      K.h = R * K.h;
    }
    move_columns(F, begin, end, R, pr);
    data.Kl[p].add_transformed(K, pr);
  }
}

}  // namespace soadyn
