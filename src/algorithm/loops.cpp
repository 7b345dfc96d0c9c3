// Closed loops on the tree (loops.hpp): each loop's velocity rows, their acceleration at q̈ = 0 and
// the closure, and forward and inverse dynamics with the loops' multipliers.
#include "soadyn/algorithm/loops.hpp"

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/frames.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include <cmath>
#include <utility>

namespace soadyn {

std::string_view to_string(LoopType t) {
  switch (t) {
    case LoopType::Point: return "point";
    case LoopType::Hinge: return "hinge";
    case LoopType::Weld: return "weld";
    case LoopType::Distance: return "distance";
  }
  return "?";
}

int loop_rows(LoopType t) {
  switch (t) {
    case LoopType::Point: return 3;
    case LoopType::Hinge: return 5;
    case LoopType::Weld: return 6;
    case LoopType::Distance: return 1;
  }
  return 0;
}

namespace {
const std::vector<const char*>& row_parts(LoopType t) {
  static const std::vector<const char*> point = {"x", "y", "z"}, hinge = {"x", "y", "z", "n1", "n2"},
                                        weld = {"x", "y", "z", "rx", "ry", "rz"}, distance = {"tension"};
  switch (t) {
    case LoopType::Point: return point;
    case LoopType::Hinge: return hinge;
    case LoopType::Weld: return weld;
    case LoopType::Distance: return distance;
  }
  return point;
}
}  // namespace

std::vector<std::string> loop_row_names(const std::vector<LoopConstraint>& loops) {
  std::vector<std::string> out;
  for (const LoopConstraint& c : loops)
    for (const char* part : row_parts(c.type)) out.push_back(c.name + "." + part);
  return out;
}

std::vector<std::string> loop_row_units(const std::vector<LoopConstraint>& loops) {
  std::vector<std::string> out;
  for (const LoopConstraint& c : loops)
    for (int r = 0; r < loop_rows(c.type); ++r) out.push_back(r >= 3 ? "N m" : "N");
  return out;
}

LoopData::LoopData(const Model& model, const std::vector<LoopConstraint>& loops) {
  for (size_t l = 0; l < loops.size(); ++l)
    for (int r = 0; r < loop_rows(loops[l].type); ++r) row_loop.push_back(int(l));
  m = int(row_loop.size());
  K = MatX::Zero(m, model.nv);
  kdot = VecX::Zero(m);
  phi = VecX::Zero(m);
  lambda = VecX::Zero(m);
  MinvKt = MatX::Zero(model.nv, m);
  A = MatX::Zero(m, m);
  J_a = MatX::Zero(6, model.nv);
  J_b = MatX::Zero(6, model.nv);
  work = articulated_solve_work(model);
  cod = Eigen::CompleteOrthogonalDecomposition<MatX>(m, m);
  cod.setThreshold(kLoopRankTolerance);
  b = VecX::Zero(m);
}

namespace {

// a frame of a loop at the current state: its pose, velocity [ω; ṗ] and, with [vel], J̇ v = [α⁰; p̈⁰]
struct LoopFrame {
  Placement X;
  Vec3 w, pd, alpha, pdd;
};

LoopFrame frame_state(const Model& model, const Data& data, int body, const Placement& on, bool motion) {
  LoopFrame f;
  f.X = body_frame_placement(model, data, body, on);
  f.w.setZero(), f.pd.setZero(), f.alpha.setZero(), f.pdd.setZero();
  if (!motion || body < 0) return f;
  const Vec6 v = body_frame_velocity(model, data, body, on, Reference::LocalWorldAligned);
  Vec6 a;
  body_frame_jacobian_dot_times_v(model, data, body, on, Reference::LocalWorldAligned, a);
  f.w = v.head<3>(), f.pd = v.tail<3>(), f.alpha = a.head<3>(), f.pdd = a.tail<3>();
  return f;
}

// the rotation vector of R (log), |θ| ≤ π
Vec3 rotation_vector(const Mat3& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

// one loop's closure rows φ into phi (from row r)
void closure_rows(const LoopConstraint& c, const LoopFrame& a, const LoopFrame& b, Eigen::Ref<VecX> phi) {
  const Vec3 delta = a.X.p - b.X.p;
  switch (c.type) {
    case LoopType::Point: phi.head<3>() = delta; return;
    case LoopType::Hinge: {
      // φ = Δ; −n₂ · a_A; n₁ · a_A (their rates are the rows n₁ · (ω_A − ω_B), n₂ · (ω_A − ω_B))
      const Vec3 axis = a.X.R.col(2);
      phi.head<3>() = delta;
      phi(3) = -b.X.R.col(1).dot(axis);
      phi(4) = b.X.R.col(0).dot(axis);
      return;
    }
    case LoopType::Weld:
      phi.head<3>() = delta;
      phi.tail<3>() = b.X.R * rotation_vector(b.X.R.transpose() * a.X.R);
      return;
    case LoopType::Distance: phi(0) = delta.norm() - c.distance; return;
  }
}

}  // namespace

void loop_closure(const Model& model, const Data& data, const std::vector<LoopConstraint>& loops, LoopData& ld) {
  int r = 0;
  for (const LoopConstraint& c : loops) {
    const LoopFrame a = frame_state(model, data, c.body_a, c.at_a, false);
    const LoopFrame b = frame_state(model, data, c.body_b, c.at_b, false);
    const int n = loop_rows(c.type);
    closure_rows(c, a, b, ld.phi.segment(r, n));
    r += n;
  }
}

void loop_rows(const Model& model, const Data& data, const std::vector<LoopConstraint>& loops, LoopData& ld) {
  int r = 0;
  for (const LoopConstraint& c : loops) {
    const LoopFrame a = frame_state(model, data, c.body_a, c.at_a, true);
    const LoopFrame b = frame_state(model, data, c.body_b, c.at_b, true);
    body_frame_jacobian(model, data, c.body_a, c.at_a, Reference::LocalWorldAligned, ld.J_a);
    body_frame_jacobian(model, data, c.body_b, c.at_b, Reference::LocalWorldAligned, ld.J_b);
    const int n = loop_rows(c.type);
    closure_rows(c, a, b, ld.phi.segment(r, n));
    const Vec3 dd = a.pd - b.pd, dw = a.w - b.w;   // Δ̇, the relative angular velocity
    const Vec3 ddd = a.pdd - b.pdd, dal = a.alpha - b.alpha;  // Δ̈⁰, α⁰_A − α⁰_B
    if (c.type == LoopType::Distance) {
      // u · Δ̇ and u̇ · Δ̇ + u · Δ̈⁰
      const Vec3 delta = a.X.p - b.X.p;
      const double len = delta.norm();
      const Vec3 u = delta / len, ud = (dd - u * u.dot(dd)) / len;
      ld.K.row(r) = u.transpose() * (ld.J_a.bottomRows<3>() - ld.J_b.bottomRows<3>());
      ld.kdot(r) = ud.dot(dd) + u.dot(ddd);
    } else {
      // the linear rows Δ̇ = (J_A − J_B) v, at q̈ = 0 Δ̈⁰
      ld.K.middleRows(r, 3) = ld.J_a.bottomRows<3>() - ld.J_b.bottomRows<3>();
      ld.kdot.segment<3>(r) = ddd;
    }
    if (c.type == LoopType::Weld) {
      // ω_A − ω_B and α⁰_A − α⁰_B
      ld.K.middleRows(r + 3, 3) = ld.J_a.topRows<3>() - ld.J_b.topRows<3>();
      ld.kdot.segment<3>(r + 3) = dal;
    } else if (c.type == LoopType::Hinge) {
      // n_i · (ω_A − ω_B), n_i fixed in B: rate (ω_B × n_i) · (ω_A − ω_B) + n_i · (α⁰_A − α⁰_B)
      for (int i = 0; i < 2; ++i) {
        const Vec3 n = b.X.R.col(i);
        ld.K.row(r + 3 + i) = n.transpose() * (ld.J_a.topRows<3>() - ld.J_b.topRows<3>());
        ld.kdot(r + 3 + i) = b.w.cross(n).dot(dw) + n.dot(dal);
      }
    }
    r += n;
  }
}

namespace {

// the margin of a decomposition of rank `rank`: the smallest kept pivot of the complete orthogonal
// factor T over the largest column pivot (0 at rank 0)
double kept_margin(const Eigen::CompleteOrthogonalDecomposition<MatX>& cod, int rank) {
  return rank > 0 ? cod.matrixT().diagonal().head(rank).cwiseAbs().minCoeff() / std::abs(cod.maxPivot()) : 0.0;
}

// λ of minimum norm for A λ = ld.b by the complete orthogonal decomposition with the loops' rank
// tolerance (ld.cod, sized once); records the rank and the margin
void solve_multipliers(LoopData& ld) {
  ld.cod.compute(ld.A);
  ld.rank = int(ld.cod.rank());
  ld.margin = kept_margin(ld.cod, ld.rank);
  ld.lambda = ld.cod.solve(ld.b);
}

// the rank and margin of one loop's diagonal block of A
std::pair<int, double> block_rank(const LoopData& ld, int loop) {
  std::vector<int> rows;
  for (int r = 0; r < ld.m; ++r)
    if (ld.row_loop[size_t(r)] == loop) rows.push_back(r);
  Eigen::CompleteOrthogonalDecomposition<MatX> cod(ld.A(rows, rows));
  cod.setThreshold(kLoopRankTolerance);
  const int rank = int(cod.rank());
  return {rank, kept_margin(cod, rank)};
}

}  // namespace

std::vector<int> loop_ranks(const LoopData& ld, int nloops) {
  std::vector<int> out;
  for (int l = 0; l < nloops; ++l) out.push_back(block_rank(ld, l).first);
  return out;
}

std::vector<int> singular_loops(const LoopData& ld, const std::vector<int>& first_rank) {
  std::vector<int> out;
  for (int l = 0; l < int(first_rank.size()); ++l) {
    const auto [rank, margin] = block_rank(ld, l);
    if (rank < first_rank[size_t(l)] || (rank > 0 && margin < kLoopSingular)) out.push_back(l);
  }
  if (out.empty())
    for (int l = 0; l < int(first_rank.size()); ++l) out.push_back(l);
  return out;
}

void loop_forward_dynamics(const Model& model, Data& data, const std::vector<LoopConstraint>& loops, const VecX& v,
                           const VecX& tau, LoopData& ld, double stabilize) {
  // q̈₀ = 𝓜⁻¹ (τ − bias) by the articulated-body route, its factor kept in data
  forward_dynamics(model, data, tau, FdMethod::ArticulatedBody);
  if (ld.m == 0) return;
  loop_rows(model, data, loops, ld);
  // 𝓜⁻¹ Kᵀ by the factor (O(N) per row), A = K 𝓜⁻¹ Kᵀ
  ld.MinvKt = ld.K.transpose();
  articulated_solve(model, data, ld.MinvKt, ld.work);
  ld.A.noalias() = ld.K * ld.MinvKt;
  // A λ = K q̈₀ + k̇ (+ 2 s K v + s² φ), q̈ = q̈₀ − 𝓜⁻¹ Kᵀ λ
  ld.b.noalias() = ld.K * data.qdd;
  ld.b += ld.kdot;
  if (stabilize > 0) {
    ld.b.noalias() += (2 * stabilize) * (ld.K * v);
    ld.b += (stabilize * stabilize) * ld.phi;
  }
  solve_multipliers(ld);
  data.qdd.noalias() -= ld.MinvKt * ld.lambda;
}

void loop_forward_dynamics_dense(const Model& model, Data& data, const std::vector<LoopConstraint>& loops,
                                 const VecX& tau, LoopData& ld) {
  // [𝓜 Kᵀ; K 0] [q̈; λ] = [τ − bias; −k̇], least squares of minimum norm
  mass_matrix(model, data);
  bias_forces(model, data);
  loop_rows(model, data, loops, ld);
  const int nv = model.nv, m = ld.m;
  MatX S = MatX::Zero(nv + m, nv + m);
  S.topLeftCorner(nv, nv) = data.M;
  S.topRightCorner(nv, m) = ld.K.transpose();
  S.bottomLeftCorner(m, nv) = ld.K;
  VecX rhs(nv + m);
  rhs << tau - data.bias, -ld.kdot;
  Eigen::CompleteOrthogonalDecomposition<MatX> cod(S);
  const VecX x = cod.solve(rhs);
  data.qdd = x.head(nv);
  ld.lambda = x.tail(m);
}

VecX loop_inverse_dynamics(const Model& model, Data& data, const std::vector<LoopConstraint>& loops,
                           const std::vector<int>& actuated, VecX& qdd, LoopData& ld) {
  const int nv = model.nv;
  std::vector<char> is_actuated(size_t(nv), 0);
  for (const int k : actuated) {
    if (k < 0 || k >= nv) throw Error("loop_inverse_dynamics: actuated: DOF " + std::to_string(k) + " is not one of the model's");
    is_actuated[size_t(k)] = 1;
  }
  std::vector<int> passive;
  for (int k = 0; k < nv; ++k)
    if (!is_actuated[size_t(k)]) passive.push_back(k);
  loop_rows(model, data, loops, ld);
  // the passive DOFs' q̈ from K_p q̈_p = −k̇ − K_a q̈_a
  if (!passive.empty()) {
    VecX qa = qdd;
    for (const int k : passive) qa(k) = 0.0;
    const MatX Kp = ld.K(Eigen::all, passive);
    Eigen::CompleteOrthogonalDecomposition<MatX> cod(Kp);
    cod.setThreshold(kLoopRankTolerance);
    if (cod.rank() < Eigen::Index(passive.size()))
      throw Error("loop_inverse_dynamics: the loops leave " + std::to_string(passive.size() - size_t(cod.rank())) +
                  " passive DOF(s) free: too few actuated DOFs or loops, or a singular configuration (a dead point)");
    const VecX qp = cod.solve(VecX(-ld.kdot - ld.K * qa));
    for (size_t j = 0; j < passive.size(); ++j) qdd(passive[j]) = qp(Eigen::Index(j));
  }
  // inverse dynamics of the tree at that q̈: 𝓜 q̈ + bias = τ − Kᵀ λ with τ_p = 0, so K_pᵀ λ = −ID_p
  inverse_dynamics(model, data, qdd);
  const VecX& id = data.tau;
  VecX tau = id;
  if (ld.m > 0) {
    VecX idp(Eigen::Index(passive.size()));
    for (size_t j = 0; j < passive.size(); ++j) idp(Eigen::Index(j)) = id(passive[j]);
    const MatX Kpt = ld.K(Eigen::all, passive).transpose();
    Eigen::CompleteOrthogonalDecomposition<MatX> cod(Kpt);
    cod.setThreshold(kLoopRankTolerance);
    ld.lambda = cod.solve(VecX(-idp));
    const double miss = (Kpt * ld.lambda + idp).norm(), scale = std::max(1.0, idp.norm());
    if (miss > 1e-8 * scale)
      throw Error("loop_inverse_dynamics: the actuated DOFs cannot make this motion (the passive joints' equations miss by " +
                  std::to_string(miss) + ")");
    tau.noalias() += ld.K.transpose() * ld.lambda;
  }
  for (const int k : passive) tau(k) = 0.0;
  return tau;
}

}  // namespace soadyn
