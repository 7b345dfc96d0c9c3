// BDF's Newton matrix I − γ ∂f/∂y, solved by its structure.
//
// For ẏ = f(y), y = [q; v; W, D] (System), BDF's Newton iterations solve (I − γJ) x = b with
// J = ∂f/∂y, and System::jacobian gives J a fixed block structure:
//
//        [ J_qq  J_qv  0 ]    J_qq = ∂q̇/∂q and J_qv = ∂q̇/∂v block-diagonal by joint (J_qq = 0 and
//   J =  [ J_vq  J_vv  0 ]    J_qv = I where a joint has no quaternion: q̇ = v), J_vq = ∂q̈/∂q,
//        [ J_wq  J_wv  0 ]    J_vv = ∂q̈/∂v, the quadratures' rows J_w; nothing depends on W, D.
//
// Eliminating x_q leaves one nv×nv system, the Schur complement of P = I − γJ_qq:
//   G = P⁻¹ J_qv (joint by joint),   S = I − γJ_vv − γ² J_vq G,
//   S x_v = b_v + γ J_vq P⁻¹ b_q,   x_q = P⁻¹ b_q + γ G x_v,   x_w = b_w + γ (J_wq x_q + J_wv x_v),
// with S factored by partial-pivot LU: nv³/3 flops per factorization and ~nv² per solve instead
// of n³/3 and n² for the dense I − γJ (n = nq + nv + 2).  set_jacobian() checks the structure entry
// by entry; a J without it (not System::jacobian's) takes the dense LU of I − γJ instead.
#pragma once

#include "soadyn/multibody/model.hpp"

#include <Eigen/LU>

#include <utility>
#include <vector>

namespace soadyn {

class System;

class NewtonSolver {
 public:
  // the layout of y: the model's q and v, then nquad quadratures
  NewtonSolver(const Model& model, int nquad);
  // the layout of a System's state (its free joints' q and v, then its quadratures), or its
  // tangent layout (System::tangent_jacobian: each joint's nv increments δ in place of its q, so
  // J_qq = 0 and J_qv = e, every block on the x_q = y + γ x_v route)
  enum class Layout { Coordinates, Tangent };
  explicit NewtonSolver(const System& system, Layout layout = Layout::Coordinates);
  // J = ∂f/∂y (n×n, n = nq + nv + nquad), copied; whether it has the structure above
  bool set_jacobian(const Eigen::Ref<const MatX>& J);
  // factors I − γJ for the J last set; false when it is singular (a zero or non-finite pivot)
  bool factor(double gamma);
  // x = (I − γJ)⁻¹ b for the last factor(); x may alias b.  Does not allocate.
  void solve(const Eigen::Ref<const VecX>& b, Eigen::Ref<VecX> x);
  // whether the last factor() took the nv×nv route (else the dense LU of I − γJ)
  bool reduced() const { return structured_; }
  int size() const { return n_; }

 private:
  using SmallMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 7, 7>;
  struct Block {  // one joint's rows of J_qq and J_qv
    int iq, mq, iv, nv;
    bool identity = true;  // J_qq,i = 0: P_i = I, G_i = J_qv,i
    Eigen::PartialPivLU<SmallMat> lu;  // of P_i otherwise
  };
  bool has_structure() const;
  NewtonSolver(int nq, int nv, int nquad);
  void add_joint(int iq, int mq, int iv, int nv);

  int nq_, nv_, nw_, n_;
  std::vector<Block> blocks_;
  std::vector<int> joint_of_q_;
  // where G is the identity (joints without a quaternion): the (q, v) index pairs, x_q = y + γ x_v;
  // the other blocks by their product
  std::vector<std::pair<int, int>> unit_;
  std::vector<int> general_;
  bool structured_ = false;
  double gamma_ = 0.0;
  MatX J_;                              // the Jacobian
  MatX G_;                              // P⁻¹ J_qv (nq×nv, block-diagonal)
  MatX S_;                              // the Schur complement, or I − γJ on the dense route
  Eigen::PartialPivLU<MatX> lu_s_, lu_full_;
  VecX y_, r_, x_;                      // solve's scratch: P⁻¹ b_q, S's right-hand side, the solution
};

}  // namespace soadyn
