// MJCF's <equality connect> and <equality weld> as loops (mjcf.hpp, MjcfModel::loops): the same
// LoopConstraints and the same motion as the scenario's loops: form of the mechanism; the closure
// φ against MuJoCo's own constraint residual (efc_pos) at random states, so that the anchors and
// relpose are read as MuJoCo reads them; a point given on a body soadyn merged lands on the body it
// moves with; what is not held is named in the one "ignored: …" line; a run's stored files give
// the same loops back.
#include "soadyn/algorithm/frames.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/io/mjcf.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/sim/simulate.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>

#include "loop_util.hpp"

using namespace soadyn;
using namespace soadyn::test;
using ::testing::HasSubstr;

namespace {

const std::string kDir = SOADYN_SOURCE_DIR "/tests/data/mjcf/";
// a fixed-step run, so that both take the same steps: MuJoCo's compiled anchor differs from the
// scenario's 0.8 by an ulp (3e-16), which CVODE's step control turns into another step sequence
// (BDF at rtol 1e-10: 4e-8 apart over the four-bar's 2 s, the integrator's own error)
const char* const kRun = "simulation: {t_end: 2.0, output_dt: 0.01, method: rk4, dt: 1.0e-3}\n";

// four_bar_connect.xml as a scenario: the same bodies drawn at the same angles, closed by a point loop
const std::string kFourBarPoint = R"(gravity: [0, -9.81, 0]
bodies:
  - name: crank
    joint: {type: revolute, name: crank, axis: [0, 0, 1]}
    origin: {rpy: [0, 0, 0.7]}
    mass: 1.0
    com: [0.15, 0, 0]
    inertia: [0.0005, 0.0075, 0.0075]
  - name: coupler
    parent: crank
    joint: {type: revolute, name: coupler, axis: [0, 0, 1]}
    origin: {xyz: [0.3, 0, 0], rpy: [0, 0, -0.061921578642202046]}
    mass: 1.5
    com: [0.5, 0, 0]
    inertia: [0.001, 0.125, 0.125]
  - name: rocker
    joint: {type: revolute, name: rocker, axis: [0, 0, 1]}
    origin: {xyz: [0.9, 0, 0], rpy: [0, 0, 1.4041580733270875]}
    mass: 2.0
    com: [0.4, 0, 0]
    inertia: [0.001, 0.107, 0.107]
loops:
  - {name: closing, type: point, a: coupler, at_a: [1.0, 0, 0], b: rocker, at_b: [0.8, 0, 0]}
)";

// an arm (shoulder about y, elbow about x) holding a free payload by a weld with a relpose (45°
// about y, at (0.1, 0, −0.4) on the forearm) and an anchor on the payload; the payload drawn where
// the weld holds at q = 0: x₂ = x₁ + relpos − R(relquat) anchor, R₂ = R(relquat)
const std::string kWeldXml = R"(<mujoco><option gravity="0 0 -9.81"/><worldbody>
  <body name="arm"><joint name="shoulder" type="hinge" axis="0 1 0"/>
    <inertial pos="0 0 -0.25" mass="1" diaginertia="0.02 0.02 0.001"/>
    <body name="forearm" pos="0 0 -0.5"><joint name="elbow" type="hinge" axis="1 0 0"/>
      <inertial pos="0 0 -0.2" mass="0.5" diaginertia="0.01 0.01 0.001"/></body></body>
  <body name="payload" pos="0.08585786437626905 -0.01 -0.885857864376269"
        quat="0.9238795325112867 0 0.3826834323650898 0"><freejoint name="payload"/>
    <inertial pos="0.05 0 0" mass="0.8" diaginertia="0.003 0.004 0.005"/></body>
</worldbody><equality>
  <weld name="grip" body1="forearm" body2="payload" relpose="0.1 0 -0.4 0.9238795325112867 0 0.3826834323650898 0"
        anchor="0.02 0.01 0"/>
</equality></mujoco>)";

// the same as a scenario: the weld's frame on the forearm a frame of the scenario's
const std::string kWeldScenario = R"(gravity: [0, 0, -9.81]
bodies:
  - {name: arm, joint: {type: revolute, name: shoulder, axis: [0, 1, 0]}, mass: 1, com: [0, 0, -0.25], inertia: [0.02, 0.02, 0.001]}
  - {name: forearm, parent: arm, joint: {type: revolute, name: elbow, axis: [1, 0, 0]}, origin: {xyz: [0, 0, -0.5]},
     mass: 0.5, com: [0, 0, -0.2], inertia: [0.01, 0.01, 0.001]}
  - {name: payload, joint: {type: free, name: payload}, mass: 0.8, com: [0.05, 0, 0], inertia: [0.003, 0.004, 0.005]}
frames:
  grip_a: {body: forearm, position: [0.1, 0, -0.4], rpy: [0, 0.78539816339744831, 0]}
loops:
  - {name: grip, type: weld, a: grip_a, b: payload, at_b: [0.02, 0.01, 0]}
initial:
  q: {payload: [0.08585786437626905, -0.01, -0.885857864376269, 0.9238795325112867, 0, 0.3826834323650898, 0]}
)";

void expect_same_loops(const std::vector<LoopConstraint>& a, const std::vector<LoopConstraint>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].name, b[k].name);
    EXPECT_EQ(a[k].type, b[k].type) << a[k].name;
    EXPECT_EQ(a[k].body_a, b[k].body_a) << a[k].name;
    EXPECT_EQ(a[k].body_b, b[k].body_b) << a[k].name;
    EXPECT_LE((a[k].at_a.p - b[k].at_a.p).cwiseAbs().maxCoeff(), 1e-12) << a[k].name;
    EXPECT_LE((a[k].at_b.p - b[k].at_b.p).cwiseAbs().maxCoeff(), 1e-12) << a[k].name;
    if (a[k].type != LoopType::Point) {  // a point's axes mean nothing
      EXPECT_LE((a[k].at_a.R - b[k].at_a.R).cwiseAbs().maxCoeff(), 1e-12) << a[k].name;
      EXPECT_LE((a[k].at_b.R - b[k].at_b.R).cwiseAbs().maxCoeff(), 1e-12) << a[k].name;
    }
  }
}

// the two scenarios run alike: the same start, the same q over the run (every sample)
void expect_same_motion(const Scenario& a, const Scenario& b, double bound) {
  ASSERT_EQ(a.q0.size(), b.q0.size());
  EXPECT_LE((a.q0 - b.q0).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LE((a.v0 - b.v0).cwiseAbs().maxCoeff(), 1e-12);
  MotionGap g;
  ASSERT_NO_FATAL_FAILURE(motion_gap(a, b, g));
  std::printf("  %zu samples over %.1f s: largest |q_mjcf - q_scenario| %.1e (q moved up to %.2f)\n", g.samples,
              g.t_end, g.gap, g.moved);
  EXPECT_LE(g.gap, bound);
  EXPECT_GT(g.moved, 0.3);  // it moves
}

std::string ignored_line(const Model& m) {
  std::string line;
  for (const std::string& w : m.warnings)
    if (w.rfind("ignored: ", 0) == 0) {
      EXPECT_TRUE(line.empty()) << "two ignored lines";
      line = w;
    }
  return line;
}

}  // namespace

TEST(MjcfLoops, AFourBarClosedByConnectIsTheScenarioWithAPointLoop) {
  const std::string start = "initial: {qd: {crank: 3.0}}\n";
  const Scenario mj = parse_scenario("model: four_bar_connect.xml\n" + start + kRun, kDir + "four_bar_mjcf.yaml");
  const Scenario sc = parse_scenario(kFourBarPoint + start + kRun, kDir + "four_bar_point.yaml");
  ASSERT_EQ(mj.inputs.loops.size(), 1u);
  EXPECT_EQ(mj.inputs.loops[0].type, LoopType::Point);
  EXPECT_EQ(mj.model.body_names, sc.model.body_names);
  expect_same_loops(mj.inputs.loops, sc.inputs.loops);
  expect_same_motion(mj, sc, 1e-9);
  EXPECT_THAT(ignored_line(mj.model), HasSubstr("the solref/solimp softness of 1 equality constraint (held exactly as a loop)"));
}

TEST(MjcfLoops, AWeldWithARelposeIsTheScenarioWeld) {
  const std::string start = "initial: {qd: {shoulder: 1.0, elbow: 2.0}}\n";
  const std::string dir = ::testing::TempDir();
  {
    std::FILE* f = std::fopen((dir + "/weld.xml").c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs(kWeldXml.c_str(), f);
    std::fclose(f);
  }
  const Scenario mj = parse_scenario("model: weld.xml\n" + start + kRun, dir + "/weld_mjcf.yaml");
  // the scenario's initial: holds the payload's pose (drawn closed) and gives the arm's rates
  std::string scenario = kWeldScenario;
  scenario.insert(scenario.find("  q: {payload"), "  qd: {shoulder: 1.0, elbow: 2.0}\n");
  const Scenario sc = parse_scenario(scenario + kRun, dir + "/weld_scenario.yaml");
  ASSERT_EQ(mj.inputs.loops.size(), 1u);
  EXPECT_EQ(mj.inputs.loops[0].type, LoopType::Weld);
  expect_same_loops(mj.inputs.loops, sc.inputs.loops);
  expect_same_motion(mj, sc, 1e-9);
}

// φ = 0 exactly where MuJoCo's constraint is: at random states, soadyn's closure against MuJoCo's
// efc_pos of the same equality (connect: p₁ − p₂; weld: p₁ − p₂ and vec(q₂⁻¹ q₁ q_rel), the vector
// part of R_Bᵀ R_A's quaternion, where soadyn's rows are R_B log(R_Bᵀ R_A)).  MuJoCo 2.2's
// torquescale (0.5 here) scales the rotation rows' Jacobian, not efc_pos: their zero set is the same
TEST(MjcfLoops, TheClosureIsMuJoCosConstraintResidual) {
  std::string xml = kWeldXml;
  // a connect from the forearm to the world, and one onto a body merged into the arm (rotated)
  xml.insert(xml.find("</equality>"), R"(<connect body1="forearm" anchor="0.1 0.2 -0.3"/>
    <connect body1="payload" body2="tag" anchor="0.1 0 0.05"/>)");
  xml.insert(xml.find("</body></body>"), R"(</body><body name="tag" pos="0.02 0.03 -0.1" euler="10 20 30">
    <inertial pos="0 0 0" mass="0.1" diaginertia="0.001 0.001 0.001"/>)");
  xml.insert(xml.find("anchor=\"0.02 0.01 0\""), "torquescale=\"0.5\" ");
  const MjcfModel mj = parse_mjcf(xml, "weld.xml", false);
  const Model& model = mj.model;
  ASSERT_EQ(mj.loops.size(), 3u);
  EXPECT_EQ(mj.loops[1].body_b, -1);
  EXPECT_EQ(mj.loops[2].body_b, model.body_index("arm"));  // the merged tag moves with the arm

  const std::string path = ::testing::TempDir() + "/residual.xml";
  std::FILE* f = std::fopen(path.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fputs(xml.c_str(), f);
  std::fclose(f);
  char error[1000] = "";
  std::unique_ptr<mjModel, void (*)(mjModel*)> m(mj_loadXML(path.c_str(), nullptr, error, sizeof error), mj_deleteModel);
  ASSERT_TRUE(m) << error;
  m->opt.disableflags |= mjDSBL_CONTACT | mjDSBL_LIMIT;
  std::unique_ptr<mjData, void (*)(mjData*)> d(mj_makeData(m.get()), mj_deleteData);
  ASSERT_EQ(m->nq, model.nq);

  std::mt19937 rng(62);
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  Data data(model);
  LoopData ld(model, mj.loops);
  for (int trial = 0; trial < 20; ++trial) {
    VecX q = mj.q0;
    for (int k = 0; k < model.nq; ++k) q(k) += u(rng);
    model.normalize(q);
    for (int k = 0; k < model.nq; ++k) d->qpos[k] = q(k);  // hinges' qpos0 and soadyn's q0 are zero here
    mj_forward(m.get(), d.get());
    ASSERT_EQ(d->ne, 12);
    update_kinematics(model, data, q);
    loop_closure(model, data, mj.loops, ld);
    // the weld: position rows as they are, rotation rows from soadyn's log to MuJoCo's quaternion
    const Mat3 R_B = body_frame_placement(model, data, mj.loops[0].body_b, mj.loops[0].at_b).R;
    const Vec3 w = R_B.transpose() * ld.phi.segment<3>(3);
    const Vec3 mujoco_rot = std::sin(w.norm() / 2) / std::max(w.norm(), 1e-300) * w;
    EXPECT_LE((ld.phi.head<3>() - Eigen::Map<const Vec3>(d->efc_pos)).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LE((mujoco_rot - Eigen::Map<const Vec3>(d->efc_pos + 3)).cwiseAbs().maxCoeff(), 1e-12) << trial;
    // the connects: p₁ − p₂
    EXPECT_LE((ld.phi.segment<6>(6) - Eigen::Map<const VecX>(d->efc_pos + 6, 6)).cwiseAbs().maxCoeff(), 1e-12) << trial;
  }
}

TEST(MjcfLoops, AConnectOnAMergedBodyLandsOnTheBodyItMovesWith) {
  // the rocker's end as a body of its own (no joint: merged into the rocker), turned 90° about z;
  // the connect from the coupler onto it, and one from it (its x is the rocker's y) to the world
  std::string xml = read_text_file(kDir + "four_bar_connect.xml");
  xml.insert(xml.find("    </body>\n  </worldbody>"), "      <body name=\"end\" pos=\"0.8 0 0\" axisangle=\"0 0 1 1.5707963267948966\"/>\n");
  xml.replace(xml.find("body2=\"rocker\""), 14, "body2=\"end\"");
  xml.insert(xml.find("  </equality>"), "    <connect name=\"pin\" body1=\"end\" anchor=\"0.1 0 0\"/>\n");
  const MjcfModel mj = parse_mjcf(xml, "merged.xml", false);
  ASSERT_EQ(mj.model.body_index("end"), -1);  // merged
  ASSERT_EQ(mj.loops.size(), 2u);
  const int rocker = mj.model.body_index("rocker");
  EXPECT_EQ(mj.loops[0].body_a, mj.model.body_index("coupler"));
  EXPECT_EQ(mj.loops[0].body_b, rocker);
  EXPECT_LE((mj.loops[0].at_b.p - Vec3(0.8, 0, 0)).norm(), 1e-12);
  EXPECT_EQ(mj.loops[1].name, "pin");
  EXPECT_EQ(mj.loops[1].body_a, rocker);
  EXPECT_LE((mj.loops[1].at_a.p - Vec3(0.8, 0.1, 0)).norm(), 1e-12);
  EXPECT_EQ(mj.loops[1].body_b, -1);
  // where the world's point is: the rocker's (0.8, 0.1) at its drawn angle, about its pivot
  const double r = 1.4041580733270875;
  const Vec3 world = Vec3(0.9, 0, 0) + Eigen::AngleAxisd(r, Vec3::UnitZ()) * Vec3(0.8, 0.1, 0);
  EXPECT_LE((mj.loops[1].at_b.p - world).norm(), 1e-12);
}

TEST(MjcfLoops, WhatIsNotHeldIsNamedInOneLine) {
  std::string xml = read_text_file(kDir + "four_bar_connect.xml");
  xml.insert(xml.find("  </equality>"), R"(    <connect body1="crank" anchor="0.1 0 0" active="false"/>
    <joint joint1="crank" joint2="rocker"/>
    <weld body1="rocker" body2="rocker_tip"/>
    <weld body1="coupler" body2="rocker" torquescale="0"/>
)");
  xml.insert(xml.find("    </body>\n  </worldbody>"), "      <body name=\"rocker_tip\" pos=\"0.8 0 0\"/>\n");
  const MjcfModel mj = parse_mjcf(xml, "m.xml", false);
  const std::string line = ignored_line(mj.model);
  EXPECT_THAT(line, HasSubstr("1 inactive equality constraint"));
  EXPECT_THAT(line, HasSubstr("1 joint equality constraint"));
  EXPECT_THAT(line, HasSubstr("1 equality constraint within one rigid body (no effect)"));
  EXPECT_THAT(line, HasSubstr("the solref/solimp softness of 2 equality constraints (held exactly as loops)"));
  EXPECT_EQ(line.find('\n'), std::string::npos);
  // the connect, and the weld without torque (torquescale 0): a point where body 2's origin was drawn
  ASSERT_EQ(mj.loops.size(), 2u);
  EXPECT_EQ(mj.loops[0].name, "closing");
  EXPECT_EQ(mj.loops[1].name, "equality4");
  EXPECT_EQ(mj.loops[1].type, LoopType::Point);
  EXPECT_LE(mj.loops[1].at_b.p.norm(), 1e-15);
}

// a run stores the MJCF's files: compiled again from them alone they give the same loops, and a
// scenario read again from the run's texts the same loops and start
TEST(MjcfLoops, ARunsStoredFilesGiveTheSameLoops) {
  const std::string text = "model: four_bar_connect.xml\ninitial: {q: {crank: 0.2}, qd: {crank: 1.0}}\n";
  const Scenario sc = parse_scenario(text, kDir + "scene.yaml");
  const MjcfModel again = parse_mjcf_files(sc.model_files, "stored");
  expect_same_loops(again.loops, sc.inputs.loops);
  const Scenario reread = parse_scenario(text, kDir + "scene.yaml", false, std::nullopt, sc.robot_text, &sc.model_files);
  expect_same_loops(reread.inputs.loops, sc.inputs.loops);
  EXPECT_EQ(reread.q0, sc.q0);
  EXPECT_EQ(reread.v0, sc.v0);
  // assembled: the crank where initial.q holds it, the others moved onto the loop
  EXPECT_EQ(sc.q0(0), 0.2);
  LoopData ld(sc.model, sc.inputs.loops);
  Data d(sc.model);
  update_kinematics(sc.model, d, sc.q0);
  loop_closure(sc.model, d, sc.inputs.loops, ld);
  EXPECT_LE(ld.phi.cwiseAbs().maxCoeff(), kLoopClosure);
  // an MJCF file loaded alone brings its loops, closed at its drawn pose
  const Scenario alone = load_scenario(kDir + "four_bar_connect.xml");
  expect_same_loops(alone.inputs.loops, sc.inputs.loops);
  EXPECT_LE(alone.q0.cwiseAbs().maxCoeff(), 1e-12);
}
