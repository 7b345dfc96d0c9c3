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
// parent's: f' = R f, n' = R n + p × f' with (R, p) the child's placement ∘ joint motion (each
// joint kind's X_i and Ĝ_i: joint_local.hpp).  One driver, the kind chosen once per body.
//
// A DOF's F̂ is moved once per ancestor: O(N·depth) 6-vector moves, against the inertial sweep's
// O(N·depth) dot products of vectors moved once.  Past kLocalDepth the dot products win, and the
// entry point keeps the composites in body axes but moves each K̂ Ĝ once to the inertial origin,
// with the entries as the inertial sweep's dot products (mass_matrix_frames).  Columns are kept in
// depth-first order so that a subtree's are one run whatever the body order.
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"

#include "dynamics_routes.hpp"
#include "joint_local.hpp"
#include "mass_matrix_entries.hpp"

namespace soadyn {

namespace {

// deepest model the local route takes (one run, chains, local against mixed: N = 16 0.57–0.59
// against 0.63–0.65 µs, 20 0.80–0.86 against 0.88, 24 1.13–1.15 against 1.03–1.06, 32 1.70–1.75
// against 1.54–1.63)
constexpr int kLocalDepth = 22;

// K̂_i = M̂_i for every body: its own inertia, constant in its axes
void body_inertias(const Model& model, Data& data) {
  for (int i = 0; i < model.nbodies; ++i)
    data.work.local.K[i] = SpatialInertia::from_origin(model.mass[i], model.com[i], model.inertia_origin[i]);
}

// body i, its subtree's composite K̂_i complete and the subtree's F̂ in its axes:
// F̂ of its own DOFs = K̂_i Ĝ_i, 𝓜_jk = Ĝ_jᵀ F̂_k for its DOFs j and every DOF k of the subtree
// (both triangles), then F̂ and K̂_i moved to the parent.  Not inlined into the driver's switch:
// fourteen kinds' steps in one function cost a tree of 15 bodies 14 % in register spills; as a
// call each keeps its own registers (tools/bench tree/mass_q/15: 466 → 390–415 ns)
template <class J>
[[gnu::noinline]] void local_step(const J& joint, const Model& model, Data& data, const VecX& q, int i) {
  const auto X = local::transform(joint, model, data, q, i);
  const auto G = local::subspace(joint, X, model, i);
  constexpr int n = decltype(G)::nv;
  const int p = model.parent[i], iv = model.idx_v[i], begin = model.dfs_begin[i], end = model.dfs_end[i];
  const SpatialInertia& K = data.work.local.K[i];
  Mat6X& F = data.work.local.Fcol;
  G.times(K, F, begin);
  const Eigen::Index nv = data.M.rows();
  double* M = data.M.data();
  for (int m = 0; m < n; ++m)
    for (int pos = begin; pos < end; ++pos) {
      const int j = model.dfs_dof[pos];
      M[iv + m + j * nv] = M[j + (iv + m) * nv] = G.entry(m, F.col(pos).data());
    }
  if (p < 0) return;
  local::move_to_parent(X, F, begin, end);
  local::add_to_parent(X, K, data.work.local.K[p]);
}

// Deeper models: the composites in body axes as above, but each K̂_i Ĝ_k moved once to the
// inertial origin, F0_k = [R n̂ + η_i × R f̂; R f̂], and the entries as dot products with
// S0_j = [a; b + η × a] (mass_matrix_entries), from the frames alone (update_frames: no inertia
// turned into inertial axes).  K̂_i Ĝ = K̂_i Rᵀ G: [R I Rᵀ a + h_w × b; m b − h_w × a] in inertial
// axes, h_w = R h
template <class J>
[[gnu::flatten]] void frames_step(const J& joint, const Model& model, Data& data, const VecX& q, int i) {
  const Workspace::BodyAxes& w = data.work.local;  // the frames of q (update_frames into the workspace)
  const SpatialInertia& K = w.K[i];
  const Mat3& R = w.R[i];
  const Vec3 eta = w.eta.col(i), hw = R * K.h;
  const int p = model.parent[i], iv = model.idx_v[i];
  const auto X = local::transform(joint, model, data, q, i);
  using G_t = decltype(local::subspace(joint, X, model, i));
  for (int c = iv; c < iv + J::nv; ++c) {
    const Vec3 ga = w.G.col(c).head<3>(), gb = w.G.col(c).tail<3>();
    Vec3 nw, fw;
    if constexpr (local::angular_axis<G_t> >= 0) {
      nw.noalias() = joint.sign * (R * K.I.col(local::angular_axis<G_t>));  // R I Rᵀ a = ±R I e_k
      fw = ga.cross(hw);
    } else {
      nw.noalias() = R * (K.I * (R.transpose() * ga));
      nw += hw.cross(gb);
      fw = K.m * gb - hw.cross(ga);
    }
    nw += eta.cross(fw);
    data.work.composite.F0.col(c).head<3>() = nw;
    data.work.composite.F0.col(c).tail<3>() = fw;
    data.work.composite.S0.col(c).head<3>() = ga;
    data.work.composite.S0.col(c).tail<3>() = gb + eta.cross(ga);
  }
  if (p < 0) return;
  // K̂_p += X_i K̂_i X_iᵀ
  local::add_to_parent(X, K, data.work.local.K[p]);
}

void mass_matrix_frames(const Model& model, Data& data, const VecX& q) {
  detail::update_frames(model, data, q, data.work.local);
  body_inertias(model, data);
  for (int i = model.nbodies - 1; i >= 0; --i)
    visit_joint(model, i, [&](const auto& joint) { frames_step(joint, model, data, q, i); });
  mass_matrix_entries(model, data);
}

}  // namespace

void mass_matrix(const Model& model, Data& data, const VecX& q) {
  data.check(model, "mass_matrix", "q", q.size(), model.nq);
  if (model.depth > kLocalDepth) {
    mass_matrix_frames(model, data, q);
    return;
  }
  joint_turns(model, q, data.work.turn, false);
  body_inertias(model, data);
  for (int i = model.nbodies - 1; i >= 0; --i)
    visit_joint(model, i, [&](const auto& joint) { local_step(joint, model, data, q, i); });
}

}  // namespace soadyn
