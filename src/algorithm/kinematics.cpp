#include "soadyn/algorithm/kinematics.hpp"

#include "soadyn/algorithm/operators.hpp"

#include "dynamics_routes.hpp"
#include "joint_inertial.hpp"
#include "point_motion.hpp"

#include <cmath>

#if defined(SOADYN_MVEC) && defined(__AVX2__)
#define SOADYN_HAVE_MVEC 1
#else
#define SOADYN_HAVE_MVEC 0
#endif

#if SOADYN_HAVE_MVEC
#include <immintrin.h>
// glibc's libmvec (the x86-64 vector function ABI): 4 doubles in a ymm register
extern "C" __m256d _ZGVdN4v_cos(__m256d);
extern "C" __m256d _ZGVdN4v_sin(__m256d);
#endif

namespace soadyn {

namespace {

const Mat3 kIdentity = Mat3::Identity();

}  // namespace

namespace {

// (cos θ, sin θ) of every revolute joint along a unit axis (Model::angles), four at a time
// through glibc's vector math library where the library is built for AVX2, else one sincos each.
// The four angles are gathered into a register, not stored and read back whole: a wide load of
// narrow stores stalls the CPU (interleaved, chain N = 8: 50 → 16 ns; binary tree N = 15:
// 100 → 38 ns; a lone angle too: bias on one body 34 → 30 ns against the scalar sincos).
// Here: (cos, sin) of x[iq[t]] into column body[t] of turn, t = from .. nt − 1.
void turns_of(const int* body, const int* iq, int from, int nt, const double* x, Eigen::Matrix2Xd& turn) {
  int t = from;
#if SOADYN_HAVE_MVEC
  for (; t + 4 <= nt; t += 4) {
    const __m256d v = _mm256_setr_pd(x[iq[t]], x[iq[t + 1]], x[iq[t + 2]], x[iq[t + 3]]);
    const __m256d c = _ZGVdN4v_cos(v), s = _ZGVdN4v_sin(v);
    // (c0 s0 c2 s2), (c1 s1 c3 s3): each (cos, sin) pair one 16-byte store into its column
    const __m256d lo = _mm256_unpacklo_pd(c, s), hi = _mm256_unpackhi_pd(c, s);
    _mm_storeu_pd(turn.col(body[t]).data(), _mm256_castpd256_pd128(lo));
    _mm_storeu_pd(turn.col(body[t + 1]).data(), _mm256_castpd256_pd128(hi));
    _mm_storeu_pd(turn.col(body[t + 2]).data(), _mm256_extractf128_pd(lo, 1));
    _mm_storeu_pd(turn.col(body[t + 3]).data(), _mm256_extractf128_pd(hi, 1));
  }
  if (t < nt) {  // the last one to three
    const int rest = nt - t;
    const __m256d v = _mm256_setr_pd(x[iq[t]], rest > 1 ? x[iq[t + 1]] : 0.0, rest > 2 ? x[iq[t + 2]] : 0.0, 0.0);
    alignas(32) double c[4], s[4];
    _mm256_store_pd(c, _ZGVdN4v_cos(v));
    _mm256_store_pd(s, _ZGVdN4v_sin(v));
    for (int k = 0; k < rest; ++k) turn.col(body[t + k]) << c[k], s[k];
    t = nt;
  }
#endif
  for (; t < nt; ++t) {
    const double a = x[iq[t]], c = std::cos(a), s = std::sin(a);  // one sincos
    turn.col(body[t]) << c, s;
  }
}

}  // namespace

void joint_turns(const Model& model, const VecX& q, Eigen::Matrix2Xd& turn, bool roots) {
  const Model::AngleBatch& batch = model.angles;
  turns_of(batch.body.data(), batch.q.data(), roots ? 0 : batch.roots, int(batch.body.size()), q.data(), turn);
}

namespace {

// where a sweep writes the frames: [kin]'s own, or a route's workspace (Workspace::BodyAxes)
struct Frames {
  std::vector<Mat3>& R;
  Mat3X &eta, &d;
  Mat6X& G;
  Eigen::Matrix2Xd& turn;
};
Frames frames_of(Data& data) { return {data.R, data.eta, data.d, data.G, data.work.turn}; }

// Each kind's part of the kinematics step: from the parent's frame Rp and the joint point η (the
// placement's offset already added), the body's frame R, η moved by the joint, and G_i.
// A revolute joint along ±e_k: g_i = ±C_j e_k, and a turn by θ about it mixes only the other two
// columns of C_j (the batched (cos θ, sin θ) of f.turn, no 3×3 product); a prismatic one along
// ±e_k slides η by x g_i.  C_j = C_p X.R, or C_p itself where the placement does not turn.
template <int k>
inline void joint_frame(const joints::RevoluteAxis<k>& j, const Model& model, Frames& f, const VecX&, int i,
                        const Mat3& Rp, Mat3& R, Vec3&) {
  turn_frame(Rp, k, f.turn(0, i), j.sign * f.turn(1, i), R);
  f.G.col(model.idx_v[i]) << j.sign * Rp.col(k), Vec3::Zero();
}
template <int k>
inline void joint_frame(const joints::TurnedRevoluteAxis<k>& j, const Model& model, Frames& f, const VecX&, int i,
                        const Mat3& Rp, Mat3& R, Vec3&) {
  Mat3 Rj;
  Rj.noalias() = Rp * model.placement[i].R;
  turn_frame(Rj, k, f.turn(0, i), j.sign * f.turn(1, i), R);
  f.G.col(model.idx_v[i]) << j.sign * Rj.col(k), Vec3::Zero();
}
template <int k>
inline void joint_frame(const joints::PrismaticAxis<k>& j, const Model& model, Frames& f, const VecX& q, int i,
                        const Mat3& Rp, Mat3& R, Vec3& eta) {
  if (j.turned) R.noalias() = Rp * model.placement[i].R;
  else R = Rp;
  const Vec3 g = j.sign * R.col(k);
  eta += q(model.idx_q[i]) * g;
  f.G.col(model.idx_v[i]) << Vec3::Zero(), g;
}
// any other kind: C_i = C_j R(q), η += C_j p(q)
template <class J>
inline void joint_frame(const J& joint, const Model& model, Frames& f, const VecX& q, int i, const Mat3& Rp, Mat3& R,
                        Vec3& eta) {
  Mat3 Rj, Rm;
  Vec3 pm;
  Rj.noalias() = Rp * model.placement[i].R;
  joint.motion(q.data() + model.idx_q[i], Rm, pm);
  R.noalias() = Rj * Rm;
  eta.noalias() += Rj * pm;
  joint.subspace(Rj, R, f.G.middleCols<J::nv>(model.idx_v[i]));
}

// body i of the kinematics sweep, its parent's frame known and its joint's (cos θ, sin θ) in
// f.turn; kInertias = false stops at the frames (R, η, d, G)
template <bool kInertias, class J>
inline void kinematics_step(const J& joint, const Model& model, Data& data, Frames& f, const VecX& q, int i) {
  const int p = model.parent[i];
  const Mat3& Rp = p < 0 ? kIdentity : f.R[p];
  // η_j = η_p + C_p X.p, then the joint's own motion
  Vec3 eta = Rp * model.placement[i].p;
  if (p >= 0) eta += f.eta.col(p);
  Mat3& R = f.R[i];
  joint_frame(joint, model, f, q, i, Rp, R, eta);
  // d_i = η_i − η_p;  s_i = C_i com_i;  r_i = η_i + s_i;  M_i = (m_i, m_i s_i, C_i I_η C_iᵀ) (eq. 12)
  f.eta.col(i) = eta;
  f.d.col(i) = p < 0 ? eta : Vec3(eta - f.eta.col(p));
  if constexpr (!kInertias) return;
  const Vec3 s = R * model.com[i];
  data.s.col(i) = s;
  data.r.col(i) = eta + s;
  data.inertia[i].m = model.mass[i];
  data.inertia[i].h = model.mass[i] * s;
  rotate_symmetric(R, model.inertia_origin[i], data.inertia[i].I);
}

template <bool kInertias>
inline void kinematics_step(const Model& model, Data& data, Frames& f, const VecX& q, int i) {
  visit_joint(model, i, [&](const auto& joint) { kinematics_step<kInertias>(joint, model, data, f, q, i); });
}

template <bool kInertias>
void kinematics_sweep(const Model& model, Data& data, Frames f, const VecX& q) {
  joint_turns(model, q, f.turn);
  for (int i = 0; i < model.nbodies; ++i) kinematics_step<kInertias>(model, data, f, q, i);
}

// the frames of body b's ancestors and then b's, parent first: the path up from b, its turned
// joints' (cos θ, sin θ) four at a time as joint_turns does, then the sweep's step on each
// (a path longer than kPath, on the stack, takes the whole sweep)
void frames_to(const Model& model, Data& data, const VecX& q, int b) {
  constexpr int kPath = 64;
  int path[kPath], turn_body[kPath], turn_q[kPath];
  int n = 0, nt = 0;
  for (int i = b; i >= 0; i = model.parent[i]) {
    if (n == kPath) return kinematics_sweep<false>(model, data, frames_of(data), q);
    path[n++] = i;
    if (turns_by_angle(model.joint_model[i])) turn_body[nt] = i, turn_q[nt++] = model.idx_q[i];
  }
  Frames f = frames_of(data);
  turns_of(turn_body, turn_q, 0, nt, q.data(), f.turn);
  for (int k = n - 1; k >= 0; --k) kinematics_step<false>(model, data, f, q, path[k]);
}

}  // namespace

void update_kinematics(const Model& model, Data& data, const VecX& q) {
  data.check(model, "update_kinematics", "q", q.size(), model.nq);
  kinematics_sweep<true>(model, data, frames_of(data), q);
  data.stages = {true, false};
}

namespace detail {
void update_frames(const Model& model, Data& data, const VecX& q, Workspace::BodyAxes& out) {
  kinematics_sweep<false>(model, data, {out.R, out.eta, out.d, out.G, data.work.turn}, q);
}
}  // namespace detail

void update_frames(const Model& model, Data& data, const VecX& q) {
  data.check(model, "update_frames", "q", q.size(), model.nq);
  kinematics_sweep<false>(model, data, frames_of(data), q);
  data.stages = {false, false};  // s, r and M_i are another q's
}

void update_frames_to(const Model& model, Data& data, const VecX& q, int body) {
  data.check(model, "update_frames_to", "q", q.size(), model.nq);
  if (body < -1 || body >= model.nbodies)
    throw Error("update_frames_to: body: expected -1 (the world) .. " + std::to_string(model.nbodies - 1) + ", got " +
                std::to_string(body));
  if (body >= 0) frames_to(model, data, q, body);
  if (body >= 0) data.stages = {false, false};  // the other bodies' frames are another q's
}

void update_kinematics_reference(const Model& model, Data& data, const VecX& q) {
  data.check(model, "update_kinematics_reference", "q", q.size(), model.nq);
  for (int i = 0; i < model.nbodies; ++i) {
    const int p = model.parent[i];
    const Mat3 Rp = p < 0 ? Mat3::Identity() : data.R[p];
    const Vec3 eta_p = p < 0 ? Vec3::Zero() : Vec3(data.eta.col(p));
    // body frame = parent frame · placement · joint motion(q)
    const Mat3 Rj = Rp * model.placement[i].R;
    Mat3 Rm;
    Vec3 pm;
    joint_motion(model.joint_type[i], model.axis[i], q.data() + model.idx_q[i], Rm, pm, model.pitch[i]);
    data.R[i].noalias() = Rj * Rm;
    data.eta.col(i) = eta_p + Rp * model.placement[i].p + Rj * pm;
    // d_i = η_i − η_p;  s_i = C_i com_i;  r_i = η_i + s_i
    data.d.col(i) = data.eta.col(i) - eta_p;
    data.s.col(i) = data.R[i] * model.com[i];
    data.r.col(i) = data.eta.col(i) + data.s.col(i);
    joint_subspace(model.joint_type[i], model.axis[i], Rj, data.R[i], data.G.middleCols(model.idx_v[i], model.nv_i[i]),
                   model.pitch[i]);
    // M_i = [I_i − m s̃ s̃, m s̃; −m s̃, m e] (eq. 12); its upper-left block, the inertia about η_i,
    // is the body-frame one turned: C_i I_η C_iᵀ
    data.inertia[i].m = model.mass[i];
    data.inertia[i].h = model.mass[i] * data.s.col(i);
    data.inertia[i].I.noalias() = data.R[i] * model.inertia_origin[i] * data.R[i].transpose();
  }
  data.stages = {true, false};
}

void update_velocities(const Model& model, Data& data, const VecX& v) {
  data.check(model, "update_velocities", "v", v.size(), model.nv);
  data.require("update_velocities", false);
  // one base-to-tip sweep: (3)-(4) v_i = D_i v_p + G_i q̇_i, i.e. v = Ψ_D G q̇, with what the
  // dynamics needs of body i formed as soon as v_i is known.  6-vectors are read and written in
  // their 3-vector halves only (see rnea in rnea.cpp: whole reads of half-written columns
  // stall the CPU's store forwarding)
  for (int i = 0; i < model.nbodies; ++i) {
    const int p = model.parent[i], iv = model.idx_v[i];
    // G_i q̇_i = [gw; gu]
    Vec3 gw, gu;
    visit_joint(model, i, [&](const auto& j) {
      inertial::motion<std::decay_t<decltype(j)>>(data.G, iv, v.data() + iv, gw, gu);
    });
    Vec3 w = gw, u = gu;
    if (p < 0) {
      // gravity enters as a base acceleration −g
      data.coriolis.col(i).head<3>().setZero();
      data.coriolis.col(i).tail<3>() = -model.gravity;
    } else {
      // D_i v_p = [ω_p; η̇_p + ω_p × d_i]
      const Vec3 wp = data.V.col(p).head<3>(), up = data.V.col(p).tail<3>();
      w += wp;
      u += up + wp.cross(Vec3(data.d.col(i)));
      // 𝔞_i = Ḋ_i v_p + Ġ_i q̇_i with Ḋ_i v_p = [0; ω_p × ḋ_i], ḋ_i = η̇_i − η̇_p, and
      //   Ġ_i q̇_i = [ω_p × (G_i q̇_i)_ω; ω_p × (G_i q̇_i)_v] for every joint type (joint.hpp)
      data.coriolis.col(i).head<3>() = wp.cross(gw);
      data.coriolis.col(i).tail<3>() = wp.cross(gu) + wp.cross(Vec3(u - up));
    }
    data.V.col(i).head<3>() = w;
    data.V.col(i).tail<3>() = u;
    // (5) v̄_i = S_i v_i: ṙ_i = η̇_i + ω_i × s_i
    data.Vbar.col(i).head<3>() = w;
    data.Vbar.col(i).tail<3>() = u + w.cross(Vec3(data.s.col(i)));
    // gyroscopic force about η_i: f = m ω × (ω × s), n = ω × I ω + s × f = ω × (I − m s̃ s̃) ω
    const Vec3& h = data.inertia[i].h;
    data.gyroscopic.col(i).head<3>() = w.cross(data.inertia[i].I * w);
    data.gyroscopic.col(i).tail<3>() = w.cross(w.cross(h));
  }
  data.stages.velocities = true;
}

Mat6 D_matrix(const Data& data, int i) {
  Mat6 D = Mat6::Identity();
  D.bottomLeftCorner<3, 3>() = -skew(data.d.col(i));
  return D;
}

Mat6 S_matrix(const Data& data, int i) {
  Mat6 S = Mat6::Identity();
  S.bottomLeftCorner<3, 3>() = -skew(data.s.col(i));
  return S;
}

Mat6 M_matrix(const Data& data, int i) { return data.inertia[i].matrix(); }

Mat3 inertia_cm(const Data& data, int i) {
  const Vec3 s = data.s.col(i);
  return data.inertia[i].I - parallel_axis(data.inertia[i].m, s);
}

Mat6G G_matrix(const Model& model, const Data& data, int i) {
  return data.G.middleCols(model.idx_v[i], model.nv_i[i]);
}

void jacobian(const Model& model, const Data& data, MatX& J) {
  data.require("jacobian", false);
  // (7) J = S Ψ_D G: all columns at once, one base-to-tip sweep over 6×nv blocks
  J.setZero(6 * model.nbodies, model.nv);
  for (int i = 0; i < model.nbodies; ++i)
    J.block(6 * i, model.idx_v[i], 6, model.nv_i[i]) = G_matrix(model, data, i);
  psi_base_to_tip(model.parent, DOperator{data.d}, [&](int i) { return J.middleRows<6>(6 * i); });
  for (int i = 0; i < model.nbodies; ++i) {
    auto Ji = J.middleRows<6>(6 * i);
    Ji.bottomRows<3>() -= skew(data.s.col(i)) * Ji.topRows<3>();  // S_i = [e 0; −s̃_i e]
  }
}

Eigen::Vector4d attitude_quaternion(const Mat3& R) {
  Eigen::Quaterniond u(R);
  if (u.w() < 0) u.coeffs() = -u.coeffs();
  return {u.w(), u.x(), u.y(), u.z()};
}

namespace detail {

// α and p̈ of the body's point p (point_motion.hpp):
// v̇_b = [Ψ_D (G q̈ + 𝔞)]_b = Σ_{j ≤ b} D_{b:j} x_j, x_j = G_j q̈_j + 𝔞_j (a root's 𝔞 is zero: the
// −g Data::coriolis holds there is gravity's base acceleration, not the frame's), then
// p̈ = η̈_b + α × r + ω × (ω × r), r = p − η_b
void point_acceleration(const Model& model, const Data& data, int b, const Vec3& p, const VecX* qdd, Vec3& alpha,
                        Vec3& pdd) {
  alpha.setZero(), pdd.setZero();
  if (b < 0) return;
  const Vec3 eta_b = data.eta.col(b);
  for (int j = b; j >= 0; j = model.parent[j]) {
    Vec3 xw = Vec3::Zero(), xv = Vec3::Zero();
    if (model.parent[j] >= 0) xw = data.coriolis.col(j).head<3>(), xv = data.coriolis.col(j).tail<3>();
    if (qdd) {
      Vec3 gw, gu;
      visit_joint(model, j, [&](const auto& joint) {
        inertial::motion<std::decay_t<decltype(joint)>>(data.G, model.idx_v[j], qdd->data() + model.idx_v[j], gw, gu);
      });
      xw += gw, xv += gu;
    }
    // D_{b:j} x = [x_ω; x_v + x_ω × (η_b − η_j)]
    alpha += xw;
    pdd += xv + xw.cross(eta_b - data.eta.col(j));
  }
  const Vec3 w = data.V.col(b).head<3>(), r = p - eta_b;
  pdd += alpha.cross(r) + w.cross(w.cross(r));
}

}  // namespace detail

}  // namespace soadyn
