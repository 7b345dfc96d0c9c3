#include "soadyn/sim/newton_solver.hpp"
#include "soadyn/sim/system.hpp"

namespace soadyn {

namespace {
// a partial-pivot LU is usable when every pivot is finite and non-zero
template <class LU>
bool regular(const LU& lu) {
  const auto d = lu.matrixLU().diagonal();
  return d.allFinite() && (d.array() != 0.0).all();
}
}  // namespace

NewtonSolver::NewtonSolver(int nq, int nv, int nquad)
    : nq_(nq),
      nv_(nv),
      nw_(nquad),
      n_(nq + nv + nquad),
      joint_of_q_(nq),
      J_(MatX::Zero(n_, n_)),
      G_(MatX::Zero(nq, nv)),
      S_(n_, n_),
      lu_s_(nv),
      lu_full_(n_),
      y_(nq),
      r_(nv),
      x_(n_) {
  unit_.reserve(nq);
}

// one joint's block: its q entries [iq, iq + mq) and v entries [iv, iv + nv) in y
void NewtonSolver::add_joint(int iq, int mq, int iv, int nv) {
  const int b = int(blocks_.size());
  blocks_.push_back(Block{iq, mq, iv, nv, true, {}});
  for (int k = 0; k < mq; ++k) joint_of_q_[size_t(iq + k)] = b;
  general_.reserve(blocks_.size());
}

NewtonSolver::NewtonSolver(const Model& m, int nquad) : NewtonSolver(m.nq, m.nv, nquad) {
  for (int i = 0; i < m.nbodies; ++i) add_joint(m.idx_q[i], m.nq_i[i], m.idx_v[i], m.nv_i[i]);
}

NewtonSolver::NewtonSolver(const System& sys, Layout layout)
    : NewtonSolver(layout == Layout::Tangent ? sys.nv_state() : sys.nq_state(), sys.nv_state(), sys.nquad) {
  for (const System::StateJoint& j : sys.state_joints())
    if (layout == Layout::Tangent) add_joint(j.iv, j.nv, j.iv, j.nv);
    else add_joint(j.iq, j.mq, j.iv, j.nv);
}

// J has the structure of the header, entry by entry: in the q rows only the joint's own columns
// (J_qq, J_qv block-diagonal), and nothing in the columns of W, D
bool NewtonSolver::has_structure() const {
  if (!J_.rightCols(nw_).isZero(0.0)) return false;
  for (const Block& b : blocks_)
    for (int r = b.iq; r < b.iq + b.mq; ++r)
      for (int c = 0; c < nq_ + nv_; ++c) {
        const bool own = c < nq_ ? joint_of_q_[c] == joint_of_q_[r] : (c - nq_ >= b.iv && c - nq_ < b.iv + b.nv);
        if (!own && J_(r, c) != 0.0) return false;
      }
  return true;
}

bool NewtonSolver::set_jacobian(const Eigen::Ref<const MatX>& J) {
  J_ = J;
  structured_ = has_structure();
  unit_.clear();
  general_.clear();
  for (int i = 0; i < int(blocks_.size()); ++i) {
    Block& b = blocks_[i];
    b.identity = J_.block(b.iq, b.iq, b.mq, b.mq).isZero(0.0);
    if (b.identity && b.mq == b.nv && J_.block(b.iq, nq_ + b.iv, b.mq, b.nv).isIdentity(0.0))
      for (int k = 0; k < b.mq; ++k) unit_.emplace_back(b.iq + k, b.iv + k);
    else
      general_.push_back(i);
  }
  return structured_;
}

bool NewtonSolver::factor(double gamma) {
  gamma_ = gamma;
  if (!structured_) {
    // the dense route: I − γJ
    S_ = -gamma * J_;
    S_.diagonal().array() += 1.0;
    lu_full_.compute(S_);
    return regular(lu_full_);
  }
  // S = I − γJ_vv − γ² J_vq G,  G_i = P_i⁻¹ J_qv,i joint by joint
  const auto Jvq = J_.block(nq_, 0, nv_, nq_);
  auto S = S_.topLeftCorner(nv_, nv_);
  S = -gamma * J_.block(nq_, nq_, nv_, nv_);
  S.diagonal().array() += 1.0;
  for (const auto& [iq, iv] : unit_) S.col(iv).noalias() -= (gamma * gamma) * Jvq.col(iq);
  for (const int i : general_) {
    Block& b = blocks_[i];
    auto Gi = G_.block(b.iq, b.iv, b.mq, b.nv);
    const auto Jqv = J_.block(b.iq, nq_ + b.iv, b.mq, b.nv);
    if (b.identity) {
      Gi = Jqv;
    } else {
      SmallMat P = -gamma * J_.block(b.iq, b.iq, b.mq, b.mq);
      P.diagonal().array() += 1.0;
      b.lu.compute(P);
      if (!regular(b.lu)) return false;
      Gi = b.lu.solve(Jqv);
    }
    S.middleCols(b.iv, b.nv).noalias() -= (gamma * gamma) * Jvq.middleCols(b.iq, b.mq) * Gi;
  }
  lu_s_.compute(S);
  return regular(lu_s_);
}

void NewtonSolver::solve(const Eigen::Ref<const VecX>& b, Eigen::Ref<VecX> x) {
  if (!structured_) {
    x_ = lu_full_.solve(b);
    x = x_;
    return;
  }
  const double g = gamma_;
  // y = P⁻¹ b_q, joint by joint (P_i = I but where a quaternion turns)
  y_ = b.head(nq_);
  for (const int i : general_) {
    const Block& blk = blocks_[i];
    if (!blk.identity) y_.segment(blk.iq, blk.mq) = blk.lu.solve(b.segment(blk.iq, blk.mq));
  }
  // S x_v = b_v + γ J_vq y
  r_ = b.segment(nq_, nv_);
  r_.noalias() += g * (J_.block(nq_, 0, nv_, nq_) * y_);
  x_.segment(nq_, nv_) = lu_s_.solve(r_);
  // x_q = y + γ G x_v (G block-diagonal)
  for (const auto& [iq, iv] : unit_) x_(iq) = y_(iq) + g * x_(nq_ + iv);
  for (const int i : general_) {
    const Block& blk = blocks_[i];
    x_.segment(blk.iq, blk.mq) = y_.segment(blk.iq, blk.mq);
    x_.segment(blk.iq, blk.mq).noalias() += g * (G_.block(blk.iq, blk.iv, blk.mq, blk.nv) * x_.segment(nq_ + blk.iv, blk.nv));
  }
  // x_w = b_w + γ [J_wq J_wv] [x_q; x_v]
  if (nw_ > 0) {
    x_.tail(nw_) = b.tail(nw_);
    x_.tail(nw_).noalias() += g * (J_.bottomLeftCorner(nw_, nq_ + nv_) * x_.head(nq_ + nv_));
  }
  x = x_;
}

}  // namespace soadyn
