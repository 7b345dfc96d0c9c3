// soadyn against its peers in the same run, on the same URDF chains and binary trees
// (tools/bench/make_models.py) and the same state, every call starting from q (and v, tau):
//   peer/<shape>/mass/<lib>   soadyn mass_matrix(q) (the local-frame route, from q alone)
//   peer/<shape>/bias/<lib>   soadyn bias_forces(q, v) (the body-axes route, from q and v alone)
//   peer/<shape>/rhs/<lib>    soadyn update_kinematics + update_velocities + O(N) forward_dynamics
// and each peer's calls for the same quantities (peer_<lib>.cpp says which), and on robots:
//   peer/frame_jacobian/<robot>/<lib>   soadyn frame_jacobian(q, frame, local_world_aligned)
//                                       against Pinocchio's computeFrameJacobian (nv as the arg)
//   peer/com_jacobian/<robot>/<lib>     com_jacobian(q) against jacobianCenterOfMass(q)
//   peer/centroidal_map/<robot>/<lib>   update_kinematics + centroidal_momentum_matrix against
//                                       computeCentroidalMap(q)
//   peer/minverse/<robot>/<lib>         update_kinematics + minverse against computeMinverse(q)
// for the robots of kFrameRobots (their URDFs in the models directory, tools/bench/run.sh).  The peers are
// plugins (peer.hpp) that CMake built when it found the library: MuJoCo always looked up,
// Pinocchio and RBDL under -DSOADYN_PEERS_PREFIX.
// Before a peer is timed on a model it must agree with soadyn there: 𝓜 to 1e-9 of max|𝓜|, bias
// to 1e-9 of max(max|C|, 1), and its q̈ must solve soadyn's 𝓜 q̈ = τ − C with a backward error
// below 1e-9.  A peer that fails, or cannot load the model, is skipped with the reason (the JSON
// holds it as an error); a fast wrong peer is never reported.
#include "models.hpp"
#include "peer.hpp"

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/frames.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/io/scenario_file.hpp"

#include <benchmark/benchmark.h>
#include <dlfcn.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#ifndef SOADYN_BENCH_PEERS
#define SOADYN_BENCH_PEERS ""  // "name=plugin.so,name=plugin.so"
#endif
#ifndef SOADYN_BENCH_PEERS_NOTE
#define SOADYN_BENCH_PEERS_NOTE ""  // why a peer was left out at configure time
#endif

namespace soadyn::bench {
namespace {

using Factory = Peer* (*)(const PeerProblem&, std::string&);
using Text = const char* (*)();

// A loaded plugin; RAII around the dlopen handle.
struct Plugin {
  std::string name;
  void* handle = nullptr;
  Factory make = nullptr;
  std::string version, variants, extra_calls;
  Plugin(std::string n, const std::string& path) : name(std::move(n)) {
    handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) throw std::runtime_error(dlerror());
    make = reinterpret_cast<Factory>(dlsym(handle, "soadyn_bench_make_peer"));
    const auto v = reinterpret_cast<Text>(dlsym(handle, "soadyn_bench_peer_version"));
    const auto w = reinterpret_cast<Text>(dlsym(handle, "soadyn_bench_peer_variants"));
    const auto x = reinterpret_cast<Text>(dlsym(handle, "soadyn_bench_peer_extra_calls"));
    if (!make || !v || !w || !x) {
      dlclose(handle);
      throw std::runtime_error(path + " is not a soadyn_bench peer");
    }
    version = v();
    variants = w();
    extra_calls = x();
  }
  bool has(const std::string& call) const { return ("," + extra_calls + ",").find("," + call + ",") != std::string::npos; }
  Plugin(const Plugin&) = delete;
  Plugin& operator=(const Plugin&) = delete;
  ~Plugin() { dlclose(handle); }
};

std::vector<std::unique_ptr<Plugin>>& plugins() {
  static std::vector<std::unique_ptr<Plugin>> p;
  return p;
}

// One timed peer: a plugin and one of its variants, named "lib" or "lib-variant".
struct Entry {
  const Plugin* plugin;
  std::string variant, name;
};

std::string models_dir() {
  const char* d = std::getenv("SOADYN_BENCH_MODELS");
  return d ? d : "build/bench_models";
}

enum Quantity { kMass, kBias, kRhs };
const char* const kQuantity[] = {"mass", "bias", "rhs"};

// soadyn on the URDF, its state, and the same problem for a peer (soadyn's dof order)
struct Setup {
  std::string file;
  Model model;
  Data data;
  VecX q, v, tau;
  PeerProblem problem;
  Setup(const std::string& shape, int n)
      : file(shape + "_" + std::to_string(n) + ".urdf"),
        model(load_urdf(models_dir() + "/" + file, false, Vec3(0, 0, -9.81))),
        data(model),
        q(random_vector(model.nq, 1, 3.0)),
        v(random_vector(model.nv, 2)),
        tau(random_vector(model.nv, 3)) {
    problem.urdf = models_dir() + "/" + file;
    for (int i = 0; i < model.nbodies; ++i) {
      if (model.nv_i[i] != 1 || model.nq_i[i] != 1) throw std::runtime_error(file + ": a joint without one dof");
      problem.joints.push_back(model.joint_names[i]);
      problem.links.push_back(model.body_names[i]);
    }
    std::vector<double> qv(model.nv), vv(model.nv), tv(model.nv);
    for (int i = 0; i < model.nbodies; ++i) {
      const int k = model.idx_v[i];  // problem order is body order; dof k of body i
      qv[size_t(i)] = q(model.idx_q[i]);
      vv[size_t(i)] = v(k);
      tv[size_t(i)] = tau(k);
    }
    problem.q = qv, problem.v = vv, problem.tau = tv;
  }
  void mass() {
    mass_matrix(model, data, q);
  }
  void bias() {
    bias_forces(model, data, q, v);
  }
  void rhs() {
    update_kinematics(model, data, q);
    update_velocities(model, data, v);
    forward_dynamics(model, data, tau, FdMethod::ArticulatedBody);
  }
};

// The peer's 𝓜, C and q̈ against soadyn's; empty when they agree, else the reason.
std::string disagreement(Setup& s, Peer& p, benchmark::State& st) {
  const int n = s.model.nv;
  s.bias();  // kinematics, velocities, C
  const VecX C = s.data.bias;
  s.mass();
  const MatX M = s.data.M;
  auto in_body_order = [&](const std::vector<double>& x) {
    VecX r(n);
    for (int i = 0; i < n; ++i) r(s.model.idx_v[i]) = x[size_t(i)];
    return r;
  };
  p.mass();
  const std::vector<double> pm = p.mass_out();
  MatX Mp(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) Mp(s.model.idx_v[i], s.model.idx_v[j]) = pm[size_t(i) * n + j];
  p.bias();
  const VecX Cp = in_body_order(p.bias_out());
  p.forward();
  const VecX qdd = in_body_order(p.forward_out());
  const double dM = (Mp - M).cwiseAbs().maxCoeff() / M.cwiseAbs().maxCoeff();
  const double dC = (Cp - C).cwiseAbs().maxCoeff() / std::max(C.cwiseAbs().maxCoeff(), 1.0);
  const VecX tau = in_body_order(s.problem.tau);
  const double inf = M.cwiseAbs().rowwise().sum().maxCoeff();
  const double dq = (M * qdd + C - tau).cwiseAbs().maxCoeff() /
                    (inf * qdd.cwiseAbs().maxCoeff() + C.cwiseAbs().maxCoeff() + tau.cwiseAbs().maxCoeff());
  st.counters["dM"] = dM, st.counters["dC"] = dC, st.counters["dqdd"] = dq;
  std::ostringstream os;
  os.precision(2);
  if (!(dM <= 1e-9)) os << " 𝓜 " << dM;
  if (!(dC <= 1e-9)) os << " bias " << dC;
  if (!(dq <= 1e-9)) os << " q̈ (backward error) " << dq;
  return os.str();
}

// entry's peer on the problem (its variant set), or nullptr with the benchmark skipped, naming file
std::unique_ptr<Peer> make_peer(benchmark::State& st, const Entry& entry, PeerProblem& problem, const std::string& file) {
  std::string error;
  problem.variant = entry.variant;
  std::unique_ptr<Peer> peer(entry.plugin->make(problem, error));
  if (!peer) st.SkipWithError((entry.name + " cannot load " + file + ": " + error).c_str());
  return peer;
}

void run(benchmark::State& st, const std::string& shape, Quantity quantity, const Entry* entry) {
  Setup s(shape, int(st.range(0)));
  st.counters["N"] = double(st.range(0));
  if (!entry) {
    for (auto _ : st) {
      if (quantity == kMass) s.mass();
      else if (quantity == kBias) s.bias();
      else s.rhs();
      benchmark::ClobberMemory();
    }
    return;
  }
  std::unique_ptr<Peer> peer = make_peer(st, *entry, s.problem, s.file);
  if (!peer) return;
  if (const std::string why = disagreement(s, *peer, st); !why.empty()) {
    st.SkipWithError((entry->name + " disagrees with soadyn on " + s.file + ":" + why + " (limit 1e-9)").c_str());
    return;
  }
  const std::function<void()>& call = quantity == kMass ? peer->mass : quantity == kBias ? peer->bias : peer->forward;
  for (auto _ : st) {
    call();
    benchmark::ClobberMemory();
  }
}

// The frame-Jacobian rows: a robot's URDF, whether its root floats, and the frame (a URDF link).
struct FrameRobot {
  const char* name;
  const char* urdf;
  bool free_root;
  const char* frame;
};
const FrameRobot kFrameRobots[] = {
    {"arm7", "arm7.urdf", false, "link_7"},                       // tests/data/arm7.urdf: the 7-DOF arm's flange
    {"humanoid", "humanoid.urdf", true, "left_index_tip"},        // tools/humanoid_urdf.py: 50 DOF on a free root
    {"chain_8", "chain_8.urdf", false, "link8"},                  // tools/bench/make_models.py's chains: the tip
    {"chain_32", "chain_32.urdf", false, "link32"},
    {"chain_64", "chain_64.urdf", false, "link64"},
};

// soadyn on the robot at a random state, and the same problem for a peer: the free root's q, then
// the 1-DOF joints in soadyn's body order
struct FrameSetup {
  Model model;
  Data data;
  VecX q;
  int frame;
  MatX J;  // soadyn's output of the timed call
  PeerProblem problem;
  explicit FrameSetup(const FrameRobot& r)
      : model(load_urdf(models_dir() + "/" + r.urdf, r.free_root, Vec3(0, 0, -9.81))), data(model), J(6, model.nv) {
    q = random_vector(model.nq, 5, 1.5);
    model.normalize(q);
    frame = model.frame_index(r.frame);
    if (frame < 0) throw std::runtime_error(std::string(r.urdf) + ": no frame " + r.frame);
    problem.urdf = models_dir() + "/" + r.urdf;
    problem.free_root = r.free_root;
    problem.frame = r.frame;
    for (int i = 0; i < model.nbodies; ++i) {
      if (r.free_root && i == 0) {
        for (int k = 0; k < 7; ++k) problem.root_q[size_t(k)] = q(k);
        continue;
      }
      if (model.nv_i[i] != 1 || model.nq_i[i] != 1) throw std::runtime_error(std::string(r.urdf) + ": a joint without one dof");
      problem.joints.push_back(model.joint_names[i]);
      problem.links.push_back(model.body_names[i]);
      problem.q.push_back(q(model.idx_q[i]));
      problem.v.push_back(0.0);
      problem.tau.push_back(0.0);
    }
  }
};

// The task-space rows: one matrix from q, by soadyn and by a peer (peer.hpp says each's layout)
enum TaskCall { kFrameJacobian, kComJacobian, kCentroidalMap, kMinverse };
const char* const kTaskCall[] = {"frame_jacobian", "com_jacobian", "centroidal_map", "minverse"};

// soadyn's, from q alone, as the peers' calls: the frame's ancestors' frames then its Jacobian;
// the frames then J_c from the subtrees' masses and first moments; the kinematics then A_G (frames.hpp)
void task_call(FrameSetup& s, TaskCall call) {
  switch (call) {
    case kFrameJacobian: frame_jacobian(s.model, s.data, s.q, s.frame, Reference::LocalWorldAligned, s.J); return;
    case kComJacobian: com_jacobian(s.model, s.data, s.q, s.J); return;
    case kCentroidalMap: update_kinematics(s.model, s.data, s.q); centroidal_momentum_matrix(s.model, s.data, s.J); return;
    case kMinverse: update_kinematics(s.model, s.data, s.q); minverse(s.model, s.data, s.J); return;
  }
}

void run_task(benchmark::State& st, const FrameRobot* robot, TaskCall call, const Entry* entry) {
  FrameSetup s(*robot);
  st.counters["N"] = double(s.model.nv);
  if (!entry) {
    for (auto _ : st) {
      task_call(s, call);
      benchmark::ClobberMemory();
    }
    return;
  }
  std::unique_ptr<Peer> peer = make_peer(st, *entry, s.problem, robot->urdf);
  if (!peer) return;
  const std::function<void()>& timed = call == kFrameJacobian ? peer->frame_jacobian
                                       : call == kComJacobian  ? peer->com_jacobian
                                       : call == kMinverse     ? peer->minverse
                                                               : peer->centroidal_map;
  const std::function<std::vector<double>()>& out = call == kFrameJacobian ? peer->frame_jacobian_out
                                                    : call == kComJacobian  ? peer->com_jacobian_out
                                                    : call == kMinverse     ? peer->minverse_out
                                                                            : peer->centroidal_map_out;
  if (!timed || !out) {
    st.SkipWithError((entry->name + ": no " + kTaskCall[call] + " call").c_str());
    return;
  }
  // the same quantity: the peer's matrix against soadyn's, to 1e-10 of its largest entry (the
  // frame Jacobian by the staged route, update_frames then frame_jacobian, not the timed one)
  MatX J;
  if (call == kFrameJacobian) {
    update_frames(s.model, s.data, s.q);
    frame_jacobian(s.model, s.data, s.frame, Reference::LocalWorldAligned, J);
  } else {
    task_call(s, call);
    J = s.J;
  }
  timed();
  const std::vector<double> pj = out();
  if (pj.size() != size_t(J.size())) {
    st.SkipWithError((entry->name + ": " + kTaskCall[call] + " of " + std::to_string(pj.size()) + " entries, soadyn's " +
                      std::to_string(J.size())).c_str());
    return;
  }
  MatX Jp(J.rows(), J.cols());
  for (Eigen::Index i = 0; i < J.rows(); ++i)
    for (Eigen::Index j = 0; j < J.cols(); ++j) Jp(i, j) = pj[size_t(i * J.cols() + j)];
  const double dJ = (Jp - J).cwiseAbs().maxCoeff() / J.cwiseAbs().maxCoeff();
  st.counters["dJ"] = dJ;
  if (!(dJ <= 1e-10)) {
    std::ostringstream os;
    os.precision(2);
    os << entry->name << " disagrees with soadyn on " << robot->urdf << ": " << kTaskCall[call] << " " << dJ << " (limit 1e-10)";
    st.SkipWithError(os.str().c_str());
    return;
  }
  for (auto _ : st) {
    timed();
    benchmark::ClobberMemory();
  }
}

}  // namespace

// Loads the plugins CMake built and registers the peer benchmarks, N-major so that soadyn and its
// peers at one N run back to back.  Prints one note for every peer left out.
void register_peers() {
  std::string missing = SOADYN_BENCH_PEERS_NOTE;
  std::stringstream list(SOADYN_BENCH_PEERS);
  for (std::string item; std::getline(list, item, ',');) {
    const auto eq = item.find('=');
    if (eq == std::string::npos) continue;
    try {
      plugins().push_back(std::make_unique<Plugin>(item.substr(0, eq), item.substr(eq + 1)));
    } catch (const std::exception& e) {
      missing += (missing.empty() ? "" : "; ") + item.substr(0, eq) + " not loaded: " + e.what();
    }
  }
  if (!missing.empty()) {
    std::fprintf(stderr, "peers left out: %s\n", missing.c_str());
    benchmark::AddCustomContext("peers_left_out", missing);
  }
  if (plugins().empty()) return;  // nothing to compare soadyn with
  static std::vector<Entry> entries;
  for (const auto& p : plugins()) {
    benchmark::AddCustomContext("peer_" + p->name, p->version);
    entries.push_back({p.get(), "", p->name});
    std::stringstream variants(p->variants);
    for (std::string v; std::getline(variants, v, ',');)
      if (!v.empty()) {
        entries.push_back({p.get(), v, p->name + "-" + v});
        benchmark::AddCustomContext("peer_" + entries.back().name, p->version + ", variant " + v);
      }
  }
  for (const FrameRobot& r : kFrameRobots) {
    int nv = 0;
    try {
      nv = load_urdf(models_dir() + "/" + r.urdf, r.free_root, Vec3(0, 0, -9.81)).nv;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "task-space rows on %s left out: %s\n", r.name, e.what());
      continue;
    }
    for (TaskCall call : {kFrameJacobian, kComJacobian, kCentroidalMap, kMinverse}) {
      const std::string base = std::string("peer/") + kTaskCall[call] + "/" + r.name + "/";
      benchmark::RegisterBenchmark((base + "soadyn").c_str(), run_task, &r, call, nullptr)->Arg(nv);
      for (const Entry& e : entries)
        if (e.plugin->has(kTaskCall[call]))
          benchmark::RegisterBenchmark((base + e.name).c_str(), run_task, &r, call, &e)->Arg(nv);
    }
  }
  std::string no_tasks;
  for (const auto& p : plugins())
    if (p->extra_calls.empty()) no_tasks += (no_tasks.empty() ? "" : ", ") + p->name;
  if (!no_tasks.empty()) std::fprintf(stderr, "task-space rows without %s (their plugins do not time those calls)\n", no_tasks.c_str());
  const std::vector<int> chain{1, 2, 4, 8, 16, 32, 64, 128, 256}, tree{1, 3, 7, 15, 31, 63, 127, 255};
  for (const std::string shape : {"chain", "tree"}) {
    for (int n : shape == "chain" ? chain : tree) {
      for (Quantity quantity : {kMass, kBias, kRhs}) {
        const std::string base = "peer/" + shape + "/" + kQuantity[quantity] + "/";
        benchmark::RegisterBenchmark((base + "soadyn").c_str(), run, shape, quantity, nullptr)->Arg(n);
        for (const Entry& e : entries)
          benchmark::RegisterBenchmark((base + e.name).c_str(), run, shape, quantity, &e)->Arg(n);
      }
    }
  }
}

}  // namespace soadyn::bench
