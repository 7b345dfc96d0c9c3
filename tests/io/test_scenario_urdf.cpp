// URDF import in the scenario reader: a random multi-branch robot written as URDF and as the
// equivalent YAML (same 𝓜 and potential energy), a hand-written scenario against the URDF it
// mirrors, joint order, free root and floating joint, and every bad-URDF case with its message.
// Real robots' URDF patterns: test_urdf.cpp; error lines: test_urdf_errors.cpp.
#include "soadyn/io/scenario_file.hpp"

#include "test_util.hpp"
#include "urdf_error.hpp"

#include <Eigen/Eigenvalues>

#include <cstdio>

using namespace soadyn;
using namespace soadyn::test;
using ::testing::HasSubstr;

namespace {

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

TEST(BadUrdf, MalformedXmlHasALine) {
  EXPECT_THAT(urdf_error("<robot name=\"r\">\n  <link name=\"a\">\n</robot>\n"), HasSubstr("robot.urdf:"));
  EXPECT_THAT(urdf_error("<robot name=\"r\">\n  <link name=\"a\">\n</robot>\n"), HasSubstr("XML"));
  EXPECT_THAT(urdf_error("<notarobot/>"), HasSubstr("expected a <robot> element"));
}

TEST(BadUrdf, SeveralRoots) {
  const std::string xml = "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/></robot>";
  EXPECT_THAT(urdf_error(xml), HasSubstr("robot.urdf:1: link 'b': a second root link (the first is 'a', line 1)"));
}

TEST(BadUrdf, MovingLinkWithoutMassAndBadInertia) {
  const std::string xml =
      "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n<joint name=\"j\" type=\"continuous\">"
      "<parent link=\"a\"/><child link=\"b\"/></joint>\n</robot>";
  EXPECT_THAT(urdf_error(xml), HasSubstr("robot.urdf:3: link 'b': inertial: expected mass properties"));
  const std::string bad =
      "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"><inertial><mass value=\"1\"/>"
      "<inertia ixx=\"1\" iyy=\"1\" izz=\"5\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>\n"
      "<joint name=\"j\" type=\"continuous\"><parent link=\"a\"/><child link=\"b\"/></joint>\n</robot>";
  EXPECT_THAT(urdf_error(bad), HasSubstr("robot.urdf:3: link 'b': "));
  EXPECT_THAT(urdf_error(bad), HasSubstr("triangle inequality"));
}

TEST(BadUrdf, CyclesAndTwoParents) {
  const std::string in = "<inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>";
  auto j = [](const std::string& n, const std::string& p, const std::string& c) {
    return "<joint name=\"" + n + "\" type=\"continuous\"><parent link=\"" + p + "\"/><child link=\"" + c + "\"/></joint>\n";
  };
  const std::string links = "<link name=\"a\">" + in + "</link>\n<link name=\"b\">" + in + "</link>\n<link name=\"c\">" + in + "</link>\n";
  EXPECT_THAT(urdf_error("<robot name=\"r\">\n" + links + j("j1", "b", "c") + j("j2", "c", "b") + "</robot>"),
              HasSubstr("cycle in the links"));
  EXPECT_THAT(urdf_error("<robot name=\"r\">\n" + links + j("j1", "a", "c") + j("j2", "b", "c") + "</robot>"),
              HasSubstr("robot.urdf:6: joint 'j2': link 'c' already has a parent joint (line 5)"));
  EXPECT_THAT(urdf_error("<robot name=\"r\">\n" + links + j("j1", "a", "c") + j("j2", "b", "c") + "</robot>"),
              HasSubstr("close the loop from a scenario's loops:"));
}

TEST(BadUrdf, UnsupportedJointType) {
  const std::string xml =
      "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"><inertial><mass value=\"1\"/>"
      "<inertia ixx=\"1\" iyy=\"1\" izz=\"1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>\n"
      "<joint name=\"j\" type=\"spherical\"><parent link=\"a\"/><child link=\"b\"/></joint>\n</robot>";
  EXPECT_THAT(urdf_error(xml), HasSubstr("robot.urdf:4: joint 'j': URDF: Joint [j] has no known type [spherical]"));
}

}  // namespace
