// Per-state arrays, sized once from a Model: the results the algorithms leave, each field named
// with the stage that fills it, and apart from them each route's own workspace.
//   [kin]  update_kinematics(q)      [vel] update_velocities(v)
//   [crb]  mass_matrix               [rne] bias_forces / inverse_dynamics
//   [fd]   forward_dynamics
// Every entry point says which results it fills; it leaves every other result as it was.  Each
// result has one owner (M: mass_matrix, bias: bias_forces, tau: inverse_dynamics, qdd:
// forward_dynamics); the few calls that are their owner at the same state as well say so where
// they are declared (the composite forward-dynamics routes fill M and bias, forward_dynamics_derivatives
// and forward_dynamics_parameter_derivative q̈, regressor τ), and no other call writes a result:
// operational_space_inertia forms 𝓜 in M and puts mass_matrix's back.  (Python, where calls
// return views, holds every call to its own results: src/python/README.md.)  The workspace
// (Data::work) holds no result: what a route leaves there is unspecified and not part of the API.
// No algorithm allocates once a Data exists.
#pragma once

#include "soadyn/multibody/inertia.hpp"
#include "soadyn/multibody/model.hpp"

#include <Eigen/Cholesky>

#include <string>
#include <vector>

namespace soadyn {

// Memory the process may use: the machine's physical memory, or less under a soft RLIMIT_AS or
// RLIMIT_DATA (ulimit -v / -d).  A workspace larger than this is refused before it is allocated.
double memory_limit_bytes();
// Refuses (soadyn::Error) a workspace of `bytes` for a model of nv DOFs that exceeds
// memory_limit_bytes(), naming nv, what needs it and both sizes in GB.
void check_memory(double bytes, int nv, const std::string& what);

// Each route's scratch, apart from the results (Data::work).
struct Workspace {
  Eigen::Matrix2Xd turn;               // (cos θ_i, sin θ_i) of each revolute joint along a unit axis (Model::angles)
  // the composite-inertia 𝓜 (mass_matrix, mass_matrix(q) past 22 bodies, centroidal.cpp)
  struct Composite {
    std::vector<SpatialInertia> K;     // composite inertia of the subtree of i, about η_i
    Mat6X S0;                          // G_k moved to the inertial origin: [a; b + η_i × a]
    Mat6X F0;                          // K_i G_k moved to the inertial origin: [n + η_i × f; f]
    Eigen::Matrix<double, Eigen::Dynamic, 6> F0t;  // F0ᵀ, nv×6: a chain's entries column by column
  } composite;
  // the body-axes routes, mass_matrix(model, data, q) and bias_forces(model, data, q, v)
  struct BodyAxes {
    std::vector<SpatialInertia> K;     // composite inertia of the subtree of i, body i's axes, about η_i
    Mat6X Fcol;                        // K_j Ĝ_k of every DOF k, column dfs position of k, in the axes of
                                       //   the body the sweep is at
    Mat6X V, A, F;                     // v̂_i, â_i, f̂_i of each body, its own axes, about η_i
    std::vector<Mat3> Xr;              // (R, p) of body i: placement ∘ joint motion (the kinds whose X_i
    Mat3X Xp;                          //   is a general rigid motion)
    std::vector<Mat3> R;               // the frames of q (R, η, d, G as [kin] has them) for the route
    Mat3X eta, d;                      //   past 22 bodies, which leaves [kin] as it was
    Mat6X G;
  } local;
  // 𝓜 factored: in place as LᵀDL along the tree (row-major: the factorization walks rows), or dense
  struct Factor {
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> L;
    Eigen::LLT<MatX> llt;              // 𝓜 = L Lᵀ
  } factor;
  // the articulated-body recursion (aba, articulated_solve's factor)
  struct Articulated {
    std::vector<Mat6> P;               // articulated inertias
    Mat6X z;                           // articulated bias forces
    std::vector<Mat6G> U;              // U_i = P_i G_i (multi-DOF joints)
    Mat6X U1;                          // U_i = P_i g_i (1-DOF joints, column i)
    VecX Dinv1;                        // 1 / (g_iᵀ P_i g_i) (1-DOF joints)
    std::vector<MatGG> Dinv;           // (G_iᵀ P_i G_i)⁻¹ (multi-DOF joints)
    VecX u;                            // τ_i − G_iᵀ z_i
  } articulated;
  // 𝓜⁻¹ by the articulated-body recursion about the inertial origin (minverse.cpp; also
  // forward_dynamics_derivatives)
  struct Origin {
    Mat6X S;                           // G_k moved to the inertial origin: [a; b + η_i × a]
    std::vector<Mat6> P;               // articulated inertias about the origin
    Mat6X UD;                          // U_i 𝒟_i⁻¹ (U_i = P_i S_i, 𝒟_i = S_iᵀ U_i), column per DOF
    Eigen::Matrix<double, Eigen::Dynamic, 6> Z;  // nv×6: the bias force of each unit force, row per
                                                 //   depth-first position (Model::dfs_begin)
    MatX A;                            // nv × 6·Model::npaths: per path, each unit force's acceleration
                                       //   of the body the sweep is at, row per DOF
    VecX row;                          // a joint's rows of 𝓜⁻¹ in depth-first positions, nv
                                       //   apart (a model not numbered depth-first)
  } origin;
};

struct Data {
  // Data's dense nv×nv matrices (𝓜 and the two factors) and minverse's blocks (48 nv bytes per
  // path of the tree, Model::npaths) are its only quadratic part, checked against
  // memory_limit_bytes() before anything is allocated
  explicit Data(const Model& model);

  // always-on: the data was sized for this model and the vector has the expected size; a wrong
  // size would otherwise read or write past an array (soadyn::Error names what and where)
  void check(const Model& model, const char* where, const char* what, Eigen::Index got, int expected) const;

  // Which stages hold: update_kinematics sets [kin] and clears [vel] (its v belongs to the old q);
  // update_velocities sets [vel]; update_frames and update_frames_to, which leave s, r and M_i of
  // another q, clear both.  Every algorithm that reads a stage checks its flag first (one branch)
  // and refuses (soadyn::Error naming the call and the missing update) a stage that does not hold:
  // a fresh Data, or [vel] after update_kinematics at a new q.  The results' stages ([crb], [rne],
  // [fd]) are outputs and not tracked.
  struct Stages {
    bool kinematics = false;           // [kin] holds for the q last given to update_kinematics
    bool velocities = false;           // [vel] holds for that q and the v last given
  } stages;
  // throws soadyn::Error unless [kin] (and, with velocities, [vel]) holds
  void require(const char* where, bool velocities) const {
    if (!stages.kinematics || (velocities && !stages.velocities)) [[unlikely]] refuse_stage(where, velocities);
  }
  [[noreturn]] void refuse_stage(const char* where, bool velocities) const;

  // [kin] positions, all inertial (the note's symbols)
  std::vector<Mat3> R;                 // body i frame → inertial (C_i^in)
  Mat3X eta;                           // η_i, joint point of body i (its frame origin)
  Mat3X d;                             // d_i = η_i − η_parent(i)   (η_i itself at a root)
  Mat3X s;                             // s_i = r_i − η_i, joint to cm
  Mat3X r;                             // r_i, centre of mass
  Mat6X G;                             // 6×nv: columns idx_v[i].. are G_i (g_i in [g;0] or [0;g])
  std::vector<SpatialInertia> inertia; // M_i, body i's spatial inertia about η_i (eq. 12)

  // [vel] velocities and velocity-product terms
  Mat6X V;                             // v_i = [ω_i; η̇_i]      (eq. 4: v = Ψ_D G q̇)
  Mat6X Vbar;                          // v̄_i = [ω_i; ṙ_i]      (eq. 5: v̄ = S v)
  Mat6X coriolis;                      // 𝔞_i = Ḋ_i v_p + Ġ_i q̇_i, and [0; −g] at roots
  Mat6X gyroscopic;                    // 𝔟_i, the gyroscopic force pair about η_i

  // [crb] the system mass matrix
  MatX M;                              // 𝓜 (eq. 14), nv×nv, full symmetric (Python's data.M)

  // [rne] and [fd]
  Mat6X A;                             // v̇_i, each body's acceleration pair at the last q̈ (inverse
                                       //   dynamics, forward dynamics by aba, the centroidal bias)
  Mat6X F;                             // each joint's force pair about η_i (inverse dynamics, bias)
  VecX bias;                           // bias(q, q̇) incl. gravity, nv
  VecX tau;                            // inverse dynamics result, nv
  VecX qdd;                            // forward dynamics result, nv

  Workspace work;                      // each route's scratch: no results (see above)
};

}  // namespace soadyn
