// One peer library (MuJoCo, Pinocchio, RBDL) behind a plain interface for soadyn_bench.
//
// Each peer is a plugin, a shared object built from tools/bench/peer_<lib>.cpp with hidden symbols
// and loaded with dlopen(RTLD_LOCAL) by bench_peers.cpp.  The peer's own Eigen build (its
// alignment, its -march) then never meets soadyn's in one link: soadyn fixes
// EIGEN_MAX_ALIGN_BYTES=16 for its users, Pinocchio's library is built with Eigen's default, and
// the same inline Eigen function compiled both ways must not be merged.  Only this header's types
// cross the boundary: no Eigen, standard containers only.
#pragma once

// the compiler that built the plugin, for its version line (peer_plugin.cmake defines it)
#ifndef SOADYN_PEER_COMPILER
#define SOADYN_PEER_COMPILER "?"
#endif

#include <array>
#include <stdexcept>
#include <functional>
#include <string>
#include <vector>

namespace soadyn::bench {

// The model and the one state every library is given.  `joints` are the URDF joint names in the
// order of q, v and tau (soadyn's body order), each with one dof, and `links` their child links;
// every output uses the same order.
struct PeerProblem {
  std::string urdf;
  std::vector<std::string> joints, links;
  std::vector<double> q, v, tau;
  std::array<double, 3> gravity{0, 0, -9.81};
  std::string variant;  // one of the plugin's soadyn_bench_peer_variants(), "" for its default
  // the frame-Jacobian rows: a free root before `joints` (q = [x y z qw qx qy qz] in root_q, its 6
  // DOFs first in every output, in soadyn's v = [ω; ṗ], both inertial), and the URDF link whose
  // frame is asked for ("" for the mass, bias and forward rows)
  bool free_root = false;
  std::array<double, 7> root_q{0, 0, 0, 1, 0, 0, 0};
  std::string frame;
};

// The three timed calls; each recomputes everything it needs from (q, v, tau), as soadyn's do.
struct Peer {
  virtual ~Peer() = default;
  std::function<void()> mass;      // 𝓜(q)
  std::function<void()> bias;      // C(q, v): Coriolis, centrifugal and gravity terms
  std::function<void()> forward;   // q̈ from (q, v, tau) by the peer's O(N) recursion
  // untimed, after the matching call: 𝓜 row-major with both triangles, C, q̈
  std::function<std::vector<double>()> mass_out, bias_out, forward_out;
  // task-space calls from q, empty in a peer without them; out row-major, columns soadyn's v
  // (a free root's [ω; ṗ] first, inertial):
  //   frame_jacobian  the frame's Jacobian about its origin in inertial axes (Pinocchio's
  //                   LOCAL_WORLD_ALIGNED), 6 × nv, rows [ω; ṗ]
  //   com_jacobian    J_c, 3 × nv, ċ = J_c v
  //   centroidal_map  A_G, 6 × nv, h_G = A_G v about the centre of mass, rows [k_G; l]
  //   minverse        𝓜⁻¹, nv × nv, rows and columns soadyn's v
  std::function<void()> frame_jacobian, com_jacobian, centroidal_map, minverse;
  std::function<std::vector<double>()> frame_jacobian_out, com_jacobian_out, centroidal_map_out, minverse_out;
};

// x in the problem's order, from a peer's own: r[k] = x[idx[k]] (any indexable vector)
template <class Vector>
std::vector<double> permuted(const Vector& x, const std::vector<int>& idx) {
  std::vector<double> r(idx.size());
  for (size_t k = 0; k < idx.size(); ++k) r[k] = x[idx[k]];
  return r;
}

// soadyn_bench_make_peer's body: a new P for the problem, or nullptr and the reason in `error`
// (among them a variant that `variants`, the plugin's comma-separated list, does not name)
template <class P>
Peer* make_peer(const PeerProblem& problem, std::string& error, const std::string& variants = "") {
  if (!problem.variant.empty() && ("," + variants + ",").find("," + problem.variant + ",") == std::string::npos) {
    error = "no variant " + problem.variant;
    return nullptr;
  }
  try {
    return new P(problem);
  } catch (const std::exception& e) {
    error = e.what();
    return nullptr;
  }
}

}  // namespace soadyn::bench

// The symbols a plugin exports: a new Peer for the problem (the caller owns it), or nullptr with a
// one-line reason in `error`; the library's name, version and compiler, e.g. "Pinocchio 3.7.0
// (Clang 14.0.6)"; its variants beside the default, comma-separated (e.g. Pinocchio's "world"
// convention), each timed as a peer of its own; and the calls its Peers fill beyond mass, bias and
// forward, comma-separated ("frame_jacobian,com_jacobian,centroidal_map"), so that soadyn_bench registers only rows it can time.
#define SOADYN_BENCH_PEER_API extern "C" __attribute__((visibility("default")))
SOADYN_BENCH_PEER_API soadyn::bench::Peer* soadyn_bench_make_peer(const soadyn::bench::PeerProblem& problem,
                                                                  std::string& error);
SOADYN_BENCH_PEER_API const char* soadyn_bench_peer_version();
SOADYN_BENCH_PEER_API const char* soadyn_bench_peer_variants();
SOADYN_BENCH_PEER_API const char* soadyn_bench_peer_extra_calls();
