// Tabulated targets (table.hpp): the natural cubic spline's orders of accuracy against a closed form,
// CSV and run-file tables and their errors (file:line: column), a computed-torque controller
// tracking a tabulated trajectory as it tracks the closed form, a PD following a run file's motion,
// and torques saturated at the URDF's <limit effort>.
#include "soadyn/io/h5log.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/sim/simulate.hpp"
#include "soadyn/io/table_file.hpp"

#include "test_util.hpp"

#include <gmock/gmock.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

using namespace soadyn;
using soadyn::test::message_of;

namespace {

// the test's own directory under the system's temporary one, removed with everything in it when the
// test program ends (a test leaves nothing behind)
struct ScratchDir {
  std::filesystem::path dir = std::filesystem::temp_directory_path() / ("soadyn_table_" + std::to_string(getpid()));
  ScratchDir() { std::filesystem::create_directories(dir); }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
};

std::string scratch(const std::string& name) {
  static const ScratchDir scratch_dir;
  return (scratch_dir.dir / name).string();
}

void write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

// largest errors of the spline through sin on [0, 2π] with n intervals (sin'' = 0 at both ends:
// the natural end conditions hold, so the error is the interior's O(h⁴), O(h³), O(h²))
Vec3 sine_errors(int n) {
  VecX t = VecX::LinSpaced(n + 1, 0, 2 * std::numbers::pi), y = t.array().sin();
  const CubicSpline s(t, y);
  Vec3 e = Vec3::Zero();
  for (int k = 0; k <= 10 * n; ++k) {
    const double x = 2 * std::numbers::pi * k / (10.0 * n) * (1 - 1e-12);
    e(0) = std::max(e(0), std::abs(s.value(x) - std::sin(x)));
    e(1) = std::max(e(1), std::abs(s.rate(x) - std::cos(x)));
    e(2) = std::max(e(2), std::abs(s.acceleration(x) + std::sin(x)));
  }
  return e;
}

TEST(CubicSpline, OrdersFourThreeTwoOnASine) {
  const Vec3 coarse = sine_errors(40), fine = sine_errors(80);
  const Vec3 order = (coarse.array() / fine.array()).log() / std::log(2.0);
  EXPECT_NEAR(order(0), 4.0, 0.15) << coarse.transpose() << " / " << fine.transpose();
  EXPECT_NEAR(order(1), 3.0, 0.15);
  EXPECT_NEAR(order(2), 2.0, 0.15);
  EXPECT_LT(fine(0), 1e-6);
}

TEST(CubicSpline, ALineStaysALineAndTheEndsAreHeld) {
  const VecX t = (VecX(4) << 0.0, 0.5, 2.0, 2.25).finished();
  const VecX y = 3.0 * t.array() - 1.0;
  const CubicSpline s(t, y);
  for (double x : {0.1, 0.7, 1.9, 2.2}) {
    EXPECT_NEAR(s.value(x), 3 * x - 1, 1e-14);
    EXPECT_NEAR(s.rate(x), 3.0, 1e-13);
    EXPECT_NEAR(s.acceleration(x), 0.0, 1e-12);
  }
  EXPECT_NEAR(s.value(-1.0), -1.0, 1e-15);
  EXPECT_NEAR(s.value(9.0), 5.75, 1e-15);
  EXPECT_EQ(s.rate(9.0), 0.0);
  EXPECT_THROW(CubicSpline(VecX::Zero(1), VecX::Zero(1)), Error);
}

TEST(Table, CsvAsWrittenByHandOrByExport) {
  const std::string p = scratch("hand.csv");
  write(p, "# a comment\n\ntime [s], q.elbow [rad], shoulder\n0, 1, 2\n0.5, 1.75, 2.75\n1.0, 2, 3\n");
  const Table t = read_table(p);
  ASSERT_EQ(t.columns, (std::vector<std::string>{"elbow", "shoulder"}));
  ASSERT_EQ(t.time.size(), 3);
  EXPECT_NEAR(t.values(1, 0), 1.75, 0);
  EXPECT_EQ(t.column("shoulder"), 1);
  EXPECT_EQ(t.column("wrist"), -1);
}

TEST(Table, CsvErrorsNameFileLineAndColumn) {
  const std::string p = scratch("bad.csv");
  write(p, "t,a\n0,1\n0.1,x\n");
  EXPECT_EQ(message_of([&] { read_table(p); }), p + ":3: column 'a': expected a finite number, got 'x'");
  write(p, "t,a\n0,1\n0.1\n");
  EXPECT_EQ(message_of([&] { read_table(p); }), p + ":3: expected 2 fields as the header has, got 1");
  write(p, "t,a\n0,1\n1,2\n0.5,3\n");
  EXPECT_EQ(message_of([&] { read_table(p); }), p + ":4: column 't': the time decreases (1 at line 3, then 0.5)");
  // a repeated time, and one closer than 1e-9 of the table's time scale (here 2 s): refused as decreasing ones are
  write(p, "time [s],a\n0,1\n\n0.5,2\n0.5,3\n2,0\n");
  EXPECT_EQ(message_of([&] { read_table(p); }), p + ":5: column 'time': the time 0.5 repeats line 4's: each sample needs a time of its own");
  write(p, "t,a\n0,1\n0.5,2\n0.500000001,3\n2,0\n");
  EXPECT_EQ(message_of([&] { read_table(p); }),
            p + ":4: column 't': 0.50000000099999997 is 1e-09 s after line 3's 0.5, closer than the 2e-09 s samples must keep "
                "(1e-09 of the table's time scale, 2 s): the spline's rate and acceleration there would stall a run");
  write(p, "t,a\n0,1\n0.5,2\n0.500000002,2\n2,0\n");
  EXPECT_EQ(read_table(p).time.size(), 4);  // just past the minimum, no jump there
  // a jump sampled 1 ms wide beside 0.5 s intervals: the spline swings 96 times the range; 10 ms wide, 9.5 times
  write(p, "t,a\n0,0\n0.5,0\n0.501,1\n1,1\n");
  EXPECT_EQ(message_of([&] { read_table(p); }).substr(0, p.size() + 80),
            (p + ":3: column 'a': the spline through the samples strays 96.1291 beyond their range [0, 1] at t = 0.288675 s")
                .substr(0, p.size() + 80));
  EXPECT_THAT(message_of([&] { read_table(p); }), testing::HasSubstr("(0.001 s before line 4, 1 s in all)"));
  write(p, "t,a\n0,0\n0.5,0\n0.51,1\n1,1\n");
  const Table stepped = read_table(p);
  const CubicSpline::Swing w = CubicSpline(stepped.time, stepped.values.col(0)).swing();
  EXPECT_NEAR(w.beyond, 9.53, 0.01);  // against scipy's natural spline sampled at 2001 points per interval
  EXPECT_LT(CubicSpline(stepped.time, VecX::Constant(4, 0.3)).swing().beyond, 1e-15);
  EXPECT_DOUBLE_EQ(min_table_spacing(1000.0, 1001.0), 1.001e-6);  // the scale is the largest |t| when it exceeds the span
  write(p, "a,t\n0,1\n");
  EXPECT_EQ(message_of([&] { read_table(p); }), p + ":1: the first column must be the time ('t' or 'time [s]'), got 'a'");
  write(p, "t,a,a\n");
  EXPECT_EQ(message_of([&] { read_table(p); }), p + ":1: column 'a' is named twice");
  write(p, "t,a\n0,1\n");
  EXPECT_EQ(message_of([&] { read_table(p); }), p + ": a table needs samples at two times at least, got 1");
  EXPECT_EQ(message_of([&] { read_table(scratch("missing.csv")); }), scratch("missing.csv") + ": cannot open the file (no such file or directory)");
  // a directory is said to be one (it read as an empty table before)
  EXPECT_EQ(message_of([&] { read_table(scratch("")); }), scratch("") + ": is a directory, expected a table (CSV or run file)");
}

const std::string kArm = R"(gravity: [0, 0, -9.81]
bodies:
  - name: upper
    joint: {type: revolute, axis: [1, 0, 0]}
    mass: 1.0
    com: [0, 0, -0.5]
    inertia: [0.08, 0.08, 0.01]
  - name: lower
    parent: upper
    joint: {type: revolute, axis: [1, 0, 0]}
    origin: {xyz: [0, 0, -1]}
    mass: 0.5
    com: [0, 0, -0.4]
    inertia: [0.03, 0.03, 0.005]
)";

// computed torque following a tabulated q_d(t) = 0.4 sin(2π 0.5 t) + 0.2 (100 samples a second)
// ends where the closed-form target's run ends, to the spline's error; and on it to 1e-6
TEST(TabulatedTarget, ComputedTorqueTracksATableAsItTracksTheClosedForm) {
  const std::string csv = scratch("track.csv");
  std::ofstream out(csv);
  out << "t,upper,lower\n";
  for (int k = 0; k <= 400; ++k) {
    const double t = 0.01 * k;
    out << t << "," << 0.4 * std::sin(std::numbers::pi * t) + 0.2 << "," << -0.3 * std::sin(std::numbers::pi * t) << "\n";
  }
  out.close();
  const std::string head = kArm + "simulation: {t_end: 3, rtol: 1.0e-11, atol: 1.0e-13, output_dt: 0.1}\n";
  const Scenario table = parse_scenario(head + "inputs:\n  controllers:\n    - {type: computed_torque, kp: 100, kd: 20, targets: track.csv}\n",
                                        scratch("track.yaml"));
  const Scenario closed = parse_scenario(head + "inputs:\n  controllers:\n    - {type: computed_torque, kp: 100, kd: 20, targets: {"
                                                "upper: {constant: 0.2, amplitude: 0.4, frequency: 0.5}, lower: {amplitude: -0.3, frequency: 0.5}}}\n",
                                         scratch("closed.yaml"));
  std::vector<Sample> a, b;
  ASSERT_TRUE(simulate(table, table.simulation, nullptr, &a).completed);
  ASSERT_TRUE(simulate(closed, closed.simulation, nullptr, &b).completed);
  ASSERT_EQ(a.size(), b.size());
  const double t = a.back().t;
  EXPECT_NEAR(a.back().q(0), 0.4 * std::sin(std::numbers::pi * t) + 0.2, 1e-6);
  EXPECT_NEAR(a.back().q(1), -0.3 * std::sin(std::numbers::pi * t), 1e-6);
  EXPECT_TRUE(test::near_rel(a.back().q, b.back().q, 1e-6));
  // a real tracking task: the targets move by tenths of a radian
  EXPECT_GT(std::abs(a[5].q(0) - a[15].q(0)), 0.1);
  // a target column that is not in the table: named, with the table's columns
  const std::string bad = message_of([&] {
    parse_scenario(kArm + "inputs:\n  controllers:\n    - {type: pd, joint: lower, kp: 1, target: {table: track.csv, column: lowr}}\n",
                   scratch("bad.yaml"));
  });
  EXPECT_NE(bad.find("has no column 'lowr' (it has upper, lower); did you mean 'lower'?"), std::string::npos) << bad;
}

// a run file as a table: a PD with a stiff gain on the second pendulum follows the first's logged q
TEST(TabulatedTarget, APdFollowsARunFilesMotion) {
  const std::string run = scratch("swing.h5");
  const Scenario swing = parse_scenario(kArm + "initial: {q: {upper: 0.6, lower: -0.3}}\nsimulation: {t_end: 2, output_dt: 0.005, rtol: 1.0e-10, atol: 1.0e-12}\n",
                                        scratch("swing.yaml"));
  std::vector<Sample> logged;
  {
    H5Log log(run, swing, swing.simulation, "test");
    ASSERT_TRUE(simulate(swing, swing.simulation, &log, &logged).completed);
  }
  const Table t = read_table(run);
  ASSERT_EQ(t.columns, swing.model.q_names());
  ASSERT_EQ(size_t(t.time.size()), logged.size());
  EXPECT_NEAR(t.values(100, 1), logged[100].q(1), 1e-15);
  const Scenario follow = parse_scenario(
      kArm + "initial: {q: {upper: 0.6, lower: -0.3}}\nsimulation: {t_end: 2, output_dt: 0.5, rtol: 1.0e-10, atol: 1.0e-12}\n"
             "inputs:\n  controllers:\n    - {type: computed_torque, kp: 400, kd: 40, targets: swing.h5}\n",
      scratch("follow.yaml"));
  std::vector<Sample> f;
  ASSERT_TRUE(simulate(follow, follow.simulation, nullptr, &f).completed);
  // the logged swing is sampled every 5 ms: the spline through it is good to ~1e-6 rad
  for (const Sample& s : f) {
    const auto k = Eigen::Index(std::lround(s.t / 0.005));
    EXPECT_NEAR(s.q(0), t.values(k, 0), 2e-5) << "t = " << s.t;
    EXPECT_NEAR(s.q(1), t.values(k, 1), 2e-5) << "t = " << s.t;
  }
}

// max_torque: effort clamps each DOF at the URDF's <limit effort>: a stiff PD pushing the joint far
// saturates at exactly ±effort; a joint with no effort is refused
TEST(Effort, SaturationAtTheUrdfEffort) {
  const std::string urdf = scratch("effort.urdf");
  write(urdf, R"(<robot name="r">
  <link name="base"/>
  <link name="arm"><inertial><mass value="1"/><origin xyz="0 0 -0.5"/><inertia ixx="0.08" iyy="0.08" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tip"><inertial><mass value="0.2"/><origin xyz="0 0 -0.1"/><inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="1 0 0"/><limit lower="-3" upper="3" effort="2.5" velocity="1"/></joint>
  <joint name="wrist" type="continuous"><parent link="arm"/><child link="tip"/><origin xyz="0 0 -1"/><axis xyz="1 0 0"/></joint>
</robot>
)");
  const Scenario sc = parse_scenario("urdf: effort.urdf\nsimulation: {t_end: 1, output_dt: 0.01}\n"
                                     "inputs:\n  controllers:\n    - {type: pd, joint: shoulder, kp: 1000, kd: 10, target: 2.0, max_torque: effort}\n",
                                     scratch("effort.yaml"));
  EXPECT_NEAR(sc.model.effort[0], 2.5, 0);
  EXPECT_TRUE(std::isinf(sc.model.effort[1]));
  std::vector<Sample> s;
  ASSERT_TRUE(simulate(sc, sc.simulation, nullptr, &s).completed);
  double largest = 0;
  for (const Sample& x : s) largest = std::max(largest, std::abs(x.control(0)));
  EXPECT_NEAR(largest, 2.5, 1e-12);  // reached and never passed
  const std::string no = message_of([&] {
    parse_scenario("urdf: effort.urdf\ninputs:\n  controllers:\n    - {type: pd, joint: wrist, kp: 1, max_torque: effort}\n",
                   scratch("no.yaml"));
  });
  EXPECT_NE(no.find("effort: joint 'wrist' has no effort"), std::string::npos) << no;
}

}  // namespace
