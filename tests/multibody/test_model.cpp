// Building a model: what it refuses (with the message), and fixed-joint merging.
#include "test_util.hpp"

#include <Eigen/Eigenvalues>

#include <cstdio>

using namespace soadyn;
using namespace soadyn::test;

namespace {

BodySpec body(const std::string& name, int parent) {
  BodySpec b;
  b.name = name;
  b.parent = parent;
  b.axis = Vec3::UnitZ();
  b.mass = 1.0;
  b.com = Vec3(0.1, 0, 0);
  b.inertia = Vec3(0.1, 0.2, 0.25).asDiagonal();
  return b;
}

std::string refusal(std::vector<BodySpec> specs) {
  try {
    Model::build(specs);
  } catch (const Error& e) {
    return e.what();
  }
  return "(accepted)";
}

using ::testing::HasSubstr;

TEST(ModelBuild, RefusesParentOrder) {
  auto specs = std::vector{body("a", -1), body("b", 0), body("c", 0)};
  specs[1].parent = 2;
  const std::string msg = refusal(specs);
  EXPECT_THAT(msg, HasSubstr("body 'b' (index 1)"));
  EXPECT_THAT(msg, HasSubstr("parent"));
  EXPECT_THAT(msg, HasSubstr("got 2"));
}

TEST(ModelBuild, RefusesNonPositiveMass) {
  for (double m : {0.0, -1.0}) {
    auto specs = std::vector{body("a", -1), body("b", 0)};
    specs[1].mass = m;
    EXPECT_THAT(refusal(specs), HasSubstr("body 'b' (index 1): mass: expected a positive mass"));
  }
}

TEST(ModelBuild, RefusesAsymmetricInertia) {
  auto specs = std::vector{body("a", -1)};
  specs[0].inertia(0, 1) = 0.01;
  EXPECT_THAT(refusal(specs), HasSubstr("inertia: expected a symmetric matrix"));
}

TEST(ModelBuild, RefusesIndefiniteInertia) {
  auto specs = std::vector{body("a", -1)};
  specs[0].inertia = Vec3(0.1, -0.2, 0.25).asDiagonal();
  EXPECT_THAT(refusal(specs), HasSubstr("inertia: expected a positive semidefinite matrix"));
}

TEST(ModelBuild, RefusesTriangleInequalityViolation) {
  auto specs = std::vector{body("a", -1)};
  specs[0].inertia = Vec3(0.1, 0.1, 0.3).asDiagonal();
  EXPECT_THAT(refusal(specs), HasSubstr("triangle inequality"));
  // a thin rod (0, I, I) is at the limit and must be accepted... but it is not positive definite;
  // a near-rod with a tiny moment is fine
  specs[0].inertia = Vec3(1e-6, 0.3, 0.3).asDiagonal();
  EXPECT_EQ(refusal(specs), "(accepted)");
}

TEST(ModelBuild, RefusesZeroAxis) {
  auto specs = std::vector{body("a", -1)};
  specs[0].axis = Vec3::Zero();
  EXPECT_THAT(refusal(specs), HasSubstr("axis: expected a non-zero vector"));
}

TEST(ModelBuild, RefusesNaNAndInf) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  {
    auto specs = std::vector{body("a", -1)};
    specs[0].mass = nan;
    EXPECT_THAT(refusal(specs), HasSubstr("mass: expected finite numbers"));
  }
  {
    auto specs = std::vector{body("a", -1)};
    specs[0].com.y() = inf;
    EXPECT_THAT(refusal(specs), HasSubstr("centre of mass: expected finite numbers"));
  }
  {
    auto specs = std::vector{body("a", -1)};
    specs[0].inertia(2, 2) = nan;
    EXPECT_THAT(refusal(specs), HasSubstr("inertia: expected finite numbers"));
  }
  {
    auto specs = std::vector{body("a", -1)};
    specs[0].placement.p.x() = -inf;
    EXPECT_THAT(refusal(specs), HasSubstr("placement translation: expected finite numbers"));
  }
  EXPECT_THROW(Model::build({body("a", -1)}, Vec3(0, 0, nan)), Error);
}

TEST(ModelBuild, RefusesFreeJointBelowTheRoot) {
  auto specs = std::vector{body("a", -1), body("b", 0)};
  specs[1].joint = JointType::Free;
  EXPECT_THAT(refusal(specs), HasSubstr("free joint only at a root"));
}

TEST(ModelBuild, RefusesNonRotationPlacement) {
  auto specs = std::vector{body("a", -1)};
  specs[0].placement.R(0, 0) = 2.0;
  EXPECT_THAT(refusal(specs), HasSubstr("placement rotation: expected a proper rotation matrix"));
}

TEST(ModelBuild, SizesAndDofTree) {
  auto specs = std::vector{body("base", -1), body("a", 0), body("b", 0)};
  specs[0].joint = JointType::Free;
  const Model m = Model::build(specs);
  EXPECT_EQ(m.nq, 9);
  EXPECT_EQ(m.nv, 8);
  EXPECT_EQ(m.depth, 2);
  EXPECT_EQ(m.dof_parent, (std::vector<int>{-1, 0, 1, 2, 3, 4, 5, 5}));
}

// A body welded by a fixed joint is merged exactly: the merged model has the same 𝓜 as the
// unmerged one with the weld replaced by a revolute joint held at a constant angle (zero).
TEST(ModelBuild, FixedJointMergesExactly) {
  for (int seed = 0; seed < 20; ++seed) {
    Rng rng(500 + seed);
    TreeOptions o{.n = 12, .branching = 0.6, .prismatic = 0.2, .free_root = seed % 2 == 1, .fixed = 4};
    const auto specs = random_specs(rng, o);
    const Model merged = Model::build(specs, o.gravity);
    EXPECT_EQ(merged.nbodies, o.n);

    auto unmerged_specs = specs;
    std::vector<int> welded;  // v indices of the would-be fixed joints
    for (auto& b : unmerged_specs)
      if (b.joint == JointType::Fixed) b.joint = JointType::Revolute;
    const Model unmerged = Model::build(unmerged_specs, o.gravity);

    // same configuration: the welded joints at zero
    const VecX q = random_q(rng, merged);
    VecX qu(unmerged.nq);
    int km = 0;
    for (int i = 0; i < int(specs.size()); ++i) {
      const int iu = i;  // unmerged keeps every spec as a body
      if (specs[i].joint == JointType::Fixed) {
        qu(unmerged.idx_q[iu]) = 0.0;
        welded.push_back(unmerged.idx_v[iu]);
      } else {
        qu.segment(unmerged.idx_q[iu], unmerged.nq_i[iu]) = q.segment(merged.idx_q[km], merged.nq_i[km]);
        ++km;
      }
    }
    Data dm(merged), du(unmerged);
    update_kinematics(merged, dm, q);
    update_kinematics(unmerged, du, qu);
    mass_matrix(merged, dm);
    mass_matrix(unmerged, du);
    // drop the welded rows and columns of the unmerged matrix
    std::vector<int> keep;
    for (int k = 0; k < unmerged.nv; ++k)
      if (std::find(welded.begin(), welded.end(), k) == welded.end()) keep.push_back(k);
    MatX Mu(keep.size(), keep.size());
    for (size_t r = 0; r < keep.size(); ++r)
      for (size_t c = 0; c < keep.size(); ++c) Mu(r, c) = du.M(keep[r], keep[c]);
    EXPECT_TRUE(near_rel(dm.M, Mu, 1e-12)) << "seed " << seed;
    EXPECT_NEAR(potential_energy(merged, dm), potential_energy(unmerged, du), 1e-10);
  }
}

// free-root kinematics: q̇(q, v) and back, and q̇ against the motion q ⊕ h v by central differences
TEST(FreeRoot, QdotAndItsReverseMap) {
  for (int seed = 0; seed < 20; ++seed) {
    Rng rng(800 + seed);
    const Model m = random_model(rng, {.n = 4, .branching = 0.5, .prismatic = 0.3, .free_root = true});
    const VecX q = random_q(rng, m), v = random_v(rng, m, 3.0);
    VecX qd(m.nq);
    m.qdot(q, v, qd);
    EXPECT_TRUE(near_rel(m.velocity(q, qd), v, 1e-14));
    const double h = 1e-6;
    const VecX fd = (m.integrate(q, v, h) - m.integrate(q, v, -h)) / (2 * h);
    EXPECT_TRUE(near_rel(qd, fd, 1e-8)) << "seed " << seed;
    EXPECT_NEAR(q.segment<4>(3).dot(qd.segment<4>(3)), 0.0, 1e-14) << "q̇uat keeps the norm";
  }
}

// vectors of the wrong size and a Data of another model are refused, not read past
TEST(Data, WrongSizesAreRefused) {
  Rng rng(12);
  const Model m = random_model(rng, {.n = 5});
  const Model other = random_model(rng, {.n = 7});
  Data d(m), d_other(other);
  EXPECT_THAT([&] {
    try { update_kinematics(m, d, VecX::Zero(m.nq + 1)); } catch (const Error& e) { return std::string(e.what()); }
    return std::string();
  }(), HasSubstr("update_kinematics: q: expected 5 entries, got 6"));
  update_kinematics(m, d, VecX::Zero(m.nq));
  EXPECT_THROW(update_velocities(m, d, VecX::Zero(2)), Error);
  update_velocities(m, d, VecX::Zero(m.nv));
  EXPECT_THROW(inverse_dynamics(m, d, VecX::Zero(3)), Error);
  EXPECT_THROW(forward_dynamics(m, d, VecX::Zero(9), FdMethod::ArticulatedBody), Error);
  EXPECT_THAT([&] {
    try { update_kinematics(m, d_other, VecX::Zero(m.nq)); } catch (const Error& e) { return std::string(e.what()); }
    return std::string();
  }(), HasSubstr("this Data was built for another model"));
}

TEST(ModelBuild, BodyWeldedToTheWorldKeepsItsPotentialEnergy) {
  auto specs = std::vector{body("ground_plate", -1), body("a", 0)};
  specs[0].joint = JointType::Fixed;
  specs[0].placement.p = Vec3(0, 0, 2.0);
  specs[0].mass = 3.0;
  specs[0].com = Vec3(0, 0, 0.5);
  const Model m = Model::build(specs, Vec3(0, 0, -9.81));
  EXPECT_EQ(m.nbodies, 1);
  EXPECT_EQ(m.parent[0], -1);
  Data d(m);
  update_kinematics(m, d, VecX::Zero(1));
  // plate cm at z = 2.5; body a: joint at z = 2, cm (0.1, 0, 0) → z = 2
  EXPECT_NEAR(potential_energy(m, d), 9.81 * (3.0 * 2.5 + 1.0 * 2.0), 1e-12);
}

// The sweeps work in world coordinates, so a body far from its joint or from the world origin costs digits:
// a model whose DOF inertia the round-off would swamp is refused; one within reach is accepted and
// its 𝓜 equals that of the same model at the origin (𝓜 of revolute joints does not depend on where
// the model stands) to the accuracy the check promises.
TEST(ModelBuild, RefusesBodiesTooFarForADouble) {
  // a puck turning about z with an arm hung far along that axis (the fuzzer's finding)
  auto puck = [](double height) {
    auto specs = std::vector{body("puck", -1), body("arm", 0)};
    specs[1].placement.p = Vec3(0.1, 0, height);
    return specs;
  };
  EXPECT_EQ(refusal(puck(10)), "(accepted)");
  const std::string msg = refusal(puck(1e30));
  EXPECT_THAT(msg, HasSubstr("body 'puck' (index 0): mass matrix: expected lengths a double resolves against "
                             "each DOF's inertia (round-off below 1e-6 of it), got DOF 0 (joint 'puck') swamped"));
  EXPECT_THAT(msg, HasSubstr("from bodies up to 1e+30 m from the world origin"));

  // a small arm (10 g links 5 cm apart) placed far from the origin on a welded plate
  auto arm = [](const Vec3& where) {
    std::vector<BodySpec> specs{body("plate", -1)};
    specs[0].joint = JointType::Fixed;
    specs[0].placement.p = where;
    for (int i = 1; i <= 3; ++i) {
      specs.push_back(body("link" + std::to_string(i), i - 1));
      specs[i].mass = 0.01;
      specs[i].com = Vec3(0.025, 0, 0);
      specs[i].inertia = Vec3(1e-7, 2e-6, 2e-6).asDiagonal();
      specs[i].axis = i == 2 ? Vec3::UnitY() : Vec3::UnitZ();
      if (i > 1) specs[i].placement.p = Vec3(0.05, 0, 0);
    }
    return specs;
  };
  EXPECT_THAT(refusal(arm(Vec3(3e6, -1e6, 0))),
              HasSubstr("body 'link1' (index 1): mass matrix: expected lengths a double resolves (round-off "
                        "below 1e-9 of the largest diagonal entry), got round-off"));
  const Model near = Model::build(arm(Vec3::Zero())), far = Model::build(arm(Vec3(300, -100, 50)));
  Data dn(near), df(far);
  Rng rng(7);
  double worst = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const VecX q = random_q(rng, near);
    update_kinematics(near, dn, q);
    update_kinematics(far, df, q);
    mass_matrix(near, dn);
    mass_matrix(far, df);
    // each entry to 1e-6 of its scale √(𝓜_ii 𝓜_jj) (entries are ~1e-5 kg m²)
    const VecX root = dn.M.diagonal().cwiseSqrt();
    const MatX scaled = (df.M - dn.M).cwiseQuotient(root * root.transpose());
    EXPECT_LE(scaled.cwiseAbs().maxCoeff(), 1e-6) << "trial " << trial;
    worst = std::max(worst, scaled.cwiseAbs().maxCoeff());
  }
  EXPECT_GT(worst, 0.0);  // the far model's round-off is there, and bounded
  std::printf("worst relative difference %.3g\n", worst);
}

}  // namespace

// Inertias breaking the triangle inequality by a CAD export's rounding (InertiaCheck)
namespace {
std::vector<BodySpec> rounded_tree() {
  auto specs = std::vector{body("a", -1), body("b", 0), body("c", 1), body("cam", 2)};
  specs[1].inertia = Vec3(0.1, 0.1, 0.205).asDiagonal();   // +2.5 %
  specs[3].joint = JointType::Fixed;                        // a welded part: +4 %
  specs[3].inertia = Vec3(0.01, 0.015, 0.026).asDiagonal();
  return specs;
}
Vec3 principal(const Mat3& I) { return Eigen::SelfAdjointEigenSolver<Mat3>(I).eigenvalues(); }
}  // namespace

TEST(ModelBuild, TriangleExcessWithinToleranceLoadsWithOneWarningNamingEveryBody) {
  const auto specs = rounded_tree();
  const Model m = Model::build(specs);
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_THAT(m.warnings[0], HasSubstr("loaded as given 2 inertias"));
  EXPECT_THAT(m.warnings[0], HasSubstr("'b' [0.1 0.1 0.205] (+2.50 %)"));
  EXPECT_THAT(m.warnings[0], HasSubstr("'cam'"));
  EXPECT_THAT(m.warnings[0], ::testing::Not(HasSubstr("'a'")));
  EXPECT_LT((m.inertia[1] - specs[1].inertia).norm(), 1e-15);  // as given
  EXPECT_TRUE(Model::build(std::vector{body("a", -1)}).warnings.empty());
}

TEST(ModelBuild, TriangleExcessBeyondToleranceOrStrictListsEveryBody) {
  auto specs = rounded_tree();
  specs[0].inertia = Vec3(0.1, 0.1, 0.24).asDiagonal();  // +20 %
  specs[2].inertia = Vec3(0.1, 0.1, 0.22).asDiagonal();  // +10 %
  const std::string warn = refusal(specs);
  EXPECT_THAT(warn, HasSubstr("within 5.00 %"));
  EXPECT_THAT(warn, HasSubstr("'a' [0.1 0.1 0.24] (+20.00 %), 'c' [0.1 0.1 0.22] (+10.00 %)"));
  EXPECT_THAT(warn, ::testing::Not(HasSubstr("'b'")));  // within tolerance
  EXPECT_THAT(warn, HasSubstr("balance"));
  try {
    Model::build(rounded_tree(), Vec3::Zero(), InertiaCheck::Strict);
    ADD_FAILURE() << "strict accepted";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("'b' [0.1 0.1 0.205] (+2.50 %), 'cam'"));
  }
}

TEST(ModelBuild, BalancedInertiaKeepsItsAxesAndLargestMomentAndIsPhysical) {
  auto specs = rounded_tree();
  // a rotated inertia, 30 % over: principal moments 0.1, 0.2, 0.39 about turned axes
  const Mat3 R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  specs[2].inertia = R * Vec3(0.1, 0.2, 0.39).asDiagonal() * R.transpose();
  const Model merged = Model::build(specs, Vec3::Zero(), InertiaCheck::Balance);
  for (int k = 0; k < merged.nbodies; ++k) {  // parts balanced, so their sums are physical
    const Vec3 l = principal(merged.inertia[k]);
    EXPECT_LE(l(2), (l(0) + l(1)) * (1 + 1e-12)) << k;
  }
  specs[3].mass = 0.0;  // a bare frame on c: body c is its own spec alone
  specs[3].inertia.setZero();
  const Model m = Model::build(specs, Vec3::Zero(), InertiaCheck::Balance);
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_THAT(m.warnings[0], HasSubstr("balanced 2 inertias"));
  // 0.1 + 0.045, 0.2 + 0.045, 0.39: the largest now the sum of the others, same axes
  const Mat3 expect = R * Vec3(0.145, 0.245, 0.39).asDiagonal() * R.transpose();
  EXPECT_LT((m.inertia[2] - expect).norm(), 1e-14);
}
