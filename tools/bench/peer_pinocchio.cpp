// Pinocchio 3 as a soadyn_bench peer (plugin; see peer.hpp):
//   mass     crba(q)                    (fills the upper triangle; the lower one is mirrored after,
//                                        untimed, for the check)
//   bias     nonLinearEffects(q, v)
//   forward  aba(q, v, tau)             (the articulated-body algorithm)
// crba and aba in Pinocchio's default convention (LOCAL), or in the variant "world" in its WORLD
// convention (the faster on long chains).  The URDF is read by Pinocchio's own
// parser with a fixed base, or a free-flyer root for a problem with free_root; a `continuous`
// joint has q = (cos θ, sin θ).
//   frame_jacobian  computeFrameJacobian(q, frame, LOCAL_WORLD_ALIGNED)  (one pass over the
//                   frame's supporting joints), when the problem names a frame
//   com_jacobian    jacobianCenterOfMass(q, false)
//   centroidal_map  computeCentroidalMap(q)  (A_G, rows [l; k_G] there)
//   minverse        computeMinverse(q)  (the upper triangle; mirrored after, untimed)
#include "peer.hpp"

#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/center-of-mass.hpp>
#include <pinocchio/algorithm/centroidal.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>
#include <pinocchio/parsers/urdf.hpp>

#include <cmath>
#include <exception>
#include <stdexcept>

namespace {
namespace pin = pinocchio;
using soadyn::bench::PeerProblem;

pin::Model load(const PeerProblem& p) {
  pin::Model m;
  if (p.free_root) pin::urdf::buildModel(p.urdf, pin::JointModelFreeFlyer(), m);
  else pin::urdf::buildModel(p.urdf, m);  // fixed base
  m.gravity.linear(Eigen::Vector3d(p.gravity[0], p.gravity[1], p.gravity[2]));
  return m;
}

struct Pinocchio : soadyn::bench::Peer {
  pin::Model model;
  pin::Data data;
  Eigen::VectorXd q, v, tau;
  std::vector<int> idx;  // problem order k -> Pinocchio v index
  pin::Data::Matrix6x J;

  explicit Pinocchio(const PeerProblem& p) : model(load(p)), data(model) {
    const int n = int(p.joints.size()), root = p.free_root ? 6 : 0;
    if (model.nv != n + root)
      throw std::runtime_error("nv = " + std::to_string(model.nv) + ", soadyn has " + std::to_string(n + root));
    q = pin::neutral(model);
    v = tau = Eigen::VectorXd::Zero(n + root);
    if (p.free_root) {  // Pinocchio's free flyer: q = [x y z qx qy qz qw], v = [Rᵀ ṗ; Rᵀ ω]
      q.head<3>() << p.root_q[0], p.root_q[1], p.root_q[2];
      q.segment<4>(3) << p.root_q[4], p.root_q[5], p.root_q[6], p.root_q[3];
    }
    for (int k = 0; k < n; ++k) {
      if (!model.existJointName(p.joints[k])) throw std::runtime_error("no joint " + p.joints[k]);
      const auto j = model.getJointId(p.joints[k]);
      const int iq = model.idx_qs[j], iv = model.idx_vs[j];
      if (model.nvs[j] != 1) throw std::runtime_error("joint " + p.joints[k] + " has nv != 1");
      if (model.nqs[j] == 2) {  // continuous: unbounded revolute
        q[iq] = std::cos(p.q[k]);
        q[iq + 1] = std::sin(p.q[k]);
      } else {
        q[iq] = p.q[k];
      }
      v[iv] = p.v[k];
      tau[iv] = p.tau[k];
      idx.push_back(iv);
    }
    const auto c = p.variant == "world" ? pin::Convention::WORLD : pin::Convention::LOCAL;
    mass = [this, c] { pin::crba(model, data, q, c); };
    bias = [this] { pin::nonLinearEffects(model, data, q, v); };
    forward = [this, c] { pin::aba(model, data, q, v, tau, c); };
    mass_out = [this] {
      Eigen::MatrixXd M = data.M;
      M.triangularView<Eigen::StrictlyLower>() = M.transpose();
      std::vector<double> r(idx.size() * idx.size());
      for (size_t i = 0; i < idx.size(); ++i)
        for (size_t j = 0; j < idx.size(); ++j) r[i * idx.size() + j] = M(idx[i], idx[j]);
      return r;
    };
    bias_out = [this] { return soadyn::bench::permuted(data.nle, idx); };
    forward_out = [this] { return soadyn::bench::permuted(data.ddq, idx); };
    if (p.frame.empty()) return;
    if (!model.existFrame(p.frame)) throw std::runtime_error("no frame " + p.frame);
    const pin::FrameIndex f = model.getFrameId(p.frame);
    J = pin::Data::Matrix6x::Zero(6, model.nv);  // the call writes the frame's supporting columns only
    frame_jacobian = [this, f] { pin::computeFrameJacobian(model, data, q, f, pin::LOCAL_WORLD_ALIGNED, J); };
    frame_jacobian_out = [this] { return out((Eigen::MatrixXd(6, model.nv) << J.bottomRows<3>(), J.topRows<3>()).finished()); };
    com_jacobian = [this] { pin::jacobianCenterOfMass(model, data, q, false); };
    com_jacobian_out = [this] { return out(data.Jcom); };
    centroidal_map = [this] { pin::computeCentroidalMap(model, data, q); };
    centroidal_map_out = [this] { return out((Eigen::MatrixXd(6, model.nv) << data.Ag.bottomRows<3>(), data.Ag.topRows<3>()).finished()); };
    minverse = [this] { pin::computeMinverse(model, data, q); };
    // 𝓜⁻¹ in soadyn's v: with Pinocchio's v = T v_s, 𝓜_s⁻¹ = Tᵀ 𝓜⁻¹ T (T orthogonal); `out` applies T
    // on the right, so twice, the second time to the transpose of the first's result
    minverse_out = [this] {
      Eigen::MatrixXd M = data.Minv;
      M.triangularView<Eigen::StrictlyLower>() = M.transpose();
      const std::vector<double> c = out(M);
      Eigen::MatrixXd C(model.nv, model.nv);
      for (int i = 0; i < model.nv; ++i)
        for (int j = 0; j < model.nv; ++j) C(i, j) = c[size_t(i * model.nv + j)];
      return out(C.transpose());
    };
  }
  // A (rows in soadyn's order, columns Pinocchio's v) row-major with soadyn's columns: the free
  // flyer's from its local v to soadyn's inertial [ω; ṗ] (A [Rᵀ ṗ; Rᵀ ω] = A_s [ω; ṗ] gives
  // A_s = [A_ω Rᵀ, A_v Rᵀ]), then the joints in the problem's order
  std::vector<double> out(const Eigen::MatrixXd& A) const {
    const int root = model.nv - int(idx.size());
    Eigen::MatrixXd As(A.rows(), model.nv);
    if (root) {
      const Eigen::Matrix3d R = Eigen::Quaterniond(q[6], q[3], q[4], q[5]).normalized().toRotationMatrix();
      As.leftCols<3>() = A.middleCols<3>(3) * R.transpose();
      As.middleCols<3>(3) = A.leftCols<3>() * R.transpose();
    }
    for (size_t k = 0; k < idx.size(); ++k) As.col(root + int(k)) = A.col(idx[k]);
    std::vector<double> r(size_t(As.size()));
    for (int i = 0; i < As.rows(); ++i)
      for (int j = 0; j < As.cols(); ++j) r[size_t(i * As.cols() + j)] = As(i, j);
    return r;
  }
};

}  // namespace

soadyn::bench::Peer* soadyn_bench_make_peer(const PeerProblem& problem, std::string& error) {
  return soadyn::bench::make_peer<Pinocchio>(problem, error, soadyn_bench_peer_variants());
}

const char* soadyn_bench_peer_version() { return "Pinocchio " PINOCCHIO_VERSION " (" SOADYN_PEER_COMPILER ")"; }

const char* soadyn_bench_peer_variants() { return "world"; }

const char* soadyn_bench_peer_extra_calls() { return "frame_jacobian,com_jacobian,centroidal_map,minverse"; }
