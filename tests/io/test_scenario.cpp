// Scenario files: the four example files, the dynamics route's word, the word-valued settings,
// inertia_check, and every bad-scenario case with its message.  URDF import: test_scenario_urdf.cpp.
#include "soadyn/sim/integrators.hpp"
#include "soadyn/sim/rollout.hpp"
#include "soadyn/io/scenario_file.hpp"

#include "test_util.hpp"

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
  EXPECT_EQ(methods.size(), 8u);
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
