// URDF import as real robot descriptions are written: every pattern under tests/data/urdf/ loads
// and has the same 𝓜, bias, q̈, energies and momentum as its hand-merged twin; a singular 𝓜 is
// refused with the DOF named; one gravity rule.  Error lines: test_urdf_errors.cpp.
#include "soadyn/io/scenario_file.hpp"

#include "test_util.hpp"
#include "urdf_error.hpp"

#include <fstream>
#include <sstream>

using namespace soadyn;
using namespace soadyn::test;
using ::testing::HasSubstr;

namespace {

const std::string kDir = SOADYN_SOURCE_DIR "/tests/data/urdf/";

std::string text_of(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}


// b's v (and q) index of each of a's, matched by joint name; the free roots match each other
struct DofMap {
  std::vector<int> v, q;
};
DofMap match(const Model& a, const Model& b) {
  DofMap map;
  for (int i = 0; i < a.nbodies; ++i) {
    int j = b.joint_index(a.joint_names[i]);
    if (j < 0 && a.joint_type[i] == JointType::Free && a.parent[i] < 0 && b.nbodies > 0 &&
        b.joint_type[0] == JointType::Free)
      j = 0;
    EXPECT_GE(j, 0) << "joint '" << a.joint_names[i] << "' is missing from the twin";
    if (j < 0) continue;
    EXPECT_EQ(a.joint_type[i], b.joint_type[j]) << a.joint_names[i];
    for (int k = 0; k < a.nv_i[i]; ++k) map.v.push_back(b.idx_v[j] + k);
    for (int k = 0; k < a.nq_i[i]; ++k) map.q.push_back(b.idx_q[j] + k);
  }
  return map;
}

struct Dynamics {
  MatX M;
  VecX bias, qdd;
  double T, V;
  Momentum h;
};
Dynamics evaluate(const Model& m, const VecX& q, const VecX& v, const VecX& tau) {
  Data d(m);
  update_kinematics(m, d, q);
  mass_matrix(m, d);
  Dynamics out;
  out.M = d.M;
  update_velocities(m, d, v);
  bias_forces(m, d);
  out.bias = d.bias;
  forward_dynamics(m, d, tau, FdMethod::ArticulatedBody);  // the articulated recursion, through the merged bodies
  out.qdd = d.qdd;
  out.T = kinetic_energy(m, d);
  out.V = potential_energy(m, d);
  out.h = momentum(m, d);
  return out;
}

// The pattern's model and the twin's agree to 1e-12 at random states.
void expect_twins(const Model& a, const Model& b, std::uint64_t seed) {
  ASSERT_EQ(a.nv, b.nv);
  ASSERT_EQ(a.nq, b.nq);
  const DofMap map = match(a, b);
  ASSERT_EQ(int(map.v.size()), a.nv);
  EXPECT_TRUE(a.gravity.isApprox(b.gravity));
  Rng rng(seed);
  for (int t = 0; t < 10; ++t) {
    const VecX qb = random_q(rng, b), vb = random_v(rng, b), taub = random_v(rng, b, 3.0);
    VecX qa(a.nq), va(a.nv), taua(a.nv);
    for (int k = 0; k < a.nq; ++k) qa(k) = qb(map.q[k]);
    for (int k = 0; k < a.nv; ++k) va(k) = vb(map.v[k]), taua(k) = taub(map.v[k]);
    const Dynamics da = evaluate(a, qa, va, taua), db = evaluate(b, qb, vb, taub);
    MatX Mb(a.nv, a.nv);
    VecX biasb(a.nv), qddb(a.nv);
    for (int r = 0; r < a.nv; ++r) {
      biasb(r) = db.bias(map.v[r]);
      qddb(r) = db.qdd(map.v[r]);
      for (int c = 0; c < a.nv; ++c) Mb(r, c) = db.M(map.v[r], map.v[c]);
    }
    ASSERT_TRUE(near_rel(da.M, Mb, 1e-12)) << "state " << t;
    ASSERT_TRUE(near_rel(da.bias, biasb, 1e-12)) << "state " << t;
    ASSERT_TRUE(near_rel(da.qdd, qddb, 1e-10)) << "state " << t;
    EXPECT_NEAR(da.T, db.T, 1e-12 * std::max(1.0, std::abs(db.T)));
    EXPECT_NEAR(da.V, db.V, 1e-12 * std::max(1.0, std::abs(db.V)));
    EXPECT_TRUE(near_rel(da.h.linear, db.h.linear, 1e-12));
    EXPECT_TRUE(near_rel(da.h.angular, db.h.angular, 1e-12));
  }
}

struct Pattern {
  const char* file;
  const char* twin;
  bool free_root;
  const char* construct;  // text the pattern file must contain, so the test cannot pass vacuously
};

// ---- the patterns real robot descriptions are written with -------------------------------------

TEST(UrdfPatterns, EachLoadsAndEqualsItsTwin) {
  const Pattern patterns[] = {
      {"point_masses.urdf", "point_masses_merged.urdf", false, "ixx=\"0\" iyy=\"0\" izz=\"0\""},
      {"point_masses.urdf", "point_masses_merged.urdf", true, "<link name=\"camera_optical_frame\"/>"},
      {"dummy_root.urdf", "dummy_root_merged.urdf", true, "<link name=\"base\"/>"},
      {"dummy_root.urdf", "dummy_root_merged.urdf", false, "<link name=\"base\"/>"},
      {"world_root.urdf", "world_root_merged.urdf", false, "<link name=\"world\"/>"},
      {"visual_collision.urdf", "arm.urdf", false, "package://"},
      {"transmission.urdf", "arm.urdf", false, "<transmission"},
      {"gazebo.urdf", "arm.urdf", false, "<gazebo reference="},
      {"mimic.urdf", "arm.urdf", false, "<mimic joint="},
      {"limits_dynamics.urdf", "arm.urdf", false, "<safety_controller"},
      {"namespaces.urdf", "arm.urdf", false, "xmlns:xacro"},
      {"fixed_axis_zero.urdf", "arm.urdf", false, "<axis xyz=\"0 0 0\"/>"},
      {"unordered.urdf", "arm.urdf", false, "<robot name=\"arm\">\n  <joint name=\"finger_b_joint\""},  // tip first
  };
  std::uint64_t seed = 900;
  for (const Pattern& p : patterns) {
    SCOPED_TRACE(std::string(p.file) + (p.free_root ? " --free-root" : ""));
    ASSERT_NE(text_of(kDir + p.file).find(p.construct), std::string::npos);
    const Model a = load_urdf(kDir + p.file, p.free_root, urdf_gravity());
    const Model b = load_urdf(kDir + p.twin, p.free_root, urdf_gravity());
    EXPECT_EQ(a.nv, p.free_root ? 11 : 5);
    expect_twins(a, b, seed++);
  }
}

// the welded parts really are merged (not dropped): the twin test above would also pass if both
// files lost the same parts, so check the bodies they went into
TEST(UrdfPatterns, WeldedPartsAreMergedIntoTheirMovingBody) {
  const Model m = load_urdf(kDir + "point_masses.urdf", false, urdf_gravity());
  EXPECT_EQ(m.merged_names[m.body_index("upper")], (std::vector<std::string>{"camera", "camera_optical_frame"}));
  EXPECT_EQ(m.merged_names[m.body_index("fore")], std::vector<std::string>{"rod"});
  EXPECT_EQ(m.merged_names[m.body_index("hand")], (std::vector<std::string>{"ft_frame", "tool_tip"}));
  EXPECT_NEAR(m.mass[m.body_index("upper")], 2.5, 1e-15);
  EXPECT_NEAR(m.mass[m.body_index("hand")], 0.625, 1e-15);
  const Model free = load_urdf(kDir + "dummy_root.urdf", true, urdf_gravity());
  EXPECT_EQ(free.body_names[0], "base");
  EXPECT_EQ(free.merged_names[0], std::vector<std::string>{"trunk"});
  EXPECT_NEAR(free.mass[0], 4.0, 1e-15);
}

// the scenario route: free_root: true frees the massless root with the trunk welded to it
TEST(UrdfPatterns, ScenarioFreesTheDummyRoot) {
  const Scenario sc = parse_scenario("urdf: dummy_root.urdf\nfree_root: true\n", kDir + "inline.yaml");
  const Model twin = load_urdf(kDir + "dummy_root_merged.urdf", true, urdf_gravity());
  EXPECT_EQ(sc.model.joint_type[0], JointType::Free);
  expect_twins(sc.model, twin, 41);
}

// URDF planar (axis = the plane's normal) against prismatic x, prismatic y, revolute z in the same
// joint frame.  The two sliders only translate, along e1 = Rj x and e2 = Rj y, so in closed form
//   𝓜_ppr = 𝓜 + diag(m_x + m_y, m_y, 0, 0),  bias_ppr = bias − [(m_x + m_y) g·e1, m_y g·e2, 0, 0],
//   T_ppr = T + ½ (m_x + m_y) ẋ² + ½ m_y ẏ²,  V_ppr = V − m_x g·r_x − m_y g·r_y.
TEST(UrdfPatterns, PlanarIsPrismaticPrismaticRevolute) {
  const Model pl = load_urdf(kDir + "planar.urdf", false, urdf_gravity());
  const Model ppr = load_urdf(kDir + "planar_ppr.urdf", false, urdf_gravity());
  ASSERT_EQ(pl.joint_type[0], JointType::Planar);
  ASSERT_EQ(pl.nv, 4);
  ASSERT_EQ(ppr.nv, 4);
  const double mx = 0.5, my = 0.25;
  const Mat3 Rj = pl.placement[0].R;  // the table is the world-welded root: the joint frame in the world
  const Vec3 p0 = pl.placement[0].p, e1 = Rj.col(0), e2 = Rj.col(1), g = urdf_gravity();
  EXPECT_TRUE(pl.axis[0].isApprox(Vec3::UnitZ()));
  Rng rng(61);
  for (int t = 0; t < 10; ++t) {
    const VecX q = random_q(rng, pl), v = random_v(rng, pl), tau = random_v(rng, pl, 3.0);
    const Dynamics a = evaluate(pl, q, v, tau), b = evaluate(ppr, q, v, tau);
    MatX M = a.M;
    M(0, 0) += mx + my;
    M(1, 1) += my;
    VecX bias = a.bias;
    bias(0) -= (mx + my) * g.dot(e1);
    bias(1) -= my * g.dot(e2);
    ASSERT_TRUE(near_rel(b.M, M, 1e-12)) << "state " << t;
    ASSERT_TRUE(near_rel(b.bias, bias, 1e-12)) << "state " << t;
    const Vec3 rx = p0 + q(0) * e1, ry = rx + q(1) * e2;
    EXPECT_NEAR(b.T, a.T + 0.5 * (mx + my) * v(0) * v(0) + 0.5 * my * v(1) * v(1), 1e-12 * std::max(1.0, b.T));
    EXPECT_NEAR(b.V, a.V - mx * g.dot(rx) - my * g.dot(ry), 1e-12 * std::max(1.0, std::abs(b.V)));
  }
}

// the mimic tags change nothing: every joint keeps its own q
TEST(UrdfPatterns, MimicJointsStayIndependent) {
  const Model m = load_urdf(kDir + "mimic.urdf", false, urdf_gravity());
  EXPECT_EQ(m.joint_names, (std::vector<std::string>{"shoulder", "elbow", "wrist", "finger_a_joint", "finger_b_joint"}));
  EXPECT_EQ(m.nv, 5);
}

// a link that moves may itself be a bare frame when a link with mass is welded to it
TEST(UrdfPatterns, MasslessMovingFrameWithAWeldedBody) {
  auto robot = [](const std::string& moving, const std::string& extra) {
    return "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\">" + moving +
           "</link>\n<joint name=\"j\" type=\"continuous\"><parent link=\"a\"/><child link=\"b\"/>"
           "<origin xyz=\"0 0 1\"/><axis xyz=\"0 1 0\"/></joint>\n" + extra + "</robot>";
  };
  const std::string inertial = "<inertial><origin xyz=\"0.3 0 0.1\"/><mass value=\"2\"/><inertia ixx=\"0.1\" "
                               "iyy=\"0.2\" izz=\"0.25\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>";
  const std::string welded = "<link name=\"c\">" + inertial + "</link>\n<joint name=\"w\" type=\"fixed\"><parent "
                             "link=\"b\"/><child link=\"c\"/><origin xyz=\"0.2 0 0\"/></joint>\n";
  const std::string merged = "<inertial><origin xyz=\"0.5 0 0.1\"/><mass value=\"2\"/><inertia ixx=\"0.1\" "
                             "iyy=\"0.2\" izz=\"0.25\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>";
  const Model a = parse_urdf(robot("", welded), "a.urdf", false, urdf_gravity());
  const Model b = parse_urdf(robot(merged, ""), "b.urdf", false, urdf_gravity());
  expect_twins(a, b, 77);
  // with nothing welded to it, the bare frame cannot move
  EXPECT_THAT(urdf_error(robot("", "")),
              HasSubstr("robot.urdf:3: link 'b': inertial: expected mass properties for a link that moves "
                        "(joint 'j' is revolute), on it or on a link welded to it"));
}

TEST(UrdfPatterns, FreeRootNeedsMassInItsWeldedGroup) {
  const std::string xml = "<robot name=\"r\">\n<link name=\"base\"/>\n<link name=\"frame\"/>\n"
                          "<joint name=\"w\" type=\"fixed\"><parent link=\"base\"/><child link=\"frame\"/></joint>\n</robot>";
  EXPECT_THAT(urdf_error(xml, true),
              HasSubstr("robot.urdf:2: link 'base': inertial: expected mass properties for a free root (--free-root)"));
  EXPECT_EQ(urdf_error(xml, false), "(accepted)");  // welded to the world, it may be massless
}

// ---- a singular 𝓜 is refused, naming the DOFs that carry no inertia ---------------------------

const char* kPoint = "<inertial><origin xyz=\"%s\"/><mass value=\"1\"/>"
                     "<inertia ixx=\"0\" iyy=\"0\" izz=\"0\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>";
std::string point_mass(const std::string& xyz) {
  std::string s = kPoint;
  return s.replace(s.find("%s"), 2, xyz);
}

TEST(SingularMassMatrix, PointMassOnItsOwnAxis) {
  auto robot = [](const std::string& xyz) {
    return "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\">" + point_mass(xyz) +
           "</link>\n<joint name=\"spin\" type=\"continuous\"><parent link=\"a\"/><child link=\"b\"/>"
           "<axis xyz=\"0 0 1\"/></joint>\n</robot>";
  };
  EXPECT_THAT(urdf_error(robot("0 0 0.3")),
              HasSubstr("robot.urdf:4: joint 'spin': mass matrix: expected positive definite at the neutral "
                        "configuration, got singular: no inertia on DOF 0 (joint 'spin')"));
  EXPECT_EQ(urdf_error(robot("0.1 0 0.3")), "(accepted)");  // off the axis it has inertia about it
}

// two coaxial joints: the first carries only a point mass on the axis, so what it moves the
// second can move too: the first is named, not the second
TEST(SingularMassMatrix, CoaxialJointsNameTheOneWithoutInertia) {
  const std::string xml =
      "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\">" + point_mass("0 0 0.2") +
      "</link>\n<link name=\"c\"><inertial><mass value=\"1\"/><inertia ixx=\"0.1\" iyy=\"0.1\" izz=\"0.1\" "
      "ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>\n"
      "<joint name=\"first\" type=\"continuous\"><parent link=\"a\"/><child link=\"b\"/><axis xyz=\"0 0 1\"/></joint>\n"
      "<joint name=\"second\" type=\"continuous\"><parent link=\"b\"/><child link=\"c\"/><origin xyz=\"0 0 0.5\"/>"
      "<axis xyz=\"0 0 1\"/></joint>\n</robot>";
  const std::string e = urdf_error(xml);
  EXPECT_THAT(e, HasSubstr("robot.urdf:5: joint 'first': mass matrix:"));
  EXPECT_THAT(e, HasSubstr("no inertia on DOF 0 (joint 'first')"));
  EXPECT_THAT(e, ::testing::Not(HasSubstr("'second'")));
}

// a rod spinning about its own length, and a free point mass (its three rotations)
TEST(SingularMassMatrix, RodAboutItsLengthAndAFreePointMass) {
  const std::string rod =
      "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"rod\"><inertial><mass value=\"1\"/>"
      "<inertia ixx=\"0\" iyy=\"0.08\" izz=\"0.08\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>\n"
      "<joint name=\"roll\" type=\"continuous\"><parent link=\"a\"/><child link=\"rod\"/><axis xyz=\"1 0 0\"/></joint>\n"
      "</robot>";
  EXPECT_THAT(urdf_error(rod), HasSubstr("robot.urdf:4: joint 'roll': mass matrix:"));
  std::string pitch = rod;
  pitch.replace(pitch.find("<axis xyz=\"1 0 0\"/>"), 19, "<axis xyz=\"0 1 0\"/>");
  EXPECT_EQ(urdf_error(pitch), "(accepted)");  // across its length a rod has inertia

  const std::string ball = "<robot name=\"r\">\n<link name=\"ball\">" + point_mass("0 0 0") + "</link>\n</robot>";
  EXPECT_THAT(urdf_error(ball, true),
              HasSubstr("robot.urdf:2: link 'ball': mass matrix: expected positive definite at the neutral "
                        "configuration, got singular: no inertia on DOF 0 (joint 'ball_free', its DOF 0), DOF 1 "
                        "(joint 'ball_free', its DOF 1), DOF 2 (joint 'ball_free', its DOF 2)"));
}

// long chains have a badly conditioned 𝓜 (the base joint moves the whole chain, the last one
// link) but a regular one: no DOF may be called singular for it
TEST(SingularMassMatrix, LongChainsAndBigTreesAreRegular) {
  std::vector<BodySpec> chain;
  for (int i = 0; i < 5000; ++i) {
    BodySpec b;
    b.name = "l" + std::to_string(i);
    b.parent = i - 1;
    b.axis = Vec3::UnitY();
    b.placement.p = Vec3(0, 0, i ? -0.1 : 0.0);
    b.mass = 1.0;
    b.com = Vec3(0, 0, -0.05);
    b.inertia = 0.01 * Mat3::Identity();
    chain.push_back(b);
  }
  EXPECT_NO_THROW(Model::build(chain, urdf_gravity()));
  Rng rng(5);
  for (double branching : {0.0, 0.5, 1.0}) {
    TreeOptions o;
    o.n = 2000;
    o.branching = branching;
    o.prismatic = 0.2;
    o.free_root = true;
    o.fixed = 300;
    EXPECT_NO_THROW(random_model(rng, o)) << "branching " << branching;
  }
}

// many singular DOFs: six named, the rest counted, on one line
TEST(SingularMassMatrix, ManyAreCounted) {
  std::vector<BodySpec> specs;
  for (int i = 0; i < 10; ++i) {
    BodySpec b;
    b.name = "p" + std::to_string(i);
    b.parent = i - 1;
    b.axis = Vec3::UnitZ();
    b.placement.p = Vec3(0, 0, 0.1);
    b.mass = 1.0;  // point masses on the common axis
    specs.push_back(b);
  }
  try {
    Model::build(specs);
    ADD_FAILURE() << "accepted";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.spec, 0);
    EXPECT_THAT(e.what(), HasSubstr("no inertia on DOF 0 (joint 'p0'), DOF 1 (joint 'p1'), DOF 2 (joint 'p2'), DOF 3 "
                                    "(joint 'p3'), DOF 4 (joint 'p4'), DOF 5 (joint 'p5') and 4 more"));
  }
}

TEST(SingularMassMatrix, ScenarioBodiesAndModelBuild) {
  const std::string yaml = "bodies:\n"
                           "  - name: b\n"
                           "    joint: {type: revolute, axis: [0, 0, 1]}\n"
                           "    mass: 1.0\n"
                           "    com: [0, 0, 0.5]\n"
                           "    inertia: [0, 0, 0]\n";
  try {
    parse_scenario(yaml, "scene.yaml");
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("scene.yaml:2:5: body 'b': mass matrix: expected positive definite"));
    EXPECT_THAT(e.what(), HasSubstr("no inertia on DOF 0 (joint 'b')"));
  }
  // Model::build: welded parts may be point masses and rods, but not negative
  BodySpec a;
  a.name = "a";
  a.mass = 1.0;
  a.inertia = Vec3(0.1, 0.1, 0.1).asDiagonal();
  BodySpec tip = a;
  tip.name = "tip";
  tip.parent = 0;
  tip.joint = JointType::Fixed;
  tip.placement.p = Vec3(0.3, 0, 0);
  for (const Vec3& moments : {Vec3(0, 0, 0), Vec3(0, 0.2, 0.2)}) {
    tip.inertia = moments.asDiagonal();
    EXPECT_NO_THROW(Model::build({a, tip}));
  }
  tip.inertia = Vec3(-0.01, 0.2, 0.2).asDiagonal();
  EXPECT_THROW(
      {
        try {
          Model::build({a, tip});
        } catch (const ModelError& e) {
          EXPECT_THAT(e.what(), HasSubstr("body 'tip' (index 1): inertia: expected a positive semidefinite matrix"));
          throw;
        }
      },
      ModelError);
}

// ---- one gravity rule wherever a URDF enters ------------------------------------------------------

TEST(UrdfGravity, SameByEveryRouteAndAScenarioOverrides) {
  const Vec3 g = load_scenario(kDir + "arm.urdf").model.gravity;
  EXPECT_TRUE(g.isApprox(Vec3(0, 0, -9.81)));
  const Scenario via = parse_scenario("urdf: arm.urdf\n", kDir + "inline.yaml");
  EXPECT_TRUE(via.model.gravity.isApprox(g)) << via.model.gravity.transpose();
  const Scenario zero = parse_scenario("urdf: arm.urdf\ngravity: [0, 0, 0]\n", kDir + "inline.yaml");
  EXPECT_TRUE(zero.model.gravity.isZero(0.0));
  const Scenario moon = parse_scenario("urdf: arm.urdf\ngravity: [0, 0, -1.62]\n", kDir + "inline.yaml");
  EXPECT_TRUE(moon.model.gravity.isApprox(Vec3(0, 0, -1.62)));
  // the gravity reaches the dynamics: the same robot, the same state, gravity's share of the bias
  Data d(via.model), dz(zero.model);
  const VecX q = VecX::Constant(via.model.nq, 0.4);
  for (auto [m, dd] : {std::pair{&via.model, &d}, std::pair{&zero.model, &dz}}) {
    update_kinematics(*m, *dd, q);
    update_velocities(*m, *dd, VecX::Zero(m->nv));
    bias_forces(*m, *dd);
  }
  EXPECT_GT((d.bias - dz.bias).norm(), 1.0);
}

}  // namespace
