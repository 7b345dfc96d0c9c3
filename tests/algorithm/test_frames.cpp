// Frames and task space (frames.hpp) against independent routes: every Jacobian against central
// differences of the placement, J̇ v against differences of J v, A_G v against `momentum`, the
// Coriolis matrix against bias and 𝓜̇, Λ against the dense formula, and merged frames against the
// same points on an unmerged twin.  The note's double pendulum: test_frames_double_pendulum.cpp.
#include "soadyn/algorithm/frames.hpp"
#include "soadyn/io/scenario_file.hpp"

#include "test_util.hpp"

#include <Eigen/Dense>

#include <cstdio>

namespace soadyn::test {
namespace {

constexpr double kH = 1e-5;  // central-difference step: error ~ h² ≈ 1e-10, round-off ~ ε/h ≈ 1e-11
const Reference kReferences[] = {Reference::World, Reference::Local, Reference::LocalWorldAligned};

std::string sci(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2e", x);
  return buf;
}

// the rotation vector of R (R = exp(θ̃))
Vec3 log3(const Mat3& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

Placement placement_at(const Model& m, const VecX& q, int frame) {
  Data d(m);
  update_kinematics(m, d, q);
  return frame_placement(m, d, frame);
}

// the frame's velocity in `reference`, from differences of its placement along q ⊕ ±h v
Vec6 velocity_by_differences(const Model& m, const VecX& q, const VecX& v, int frame, Reference reference) {
  const Placement a = placement_at(m, m.integrate(q, v, -kH), frame), b = placement_at(m, m.integrate(q, v, kH), frame);
  const Placement X = placement_at(m, q, frame);
  const Vec3 w = log3(b.R * a.R.transpose()) / (2 * kH);  // inertial axes: R(t) ≈ exp(t ω̃) R(0)
  const Vec3 pd = (b.p - a.p) / (2 * kH);
  Vec6 out;
  switch (reference) {
    case Reference::LocalWorldAligned: out << w, pd; break;
    case Reference::Local: out << X.R.transpose() * w, X.R.transpose() * pd; break;
    case Reference::World: out << w, pd - w.cross(X.p); break;  // the body's point at the origin
  }
  return out;
}

// a random model with a few frames added on random bodies and on the world
Model model_with_frames(Rng& rng, const TreeOptions& o) {
  Model m = random_model(rng, o);
  for (int k = 0; k < 4; ++k) m.add_frame("extra" + std::to_string(k), rng.integer(-1, m.nbodies - 1), {rng.rotation(), rng.vec3()});
  return m;
}

class Frames : public ::testing::TestWithParam<TreeCase> {};

TreeOptions chain() {
  TreeOptions o;
  o.n = 6;
  o.branching = 0.0;
  return o;
}
TreeOptions mixed() {
  TreeOptions o;
  o.n = 9;
  o.prismatic = 0.2;
  o.ball = 0.2;
  o.planar = 0.1;
  o.fixed = 4;
  o.unit_axis = 0.4;
  return o;
}
TreeOptions free_root() {
  TreeOptions o = mixed();
  o.free_root = true;
  return o;
}
TreeOptions helical() {
  TreeOptions o = free_root();
  o.helical = 0.4;
  return o;
}

INSTANTIATE_TEST_SUITE_P(Trees, Frames,
                         ::testing::Values(TreeCase{"chain", chain()}, TreeCase{"mixed", mixed()},
                                           TreeCase{"free_root", free_root()}, TreeCase{"helical", helical()}),
                         [](const auto& info) { return std::string(info.param.name); });

TEST_P(Frames, JacobianMatchesDifferencesOfThePlacement) {
  Rng rng(11);
  double worst = 0;
  for (int trial = 0; trial < 3; ++trial) {
    const Model m = model_with_frames(rng, GetParam().options);
    Data d(m);
    const VecX q = random_q(rng, m), v = random_v(rng, m);
    update_kinematics(m, d, q);
    update_velocities(m, d, v);
    MatX J;
    for (int f = 0; f < int(m.frame_names.size()); ++f)
      for (Reference r : kReferences) {
        frame_jacobian(m, d, f, r, J);
        ASSERT_EQ(J.rows(), 6);
        ASSERT_EQ(J.cols(), m.nv);
        const Vec6 Jv = J * v, expected = velocity_by_differences(m, q, v, f, r);
        worst = std::max(worst, (Jv - expected).cwiseAbs().maxCoeff());
        EXPECT_TRUE(near_rel(Jv, expected, 1e-7)) << m.frame_names[f] << " " << to_string(r);
        EXPECT_TRUE(near_rel(frame_velocity(m, d, f, r), Jv, 1e-12)) << m.frame_names[f] << " " << to_string(r);
      }
  }
  RecordProperty("max_abs_error", sci(worst));
}

TEST_P(Frames, JdotVMatchesDifferencesOfJv) {
  Rng rng(12);
  double worst = 0;
  for (int trial = 0; trial < 3; ++trial) {
    const Model m = model_with_frames(rng, GetParam().options);
    Data d(m), a(m), b(m);
    const VecX q = random_q(rng, m), v = random_v(rng, m);
    update_kinematics(m, d, q);
    update_velocities(m, d, v);
    update_kinematics(m, a, m.integrate(q, v, -kH));
    update_kinematics(m, b, m.integrate(q, v, kH));
    MatX Ja, Jb;
    for (int f = 0; f < int(m.frame_names.size()); ++f)
      for (Reference r : kReferences) {
        frame_jacobian(m, a, f, r, Ja);
        frame_jacobian(m, b, f, r, Jb);
        const Vec6 expected = (Jb - Ja) * v / (2 * kH);
        Vec6 Jdv;
        frame_jacobian_dot_times_v(m, d, f, r, Jdv);
        worst = std::max(worst, (Jdv - expected).cwiseAbs().maxCoeff());
        EXPECT_TRUE(near_rel(Jdv, expected, 1e-7)) << m.frame_names[f] << " " << to_string(r);
      }
  }
  RecordProperty("max_abs_error", sci(worst));
}

// frame_acceleration against differences of frame_velocity along q(t) = q ⊕ t v, v(t) = v + t q̈,
// and J q̈ + J̇ v against the derivative of each reference's velocity
TEST_P(Frames, AccelerationMatchesDifferencesOfTheVelocity) {
  Rng rng(13);
  for (int trial = 0; trial < 3; ++trial) {
    const Model m = model_with_frames(rng, GetParam().options);
    Data d(m), a(m), b(m);
    const VecX q = random_q(rng, m), v = random_v(rng, m), qdd = random_v(rng, m, 2.0);
    update_kinematics(m, d, q);
    update_velocities(m, d, v);
    update_kinematics(m, a, m.integrate(q, v, -kH));
    update_velocities(m, a, v - kH * qdd);
    update_kinematics(m, b, m.integrate(q, v, kH));
    update_velocities(m, b, v + kH * qdd);
    MatX J;
    for (int f = 0; f < int(m.frame_names.size()); ++f) {
      const Placement X = frame_placement(m, d, f);
      const Vec6 lwa = frame_velocity(m, d, f, Reference::LocalWorldAligned);
      const Vec3 w = lwa.head<3>(), pd = lwa.tail<3>();
      for (Reference r : kReferences) {
        // d/dt of the reference's velocity
        const Vec6 dv = (frame_velocity(m, b, f, r) - frame_velocity(m, a, f, r)) / (2 * kH);
        // which frame_acceleration is that derivative: world and local spatial, local_world_aligned classical
        const bool classical = r == Reference::LocalWorldAligned;
        EXPECT_TRUE(near_rel(frame_acceleration(m, d, f, qdd, r, classical), dv, 1e-7)) << m.frame_names[f] << " " << to_string(r);
        Vec6 Jdv;
        frame_jacobian_dot_times_v(m, d, f, r, Jdv);
        frame_jacobian(m, d, f, r, J);
        EXPECT_TRUE(near_rel(J * qdd + Jdv, frame_acceleration(m, d, f, qdd, r, classical), 1e-11));
      }
      // the other kind of each, from the classical one in inertial axes [α; p̈]
      const Vec6 c = frame_acceleration(m, d, f, qdd, Reference::LocalWorldAligned, true);
      const Vec3 al = c.head<3>(), pdd = c.tail<3>();
      Vec6 lwa_spatial, local_classical, world_classical;
      lwa_spatial << al, pdd - w.cross(pd);
      local_classical << X.R.transpose() * al, X.R.transpose() * pdd;
      world_classical << al, pdd - al.cross(X.p) - w.cross(w.cross(X.p));
      EXPECT_TRUE(near_rel(frame_acceleration(m, d, f, qdd, Reference::LocalWorldAligned, false), lwa_spatial, 1e-12));
      EXPECT_TRUE(near_rel(frame_acceleration(m, d, f, qdd, Reference::Local, true), local_classical, 1e-12));
      EXPECT_TRUE(near_rel(frame_acceleration(m, d, f, qdd, Reference::World, true), world_classical, 1e-12));
    }
  }
}

// frames.hpp's claim: the placements and frame Jacobians need only update_frames' R, η and G
TEST_P(Frames, PlacementAndJacobianNeedOnlyTheFrames) {
  Rng rng(21);
  const Model m = model_with_frames(rng, GetParam().options);
  Data full(m), frames(m);
  const VecX q = random_q(rng, m);
  update_kinematics(m, full, q);
  update_frames(m, frames, q);
  MatX Ja, Jb;
  for (int f = 0; f < int(m.frame_names.size()); ++f) {
    EXPECT_TRUE(near_rel(frame_placement(m, frames, f).p, frame_placement(m, full, f).p, 1e-15));
    EXPECT_TRUE(near_rel(frame_placement(m, frames, f).R, frame_placement(m, full, f).R, 1e-15));
    frame_jacobian(m, full, f, Reference::World, Ja);
    frame_jacobian(m, frames, f, Reference::World, Jb);
    EXPECT_TRUE(near_rel(Jb, Ja, 1e-15));
  }
}

// frame_jacobian(q) walks the frame's body's ancestors only: the same J as the staged calls, from
// a Data that holds another state (a body it skipped, or a turn it did not recompute, shows)
TEST_P(Frames, JacobianFromQTouchesTheAncestorsOnly) {
  Rng rng(22);
  const Model m = model_with_frames(rng, GetParam().options);
  Data staged(m), from_q(m);
  MatX Ja, Jb;
  double worst = 0;
  for (int trial = 0; trial < 3; ++trial) {
    const VecX q = random_q(rng, m);
    update_frames(m, from_q, random_q(rng, m));  // stale
    update_frames(m, staged, q);
    for (int f = 0; f < int(m.frame_names.size()); ++f)
      for (const Reference r : kReferences) {
        frame_jacobian(m, staged, f, r, Ja);
        frame_jacobian(m, from_q, q, f, r, Jb);
        worst = std::max(worst, (Jb - Ja).cwiseAbs().maxCoeff() / std::max(1.0, Ja.cwiseAbs().maxCoeff()));
        update_frames(m, from_q, random_q(rng, m));
      }
  }
  EXPECT_LT(worst, 1e-14) << "largest relative difference " << sci(worst);
}

TEST_P(Frames, PointJacobianIsTheFramesLinearRows) {
  Rng rng(14);
  Model m = random_model(rng, GetParam().options);
  Data d(m);
  const VecX q = random_q(rng, m);
  update_kinematics(m, d, q);
  for (int b = 0; b < m.nbodies; ++b) {
    const Vec3 point = rng.vec3();
    const int f = m.add_frame("at" + std::to_string(b), b, {rng.rotation(), point});
    MatX Jp, Jf;
    point_jacobian(m, d, b, point, Jp);
    frame_jacobian(m, d, f, Reference::LocalWorldAligned, Jf);
    EXPECT_TRUE(near_rel(Jp, Jf.bottomRows<3>(), 1e-13));
  }
}

TEST_P(Frames, CentreOfMassAndCentroidalMomentum) {
  Rng rng(15);
  double worst_jc = 0, worst_ag = 0, worst_agd = 0;
  for (int trial = 0; trial < 3; ++trial) {
    const Model m = random_model(rng, GetParam().options);
    Data d(m), a(m), b(m);
    const VecX q = random_q(rng, m), v = random_v(rng, m);
    update_kinematics(m, d, q);
    update_velocities(m, d, v);
    // ċ = J_c v, and against differences of c
    update_kinematics(m, a, m.integrate(q, v, -kH));
    update_kinematics(m, b, m.integrate(q, v, kH));
    MatX Jc;
    com_jacobian(m, d, Jc);
    const Vec3 cd = (com(m, b) - com(m, a)) / (2 * kH);
    worst_jc = std::max(worst_jc, (Jc * v - cd).cwiseAbs().maxCoeff());
    EXPECT_TRUE(near_rel(Jc * v, cd, 1e-7));
    EXPECT_TRUE(near_rel(com_velocity(m, d), Jc * v, 1e-12));
    // from q alone (frames, subtree masses and first moments): the same J_c on a fresh Data
    Data fresh(m);
    MatX Jq;
    com_jacobian(m, fresh, q, Jq);
    EXPECT_TRUE(near_rel(Jq, Jc, 1e-12));
    // h_G = A_G v against momentum(): l = p, k_G = L_O − c × p
    MatX AG;
    centroidal_momentum_matrix(m, d, AG);
    const Momentum h = momentum(m, d);
    Vec6 expected;
    expected << h.angular - com(m, d).cross(h.linear), h.linear;
    worst_ag = std::max(worst_ag, (AG * v - expected).cwiseAbs().maxCoeff());
    EXPECT_TRUE(near_rel(AG * v, expected, 1e-11));
    EXPECT_TRUE(near_rel(centroidal_momentum(m, d), expected, 1e-11));
    EXPECT_TRUE(near_rel(AG.bottomRows<3>() / Eigen::Map<const VecX>(m.mass.data(), m.nbodies).sum(), Jc, 1e-12));
    // Ȧ_G v against differences of A_G(q) v
    MatX Aa, Ab;
    centroidal_momentum_matrix(m, a, Aa);
    centroidal_momentum_matrix(m, b, Ab);
    const Vec6 agd = (Ab - Aa) * v / (2 * kH), got = centroidal_momentum_matrix_dot_times_v(m, d);
    worst_agd = std::max(worst_agd, (got - agd).cwiseAbs().maxCoeff());
    EXPECT_TRUE(near_rel(got, agd, 1e-7));
    // the composite inertia about c, body by body
    const SpatialInertia KG = centroidal_inertia(m, d);
    Mat3 I = Mat3::Zero();
    double mass = 0;
    for (int i = 0; i < m.nbodies; ++i) {
      I += inertia_cm(d, i) + parallel_axis(m.mass[i], Vec3(d.r.col(i)) - com(m, d));
      mass += m.mass[i];
    }
    EXPECT_NEAR(KG.m, mass, 1e-12 * mass);
    EXPECT_TRUE(near_rel(KG.h, Vec3::Zero(), 1e-12 * mass));
    EXPECT_TRUE(near_rel(KG.I, I, 1e-12));
  }
  RecordProperty("max_abs_error_com_jacobian", sci(worst_jc));
  RecordProperty("max_abs_error_AG_v", sci(worst_ag));
  RecordProperty("max_abs_error_AGdot_v", sci(worst_agd));
}

TEST_P(Frames, CoriolisMatrixGivesTheBiasAndASkewMdotMinus2C) {
  Rng rng(16);
  double worst_cv = 0, worst_skew = 0;
  for (int trial = 0; trial < 3; ++trial) {
    const Model m = random_model(rng, GetParam().options);
    Data d(m), a(m), b(m);
    const VecX q = random_q(rng, m), v = random_v(rng, m);
    update_kinematics(m, d, q);
    update_velocities(m, d, v);
    MatX C;
    coriolis_matrix(m, d, C);
    // C v = bias(q, v) − bias(q, 0)
    const VecX cv = bias_at(m, q, v) - bias_at(m, q, VecX::Zero(m.nv));
    worst_cv = std::max(worst_cv, (C * v - cv).cwiseAbs().maxCoeff());
    EXPECT_TRUE(near_rel(C * v, cv, 1e-11));
    // 𝓜̇ along v by central differences; 𝓜̇ − 2C skew-symmetric
    update_kinematics(m, a, m.integrate(q, v, -kH));
    mass_matrix(m, a);
    update_kinematics(m, b, m.integrate(q, v, kH));
    mass_matrix(m, b);
    const MatX Md = (b.M - a.M) / (2 * kH), N = Md - 2 * C;
    worst_skew = std::max(worst_skew, (N + N.transpose()).cwiseAbs().maxCoeff());
    EXPECT_TRUE(near_rel(N + N.transpose(), MatX::Zero(m.nv, m.nv), 1e-7 * std::max(1.0, Md.cwiseAbs().maxCoeff())));
    // and not by accident: C itself is not symmetric, nor 𝓜̇ − C skew
    EXPECT_GT((C - C.transpose()).cwiseAbs().maxCoeff(), 1e-3);
  }
  RecordProperty("max_abs_error_Cv", sci(worst_cv));
  RecordProperty("max_abs_symmetric_part", sci(worst_skew));
}

TEST_P(Frames, OperationalSpaceInertiaMatchesTheDenseFormula) {
  Rng rng(17);
  TreeOptions o = GetParam().options;
  o.n = std::max(o.n, 8);
  const Model m0 = random_model(rng, o);
  Model m = m0;
  m.add_frame("tool", m.nbodies - 1, {rng.rotation(), rng.vec3()});
  Data d(m);
  const VecX q = random_q(rng, m);
  update_kinematics(m, d, q);
  MatX J, L;
  frame_jacobian(m, d, m.frame_index("tool"), Reference::LocalWorldAligned, J);
  // a chain's last body has at least 6 DOFs above it here; a tree's may not: its linear rows
  const bool full = Eigen::FullPivLU<MatX>(J).rank() == 6;
  const MatX task = full ? J : MatX(J.bottomRows<3>());
  if (Eigen::FullPivLU<MatX>(task).rank() < task.rows()) GTEST_SKIP() << "the tool's body has too few DOFs above it";
  operational_space_inertia(m, d, task, L);
  mass_matrix(m, d);
  const MatX dense = (task * d.M.inverse() * task.transpose()).inverse();
  EXPECT_TRUE(near_rel(L, dense, 1e-9)) << (full ? "6 rows" : "3 rows");
}

// the links a URDF welds by fixed joints, as frames, are the same points as those links' body
// frames on the twin URDF where the joints turn (held at 0): placement and Jacobian
TEST(FramesMerged, FixedJointFramesEqualTheUnmergedTwin) {
  for (const bool free : {false, true}) {
    const std::string dir = std::string(SOADYN_SOURCE_DIR) + "/tests/data/frames/";
    const Model merged = load_urdf(dir + "arm_fixed.urdf", free, urdf_gravity());
    const Model twin = load_urdf(dir + "arm_unmerged.urdf", free, urdf_gravity());
    ASSERT_EQ(merged.nv + 3, twin.nv);
    for (const char* name : {"base_link", "link1", "link2", "link3", "flange", "tool", "camera"}) {
      ASSERT_GE(merged.frame_index(name), 0) << name;
    }
    EXPECT_EQ(merged.frame_body[merged.frame_index("tool")], merged.body_index("link3"));
    EXPECT_EQ(merged.frame_body[merged.frame_index("camera")], free ? merged.body_index("base_link") : -1);
    Rng rng(19);
    Data dm(merged), dt(twin);
    for (int trial = 0; trial < 4; ++trial) {
      const VecX q = random_q(rng, merged);
      // the twin's q: the merged joints' coordinates, the extra joints at 0
      VecX qt = twin.neutral_configuration();
      for (int i = 0; i < merged.nbodies; ++i) {
        const int j = twin.joint_index(merged.joint_names[i]);
        qt.segment(twin.idx_q[j], twin.nq_i[j]) = q.segment(merged.idx_q[i], merged.nq_i[i]);
      }
      update_kinematics(merged, dm, q);
      update_kinematics(twin, dt, qt);
      for (const char* name : {"link3", "flange", "tool", "camera"}) {
        const Placement a = frame_placement(merged, dm, merged.frame_index(name));
        const Placement b = frame_placement(twin, dt, twin.frame_index(name));
        EXPECT_TRUE(near_rel(a.R, b.R, 1e-14)) << name;
        EXPECT_TRUE(near_rel(a.p, b.p, 1e-14)) << name;
        for (Reference r : kReferences) {
          MatX Ja, Jb;
          frame_jacobian(merged, dm, merged.frame_index(name), r, Ja);
          frame_jacobian(twin, dt, twin.frame_index(name), r, Jb);
          for (int i = 0; i < merged.nbodies; ++i) {
            const int j = twin.joint_index(merged.joint_names[i]);
            EXPECT_TRUE(near_rel(Ja.middleCols(merged.idx_v[i], merged.nv_i[i]), Jb.middleCols(twin.idx_v[j], twin.nv_i[j]), 1e-13))
                << name << " " << to_string(r) << " joint " << merged.joint_names[i];
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace soadyn::test
