// Scenario files and URDF import: the four example files, URDF = equivalent YAML, and every
// bad-input case with its message.
#include "soadyn/integrators.hpp"
#include "soadyn/rollout.hpp"
#include "soadyn/scenario.hpp"

#include "test_util.hpp"

#include <Eigen/Eigenvalues>

#include <cstdio>
#include <numbers>
#include <filesystem>
#include <fstream>

using namespace soadyn;
using namespace soadyn::test;
using ::testing::HasSubstr;

namespace {

const std::string kDir = SOADYN_SOURCE_DIR "/scenarios/";

std::string error_of(const std::string& yaml) {
  try {
    parse_scenario(yaml, "scene.yaml");
  } catch (const Error& e) {
    return e.what();
  }
  return "(accepted)";
}

std::string urdf_error_of(const std::string& xml, bool free_root = false) {
  try {
    parse_urdf(xml, "robot.urdf", free_root, Vec3(0, 0, -9.81));
  } catch (const Error& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(ScenarioFiles, TheFourExamplesLoad) {
  struct Expect {
    const char* file;
    int nq, nv, nbodies;
  };
  for (const Expect& e : {Expect{"pendulum_on_cart.yaml", 2, 2, 2}, Expect{"double_pendulum.yaml", 2, 2, 2},
                          Expect{"satellite_two_arrays.yaml", 9, 8, 3}, Expect{"three_link_arm.yaml", 3, 3, 3}}) {
    const Scenario sc = load_scenario(kDir + e.file);
    EXPECT_EQ(sc.model.nq, e.nq) << e.file;
    EXPECT_EQ(sc.model.nv, e.nv) << e.file;
    EXPECT_EQ(sc.model.nbodies, e.nbodies) << e.file;
    EXPECT_GE(sc.simulation.t_end, 10.0) << e.file;
    EXPECT_TRUE(sc.inputs.empty()) << e.file << ": the note's examples are conservative";
    EXPECT_NE(sc.text.find("bodies:"), std::string::npos);
  }
  const Scenario sat = load_scenario(kDir + "satellite_two_arrays.yaml");
  EXPECT_TRUE(sat.model.gravity.isZero(0.0));
  EXPECT_NEAR(sat.q0(7), 0.3, 1e-15);
  EXPECT_NEAR(sat.v0(2), 0.05, 1e-15);
}

// ---- URDF = the equivalent YAML ------------------------------------------------------------

std::string g(double x) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", x);
  return b;
}
std::string g3(const Vec3& v) { return g(v.x()) + " " + g(v.y()) + " " + g(v.z()); }
std::string l3(const Vec3& v) { return "[" + g(v.x()) + ", " + g(v.y()) + ", " + g(v.z()) + "]"; }

Mat3 rpy(const Vec3& a) {
  return (Eigen::AngleAxisd(a.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(a.y(), Vec3::UnitY()) *
          Eigen::AngleAxisd(a.x(), Vec3::UnitX()))
      .toRotationMatrix();
}

struct Pair {
  std::string urdf, yaml;
};

// A random multi-branch robot written twice: URDF (inertia in a rotated inertial frame) and YAML
// (the same inertia rotated into the link frame by hand).
Pair random_robot(Rng& rng, int n, int fixed) {
  Pair p;
  p.urdf = "<?xml version=\"1.0\"?>\n<robot name=\"r\">\n";
  p.yaml = "gravity: [0, 0, -9.81]\nbodies:\n";
  std::vector<int> kinds(n);  // 0 revolute, 1 prismatic, 2 fixed, 3 continuous
  for (int i = 1; i < n; ++i) kinds[i] = rng.integer(0, 3) == 1 ? 1 : (rng.integer(0, 1) ? 0 : 3);
  for (int k = 0; k < fixed; ++k) kinds[rng.integer(1, n - 1)] = 2;
  std::string joints;
  for (int i = 0; i < n; ++i) {
    const std::string name = "link" + std::to_string(i);
    const double mass = rng.uniform(0.5, 3);
    const Vec3 com = rng.vec3(-0.3, 0.3), in_rpy = rng.vec3(-3, 3);
    const Vec3 moments = rng.vec3(0.05, 1.0);
    const Vec3 l(moments.y() + moments.z(), moments.x() + moments.z(), moments.x() + moments.y());
    Mat3 I = Mat3::Zero();  // in the inertial frame: off-diagonal on purpose
    I = rpy(rng.vec3(-1, 1)) * l.asDiagonal() * rpy(rng.vec3(-1, 1)).transpose();
    I = 0.5 * (I + I.transpose());
    const Eigen::SelfAdjointEigenSolver<Mat3> es(I);
    I = es.eigenvectors() * l.asDiagonal() * es.eigenvectors().transpose();
    p.urdf += "  <link name=\"" + name + "\">\n    <inertial>\n      <origin xyz=\"" + g3(com) + "\" rpy=\"" +
              g3(in_rpy) + "\"/>\n      <mass value=\"" + g(mass) + "\"/>\n      <inertia ixx=\"" + g(I(0, 0)) +
              "\" ixy=\"" + g(I(0, 1)) + "\" ixz=\"" + g(I(0, 2)) + "\" iyy=\"" + g(I(1, 1)) + "\" iyz=\"" +
              g(I(1, 2)) + "\" izz=\"" + g(I(2, 2)) + "\"/>\n    </inertial>\n  </link>\n";
    const Mat3 Il = rpy(in_rpy) * I * rpy(in_rpy).transpose();
    p.yaml += "  - name: " + name + "\n";
    if (i == 0) {
      p.yaml += "    joint: {type: fixed}\n";
    } else {
      const int parent = rng.integer(std::max(0, i - 3), i - 1);
      const Vec3 xyz = rng.vec3(-0.5, 0.5), jrpy = rng.vec3(-3, 3), axis = rng.vec3().normalized() * 2.0;
      const char* type[] = {"revolute", "prismatic", "fixed", "continuous"};
      const std::string jn = "j" + std::to_string(i);
      joints += "  <joint name=\"" + jn + "\" type=\"" + type[kinds[i]] + "\">\n    <parent link=\"link" +
                std::to_string(parent) + "\"/>\n    <child link=\"" + name + "\"/>\n    <origin xyz=\"" + g3(xyz) +
                "\" rpy=\"" + g3(jrpy) + "\"/>\n    <axis xyz=\"" + g3(axis) + "\"/>\n" +
                (kinds[i] == 0 || kinds[i] == 1 ? "    <limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>\n" : "") +
                "  </joint>\n";
      const char* ytype = kinds[i] == 1 ? "prismatic" : kinds[i] == 2 ? "fixed" : "revolute";
      p.yaml += "    parent: link" + std::to_string(parent) + "\n    joint: {type: " + ytype + ", name: " + jn +
                (kinds[i] == 2 ? "" : ", axis: " + l3(axis)) + "}\n    origin: {xyz: " + l3(xyz) +
                ", rpy: " + l3(jrpy) + "}\n";
    }
    p.yaml += "    mass: " + g(mass) + "\n    com: " + l3(com) + "\n    inertia: {ixx: " + g(Il(0, 0)) +
              ", iyy: " + g(Il(1, 1)) + ", izz: " + g(Il(2, 2)) + ", ixy: " + g(Il(0, 1)) + ", ixz: " +
              g(Il(0, 2)) + ", iyz: " + g(Il(1, 2)) + "}\n";
  }
  p.urdf += joints + "</robot>\n";
  return p;
}

TEST(Urdf, SameMassMatrixAsTheEquivalentYaml) {
  for (int seed = 0; seed < 12; ++seed) {
    Rng rng(2000 + seed);
    const Pair pr = random_robot(rng, 12, 3);
    const Model mu = parse_urdf(pr.urdf, "robot.urdf", false, Vec3(0, 0, -9.81));
    const Model my = parse_scenario(pr.yaml, "robot.yaml").model;
    ASSERT_EQ(mu.nv, my.nv) << pr.yaml;
    ASSERT_EQ(mu.joint_names, my.joint_names);
    EXPECT_LT(mu.nbodies, 12) << "fixed joints merged";
    for (int t = 0; t < 5; ++t) {
      const VecX q = random_q(rng, mu);
      Data du(mu), dy(my);
      update_kinematics(mu, du, q);
      update_kinematics(my, dy, q);
      mass_matrix(mu, du);
      mass_matrix(my, dy);
      ASSERT_TRUE(near_rel(du.M, dy.M, 1e-12)) << "seed " << seed;
      EXPECT_NEAR(potential_energy(mu, du), potential_energy(my, dy), 1e-10);
    }
  }
}

// a hand-written scenario against the URDF it mirrors: fixed joints, rpy offsets, a skewed axis,
// off-diagonal inertia in a turned inertial frame
TEST(Urdf, SameAsTheHandWrittenScenario) {
  const Model mu = load_urdf(SOADYN_SOURCE_DIR "/tests/fuzz/seeds/branched_arm.urdf", false, Vec3(0, 0, -9.81));
  const Model my = load_scenario(SOADYN_SOURCE_DIR "/tests/data/branched_arm.yaml").model;
  ASSERT_EQ(mu.joint_names, (std::vector<std::string>{"yaw", "left_pitch", "right_pitch", "extend"}));
  ASSERT_EQ(my.joint_names, mu.joint_names);
  EXPECT_EQ(mu.merged_names[0], std::vector<std::string>{"sensor"});
  Rng rng(31);
  for (int t = 0; t < 20; ++t) {
    const VecX q = random_q(rng, mu), v = random_v(rng, mu);
    Data du(mu), dy(my);
    for (auto [m, d] : {std::pair{&mu, &du}, std::pair{&my, &dy}}) {
      update_kinematics(*m, *d, q);
      mass_matrix(*m, *d);
      update_velocities(*m, *d, v);
      bias_forces(*m, *d);
    }
    ASSERT_TRUE(near_rel(du.M, dy.M, 1e-12));
    ASSERT_TRUE(near_rel(du.bias, dy.bias, 1e-12));
    EXPECT_NEAR(potential_energy(mu, du), potential_energy(my, dy), 1e-12);
  }
}

// the URDF's own joint order is kept when it is parent-first; otherwise depth-first from the root
TEST(Urdf, JointOrder) {
  const std::string link = "<inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>";
  auto robot = [&](const std::string& joints) {
    return "<robot name=\"r\"><link name=\"a\">" + link + "</link><link name=\"b\">" + link +
           "</link><link name=\"c\">" + link + "</link><link name=\"d\">" + link + "</link>" + joints + "</robot>";
  };
  auto joint = [](const std::string& n, const std::string& p, const std::string& c) {
    return "<joint name=\"" + n + "\" type=\"continuous\"><parent link=\"" + p + "\"/><child link=\"" + c +
           "\"/><axis xyz=\"0 0 1\"/></joint>";
  };
  // parent-first already, names out of alphabetical order: kept
  const Model m1 = parse_urdf(robot(joint("zeta", "a", "b") + joint("alpha", "a", "c") + joint("mid", "c", "d")),
                              "r.urdf", false, Vec3::Zero());
  EXPECT_EQ(m1.joint_names, (std::vector<std::string>{"zeta", "alpha", "mid"}));
  // a child listed before its parent: reordered parent-first
  const Model m2 = parse_urdf(robot(joint("mid", "c", "d") + joint("zeta", "a", "b") + joint("alpha", "a", "c")),
                              "r.urdf", false, Vec3::Zero());
  ASSERT_EQ(m2.nbodies, 3);
  for (int i = 0; i < m2.nbodies; ++i) EXPECT_LT(m2.parent[i], i);
  EXPECT_EQ(m2.joint_index("mid") > m2.joint_index("alpha"), true);
}

TEST(Urdf, FreeRootAndFloatingJoint) {
  const std::string inertial = "<inertial><mass value=\"2\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>";
  const std::string two = "<robot name=\"r\"><link name=\"base\">" + inertial + "</link><link name=\"arm\">" + inertial +
                          "</link><joint name=\"j\" type=\"revolute\"><parent link=\"base\"/><child link=\"arm\"/>"
                          "<axis xyz=\"0 1 0\"/><limit lower=\"0\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint></robot>";
  EXPECT_EQ(parse_urdf(two, "r.urdf", false, Vec3::Zero()).nv, 1);
  const Model f = parse_urdf(two, "r.urdf", true, Vec3::Zero());
  EXPECT_EQ(f.nv, 7);
  EXPECT_EQ(f.nq, 8);
  EXPECT_EQ(f.joint_type[0], JointType::Free);
  const std::string floating = "<robot name=\"r\"><link name=\"world\"/><link name=\"base\">" + inertial +
                               "</link><joint name=\"float\" type=\"floating\"><parent link=\"world\"/><child link=\"base\"/></joint></robot>";
  const Model fl = parse_urdf(floating, "r.urdf", false, Vec3::Zero());
  EXPECT_EQ(fl.nv, 6);
  EXPECT_EQ(fl.joint_names[0], "float");
}

// ---- bad input: one clear message each -----------------------------------------------------

const std::string kGood = R"(gravity: [0, 0, -9.81]
bodies:
  - name: a
    joint: {type: revolute, axis: [0, 0, 1]}
    mass: 1.0
    inertia: [0.1, 0.1, 0.1]
  - name: b
    parent: a
    joint: {type: revolute, axis: [1, 0, 0]}
    mass: 1.0
    inertia: [0.1, 0.1, 0.1]
)";

std::string with(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(BadScenario, GoodOneIsAccepted) { EXPECT_EQ(error_of(kGood), "(accepted)"); }

TEST(BadScenario, YamlSyntaxErrorHasLineAndColumn) {
  const std::string msg = error_of(with(kGood, "mass: 1.0\n    inertia", "mass: [1.0\n    inertia"));
  EXPECT_THAT(msg, HasSubstr("scene.yaml:"));
  EXPECT_THAT(msg, HasSubstr("YAML syntax"));
}

TEST(BadScenario, UnknownKeyWithSuggestion) {
  EXPECT_THAT(error_of(with(kGood, "    mass: 1.0\n    inertia: [0.1, 0.1, 0.1]\n  - name: b",
                            "    mas: 1.0\n    inertia: [0.1, 0.1, 0.1]\n  - name: b")),
              HasSubstr("scene.yaml:5:5: bodies[0]: unknown key 'mas'; did you mean 'mass'?"));
  EXPECT_THAT(error_of("gravty: [0, 0, 0]\n" + kGood.substr(kGood.find("bodies"))),
              HasSubstr("scene.yaml:1:1: scenario: unknown key 'gravty'; did you mean 'gravity'?"));
}

TEST(BadScenario, MissingRequiredField) {
  EXPECT_THAT(error_of(with(kGood, "    mass: 1.0\n    inertia: [0.1, 0.1, 0.1]\n  - name: b",
                            "    inertia: [0.1, 0.1, 0.1]\n  - name: b")),
              HasSubstr("body 'a': missing required field 'mass'"));
  EXPECT_THAT(error_of("gravity: [0, 0, 0]\n"), HasSubstr("missing required field 'bodies'"));
  EXPECT_THAT(error_of(with(kGood, "joint: {type: revolute, axis: [0, 0, 1]}", "joint: {type: revolute}")),
              HasSubstr("scene.yaml:4:12: body 'a'.joint: missing required field 'axis'"));
}

TEST(BadScenario, WrongTypes) {
  EXPECT_THAT(error_of(with(kGood, "mass: 1.0", "mass: heavy")),
              HasSubstr("scene.yaml:5:11: body 'a'.mass: expected a number, got 'heavy'"));
  EXPECT_THAT(error_of(with(kGood, "gravity: [0, 0, -9.81]", "gravity: [0, 0]")),
              HasSubstr("gravity: expected 3 numbers, got 2"));
  EXPECT_THAT(error_of(with(kGood, "inertia: [0.1, 0.1, 0.1]", "inertia: 0.1")),
              HasSubstr("body 'a'.inertia: expected [ixx, iyy, izz]"));
  EXPECT_THAT(error_of(with(kGood, "type: revolute, axis: [0, 0, 1]", "type: hinge, axis: [0, 0, 1]")),
              HasSubstr("unknown joint type 'hinge'"));
}

TEST(BadScenario, MissingParentSuggestsTheClosestName) {
  EXPECT_THAT(error_of(with(kGood, "parent: a", "parent: aa")),
              HasSubstr("scene.yaml:8:13: body 'b'.parent: no body named 'aa'; did you mean 'a'?"));
}

TEST(BadScenario, ParentListedAfterItsChild) {
  const std::string text = R"(bodies:
  - name: b
    parent: a
    joint: {type: revolute, axis: [1, 0, 0]}
    mass: 1.0
    inertia: [0.1, 0.1, 0.1]
  - name: a
    joint: {type: revolute, axis: [0, 0, 1]}
    mass: 1.0
    inertia: [0.1, 0.1, 0.1]
)";
  EXPECT_THAT(error_of(text), HasSubstr("scene.yaml:3:13: body 'b'.parent: parent 'a' is listed after 'b'"));
}

TEST(BadScenario, Cycles) {
  EXPECT_THAT(error_of(with(kGood, "parent: a", "parent: b")), HasSubstr("cycle in the tree: b -> b"));
  const std::string two = R"(bodies:
  - name: a
    parent: b
    joint: {type: revolute, axis: [1, 0, 0]}
    mass: 1.0
    inertia: [0.1, 0.1, 0.1]
  - name: b
    parent: a
    joint: {type: revolute, axis: [0, 0, 1]}
    mass: 1.0
    inertia: [0.1, 0.1, 0.1]
)";
  EXPECT_THAT(error_of(two), HasSubstr("cycle in the tree: a -> b -> a"));
}

TEST(BadScenario, DuplicateNames) {
  EXPECT_THAT(error_of(with(kGood, "- name: b", "- name: a")), HasSubstr("duplicate body name 'a'"));
  EXPECT_THAT(error_of(with(with(kGood, "type: revolute, axis: [0, 0, 1]", "type: revolute, name: j, axis: [0, 0, 1]"),
                            "type: revolute, axis: [1, 0, 0]", "type: revolute, name: j, axis: [1, 0, 0]")),
              HasSubstr("duplicate joint name 'j'"));
}

TEST(BadScenario, NonSpdInertiaAndTriangleInequality) {
  EXPECT_THAT(error_of(with(kGood, "inertia: [0.1, 0.1, 0.1]\n  - name: b", "inertia: [0.1, -0.1, 0.1]\n  - name: b")),
              HasSubstr("scene.yaml:3:5: body 'a': inertia: expected a positive semidefinite matrix"));
  EXPECT_THAT(error_of(with(kGood, "inertia: [0.1, 0.1, 0.1]\n  - name: b", "inertia: [0.1, 0.1, 0.5]\n  - name: b")),
              HasSubstr("triangle inequality"));
  EXPECT_THAT(error_of(with(kGood, "inertia: [0.1, 0.1, 0.1]\n  - name: b",
                            "inertia: {ixx: 0.1, iyy: 0.1, izz: 0.1, ixy: 0.2}\n  - name: b")),
              HasSubstr("positive semidefinite"));
}

// inertia_check: warn (default) | balance | strict, and the caller's choice over the file's
TEST(Scenario, InertiaCheckKey) {
  const std::string rounded = with(kGood, "inertia: [0.1, 0.1, 0.1]\n  - name: b", "inertia: [0.1, 0.1, 0.205]\n  - name: b");
  const Scenario warned = parse_scenario(rounded, "scene.yaml");
  ASSERT_EQ(warned.model.warnings.size(), 1u);
  EXPECT_THAT(warned.model.warnings[0], HasSubstr("loaded as given 1 inertia"));
  EXPECT_THAT(error_of("inertia_check: strict\n" + rounded), HasSubstr("scene.yaml:4:5: body 'a': inertia: expected"));
  const Scenario balanced = parse_scenario("inertia_check: balance\n" + rounded, "scene.yaml");
  EXPECT_THAT(balanced.model.warnings.at(0), HasSubstr("balanced 1 inertia"));
  EXPECT_NEAR(balanced.model.inertia[0](0, 0), 0.1025, 1e-15);
  // the caller's (--inertia-check) wins over the file's
  EXPECT_THAT(parse_scenario("inertia_check: strict\n" + rounded, "scene.yaml", false, InertiaCheck::Warn).model.warnings.at(0),
              HasSubstr("loaded as given"));
  EXPECT_THAT(error_of("inertia_check: balanse\n" + kGood),
              HasSubstr("scene.yaml:1:16: inertia_check: expected warn, balance or strict, got 'balanse'; did you mean 'balance'?"));
}

TEST(BadScenario, ZeroOrNegativeMass) {
  EXPECT_THAT(error_of(with(kGood, "mass: 1.0", "mass: 0")), HasSubstr("body 'a'.mass: expected a positive mass, got '0'"));
  EXPECT_THAT(error_of(with(kGood, "mass: 1.0", "mass: -2")), HasSubstr("expected a positive mass, got '-2'"));
}

TEST(BadScenario, ZeroAxis) {
  EXPECT_THAT(error_of(with(kGood, "axis: [0, 0, 1]", "axis: [0, 0, 0]")),
              HasSubstr("body 'a'.joint.axis: expected a non-zero axis"));
}

TEST(BadScenario, NanAndInfAnywhere) {
  EXPECT_THAT(error_of(with(kGood, "mass: 1.0", "mass: .nan")), HasSubstr("body 'a'.mass: expected a finite number, got '.nan'"));
  EXPECT_THAT(error_of(with(kGood, "gravity: [0, 0, -9.81]", "gravity: [0, .inf, -9.81]")),
              HasSubstr("gravity[1]: expected a finite number, got '.inf'"));
  EXPECT_THAT(error_of(with(kGood, "axis: [0, 0, 1]", "axis: [0, -.inf, 1]")), HasSubstr("expected a finite number"));
  EXPECT_THAT(error_of(with(kGood, "inertia: [0.1, 0.1, 0.1]", "inertia: [0.1, .NaN, 0.1]")),
              HasSubstr("expected a finite number"));
  EXPECT_THAT(error_of(kGood + "initial:\n  q: {a: .nan}\n"), HasSubstr("initial.q.a: expected a finite number"));
}

TEST(BadScenario, InitialStateAndInputs) {
  EXPECT_THAT(error_of(kGood + "initial:\n  q: {c: 1.0}\n"), HasSubstr("initial.q: no joint named 'c'"));
  EXPECT_THAT(error_of(kGood + "initial:\n  qd: {a: [1, 2]}\n"), HasSubstr("initial.qd.a: expected a number"));
  EXPECT_THAT(error_of(kGood + "simulation:\n  method: rk5\n"), HasSubstr("unknown method 'rk5'; did you mean 'rk4'?"));
  EXPECT_THAT(error_of(kGood + "simulation:\n  rtol: -1\n"), HasSubstr("simulation.rtol: expected a positive number"));
  EXPECT_THAT(error_of(kGood + "inputs:\n  springs:\n    - {joint: b, stiffnes: 3}\n"),
              HasSubstr("unknown key 'stiffnes'; did you mean 'stiffness'?"));
  const Scenario sc = parse_scenario(kGood + "inputs:\n  torques:\n    - {joint: b, constant: 2, amplitude: 1, frequency: 0.5}\n"
                                             "  springs:\n    - {joint: a, stiffness: 10, rest: 0.1}\n"
                                             "  dampers:\n    - {joint: a, damping: 0.5}\n", "scene.yaml");
  VecX tau(2);
  sc.inputs.evaluate(0.5, Eigen::Vector2d(0.3, 0), Eigen::Vector2d(2, 0), tau);
  EXPECT_NEAR(tau(0), -10 * 0.2 - 0.5 * 2, 1e-14);
  EXPECT_NEAR(tau(1), 2 + std::sin(std::numbers::pi * 0.5), 1e-14);
}

TEST(BadScenario, UnreadableAndEmptyFiles) {
  EXPECT_THAT([] {
    try { load_scenario("/nonexistent/scene.yaml"); } catch (const Error& e) { return std::string(e.what()); }
    return std::string();
  }(), HasSubstr("/nonexistent/scene.yaml: cannot open the file"));
  const std::string empty = std::filesystem::temp_directory_path() / "soadyn_empty.yaml";
  std::ofstream(empty) << "  \n";
  EXPECT_THAT([&] {
    try { load_scenario(empty); } catch (const Error& e) { return std::string(e.what()); }
    return std::string();
  }(), HasSubstr("the file is empty"));
  std::filesystem::remove(empty);
}

TEST(BadUrdf, MalformedXmlHasALine) {
  EXPECT_THAT(urdf_error_of("<robot name=\"r\">\n  <link name=\"a\">\n</robot>\n"), HasSubstr("robot.urdf:"));
  EXPECT_THAT(urdf_error_of("<robot name=\"r\">\n  <link name=\"a\">\n</robot>\n"), HasSubstr("XML"));
  EXPECT_THAT(urdf_error_of("<notarobot/>"), HasSubstr("expected a <robot> element"));
}

TEST(BadUrdf, SeveralRoots) {
  const std::string xml = "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/></robot>";
  EXPECT_THAT(urdf_error_of(xml), HasSubstr("robot.urdf:1: link 'b': a second root link (the first is 'a', line 1)"));
}

TEST(BadUrdf, MovingLinkWithoutMassAndBadInertia) {
  const std::string xml =
      "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n<joint name=\"j\" type=\"continuous\">"
      "<parent link=\"a\"/><child link=\"b\"/></joint>\n</robot>";
  EXPECT_THAT(urdf_error_of(xml), HasSubstr("robot.urdf:3: link 'b': inertial: expected mass properties"));
  const std::string bad =
      "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"><inertial><mass value=\"1\"/>"
      "<inertia ixx=\"1\" iyy=\"1\" izz=\"5\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>\n"
      "<joint name=\"j\" type=\"continuous\"><parent link=\"a\"/><child link=\"b\"/></joint>\n</robot>";
  EXPECT_THAT(urdf_error_of(bad), HasSubstr("robot.urdf:3: link 'b': "));
  EXPECT_THAT(urdf_error_of(bad), HasSubstr("triangle inequality"));
}

TEST(BadUrdf, CyclesAndTwoParents) {
  const std::string in = "<inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>";
  auto j = [](const std::string& n, const std::string& p, const std::string& c) {
    return "<joint name=\"" + n + "\" type=\"continuous\"><parent link=\"" + p + "\"/><child link=\"" + c + "\"/></joint>\n";
  };
  const std::string links = "<link name=\"a\">" + in + "</link>\n<link name=\"b\">" + in + "</link>\n<link name=\"c\">" + in + "</link>\n";
  EXPECT_THAT(urdf_error_of("<robot name=\"r\">\n" + links + j("j1", "b", "c") + j("j2", "c", "b") + "</robot>"),
              HasSubstr("cycle in the links"));
  EXPECT_THAT(urdf_error_of("<robot name=\"r\">\n" + links + j("j1", "a", "c") + j("j2", "b", "c") + "</robot>"),
              HasSubstr("robot.urdf:6: joint 'j2': link 'c' already has a parent joint (line 5)"));
}

TEST(BadUrdf, UnsupportedJointType) {
  const std::string xml =
      "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"><inertial><mass value=\"1\"/>"
      "<inertia ixx=\"1\" iyy=\"1\" izz=\"1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>\n"
      "<joint name=\"j\" type=\"spherical\"><parent link=\"a\"/><child link=\"b\"/></joint>\n</robot>";
  EXPECT_THAT(urdf_error_of(xml), HasSubstr("robot.urdf:4: joint 'j': URDF: Joint [j] has no known type [spherical]"));
}

}  // namespace

// the O(N) route's word is aba; on, its old word (YAML 1.1 and PyYAML read a bare on as true), is
// still taken and stored as aba; anything else is refused with the words allowed
TEST(ScenarioFiles, DynamicsRouteWordAndItsOldAlias) {
  const std::string head =
      "bodies:\n  - {name: a, joint: {type: revolute, axis: [0, 0, 1]}, mass: 1, inertia: [1, 1, 1]}\nsimulation:\n  dynamics: ";
  EXPECT_EQ(parse_scenario(head + "aba\n", "scene.yaml").simulation.dynamics, FdMethod::ArticulatedBody);
  EXPECT_EQ(parse_scenario(head + "on\n", "scene.yaml").simulation.dynamics, FdMethod::ArticulatedBody);
  EXPECT_EQ(parse_scenario(head + "sparse\n", "scene.yaml").simulation.dynamics, FdMethod::Sparse);
  EXPECT_EQ(SimulationSettings().dynamics, FdMethod::ArticulatedBody);
  EXPECT_EQ(parse_fd_method("on"), FdMethod::ArticulatedBody);
  EXPECT_THAT([&] { parse_scenario(head + "abb\n", "scene.yaml"); },
              testing::ThrowsMessage<Error>(testing::HasSubstr("did you mean 'aba'")));
}

// the word-valued settings are enums inside: every word of each Word row of the table goes word →
// enum → word unchanged, each to a different value; the integrators' registry gives every Method
// its one row and word
TEST(Settings, EveryWordRoundTripsThroughItsEnum) {
  int word_rows = 0;
  for (const SettingInfo& info : setting_table()) {
    if (info.kind != SettingKind::Word) continue;
    ++word_rows;
    std::vector<SimulationSettings> set;
    for (const std::string& word : info.words()) {
      SimulationSettings s;
      set_setting(s, info, word);
      EXPECT_EQ(setting_text(s, info), word) << info.name;
      EXPECT_EQ(std::get<WordField>(info.field).get(s), word) << info.name;
      for (const SimulationSettings& other : set) EXPECT_NE(setting_text(other, info), word) << info.name;
      set.push_back(s);
    }
    SimulationSettings s;
    EXPECT_THROW(set_setting(s, info, std::string("x")), Error) << info.name;
  }
  EXPECT_EQ(word_rows, 4);
  std::vector<Method> methods;
  for (const IntegratorInfo& info : integrators()) {
    EXPECT_EQ(to_string(info.method), info.name);
    EXPECT_EQ(parse_method(info.name), info.method);
    EXPECT_EQ(&find_integrator(info.method), &info);
    for (Method m : methods) EXPECT_NE(m, info.method) << info.name;
    methods.push_back(info.method);
  }
  EXPECT_EQ(methods.size(), 7u);
  EXPECT_EQ(parse_jacobian("dq"), Jacobian::Dq);
  EXPECT_EQ(to_string(Newton::Simplified), "simplified");
  EXPECT_THAT([] { parse_method("rk5"); },
              testing::ThrowsMessage<Error>(testing::StrEq("method: unknown method 'rk5'; did you mean 'rk4'?")));
  // one IntegrationSettings: a scenario's integration settings reach a batch of rollouts whole
  SimulationSettings s;
  s.method = Method::ImplicitMidpoint, s.dt = 2e-3, s.rtol = 1e-6, s.atol = 1e-9, s.max_step = 0.1, s.max_steps = 7;
  s.dynamics = FdMethod::Dense, s.jacobian = Jacobian::Dq, s.newton = Newton::Simplified;
  const RolloutSettings r = rollout_settings(s);
  EXPECT_EQ(r.method, Method::ImplicitMidpoint);
  EXPECT_EQ(r.dt, 2e-3);
  EXPECT_EQ(r.rtol, 1e-6);
  EXPECT_EQ(r.atol, 1e-9);
  EXPECT_EQ(r.max_step, 0.1);
  EXPECT_EQ(r.max_steps, 7);
  EXPECT_EQ(r.dynamics, FdMethod::Dense);
  EXPECT_EQ(r.jacobian, Jacobian::Dq);
  EXPECT_EQ(r.newton, Newton::Simplified);
  EXPECT_EQ(RolloutSettings().method, Method::Rk4);
  EXPECT_EQ(SimulationSettings().method, Method::CvodeAdams);
}
