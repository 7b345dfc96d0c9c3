// MJCF values MuJoCo takes without a word: each dropped one named in the "ignored" line or mapped,
// each invalid one (NaN or infinity anywhere, negative joint damping, stiffness, frictionloss,
// armature) refused at its file and line, an <include>d file's included; MuJoCo's handlers put back
// after every load; generated frame names never a real body's name; massless frames kept by
// with_parameters.
#include "soadyn/io/mjcf.hpp"
#include "soadyn/algorithm/regressor.hpp"
#include "soadyn/io/scenario_file.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

using namespace soadyn;
using ::testing::HasSubstr;
using ::testing::Not;

namespace {

namespace fs = std::filesystem;

// a one-body model with `joint` (attributes) and `extra` inside <mujoco>
std::string model(const std::string& joint, const std::string& extra = "", const std::string& body = "") {
  return "<mujoco>\n" + extra + "\n<worldbody>\n<body name=\"a\" " + body + ">\n<joint name=\"j\" " + joint +
         "/>\n<geom type=\"sphere\" size=\"0.1\" contype=\"0\" conaffinity=\"0\"/>\n</body>\n</worldbody>\n</mujoco>\n";
}

std::string refusal(const std::string& xml) {
  try {
    parse_mjcf(xml, "m.xml", false);
  } catch (const Error& e) {
    return e.what();
  }
  return "(accepted)";
}

std::string warnings(const std::string& xml) {
  std::string all;
  for (const std::string& w : parse_mjcf(xml, "m.xml", false).model.warnings) all += w + "\n";
  return all;
}

struct TempDir {
  fs::path path;
  TempDir() {
    char name[] = "/tmp/soadyn_mjcf_values_XXXXXX";
    path = mkdtemp(name);
  }
  ~TempDir() { fs::remove_all(path); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path / name) << text;
    return (path / name).string();
  }
};

TEST(MjcfValues, EachDroppedValueIsNamed) {
  const std::string w = warnings(R"(<mujoco>
    <option wind="1 0 0" density="1.2" viscosity="0.01"/>
    <worldbody>
      <body name="a"><joint name="h" type="hinge" frictionloss="0.3"/><geom type="sphere" size="0.1" contype="0" conaffinity="0"/>
        <body name="b" pos="0 0 0.3"><joint name="s" type="ball" damping="0.2" stiffness="1"/>
          <geom type="sphere" size="0.1" contype="0" conaffinity="0"/></body></body>
      <body name="c" pos="1 0 0"><freejoint name="f"/><geom type="sphere" size="0.1" contype="0" conaffinity="0"/></body>
    </worldbody></mujoco>)");
  EXPECT_THAT(w, HasSubstr("ignored: "));
  EXPECT_THAT(w, HasSubstr("1 joint frictionloss (dry friction)"));
  EXPECT_THAT(w, HasSubstr("1 ball- or free-joint damping"));
  EXPECT_THAT(w, HasSubstr("1 ball- or free-joint stiffness"));
  EXPECT_THAT(w, HasSubstr("<option wind density viscosity> (fluid forces)"));
  // a free joint's damping (MuJoCo's <joint type="free" damping>) and only the wind
  const std::string free = warnings(R"(<mujoco><option wind="0 0 2"/><worldbody>
      <body name="c"><joint type="free" damping="0.5"/><geom type="sphere" size="0.1" contype="0" conaffinity="0"/></body>
    </worldbody></mujoco>)");
  EXPECT_THAT(free, HasSubstr("1 ball- or free-joint damping"));
  EXPECT_THAT(free, HasSubstr("<option wind> (fluid forces)"));
  // nothing dropped: no line at all
  EXPECT_EQ(warnings(model("type=\"hinge\" damping=\"0.5\" stiffness=\"2\"")), "");
}

TEST(MjcfValues, MuJoCosFlagsAreMapped) {
  const MjcfModel on = parse_mjcf(model("type=\"hinge\" damping=\"0.5\" stiffness=\"2\""), "m.xml", false);
  EXPECT_EQ(on.dampers.size(), 1u);
  EXPECT_EQ(on.springs.size(), 1u);
  EXPECT_NEAR(on.model.gravity.z(), -9.81, 1e-15);
  const MjcfModel off = parse_mjcf(model("type=\"hinge\" damping=\"0.5\" stiffness=\"2\" frictionloss=\"1\"",
                                         "<option><flag passive=\"disable\" gravity=\"disable\" frictionloss=\"disable\"/></option>"),
                                   "m.xml", false);
  EXPECT_TRUE(off.dampers.empty());
  EXPECT_TRUE(off.springs.empty());
  EXPECT_EQ(off.model.gravity.norm(), 0.0);
  EXPECT_TRUE(off.model.warnings.empty()) << off.model.warnings.at(0);
}

// (the model's attributes, what the refusal says): file, line, element, attribute
struct Bad {
  std::string xml, expect;
};

class InvalidValues : public ::testing::TestWithParam<Bad> {};

TEST_P(InvalidValues, AreRefusedAtTheirLine) {
  const std::string got = refusal(GetParam().xml);
  EXPECT_THAT(got, HasSubstr(GetParam().expect));
  EXPECT_THAT(got, Not(HasSubstr("\n")));
}

INSTANTIATE_TEST_SUITE_P(
    Cases, InvalidValues,
    ::testing::Values(
        Bad{model("type=\"hinge\"", "", "pos=\"nan 0 1\""), "m.xml:4: body: attribute 'pos': expected finite numbers"},
        Bad{model("type=\"hinge\"", "", "pos=\"0 inf 1\""), "m.xml:4: body: attribute 'pos': expected finite numbers"},
        Bad{model("stiffness=\"nan\""), "m.xml:5: joint: attribute 'stiffness': expected finite numbers, got 'nan'"},
        Bad{model("stiffness=\"1e999\""), "m.xml:5: joint: attribute 'stiffness': expected finite numbers"},
        Bad{model("damping=\"-1\""), "m.xml:5: joint: attribute 'damping': expected a number >= 0, got '-1'"},
        Bad{model("stiffness=\"-2\""), "m.xml:5: joint: attribute 'stiffness': expected a number >= 0"},
        Bad{model("frictionloss=\"-0.1\""), "m.xml:5: joint: attribute 'frictionloss': expected a number >= 0"},
        Bad{model("armature=\"-1\""), "m.xml:5: joint: attribute 'armature': expected a number >= 0"},
        Bad{model("", "<default><joint damping=\"-0.5\"/></default>"), "m.xml:2: joint: attribute 'damping': expected a number >= 0"},
        Bad{model("", "<option gravity=\"0 0 nan\"/>"), "m.xml:2: option: attribute 'gravity': expected finite numbers"},
        Bad{model("axis=\"0 NaN 1\""), "m.xml:5: joint: attribute 'axis': expected finite numbers"},
        Bad{model("range=\"-1 -inf\" limited=\"true\""), "m.xml:5: joint: attribute 'range': expected finite numbers"}));

TEST(MjcfValues, ANameIsNotANumber) {
  // a joint and a body named "nan" and "inf": names, not numbers
  const MjcfModel mj = parse_mjcf(R"(<mujoco><worldbody><body name="inf"><joint name="nan"/>
    <geom type="sphere" size="0.1" contype="0" conaffinity="0"/></body></worldbody></mujoco>)", "m.xml", false);
  EXPECT_GE(mj.model.joint_index("nan"), 0);
  EXPECT_GE(mj.model.body_index("inf"), 0);
}

TEST(MjcfValues, AnIncludedFilesValueIsRefusedAtItsOwnLine) {
  TempDir dir;
  dir.write("part.xml", "<mujoco>\n<body name=\"b\" pos=\"0 0 0.2\">\n<joint damping=\"nan\"/>\n"
                        "<geom type=\"sphere\" size=\"0.1\" contype=\"0\" conaffinity=\"0\"/></body>\n</mujoco>\n");
  const std::string text = "<mujoco>\n<worldbody>\n<body name=\"a\"><joint/><geom type=\"sphere\" size=\"0.1\" "
                           "contype=\"0\" conaffinity=\"0\"/>\n<include file=\"part.xml\"/>\n</body>\n</worldbody>\n</mujoco>\n";
  const std::string path = dir.write("main.xml", text);
  try {
    load_scenario(path);
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr((dir.path / "part.xml").string() + ":3: joint: attribute 'damping': expected finite numbers"));
  }
}

void sentinel_warning(const char*) {}
void sentinel_error(const char*) {}

TEST(MjcfValues, MuJoCosHandlersArePutBackAfterEveryLoad) {
  mju_user_warning = sentinel_warning;
  mju_user_error = sentinel_error;
  EXPECT_EQ(refusal(model("type=\"hinge\"", "", "pos=\"nan 0 1\"")).substr(0, 6), "m.xml:");  // refused before MuJoCo
  EXPECT_THAT(refusal("<mujoco><worldbody><body><joint type=\"bogus\"/></body></worldbody></mujoco>"), HasSubstr("m.xml:1: joint"));
  parse_mjcf(model("type=\"hinge\""), "m.xml", false);
  EXPECT_EQ(mju_user_warning, &sentinel_warning);
  EXPECT_EQ(mju_user_error, &sentinel_error);
  mju_user_warning = nullptr;
  mju_user_error = nullptr;
}

TEST(MjcfValues, GeneratedFrameNamesNeverTakeARealBodysName) {
  TempDir dir;
  // upper has joints x and y: its frame for x would be "upper.x", which a real body already is
  dir.write("arm.xml", R"(<mujoco><worldbody>
    <body name="upper"><joint name="x" axis="1 0 0"/><joint name="y" axis="0 1 0"/>
      <inertial pos="0 0 0" mass="2" diaginertia="0.1 0.1 0.1"/>
      <body name="upper.x" pos="0 0 0.5"><joint name="z"/><inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/></body>
    </body>
  </worldbody></mujoco>)");
  const Scenario plain = load_scenario((dir.path / "arm.xml").string());
  const Model& m = plain.model;
  ASSERT_GE(m.body_index("upper.x"), 0);
  ASSERT_GE(m.body_index("upper.x~2"), 0);
  EXPECT_NEAR(m.mass[size_t(m.body_index("upper.x"))], 1.0, 1e-15);    // the real body
  EXPECT_EQ(m.mass[size_t(m.body_index("upper.x~2"))], 0.0);            // the generated frame
  EXPECT_EQ(m.body_names.size(), 3u);
  std::string w;
  for (const std::string& s : m.warnings) w += s;
  EXPECT_THAT(w, HasSubstr("upper.x -> upper.x~2"));
  // inertial: upper.x changes the real body, not the frame
  dir.write("scene.yaml", "model: arm.xml\ninertial:\n  upper.x: {mass: 3, com: [0, 0, 0], inertia: [0.02, 0.02, 0.02]}\n");
  const Scenario sc = load_scenario((dir.path / "scene.yaml").string());
  EXPECT_NEAR(sc.model.mass[size_t(sc.model.body_index("upper.x"))], 3.0, 1e-15);
  EXPECT_EQ(sc.model.mass[size_t(sc.model.body_index("upper.x~2"))], 0.0);
}

TEST(MjcfValues, AnUnnamedBodyOrJointNeverTakesARealName) {
  // body 2 is unnamed ("body2"), body 1 is named "body2"; joint 1 unnamed ("joint1"), joint 0 named "joint1"
  const MjcfModel mj = parse_mjcf(R"(<mujoco><worldbody>
    <body name="body2"><joint name="joint1" damping="1"/><inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/></body>
    <body pos="1 0 0"><joint damping="2"/><inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/></body>
  </worldbody></mujoco>)", "m.xml", false);
  const Model& m = mj.model;
  EXPECT_GE(m.body_index("body2"), 0);
  EXPECT_GE(m.body_index("body2~2"), 0);
  ASSERT_EQ(mj.dampers.size(), 2u);
  EXPECT_EQ(mj.dampers[0].joint, "joint1");
  EXPECT_NEAR(mj.dampers[0].damping, 1.0, 1e-15);
  EXPECT_EQ(mj.dampers[1].joint, "joint1~2");
  EXPECT_NEAR(mj.dampers[1].damping, 2.0, 1e-15);
}

TEST(MjcfValues, WithParametersKeepsMasslessFrames) {
  const MjcfModel mj = parse_mjcf(R"(<mujoco><worldbody>
    <body name="u"><joint name="x" axis="1 0 0"/><joint name="y" axis="0 1 0"/>
      <inertial pos="0 0 0.1" mass="2" diaginertia="0.1 0.1 0.1"/></body></worldbody></mujoco>)", "m.xml", false);
  const Model& m = mj.model;
  ASSERT_EQ(m.nbodies, 2);
  const Model same = with_parameters(m, parameters(m));
  EXPECT_EQ(same.mass[0], 0.0);
  EXPECT_NEAR(same.mass[1], 2.0, 1e-15);
  VecX pi = parameters(m);
  pi(0) = -1e-3;  // a frame given a mass, and a negative one: refused as before
  EXPECT_THROW(with_parameters(m, pi), Error);
}

}  // namespace
