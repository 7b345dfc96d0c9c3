// MuJoCo as a soadyn_bench peer (plugin; see peer.hpp), on the same URDF (its <mujoco> block turns
// off the importer's inertia balancing and body fusion):
//   mass     mj_kinematics + mj_comPos + mj_crb + mj_fullM
//   bias     mj_kinematics + mj_comPos + mj_comVel + mj_rne(flg_acc = 0)
//   forward  mj_forward with contacts, limits, passive forces and constraints off (tau applied as
//            qfrc_applied; its q̈ comes from a dense LᵀDL of 𝓜, MuJoCo has no O(N) route)
#include "peer.hpp"

#include <mujoco/mujoco.h>

#include <exception>
#include <stdexcept>

namespace {
using soadyn::bench::PeerProblem;

// RAII for the model and data handles
struct MjModel {
  mjModel* m = nullptr;
  explicit MjModel(const std::string& path) {
    char err[1000] = "";
    m = mj_loadXML(path.c_str(), nullptr, err, sizeof err);
    if (!m) throw std::runtime_error(std::string("mj_loadXML: ") + err);
  }
  MjModel(const MjModel&) = delete;
  MjModel& operator=(const MjModel&) = delete;
  ~MjModel() { mj_deleteModel(m); }
};
struct MjData {
  mjData* d;
  explicit MjData(const mjModel* m) : d(mj_makeData(m)) {
    if (!d) throw std::runtime_error("mj_makeData failed");
  }
  MjData(const MjData&) = delete;
  MjData& operator=(const MjData&) = delete;
  ~MjData() { mj_deleteData(d); }
};

struct MuJoCo : soadyn::bench::Peer {
  MjModel model;
  MjData data;
  std::vector<double> full, rne;
  std::vector<int> idx;  // problem order k -> MuJoCo dof

  explicit MuJoCo(const PeerProblem& p) : model(p.urdf), data(model.m) {
    mjModel* m = model.m;
    mjData* d = data.d;
    const int n = int(p.joints.size());
    if (m->nv != n || m->nq != n) throw std::runtime_error("nv = " + std::to_string(m->nv) + ", soadyn has " + std::to_string(n));
    m->opt.disableflags |= mjDSBL_CONTACT | mjDSBL_LIMIT | mjDSBL_PASSIVE | mjDSBL_CONSTRAINT;
    for (int k = 0; k < 3; ++k) m->opt.gravity[k] = p.gravity[k];
    for (int k = 0; k < n; ++k) {
      const int j = mj_name2id(m, mjOBJ_JOINT, p.joints[k].c_str());
      if (j < 0) throw std::runtime_error("no joint " + p.joints[k]);
      d->qpos[m->jnt_qposadr[j]] = p.q[k];
      d->qvel[m->jnt_dofadr[j]] = p.v[k];
      d->qfrc_applied[m->jnt_dofadr[j]] = p.tau[k];
      idx.push_back(m->jnt_dofadr[j]);
    }
    full.resize(size_t(n) * n);
    rne.resize(n);
    mass = [m, d, this] {
      mj_kinematics(m, d);
      mj_comPos(m, d);
      mj_crb(m, d);
      mj_fullM(m, full.data(), d->qM);
    };
    bias = [m, d, this] {
      mj_kinematics(m, d);
      mj_comPos(m, d);
      mj_comVel(m, d);
      mj_rne(m, d, 0, rne.data());
    };
    forward = [m, d] { mj_forward(m, d); };
    mass_out = [this] {
      const size_t nv = idx.size();
      std::vector<double> r(nv * nv);
      for (size_t i = 0; i < nv; ++i)
        for (size_t j = 0; j < nv; ++j) r[i * nv + j] = full[size_t(idx[i]) * nv + size_t(idx[j])];
      return r;
    };
    bias_out = [this] { return soadyn::bench::permuted(rne.data(), idx); };
    forward_out = [this] { return soadyn::bench::permuted(data.d->qacc, idx); };
  }
};

}  // namespace

soadyn::bench::Peer* soadyn_bench_make_peer(const PeerProblem& problem, std::string& error) {
  return soadyn::bench::make_peer<MuJoCo>(problem, error);
}

const char* soadyn_bench_peer_version() {
  static const std::string v = std::string("MuJoCo ") + mj_versionString();
  return v.c_str();
}

const char* soadyn_bench_peer_variants() { return ""; }

const char* soadyn_bench_peer_extra_calls() { return ""; }
