// Frames on the note's double pendulum (scenarios/double_pendulum.yaml): closed forms of a tip
// frame from the scenario's own `frames:` (placement, Jacobian, J̇ v, centre of mass), Λ refused
// for more task rows than joints or at a singular pose, and the refusals of `frames:`, add_frame
// and parse_reference.  Random trees and merged frames: test_frames.cpp.
#include "soadyn/algorithm/frames.hpp"
#include "soadyn/io/scenario_file.hpp"

#include "test_util.hpp"

#include <Eigen/Dense>

#include <fstream>
#include <sstream>

namespace soadyn::test {
namespace {

using Vec2d = Eigen::Vector2d;

TEST(FramesSingular, OperationalSpaceInertiaRefusesMoreRowsThanJoints) {
  const Scenario sc = load_scenario(std::string(SOADYN_SOURCE_DIR) + "/scenarios/double_pendulum.yaml");
  Model m = sc.model;
  const int f = m.add_frame("tip", m.body_index("lower"), {Mat3::Identity(), Vec3(0, 0, -1)});
  Data d(m);
  update_kinematics(m, d, Vec2d(0.3, 0.4));
  MatX J, L;
  frame_jacobian(m, d, f, Reference::LocalWorldAligned, J);
  try {
    operational_space_inertia(m, d, J, L);
    FAIL() << "a 6-row task on 2 joints was accepted";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("singular: rank 2 of 6"));
  }
  // the tip's y and z: a 2×2 Λ, the dense formula's
  const MatX task = J.bottomRows<2>();
  operational_space_inertia(m, d, task, L);
  mass_matrix(m, d);
  EXPECT_TRUE(near_rel(L, (task * d.M.inverse() * task.transpose()).inverse(), 1e-10));
  // straight arm: the tip cannot move along the links
  update_kinematics(m, d, Vec2d(0.3, 0.0));
  frame_jacobian(m, d, f, Reference::LocalWorldAligned, J);
  EXPECT_THROW(operational_space_inertia(m, d, MatX(J.bottomRows<2>()), L), Error);
}

// the note's Example 2 with a tip frame from the scenario's own `frames:`: closed forms
TEST(FramesClosedForm, DoublePendulumTip) {
  std::ifstream in(std::string(SOADYN_SOURCE_DIR) + "/scenarios/double_pendulum.yaml");
  std::stringstream text;
  text << in.rdbuf();
  const std::string yaml = text.str() + "frames:\n  tip: {body: lower, position: [0, 0, -1.0]}\n";
  const Scenario sc = parse_scenario(yaml, std::string(SOADYN_SOURCE_DIR) + "/scenarios/dp_tip.yaml");
  const Model& m = sc.model;
  const int f = m.frame_index("tip");
  ASSERT_GE(f, 0);
  Data d(m);
  Rng rng(18);
  for (int trial = 0; trial < 5; ++trial) {
    const double t1 = rng.uniform(-3, 3), t2 = rng.uniform(-3, 3), w1 = rng.uniform(-2, 2), w2 = rng.uniform(-2, 2);
    const double s1 = std::sin(t1), c1 = std::cos(t1), s12 = std::sin(t1 + t2), c12 = std::cos(t1 + t2), w12 = w1 + w2;
    update_kinematics(m, d, Vec2d(t1, t2));
    update_velocities(m, d, Vec2d(w1, w2));
    // hinges about e_x, links 1 m down: tip = [0, s1 + s12, −c1 − c12]
    const Placement X = frame_placement(m, d, f);
    EXPECT_TRUE(near_rel(X.p, Vec3(0, s1 + s12, -c1 - c12), 1e-14));
    EXPECT_TRUE(near_rel(X.R, Eigen::AngleAxisd(t1 + t2, Vec3::UnitX()).toRotationMatrix(), 1e-14));
    MatX J, Jexp(6, 2);
    frame_jacobian(m, d, f, Reference::LocalWorldAligned, J);
    Jexp << 1, 1, 0, 0, 0, 0, 0, 0, c1 + c12, c12, s1 + s12, s12;
    EXPECT_TRUE(near_rel(J, Jexp, 1e-14));
    // J̇ v = p̈ at q̈ = 0: [0, −s1 w1² − s12 w12², c1 w1² + c12 w12²]
    Vec6 Jdv, expected;
    frame_jacobian_dot_times_v(m, d, f, Reference::LocalWorldAligned, Jdv);
    expected << 0, 0, 0, 0, -s1 * w1 * w1 - s12 * w12 * w12, c1 * w1 * w1 + c12 * w12 * w12;
    EXPECT_TRUE(near_rel(Jdv, expected, 1e-14));
    // both unit masses at mid-link: c = ((s1/2) + (s1 + s12/2)) / 2 in y, likewise z
    EXPECT_TRUE(near_rel(com(m, d), Vec3(0, (1.5 * s1 + 0.5 * s12) / 2, -(1.5 * c1 + 0.5 * c12) / 2), 1e-14));
  }
}

TEST(FramesErrors, NamesBodiesAndReferences) {
  const std::string dir = std::string(SOADYN_SOURCE_DIR) + "/scenarios/";
  std::ifstream in(dir + "double_pendulum.yaml");
  std::stringstream text;
  text << in.rdbuf();
  auto parse = [&](const std::string& frames) { return parse_scenario(text.str() + frames, dir + "dp.yaml"); };
  // on a frame the model has, on the world, on an earlier entry
  const Scenario sc = parse("frames:\n  a: {body: world, position: [1, 2, 3]}\n  b: {body: lower, rpy: [0, 0, 1.5707963267948966]}\n"
                            "  c: {body: b, position: [1, 0, 0]}\n");
  Data d(sc.model);
  update_kinematics(sc.model, d, Vec2d(0, 0));
  EXPECT_TRUE(near_rel(frame_placement(sc.model, d, sc.model.frame_index("a")).p, Vec3(1, 2, 3), 1e-15));
  EXPECT_TRUE(near_rel(frame_placement(sc.model, d, sc.model.frame_index("c")).p, Vec3(0, 1, -1), 1e-15));
  EXPECT_EQ(sc.model.frame_body[sc.model.frame_index("a")], -1);
  auto message = [&](const std::string& frames) {
    try {
      parse(frames);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_THAT(message("frames:\n  tip: {body: lowr}\n"), ::testing::HasSubstr("frames.tip.body: no body or frame named 'lowr'; did you mean 'lower'?"));
  EXPECT_THAT(message("frames:\n  upper: {body: lower}\n"), ::testing::HasSubstr("already has a frame named 'upper'"));
  EXPECT_THAT(message("frames:\n  tip: {body: lower, position: [0, 1]}\n"), ::testing::HasSubstr("frames.tip.position: expected 3 numbers"));
  EXPECT_THAT(message("frames:\n  tip: {body: lower, pos: [0, 1, 0]}\n"), ::testing::HasSubstr("unknown key 'pos'"));
  EXPECT_THAT(message("frames: [tip]\n"), ::testing::HasSubstr("frames: expected a map"));
  EXPECT_THAT(message("frames:\n  tip: {body: lower}\n"), ::testing::StrEq("accepted"));
  // the library's own checks
  Model m = sc.model;
  EXPECT_THROW(m.add_frame("a", 0, {}), Error);
  EXPECT_THROW(m.add_frame("z", 7, {}), Error);
  EXPECT_THROW(m.add_frame("z", 0, {2 * Mat3::Identity(), Vec3::Zero()}), Error);
  MatX J;
  EXPECT_THROW(frame_jacobian(m, d, int(m.frame_names.size()), Reference::World, J), Error);
  EXPECT_EQ(parse_reference("local"), Reference::Local);
  try {
    parse_reference("wrld");
    FAIL();
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("did you mean 'world'?"));
  }
}

}  // namespace
}  // namespace soadyn::test
