// Closed loops on the tree: constraints between a frame on body A and one on body B (or the
// world), held as the tree's equations of motion with multipliers,
//   𝓜 q̈ + Kᵀ λ = τ − bias,   K q̈ = −k̇,
// K (m × nv) the loops' velocity rows (K v = 0 on the loop) and k̇ = K̇ v their acceleration at
// q̈ = 0.  Each loop's rows, from its frames' poses (p, R), velocities (ω, ṗ) and Jacobians (J_A,
// J_B: [ω; ṗ] about the frame's origin, inertial axes; frames.hpp) and Δ = p_A − p_B:
//   point     3  ṗ_A − ṗ_B                          φ = Δ
//   hinge     5  ṗ_A − ṗ_B; n_i · (ω_A − ω_B), i = 1, 2,  n_i ⟂ the axis, fixed in B
//                                                  φ = Δ; n_i · a_A (a_A the axis fixed in A)
//   weld      6  ṗ_A − ṗ_B; ω_A − ω_B                φ = Δ; R_B log(R_Bᵀ R_A)
//   distance  1  u · (ṗ_A − ṗ_B), u = Δ / |Δ|        φ = |Δ| − d
// and their derivatives at q̈ = 0: p̈⁰_A − p̈⁰_B; (ω_B × n_i) · (ω_A − ω_B) + n_i · (α⁰_A − α⁰_B);
// α⁰_A − α⁰_B; u̇ · Δ̇ + u · Δ̈⁰ with u̇ = (Δ̇ − u (u · Δ̇)) / |Δ|.  φ(q) = 0 is the loop's closure
// (its rows vanish with K's on the loop: the projection and assembly drive it to zero).
//
// Forward dynamics with loops: q̈₀ by the articulated-body recursion, 𝓜⁻¹ Kᵀ by its factor (O(N)
// per row), the m × m matrix A = K 𝓜⁻¹ Kᵀ, A λ = K q̈₀ + k̇ solved by a rank-revealing factor (λ
// of minimum norm when rows depend on each other: a planar four-bar closed by a hinge), and
// q̈ = q̈₀ − 𝓜⁻¹ Kᵀ λ.  Inverse dynamics with loops: the actuated joints' q̈ given, the passive
// ones' from K q̈ = −k̇, λ from the passive rows of the equations of motion (their τ = 0), the
// actuators' τ from theirs.
#pragma once

#include "soadyn/multibody/data.hpp"
#include "soadyn/multibody/model.hpp"

#include <Eigen/QR>

#include <string>
#include <string_view>
#include <vector>

namespace soadyn {

enum class LoopType { Point, Hinge, Weld, Distance };
std::string_view to_string(LoopType t);
int loop_rows(LoopType t);  // 3, 5, 6, 1

// One loop: frame X_a on body_a against X_b on body_b (−1: the world).  hinge: the axis is X_a's z
// in A and X_b's z in B; weld: X_a and X_b coincide; distance: |p_A − p_B| = distance (> 0).
struct LoopConstraint {
  std::string name;
  LoopType type = LoopType::Point;
  int body_a = -1, body_b = -1;
  Placement at_a, at_b;
  double distance = 0.0;
};

// Each row's name "<loop>.<part>" (point: x y z; hinge: x y z n1 n2; weld: x y z rx ry rz;
// distance: tension) and its multiplier's unit (N, or N m for the angular rows): a run file's
// /loops/force columns
std::vector<std::string> loop_row_names(const std::vector<LoopConstraint>& loops);
std::vector<std::string> loop_row_units(const std::vector<LoopConstraint>& loops);

// Scratch and results of the loop functions for one model and one set of loops.
struct LoopData {
  LoopData() = default;
  LoopData(const Model& model, const std::vector<LoopConstraint>& loops);
  int m = 0;         // rows
  MatX K;            // m × nv
  VecX kdot;         // m: K̇ v
  VecX phi;          // m: the closure φ(q)
  VecX lambda;       // m: the multipliers of the last solve (N or N m per row)
  MatX MinvKt;       // nv × m: 𝓜⁻¹ Kᵀ
  MatX A;            // m × m: K 𝓜⁻¹ Kᵀ
  int rank = 0;      // A's rank at the last solve
  double margin = 1; // A's smallest kept pivot over its largest at the last solve (1 with no rows):
                     // it falls towards 0 as the loops near a singular configuration (a dead point)
  std::vector<int> row_loop;  // the loop of each row
  MatX J_a, J_b, work;        // 6 × nv each; articulated_solve's workspace
  // A's complete orthogonal decomposition and the solve's right-hand side, sized once (m × m, m):
  // an evaluation allocates neither
  Eigen::CompleteOrthogonalDecomposition<MatX> cod;
  VecX b;
};

// [kin][vel] K, k̇ and φ of the loops at the current state (O(m · depth))
void loop_rows(const Model& model, const Data& data, const std::vector<LoopConstraint>& loops, LoopData& ld);
// [kin] φ(q) alone (assembly, projection): ld.phi
void loop_closure(const Model& model, const Data& data, const std::vector<LoopConstraint>& loops, LoopData& ld);

// A loop closed to this (m, or rad for the angular rows): the projections' target
inline constexpr double kLoopClosure = 1e-12;

// The rank tolerance: singular values of A below this times the largest are dropped (their
// directions take no force: dependent rows)
inline constexpr double kLoopRankTolerance = 1e-10;

// A run stops at a singular configuration of its loops (a dead point, where their rows lose rank
// and the motion is not determined by them) when A's margin falls below this or its rank below the
// run's first (LoopData::margin; A's pivots go as the square of the distance to the dead point, so
// this is about 1e-4 rad from it)
inline constexpr double kLoopSingular = 1e-8;

// The loops whose own rows are singular at the last solve (A's diagonal block of each alone below
// the rank `first_rank` gave them, or its margin below kLoopSingular); every loop when no one
// alone is (the loops together are)
std::vector<int> singular_loops(const LoopData& ld, const std::vector<int>& first_rank);
// each loop's own rank (its diagonal block of A) at the last solve: singular_loops' reference
std::vector<int> loop_ranks(const LoopData& ld, int nloops);

// [kin][vel] q̈ of the tree closed by the loops under τ at velocity v (the one [vel] holds), into
// data.qdd; λ into ld.lambda.  Uses forward_dynamics' articulated-body route and leaves its factor
// in data.  `stabilize` (≥ 0, 1/s): Baumgarte's K q̈ = −k̇ − 2 s K v − s² φ (0: none; a run's
// projection holds the loop instead).
void loop_forward_dynamics(const Model& model, Data& data, const std::vector<LoopConstraint>& loops, const VecX& v,
                           const VecX& tau, LoopData& ld, double stabilize = 0.0);

// The same by forming 𝓜 and solving the saddle-point system densely (a reference for tests)
void loop_forward_dynamics_dense(const Model& model, Data& data, const std::vector<LoopConstraint>& loops,
                                 const VecX& tau, LoopData& ld);

// [kin][vel] Inverse dynamics with loops: `actuated` lists the DOFs whose q̈ is given (qdd's
// entries there; the others' are solved from K q̈ = −k̇ and written into qdd), every other DOF
// passive (τ = 0 there).  Returns τ (nv: the actuators', zero on the passive DOFs) and λ in
// ld.lambda.  Throws soadyn::Error when the passive DOFs are not determined by the loops (K's
// passive columns of lower rank than their number) or when the actuators cannot make the motion
// (the passive rows' equations of motion inconsistent with any λ beyond 1e-8 relative).
VecX loop_inverse_dynamics(const Model& model, Data& data, const std::vector<LoopConstraint>& loops,
                           const std::vector<int>& actuated, VecX& qdd, LoopData& ld);

}  // namespace soadyn
