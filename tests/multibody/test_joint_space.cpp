// Each joint kind's configuration geometry (joint_space.hpp) and the model-level functions built on
// it (configuration.hpp): q0 ⊕ (q1 ⊖ q0) = q1, T(q) against differences of integrate, ∂q̇/∂q and
// ∂q̇/∂v against differences of q̇, for every kind at seeded random configurations; the model's
// block functions against the dense T and Jacobians; the kinds run on another scalar.
#include "test_util.hpp"

#include "soadyn/multibody/configuration.hpp"
#include "soadyn/multibody/joint_model.hpp"

#include <set>

namespace soadyn::test {
namespace {

// one joint of every kind (classify_joint's cases), for the per-kind checks
std::vector<JointModel> every_kind() {
  const Mat3 e = Mat3::Identity(), turn = Eigen::AngleAxisd(0.3, Vec3::UnitX()).toRotationMatrix();
  const Vec3 skew = Vec3(0.3, -0.5, 0.8).normalized();
  std::vector<JointModel> kinds;
  for (int k = 0; k < 3; ++k) {
    kinds.push_back(classify_joint(JointType::Revolute, Vec3::Unit(k), e));
    kinds.push_back(classify_joint(JointType::Revolute, -Vec3::Unit(k), turn));
    kinds.push_back(classify_joint(JointType::Prismatic, Vec3::Unit(k), e));
  }
  for (const JointType t : {JointType::Revolute, JointType::Prismatic, JointType::Ball, JointType::Planar, JointType::Free})
    kinds.push_back(classify_joint(t, skew, turn));
  kinds.push_back(classify_joint(JointType::Helical, skew, turn, 0.07));
  std::set<size_t> seen;
  for (const JointModel& j : kinds) seen.insert(j.index());
  EXPECT_EQ(seen.size(), std::variant_size_v<JointModel>);  // every kind is here
  return kinds;
}

// a random configuration of the kind (unit quaternions)
template <class J>
VecX random_of(const J& j, std::mt19937_64& gen) {
  VecX q(J::nq);
  j.random(gen, q.data());
  return q;
}

// the rotation and translation of q, to compare configurations whose quaternions may differ in sign
template <class J>
std::pair<Mat3, Vec3> pose_of(const J& j, const VecX& q) {
  Mat3 R;
  Vec3 p;
  j.motion(q.data(), R, p);
  return {R, p};
}

TEST(JointSpace, IntegrateOfDifferenceReturnsEveryKind) {
  std::mt19937_64 gen(2026);
  for (const JointModel& kind : every_kind())
    std::visit(
        [&](const auto& j) {
          using J = std::decay_t<decltype(j)>;
          for (int trial = 0; trial < 20; ++trial) {
            const VecX q0 = random_of(j, gen), q1 = random_of(j, gen);
            VecX v(J::nv), back(J::nq), again(J::nv);
            j.difference(q0.data(), q1.data(), v.data());
            j.integrate(q0.data(), v.data(), 1.0, back.data());
            const auto [R1, p1] = pose_of(j, q1);
            const auto [Rb, pb] = pose_of(j, back);
            EXPECT_TRUE(near_rel(Rb, R1, 1e-12)) << kind_name(kind);
            EXPECT_TRUE(near_rel(pb, p1, 1e-12)) << kind_name(kind);
            // and the other way: (q0 ⊕ v) ⊖ q0 = v for v within the shorter turn
            const VecX w = 0.5 * v;
            j.integrate(q0.data(), w.data(), 1.0, back.data());
            j.difference(q0.data(), back.data(), again.data());
            EXPECT_TRUE(near_rel(again, w, 1e-12)) << kind_name(kind);
            // q ⊖ q = 0
            j.difference(q0.data(), q0.data(), again.data());
            EXPECT_LE(again.norm(), 1e-15) << kind_name(kind);
          }
        },
        kind);
}

// dδ = T dq: T times the central difference of q ⊕ h e_c in h is e_c; and q̇ = T̄(q) v is that
// derivative for v = e_c
TEST(JointSpace, TangentMapAndQdotAgainstDifferencesOfIntegrate) {
  std::mt19937_64 gen(2027);
  const double h = 1e-6;
  for (const JointModel& kind : every_kind())
    std::visit(
        [&](const auto& j) {
          using J = std::decay_t<decltype(j)>;
          for (int trial = 0; trial < 5; ++trial) {
            const VecX q = random_of(j, gen);
            const Eigen::Matrix<double, J::nv, J::nq> T = j.tangent(q.data());
            for (int c = 0; c < J::nv; ++c) {
              const VecX e = VecX::Unit(J::nv, c);
              VecX qp(J::nq), qm(J::nq), qd(J::nq);
              j.integrate(q.data(), e.data(), h, qp.data());
              j.integrate(q.data(), e.data(), -h, qm.data());
              const VecX dq = (qp - qm) / (2 * h);
              EXPECT_TRUE(near_rel(T * dq, e, 1e-8)) << kind_name(kind) << " column " << c;
              j.qdot(q.data(), e.data(), qd.data());
              EXPECT_TRUE(near_rel(qd, dq, 1e-8)) << kind_name(kind) << " column " << c;
              VecX v(J::nv);
              j.velocity(q.data(), qd.data(), v.data());
              EXPECT_TRUE(near_rel(v, e, 1e-14)) << kind_name(kind);
            }
          }
        },
        kind);
}

// u̇ = dexp⁻¹_u(v): q0 ⊕ u(t) moves at v when u moves at the increment rate, i.e. the central
// difference of (q0 ⊕ (u ± h r)) ⊖ (q0 ⊕ u) in h is v; for turns from 10⁻³ rad (the series) to 2.5 rad
TEST(JointSpace, IncrementRateMovesTheIncrementedConfigurationAtV) {
  std::mt19937_64 gen(2029);
  std::uniform_real_distribution<double> uni(-1, 1);
  const double h = 1e-6;
  for (const JointModel& kind : every_kind())
    std::visit(
        [&](const auto& j) {
          using J = std::decay_t<decltype(j)>;
          for (const double size : {1e-3, 0.1, 1.0, 2.5}) {
            const VecX q0 = random_of(j, gen);
            VecX u(J::nv), v(J::nv), r(J::nv);
            for (int c = 0; c < J::nv; ++c) u(c) = uni(gen), v(c) = uni(gen);
            u *= size / u.norm();
            j.increment_rate(u.data(), v.data(), r.data());
            VecX qu(J::nq), qp(J::nq), qm(J::nq), dp(J::nv), dm(J::nv);
            const VecX up = u + h * r, um = u - h * r;
            j.integrate(q0.data(), u.data(), 1.0, qu.data());
            j.integrate(q0.data(), up.data(), 1.0, qp.data());
            j.integrate(q0.data(), um.data(), 1.0, qm.data());
            j.difference(qu.data(), qp.data(), dp.data());
            j.difference(qu.data(), qm.data(), dm.data());
            EXPECT_TRUE(near_rel((dp - dm) / (2 * h), v, 1e-8)) << kind_name(kind) << " |u| = " << size;
          }
        },
        kind);
}

TEST(JointSpace, QdotJacobianAgainstDifferences) {
  std::mt19937_64 gen(2028);
  std::uniform_real_distribution<double> u(-2, 2);
  const double h = 1e-6;
  for (const JointModel& kind : every_kind())
    std::visit(
        [&](const auto& j) {
          using J = std::decay_t<decltype(j)>;
          const VecX q = random_of(j, gen);
          VecX v(J::nv);
          for (int c = 0; c < J::nv; ++c) v(c) = u(gen);
          Eigen::Matrix<double, J::nq, J::nq> dq;
          Eigen::Matrix<double, J::nq, J::nv> dv;
          j.qdot_jacobian(q.data(), v.data(), dq, dv);
          const auto qdot = [&](const VecX& qq, const VecX& vv) {
            VecX out(J::nq);
            j.qdot(qq.data(), vv.data(), out.data());
            return out;
          };
          MatX ndq(J::nq, J::nq), ndv(J::nq, J::nv);
          for (int c = 0; c < J::nq; ++c) {
            const VecX e = h * VecX::Unit(J::nq, c);
            ndq.col(c) = (qdot(q + e, v) - qdot(q - e, v)) / (2 * h);
          }
          for (int c = 0; c < J::nv; ++c) {
            const VecX e = h * VecX::Unit(J::nv, c);
            ndv.col(c) = (qdot(q, v + e) - qdot(q, v - e)) / (2 * h);
          }
          EXPECT_TRUE(near_rel(dq, ndq, 1e-8)) << kind_name(kind);
          EXPECT_TRUE(near_rel(dv, ndv, 1e-8)) << kind_name(kind);
        },
        kind);
}

// the model's functions, joint by joint, against the dense T, ∂q̇/∂q, ∂q̇/∂v they stand for
TEST(JointSpace, ModelFunctionsAgreeWithTheDenseMaps) {
  Rng rng(2029);
  for (int trial = 0; trial < 4; ++trial) {
    const Model m = random_model(rng, {.n = 10, .branching = 0.5, .prismatic = 0.2, .ball = 0.2, .planar = 0.1,
                                       .helical = 0.2, .free_root = trial % 2 == 0});
    const VecX q0 = random_configuration(m, rng.gen), q1 = random_configuration(m, rng.gen), v = random_v(rng, m);
    // q0 ⊕ (q1 ⊖ q0) = q1, by the poses of the bodies
    const VecX back = m.integrate(q0, difference(m, q0, q1), 1.0);
    Data d1(m), db(m);
    update_kinematics(m, d1, q1), update_kinematics(m, db, back);
    EXPECT_TRUE(near_rel(db.eta, d1.eta, 1e-12));
    for (int i = 0; i < m.nbodies; ++i) EXPECT_TRUE(near_rel(db.R[i], d1.R[i], 1e-12));
    // T against its blocks' products
    const MatX T = tangent_map(m, q0);
    const MatX A = MatX::Random(m.nq, 3), B = MatX::Random(4, m.nv);
    MatX TA(m.nv, 3);
    tangent_times(m, q0, A, TA);
    EXPECT_TRUE(near_rel(TA, T * A, 1e-14));
    MatX BT = MatX::Ones(4, m.nq);
    add_times_tangent(m, q0, B, BT);
    EXPECT_TRUE(near_rel(BT, MatX::Ones(4, m.nq) + B * T, 1e-14));
    const VecX g = VecX::Random(m.nv);
    VecX Tg = VecX::Ones(m.nq);
    add_tangent_transpose_times(m, q0, g, Tg);
    EXPECT_TRUE(near_rel(Tg, VecX::Ones(m.nq) + T.transpose() * g, 1e-14));
    EXPECT_TRUE(near_rel(T * tangent_to_coordinates(m, q0), MatX::Identity(m.nv, m.nv), 1e-13));
    // ∂q̇/∂q, ∂q̇/∂v and their products
    MatX Jq = MatX::Zero(m.nq, m.nq), Jv = MatX::Zero(m.nq, m.nv);
    qdot_jacobian(m, q0, v, Jq, Jv);
    const MatX Sq = MatX::Random(m.nq, 2), Sv = MatX::Random(m.nv, 2);
    MatX out(m.nq, 2);
    qdot_jacobian_times(m, q0, v, Sq, Sv, out);
    EXPECT_TRUE(near_rel(out, Jq * Sq + Jv * Sv, 1e-14));
    const VecX lambda = VecX::Random(m.nq);
    VecX oq = VecX::Zero(m.nq), ov = VecX::Zero(m.nv);
    add_qdot_jacobian_transpose_times(m, q0, v, lambda, oq, ov);
    EXPECT_TRUE(near_rel(oq, Jq.transpose() * lambda, 1e-14));
    EXPECT_TRUE(near_rel(ov, Jv.transpose() * lambda, 1e-14));
    // the quaternions random_configuration draws are unit; the per-joint trait finds them
    for (int i = 0; i < m.nbodies; ++i)
      if (const int k = joint_quaternion(m, i); k >= 0) {
        EXPECT_NEAR(q0.segment<4>(m.idx_q[i] + k).norm(), 1.0, 1e-15);
      }
  }
}

// the kinds' geometry is a template on the scalar: the same code in long double agrees with double
TEST(JointSpace, KindsRunOnAnotherScalar) {
  std::mt19937_64 gen(2030);
  for (const JointModel& kind : every_kind())
    std::visit(
        [&](const auto& j) {
          using J = std::decay_t<decltype(j)>;
          using L = long double;
          const VecX q = random_of(j, gen), v = VecX::Random(J::nv);
          const Eigen::Matrix<L, Eigen::Dynamic, 1> ql = q.cast<L>(), vl = v.cast<L>();
          Eigen::Matrix<L, Eigen::Dynamic, 1> outl(J::nq);
          VecX out(J::nq);
          j.integrate(ql.data(), vl.data(), L(0.3), outl.data());
          j.integrate(q.data(), v.data(), 0.3, out.data());
          EXPECT_TRUE(near_rel(outl.template cast<double>(), out, 1e-14)) << kind_name(kind);
          Mat3 R;
          Vec3 p;
          Eigen::Matrix<L, 3, 3> Rl;
          Eigen::Matrix<L, 3, 1> pl;
          j.motion(q.data(), R, p);
          j.motion(ql.data(), Rl, pl);
          EXPECT_TRUE(near_rel(Rl.template cast<double>(), R, 1e-14)) << kind_name(kind);
          EXPECT_TRUE(near_rel(pl.template cast<double>(), p, 1e-14)) << kind_name(kind);
        },
        kind);
}

}  // namespace
}  // namespace soadyn::test
