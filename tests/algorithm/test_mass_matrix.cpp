// The system mass matrix: the note's four hand-derived examples, literal procedure vs composite
// algorithm on random trees, 𝓜 = ∂²T/∂q̇² with T from finite-differenced body motion, SPD.
#include "test_util.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>

using namespace soadyn;
using namespace soadyn::test;

namespace {

const Vec3 ex = Vec3::UnitX(), ey = Vec3::UnitY(), ez = Vec3::UnitZ();

BodySpec random_body(Rng& rng, const std::string& name, int parent, JointType j, const Vec3& axis) {
  BodySpec b;
  b.name = name;
  b.parent = parent;
  b.joint = j;
  b.axis = axis;
  b.mass = rng.uniform(0.3, 5.0);
  b.com = rng.vec3(-1, 1);
  b.inertia = rng.inertia();
  return b;
}

constexpr int kTrials = 200;

// Example 1, pendulum with a moving base: 𝓜 = [m1 + m2, m2 L cos θ; m2 L cos θ, I2zz + m2 L²]
TEST(NoteExamples, Example1PendulumOnCart) {
  Rng rng(1);
  for (int t = 0; t < kTrials; ++t) {
    auto cart = random_body(rng, "cart", -1, JointType::Prismatic, ex);
    auto pend = random_body(rng, "pendulum", 0, JointType::Revolute, ez);
    const double L = rng.uniform(0.1, 3.0);
    pend.com = Vec3(0, -L, 0);  // s_2 = L (sin θ e_x − cos θ e_y)
    const Model model = Model::build({cart, pend});
    Data data(model);
    const double x = rng.uniform(-5, 5), th = rng.uniform(-4, 4);
    const Computed c = both(model, data, Eigen::Vector2d(x, th));
    const double m1 = cart.mass, m2 = pend.mass, Izz = pend.inertia(2, 2);
    MatX expected(2, 2);
    expected << m1 + m2, m2 * L * std::cos(th), m2 * L * std::cos(th), Izz + m2 * L * L;
    ASSERT_TRUE(near_rel(c.literal, expected, 1e-12)) << "trial " << t;
    ASSERT_TRUE(near_rel(c.composite, expected, 1e-12)) << "trial " << t;
  }
}

// The positions and inertias the closed forms of Examples 2–4 need, computed here from each
// example's geometry (axes, joint placements, centres of mass) with Rodrigues' formula and the
// quaternion's matrix — never from the Data under test.
Mat3 rodrigues(const Vec3& unit_axis, double angle) {
  const Mat3 K = skew(unit_axis);
  return Mat3::Identity() + std::sin(angle) * K + (1 - std::cos(angle)) * K * K;
}

Mat3 quaternion_matrix(double w, double x, double y, double z) {
  const double n = std::sqrt(w * w + x * x + y * y + z * z);
  w /= n, x /= n, y /= n, z /= n;
  Mat3 R;
  R << 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),  //
      2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),   //
      2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y);
  return R;
}

// body j of an example at one configuration, inertial: η_j, s_j, r_j = η_j + s_j, I_j about the cm
struct Pose {
  Mat3 R;
  Vec3 eta, s, r;
  Mat3 I;
  double m;
};

Pose pose(const BodySpec& b, const Mat3& R, const Vec3& eta) {
  const Vec3 s = R * b.com;
  return {R, eta, s, eta + s, R * b.inertia * R.transpose(), b.mass};
}

// Example 2, double pendulum about e_x: (N6) expanded, r1 = s1, r2 = d2 + s2
TEST(NoteExamples, Example2DoublePendulum) {
  Rng rng(2);
  for (int t = 0; t < kTrials; ++t) {
    auto b1 = random_body(rng, "upper", -1, JointType::Revolute, ex);
    auto b2 = random_body(rng, "lower", 0, JointType::Revolute, ex);
    b2.placement.p = rng.vec3(-1, 1);
    const Model model = Model::build({b1, b2});
    Data data(model);
    const double th1 = rng.uniform(-4, 4), th2 = rng.uniform(-4, 4);
    const Computed c = both(model, data, Eigen::Vector2d(th1, th2));
    // η_1 = 0, η_2 = d_2 = C_1 p_2; C_1 = rot(e_x, θ_1), C_2 = C_1 rot(e_x, θ_2)
    const Mat3 C1 = rodrigues(ex, th1), C2 = C1 * rodrigues(ex, th2);
    const Pose p1 = pose(b1, C1, Vec3::Zero()), p2 = pose(b2, C2, C1 * b2.placement.p);
    const Mat3 r1 = skew(p1.r), r2 = skew(p2.r), S2 = skew(p2.s);
    const Mat3 &I1 = p1.I, &I2 = p2.I;
    const double m1 = b1.mass, m2 = b2.mass;
    MatX expected(2, 2);
    expected << ex.dot((I1 + I2 - m1 * r1 * r1 - m2 * r2 * r2) * ex), ex.dot((I2 - m2 * r2 * S2) * ex),
        ex.dot((I2 - m2 * S2 * r2) * ex), ex.dot((I2 - m2 * S2 * S2) * ex);
    ASSERT_TRUE(near_rel(c.literal, expected, 1e-12)) << "trial " << t;
    ASSERT_TRUE(near_rel(c.composite, expected, 1e-12)) << "trial " << t;
  }
}

// Example 3, satellite with two arrays: the 8×8 matrix with the free root, e_x = C_1 [1,0,0].
// The note takes η_1 = 0 (r_1 = s_1); for a satellite anywhere, every r_j is measured from η_1.
TEST(NoteExamples, Example3SatelliteWithTwoArrays) {
  Rng rng(3);
  for (int t = 0; t < kTrials; ++t) {
    auto bus = random_body(rng, "bus", -1, JointType::Free, Vec3::Zero());
    auto a2 = random_body(rng, "array_left", 0, JointType::Revolute, ex);
    auto a3 = random_body(rng, "array_right", 0, JointType::Revolute, ex);
    a2.placement.p = rng.vec3(-2, 2);
    a3.placement.p = rng.vec3(-2, 2);
    const Model model = Model::build({bus, a2, a3});
    Data data(model);
    VecX q(9);
    const bool at_origin = t % 2 == 0;
    q.head<3>() = at_origin ? Vec3::Zero() : rng.vec3(-10, 10);
    q.segment<4>(3) = Eigen::Vector4d::Random().normalized();
    q.tail<2>() = Eigen::Vector2d(rng.uniform(-4, 4), rng.uniform(-4, 4));
    const Computed c = both(model, data, q);

    // C_1 from the quaternion (w, x, y, z); η_1 = the bus position; d_j = C_1 p_j;
    // C_j = C_1 rot(e_x, θ_j).  Positions relative to η_1.
    const Mat3 C1 = quaternion_matrix(q(3), q(4), q(5), q(6));
    const std::vector<Pose> P = {pose(bus, C1, Vec3::Zero()),
                                 pose(a2, C1 * rodrigues(ex, q(7)), C1 * a2.placement.p),
                                 pose(a3, C1 * rodrigues(ex, q(8)), C1 * a3.placement.p)};
    const Vec3 e = C1 * ex;
    double mbar = 0.0;
    Vec3 h = Vec3::Zero();
    Mat3 I00 = Mat3::Zero();
    for (int j = 0; j < 3; ++j) {
      I00 += P[j].I - P[j].m * skew(P[j].r) * skew(P[j].r);  // r_1 = s_1, r_j = d_j + s_j
      mbar += P[j].m;
      h += P[j].m * P[j].r;
    }
    const Vec3 cbar = h / mbar;
    MatX expected = MatX::Zero(8, 8);
    expected.block<3, 3>(0, 0) = I00;
    expected.block<3, 3>(0, 3) = mbar * skew(cbar);
    expected.block<3, 3>(3, 0) = -mbar * skew(cbar);
    expected.block<3, 3>(3, 3) = mbar * Mat3::Identity();
    for (int j = 1; j < 3; ++j) {
      const double mj = P[j].m;
      const Mat3 &Ij = P[j].I, S = skew(P[j].s), Rj = skew(P[j].r);
      expected.block<3, 1>(0, 5 + j) = (Ij - mj * Rj * S) * e;
      expected.block<3, 1>(3, 5 + j) = -mj * S * e;
      expected.block<1, 3>(5 + j, 0) = e.transpose() * (Ij - mj * S * Rj);
      expected.block<1, 3>(5 + j, 3) = e.transpose() * mj * S;
      expected(5 + j, 5 + j) = e.dot((Ij - mj * S * S) * e);
    }
    ASSERT_TRUE(near_rel(c.literal, expected, 1e-12)) << "trial " << t;
    ASSERT_TRUE(near_rel(c.composite, expected, 1e-12)) << "trial " << t;
  }
}

// Example 4, 3-link arm, (P7).  Discrepancy in the note: the hinge axes of joints 2 and 3 are
// written e_x, but they turn with θ_1 about e_z.  (P7) holds with e_x read as the inertial image
// of body 1's x axis, C_1 e_x = g_2 = g_3; with the literal inertial e_x it holds only at
// θ_1 = 0 (mod π).  We test the corrected reading, and that the literal one fails elsewhere.
struct Arm {
  BodySpec b1, b2, b3;
};

// C_1 = rot(e_z, θ_1), C_2 = C_1 rot(e_x, θ_2), C_3 = C_2 rot(e_x, θ_3); η_1 = 0, η_2 = C_1 p_2,
// η_3 = η_2 + C_2 p_3
std::vector<Pose> arm_poses(const Arm& a, const Vec3& q) {
  const Mat3 C1 = rodrigues(ez, q(0)), C2 = C1 * rodrigues(ex, q(1)), C3 = C2 * rodrigues(ex, q(2));
  const Vec3 eta2 = C1 * a.b2.placement.p, eta3 = eta2 + C2 * a.b3.placement.p;
  return {pose(a.b1, C1, Vec3::Zero()), pose(a.b2, C2, eta2), pose(a.b3, C3, eta3)};
}

MatX example4_closed_form(const std::vector<Pose>& P, const Vec3& e) {
  const Vec3 eta2 = P[1].eta;  // η_2 = d_2 (η_1 = 0)
  auto m = [&](int j) { return P[j].m; };
  auto sk = [](const Vec3& v) { return skew(v); };
  std::vector<Vec3> r = {P[0].r, P[1].r, P[2].r};
  std::vector<Mat3> I = {P[0].I, P[1].I, P[2].I};
  const Mat3 S3 = sk(P[2].s), E2 = sk(eta2);
  MatX M(3, 3);
  Mat3 A11 = Mat3::Zero(), A12 = Mat3::Zero(), A22 = Mat3::Zero(), A21 = Mat3::Zero();
  for (int j = 0; j < 3; ++j) A11 += I[j] - m(j) * sk(r[j]) * sk(r[j]);
  for (int j = 1; j < 3; ++j) {
    A12 += I[j] - m(j) * sk(r[j]) * (sk(r[j]) - E2);
    A21 += I[j] - m(j) * (sk(r[j]) - E2) * sk(r[j]);
    A22 += I[j] - m(j) * (sk(r[j]) - E2) * (sk(r[j]) - E2);
  }
  M(0, 0) = ez.dot(A11 * ez);
  M(0, 1) = ez.dot(A12 * e);
  M(0, 2) = ez.dot((I[2] - m(2) * sk(r[2]) * S3) * e);
  M(1, 0) = e.dot(A21 * ez);
  M(1, 1) = e.dot(A22 * e);
  M(1, 2) = e.dot((I[2] - m(2) * (sk(r[2]) - E2) * S3) * e);
  M(2, 0) = e.dot((I[2] - m(2) * S3 * sk(r[2])) * ez);
  M(2, 1) = e.dot((I[2] - m(2) * S3 * (sk(r[2]) - E2)) * e);
  M(2, 2) = e.dot((I[2] - m(2) * S3 * S3) * e);
  return M;
}

Arm random_arm(Rng& rng) {
  Arm a{random_body(rng, "base", -1, JointType::Revolute, ez), random_body(rng, "upper_arm", 0, JointType::Revolute, ex),
        random_body(rng, "forearm", 1, JointType::Revolute, ex)};
  a.b2.placement.p = rng.vec3(-1, 1);
  a.b3.placement.p = rng.vec3(-1, 1);
  return a;
}

TEST(NoteExamples, Example4ThreeLinkArm) {
  Rng rng(4);
  int literal_reading_failures = 0;
  for (int t = 0; t < kTrials; ++t) {
    const Arm arm = random_arm(rng);
    const Model model = Model::build({arm.b1, arm.b2, arm.b3});
    Data data(model);
    const Eigen::Vector3d q(rng.uniform(0.2, 2.9), rng.uniform(-4, 4), rng.uniform(-4, 4));
    const Computed c = both(model, data, q);
    const std::vector<Pose> P = arm_poses(arm, q);
    const Vec3 g2 = P[0].R * ex;  // C_1 e_x
    const MatX expected = example4_closed_form(P, g2);
    ASSERT_TRUE(near_rel(c.literal, expected, 1e-12)) << "trial " << t;
    ASSERT_TRUE(near_rel(c.composite, expected, 1e-12)) << "trial " << t;
    if (!near_rel(c.composite, example4_closed_form(P, ex), 1e-6)) ++literal_reading_failures;
  }
  EXPECT_EQ(literal_reading_failures, kTrials) << "the literal inertial e_x should fail for θ_1 in (0.2, 2.9)";
  // and at θ_1 = 0 both readings agree
  Rng rng0(40);
  Arm arm = random_arm(rng0);
  const Model model = Model::build({arm.b1, arm.b2, arm.b3});
  Data data(model);
  const Eigen::Vector3d q(0.0, 0.7, -1.3);
  const Computed c = both(model, data, q);
  EXPECT_TRUE(near_rel(c.composite, example4_closed_form(arm_poses(arm, q), ex), 1e-12));
}

// literal procedure = composite algorithm on random trees
class RandomTrees : public ::testing::TestWithParam<TreeCase> {};

TEST_P(RandomTrees, LiteralEqualsCompositeAndIsSPD) {
  const TreeCase& tc = GetParam();
  for (int seed = 0; seed < 5; ++seed) {
    Rng rng(100 * seed + tc.options.n);
    const Model model = random_model(rng, tc.options);
    Data data(model);
    const Computed c = both(model, data, random_q(rng, model));
    // both triangles: the literal Jᵀ (M J) computes every entry, the sweep writes one triangle and mirrors it
    ASSERT_TRUE(near_rel(c.composite, c.literal, 1e-12)) << tc.name << " seed " << seed;
    Eigen::LLT<MatX> llt(c.composite);
    ASSERT_EQ(llt.info(), Eigen::Success) << "not positive definite";
    const Eigen::SelfAdjointEigenSolver<MatX> es(c.composite);
    ASSERT_GT(es.eigenvalues().minCoeff(), 0.0);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Trees, RandomTrees,
    ::testing::Values(TreeCase{"chain8", {.n = 8, .branching = 0.0}},
                      TreeCase{"chain200", {.n = 200, .branching = 0.0}},
                      TreeCase{"branched50", {.n = 50, .branching = 0.7}},
                      TreeCase{"mixed60", {.n = 60, .branching = 0.5, .prismatic = 0.4}},
                      TreeCase{"free40", {.n = 40, .branching = 0.5, .prismatic = 0.2, .free_root = true}},
                      TreeCase{"free200", {.n = 200, .branching = 0.3, .prismatic = 0.3, .free_root = true}},
                      TreeCase{"fixed30", {.n = 30, .branching = 0.5, .prismatic = 0.2, .fixed = 8}},
                      TreeCase{"unit_axes40", {.n = 40, .branching = 0.5, .prismatic = 0.3, .unit_axis = 0.7}},
                      TreeCase{"unit_axes_chain64", {.n = 64, .branching = 0.0, .unit_axis = 1.0}},
                      TreeCase{"helical40", {.n = 40, .branching = 0.5, .prismatic = 0.2, .helical = 0.4}}),
    [](const auto& info) { return std::string(info.param.name); });

// The specialized kinematics (joints along ±x, ±y, ±z of their frame, unturned placements) against
// the generic joint interface it replaces, on every joint type and both kinds of axis.
TEST(Kinematics, SpecializedPathEqualsReference) {
  int specialized = 0;
  for (int seed = 0; seed < 20; ++seed) {
    Rng rng(7000 + seed);
    const Model model = random_model(rng, {.n = 30, .branching = 0.5, .prismatic = 0.3, .ball = 0.1, .planar = 0.1,
                                           .free_root = seed % 2 == 0, .fixed = 3, .unit_axis = 0.6});
    for (int i = 0; i < model.nbodies; ++i)
      specialized += std::string(kind_name(model.joint_model[i])).find("-axis-") != std::string::npos;
    Data fast(model), ref(model);
    VecX q = random_q(rng, model);
    // half the seeds turn the revolute joints far (the batched turns reduce large angles too)
    if (seed >= 10)
      for (int i = 0; i < model.nbodies; ++i)
        if (model.joint_type[i] == JointType::Revolute) q(model.idx_q[i]) *= 1e3;
    update_kinematics(model, fast, q);
    update_kinematics_reference(model, ref, q);
    for (int i = 0; i < model.nbodies; ++i) {
      ASSERT_TRUE(near_rel(fast.R[i], ref.R[i], 1e-14)) << "seed " << seed << " body " << i;
      ASSERT_TRUE(near_rel(fast.inertia[i].I, ref.inertia[i].I, 1e-13)) << "seed " << seed << " body " << i;
      ASSERT_TRUE(near_rel(fast.inertia[i].h, ref.inertia[i].h, 1e-13)) << "seed " << seed << " body " << i;
    }
    for (const auto& [a, b] : {std::pair{&fast.eta, &ref.eta}, {&fast.d, &ref.d}, {&fast.s, &ref.s}, {&fast.r, &ref.r}})
      ASSERT_TRUE(near_rel(*a, *b, 1e-13)) << "seed " << seed;
    ASSERT_TRUE(near_rel(fast.G, ref.G, 1e-14)) << "seed " << seed;
  }
  EXPECT_GT(specialized, 100);  // the path under test was taken
}

// joint_turns against std::cos and std::sin: every revolute joint along a unit axis and nothing
// else (Model::angles, roots first), for every count of turning joints modulo the batch of
// four, with roots = false leaving the root joints' columns as they were
TEST(Kinematics, JointTurnsAreEveryUnitRevoluteJointsCosSin) {
  for (int n = 1; n <= 14; ++n) {
    Rng rng(7100 + n);
    // several roots (branching 1 draws parents among all earlier bodies, the first hangs from the ground)
    std::vector<BodySpec> specs = random_specs(rng, {.n = n, .branching = 1.0, .prismatic = 0.2, .unit_axis = 0.8});
    for (size_t k = 1; k < specs.size(); k += 3) specs[k].parent = -1;
    const Model model = Model::build(specs);
    std::vector<int> expected;
    for (const bool roots : {true, false})
      for (int i = 0; i < model.nbodies; ++i)
        if (model.joint_type[i] == JointType::Revolute && (model.parent[i] < 0) == roots &&
            model.axis[i].cwiseAbs().maxCoeff() == 1.0 && model.axis[i].cwiseAbs().sum() == 1.0)
          expected.push_back(i);
    ASSERT_EQ(model.angles.body, expected) << "n " << n;
    VecX q = random_q(rng, model);
    q *= 40.0;  // angles beyond ±π
    for (const bool roots : {true, false}) {
      Eigen::Matrix2Xd turn = Eigen::Matrix2Xd::Constant(2, model.nbodies, 7.0);
      joint_turns(model, q, turn, roots);
      for (int i = 0; i < model.nbodies; ++i) {
        const bool listed = std::find(expected.begin(), expected.end(), i) != expected.end();
        if (!listed || (!roots && model.parent[i] < 0)) {
          EXPECT_EQ(turn(0, i), 7.0) << "n " << n << " body " << i << " was written";
          continue;
        }
        const double x = q(model.idx_q[i]);
        EXPECT_NEAR(turn(0, i), std::cos(x), 4e-16) << "n " << n << " body " << i;
        EXPECT_NEAR(turn(1, i), std::sin(x), 4e-16) << "n " << n << " body " << i;
      }
    }
  }
}

// T from eq. (9) with ω_i and ṙ_i by central differences of the body poses along q ⊕ h v —
// independent of the velocity sweep — and 𝓜_jk = T(e_j + e_k) − T(e_j) − T(e_k).
double kinetic_energy_fd(const Model& model, const VecX& q, const VecX& v) {
  const double h = 1e-5;
  Data plus(model), minus(model), mid(model);
  update_kinematics(model, plus, model.integrate(q, v, h));
  update_kinematics(model, minus, model.integrate(q, v, -h));
  update_kinematics(model, mid, q);
  double T = 0.0;
  for (int i = 0; i < model.nbodies; ++i) {
    const Vec3 rdot = (plus.r.col(i) - minus.r.col(i)) / (2 * h);
    const Mat3 W = (plus.R[i] - minus.R[i]) / (2 * h) * mid.R[i].transpose();  // Ṙ Rᵀ = ω̃
    const Vec3 w(W(2, 1), W(0, 2), W(1, 0));
    T += 0.5 * (w.dot(inertia_cm(mid, i) * w) + model.mass[i] * rdot.squaredNorm());
  }
  return T;
}

TEST(MassMatrix, IsSecondDerivativeOfKineticEnergy) {
  for (int seed = 0; seed < 6; ++seed) {
    Rng rng(900 + seed);
    const Model model = random_model(rng, {.n = 9, .branching = 0.5, .prismatic = 0.3, .free_root = seed % 2 == 0});
    Data data(model);
    const VecX q = random_q(rng, model);
    update_kinematics(model, data, q);
    mass_matrix(model, data);
    MatX Mfd(model.nv, model.nv);
    const MatX E = MatX::Identity(model.nv, model.nv);
    for (int j = 0; j < model.nv; ++j)
      for (int k = 0; k < model.nv; ++k)
        Mfd(j, k) = kinetic_energy_fd(model, q, E.col(j) + E.col(k)) - kinetic_energy_fd(model, q, E.col(j)) -
                    kinetic_energy_fd(model, q, E.col(k));
    EXPECT_TRUE(near_rel(Mfd, data.M, 1e-7)) << "seed " << seed;

    // T = ½ q̇ᵀ 𝓜 q̇, with T from eq. (9) on the swept body velocities (eq. 6), and from the FD motion
    const VecX v = random_v(rng, model, 2.0);
    update_velocities(model, data, v);
    const double T_quad = 0.5 * v.dot(data.M * v);
    EXPECT_NEAR(kinetic_energy(model, data), T_quad, 1e-12 * std::max(1.0, T_quad));
    EXPECT_NEAR(kinetic_energy_fd(model, q, v), T_quad, 1e-7 * std::max(1.0, T_quad));
  }
}

// M_i = S_iᵀ M̄_i S_i (eq. 12) with M̄_i = diag(I_i, m_i e), from the 6×6 matrices themselves; and
// SpatialInertia::from_body builds the same M_i from (m, s, I_cm)
TEST(MassMatrix, BodyInertiaAtTheJointPointIsEq12) {
  Rng rng(78);
  const Model model = random_model(rng, {.n = 20, .branching = 0.5, .prismatic = 0.3, .free_root = true});
  Data data(model);
  update_kinematics(model, data, random_q(rng, model));
  for (int i = 0; i < model.nbodies; ++i) {
    Mat6 Mbar = Mat6::Zero();
    Mbar.topLeftCorner<3, 3>() = data.R[i] * model.inertia[i] * data.R[i].transpose();
    Mbar.bottomRightCorner<3, 3>() = model.mass[i] * Mat3::Identity();
    const Mat6 S = S_matrix(data, i);
    EXPECT_TRUE(near_rel(M_matrix(data, i), S.transpose() * Mbar * S, 1e-13)) << "body " << i;
    const SpatialInertia K = SpatialInertia::from_body(model.mass[i], data.s.col(i), inertia_cm(data, i));
    EXPECT_TRUE(near_rel(K.matrix(), S.transpose() * Mbar * S, 1e-13)) << "body " << i;
  }
}

// J = S Ψ_D G gives v̄ = J q̇ (eq. 6), and 𝓜 = Jᵀ M̄ J (eq. 12)
TEST(MassMatrix, JacobianGivesBodyVelocitiesAndFactorsM) {
  Rng rng(77);
  const Model model = random_model(rng, {.n = 30, .branching = 0.5, .prismatic = 0.3, .free_root = true});
  Data data(model);
  update_kinematics(model, data, random_q(rng, model));
  const VecX v = random_v(rng, model);
  update_velocities(model, data, v);
  MatX J;
  jacobian(model, data, J);
  const VecX vbar = J * v;
  EXPECT_TRUE(near_rel(Eigen::Map<const VecX>(vbar.data(), vbar.size()),
                       Eigen::Map<const VecX>(data.Vbar.data(), data.Vbar.size()), 1e-12));
  MatX Mbar = MatX::Zero(6 * model.nbodies, 6 * model.nbodies);
  for (int i = 0; i < model.nbodies; ++i) {
    Mbar.block<3, 3>(6 * i, 6 * i) = inertia_cm(data, i);
    Mbar.block<3, 3>(6 * i + 3, 6 * i + 3) = model.mass[i] * Mat3::Identity();
  }
  mass_matrix(model, data);
  EXPECT_TRUE(near_rel(J.transpose() * Mbar * J, data.M, 1e-12));
}

}  // namespace
