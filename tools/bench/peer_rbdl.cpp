// RBDL 3 as a soadyn_bench peer (plugin; see peer.hpp):
//   mass     CompositeRigidBodyAlgorithm(q, H, update_kinematics = true)
//   bias     NonlinearEffects(q, v)
//   forward  ForwardDynamics(q, v, tau)   (the articulated-body algorithm)
// The URDF is read by RBDL's URDF reader (addons/urdfreader) with a fixed base.  Each dof is found
// through the child link of its URDF joint: RBDL names bodies after links.
#include "peer.hpp"

#include <rbdl/addons/urdfreader/urdfreader.h>
#include <rbdl/rbdl.h>

#include <exception>
#include <limits>
#include <stdexcept>

namespace {
namespace R = RigidBodyDynamics;
using soadyn::bench::PeerProblem;

struct Rbdl : soadyn::bench::Peer {
  R::Model model;
  R::Math::VectorNd q, v, tau, qdd, nle;
  R::Math::MatrixNd H;
  std::vector<int> idx;  // problem order k -> RBDL dof

  explicit Rbdl(const PeerProblem& p) {
    if (!R::Addons::URDFReadFromFile(p.urdf.c_str(), &model, false, false))
      throw std::runtime_error("URDFReadFromFile failed on " + p.urdf);
    model.gravity = R::Math::Vector3d(p.gravity[0], p.gravity[1], p.gravity[2]);
    const int n = int(p.joints.size());
    if (int(model.dof_count) != n || int(model.q_size) != n)
      throw std::runtime_error("dof_count = " + std::to_string(model.dof_count) + ", soadyn has " + std::to_string(n));
    q = v = tau = qdd = nle = R::Math::VectorNd::Zero(n);
    H = R::Math::MatrixNd::Zero(n, n);  // once: CompositeRigidBodyAlgorithm writes only what can be non-zero
    for (int k = 0; k < n; ++k) {
      const unsigned id = model.GetBodyId(p.links[k].c_str());
      if (id == std::numeric_limits<unsigned>::max() || model.IsFixedBodyId(id) || model.mJoints[id].mDoFCount != 1)
        throw std::runtime_error("no 1-dof body " + p.links[k]);
      const int i = int(model.mJoints[id].q_index);
      q[i] = p.q[k];
      v[i] = p.v[k];
      tau[i] = p.tau[k];
      idx.push_back(i);
    }
    mass = [this] { R::CompositeRigidBodyAlgorithm(model, q, H, true); };
    bias = [this] { R::NonlinearEffects(model, q, v, nle); };
    forward = [this] { R::ForwardDynamics(model, q, v, tau, qdd); };
    mass_out = [this] {
      std::vector<double> r(idx.size() * idx.size());
      for (size_t i = 0; i < idx.size(); ++i)
        for (size_t j = 0; j < idx.size(); ++j) r[i * idx.size() + j] = H(idx[i], idx[j]);
      return r;
    };
    bias_out = [this] { return soadyn::bench::permuted(nle, idx); };
    forward_out = [this] { return soadyn::bench::permuted(qdd, idx); };
  }
};

}  // namespace

soadyn::bench::Peer* soadyn_bench_make_peer(const PeerProblem& problem, std::string& error) {
  return soadyn::bench::make_peer<Rbdl>(problem, error);
}

const char* soadyn_bench_peer_version() {
  static const std::string v = [] {
    const int api = (RBDL_API_VERSION);  // the macro lacks outer parentheses
    return "RBDL " + std::to_string(api >> 16) + "." + std::to_string((api >> 8) & 0xff) + "." +
           std::to_string(api & 0xff) + " (" SOADYN_PEER_COMPILER ")";
  }();
  return v.c_str();
}

const char* soadyn_bench_peer_variants() { return ""; }

const char* soadyn_bench_peer_extra_calls() { return ""; }
