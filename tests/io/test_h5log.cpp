// The HDF5 run file read back with the HDF5 C API: every dataset and every attribute, by value,
// against the samples, summary, model and settings of the run that wrote it in this process; the
// file must hold nothing the test does not check.  And the file `soadyn run` writes against an
// in-memory run of the same scenario.
#include "soadyn/io/h5log.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/sim/simulate.hpp"

#include "h5_reader.hpp"
#include "test_util.hpp"

#include <unistd.h>

#include <filesystem>
#include <functional>
#include <sstream>

using namespace soadyn;
using namespace soadyn::test;

namespace {

const std::string kDir = SOADYN_SOURCE_DIR "/scenarios/";

std::string tmp(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("soadyn_h5_" + std::to_string(getpid()) + "_" + name)).string();
}

// Checks one file item by item and remembers what it checked.  Stored doubles must come back
// bit for bit (tol = 0): a round trip through the file is lossless; a file written by another
// process is compared with a relative tolerance.
class FileCheck {
 public:
  FileCheck(hid_t file, double tol) : f_(file), tol_(tol) {}

  void object(const std::string& path) { seen_.insert(path); }

  // a T-row dataset (cols = 0: one-dimensional) whose row k, column c is value(k, c)
  void series(const std::string& path, size_t rows, int cols, const std::function<double(size_t, int)>& value) {
    seen_.insert(path);
    const Table t = read_table(f_, path);
    ASSERT_TRUE(t.found) << path;
    ASSERT_EQ(t.rows, rows) << path;
    ASSERT_EQ(t.cols, hsize_t(cols)) << path;
    int wrong = 0;
    for (size_t k = 0; k < rows; ++k)
      for (int c = 0; c < std::max(cols, 1); ++c) {
        const double want = value(k, c), got = t.at(k, c);
        if (!(std::abs(got - want) <= tol_ * std::max(1.0, std::abs(want))) && wrong++ < 3)
          ADD_FAILURE() << path << "[" << k << "," << c << "] = " << got << ", expected " << want;
      }
    EXPECT_EQ(wrong, 0) << path << ": values differ";
  }

  // a T × bodies × cols view: checked as T rows of bodies·cols numbers
  void series3(const std::string& path, size_t rows, int bodies, int cols, const std::function<double(size_t, int)>& value) {
    const Table t = read_table(f_, path);
    ASSERT_EQ(t.rank, 3) << path;
    EXPECT_EQ(t.dims[1], hsize_t(bodies)) << path;
    EXPECT_EQ(t.dims[2], hsize_t(cols)) << path;
    series(path, rows, bodies * cols, value);
  }

  // a dataset of fixed-length strings (layout 5: no variable-length data)
  void strings(const std::string& path, const std::vector<std::string>& expected) {
    seen_.insert(path);
    EXPECT_EQ(string_list_dataset(f_, path), expected) << path;
  }
  // an attribute: a list of fixed-length strings, or numbers
  void texts(const std::string& path, const std::string& name, const std::vector<std::string>& expected) {
    seen_.insert(path + "@" + name);
    EXPECT_EQ(string_list_attribute(f_, path, name), expected) << path << "@" << name;
  }
  void numbers(const std::string& path, const std::string& name, const std::vector<double>& expected) {
    seen_.insert(path + "@" + name);
    EXPECT_EQ(numbers_attribute(f_, path, name), expected) << path << "@" << name;
  }
  // a units attribute: one string when every column has the same unit, else one per column
  void units(const std::string& path, const std::vector<std::string>& per_column) {
    if (std::all_of(per_column.begin(), per_column.end(), [&](const std::string& u) { return u == per_column[0]; }))
      text(path, "units", per_column[0]);
    else
      texts(path, "units", per_column);
  }
  // a string attribute that must say at least these things
  void mentions(const std::string& path, const std::string& name, const std::vector<std::string>& parts) {
    seen_.insert(path + "@" + name);
    const std::string got = string_attribute(f_, path, name);
    for (const auto& p : parts) EXPECT_NE(got.find(p), std::string::npos) << path << "@" << name << " = '" << got << "' lacks '" << p << "'";
  }
  void ints(const std::string& path, const std::vector<int>& expected) {
    series(path, expected.size(), 0, [&](size_t i, int) { return double(expected[i]); });
    text(path, "units", "1");
  }

  // scalar datasets: a string, or a number stored as an integer or a double
  void scalar(const std::string& path, const std::string& expected) {
    seen_.insert(path);
    EXPECT_EQ(dataset_class(f_, path), H5T_STRING) << path;
    EXPECT_EQ(scalar_text(f_, path), expected) << path;
  }
  void scalar(const std::string& path, double expected, H5T_class_t type, double tol = -1) {
    seen_.insert(path);
    EXPECT_EQ(dataset_class(f_, path), type) << path;
    const double got = scalar_number(f_, path), t = tol < 0 ? tol_ : tol;
    EXPECT_LE(std::abs(got - expected), t * std::max(1.0, std::abs(expected))) << path << " = " << got << ", expected "
                                                                             << expected;
  }

  void text(const std::string& path, const std::string& name, const std::string& expected) {
    seen_.insert(path + "@" + name);
    EXPECT_EQ(string_attribute(f_, path, name), expected) << path << "@" << name;
  }

  // a numeric attribute; integer counts are stored as integers, quantities as doubles
  void number(const std::string& path, const std::string& name, double expected, H5T_class_t type, double tol = -1) {
    seen_.insert(path + "@" + name);
    EXPECT_EQ(attribute_class(f_, path, name), type) << path << "@" << name;
    const double got = number_attribute(f_, path, name);
    const double t = tol < 0 ? tol_ : tol;
    EXPECT_LE(std::abs(got - expected), t * std::max(1.0, std::abs(expected))) << path << "@" << name << " = " << got
                                                                             << ", expected " << expected;
  }

  // everything in the file was checked, and everything checked is in the file
  void complete() const {
    const std::set<std::string> present = inventory(f_);
    std::ostringstream unchecked, absent;
    for (const auto& p : present)
      if (!seen_.count(p)) unchecked << " " << p;
    for (const auto& p : seen_)
      if (!present.count(p)) absent << " " << p;
    EXPECT_EQ(unchecked.str(), "") << "in the file but not checked by this test";
    EXPECT_EQ(absent.str(), "") << "checked but not in the file";
  }

 private:
  hid_t f_;
  double tol_;
  std::set<std::string> seen_;
};

// SI units of each q and v by joint type, written out here rather than taken from the library
void joint_units(const Model& m, std::vector<std::string>& qu, std::vector<std::string>& vu) {
  for (JointType t : m.joint_type) {
    std::vector<std::string> q, v;
    switch (t) {
      case JointType::Revolute: q = {"rad"}, v = {"rad/s"}; break;
      case JointType::Prismatic: q = {"m"}, v = {"m/s"}; break;
      case JointType::Helical: q = {"rad"}, v = {"rad/s"}; break;
      case JointType::Ball: q = {"1", "1", "1", "1"}, v = {"rad/s", "rad/s", "rad/s"}; break;
      case JointType::Planar: q = {"m", "m", "rad"}, v = {"m/s", "m/s", "rad/s"}; break;
      case JointType::Free: q = {"m", "m", "m", "1", "1", "1", "1"}, v = {"rad/s", "rad/s", "rad/s", "m/s", "m/s", "m/s"}; break;
      case JointType::Fixed: break;
    }
    qu.insert(qu.end(), q.begin(), q.end());
    vu.insert(vu.end(), v.begin(), v.end());
  }
}

// the whole layout of a run file (h5log.hpp, layout_version 5) against the run's samples, summary
// and settings
void check_run_file(FileCheck& c, const Scenario& sc, const SimulationSettings& s, const std::vector<Sample>& x,
                    const RunSummary& r, const std::string& version, bool same_process, const LogGroups& g = {}) {
  const Model& m = sc.model;
  const size_t T = x.size();
  const int N = m.nbodies;
  c.object("/");
  c.text("/", "scenario_path", sc.path);
  c.text("/", "soadyn_version", version);
  c.number("/", "layout_version", kLayoutVersion, H5T_INTEGER);
  c.text("/", "log_groups", g.str());
  c.scalar("/scenario", sc.text);
  if (!sc.robot_text.empty()) {  // the URDF the scenario named, as read
    c.scalar("/robot", sc.robot_text);
    c.text("/robot", "path", sc.robot_path);
  }

  std::vector<std::string> qu, vu, types;
  joint_units(m, qu, vu);
  for (JointType t : m.joint_type) types.emplace_back(to_string(t));
  c.object("/model");
  c.number("/model", "nq", m.nq, H5T_INTEGER);
  c.number("/model", "nv", m.nv, H5T_INTEGER);
  c.texts("/model", "q_names", m.q_names());
  c.texts("/model", "v_names", m.v_names());
  c.texts("/model", "q_units", qu);
  c.texts("/model", "v_units", vu);
  c.texts("/model", "joint_names", m.joint_names);
  c.texts("/model", "joint_types", types);
  c.texts("/model", "body_names", m.body_names);
  c.numbers("/model", "gravity", {m.gravity.x(), m.gravity.y(), m.gravity.z()});
  c.text("/model", "gravity_units", "m/s^2");
  c.mentions("/model", "units", {"SI", "s, m, kg, rad"});
  c.mentions("/model", "free_joint", {"[x y z qw qx qy qz]", "body to inertial", "[wx wy wz vx vy vz]", "inertial coordinates"});
  c.mentions("/model", "ball_joint", {"[qw qx qy qz]", "[wx wy wz]", "in the child's frame"});
  c.mentions("/model", "planar_joint", {"[x y theta]"});
  c.mentions("/model", "helical_joint", {"[theta]", "pitch * theta", "m/rad"});
  c.numbers("/model", "joint_pitches", m.pitch);
  c.ints("/model/parents", std::vector<int>(m.parent.begin(), m.parent.end()));
  c.ints("/model/joint_q_index", std::vector<int>(m.idx_q.begin(), m.idx_q.end()));
  c.ints("/model/joint_v_index", std::vector<int>(m.idx_v.begin(), m.idx_v.end()));

  // fixed at the start: attributes
  c.object("/solver");
  c.text("/solver", "method", std::string(to_string(s.method)));
  c.text("/solver", "dynamics", std::string(to_string(s.dynamics)));
  c.text("/solver", "jacobian", std::string(to_string(s.jacobian)));
  c.text("/solver", "newton", std::string(to_string(s.newton)));
  c.number("/solver", "rtol", s.rtol, H5T_FLOAT);
  c.number("/solver", "atol", s.atol, H5T_FLOAT);
  c.number("/solver", "dt", s.dt, H5T_FLOAT);
  c.number("/solver", "t_end", s.t_end, H5T_FLOAT);
  c.number("/solver", "output_dt", r.output_dt, H5T_FLOAT);
  c.number("/solver", "max_step", s.max_step, H5T_FLOAT);
  c.number("/solver", "max_steps", double(s.max_steps), H5T_FLOAT);
  c.text("/solver", "limits", s.limits ? "true" : "false");
  c.number("/solver", "restitution", s.restitution, H5T_FLOAT);
  c.number("/solver", "control_dt", s.control_dt, H5T_FLOAT);
  // rewritten at every flush: scalar datasets, here as the run ended
  c.scalar("/solver/status", r.status);
  c.scalar("/solver/quaternion_handling", r.quaternion_handling);
  c.scalar("/solver/t_reached", r.t_reached, H5T_FLOAT);
  c.scalar("/solver/steps", double(r.stats.steps), H5T_INTEGER);
  c.scalar("/solver/rhs_evals", double(r.stats.rhs_evals), H5T_INTEGER);
  c.scalar("/solver/jac_evals", double(r.stats.jac_evals), H5T_INTEGER);
  c.scalar("/solver/error_test_failures", double(r.stats.error_test_failures), H5T_INTEGER);
  c.scalar("/solver/nonlinear_iterations", double(r.stats.nonlinear_iterations), H5T_INTEGER);
  c.scalar("/solver/max_energy_balance_error", r.max_energy_balance_error, H5T_FLOAT);
  c.scalar("/solver/final_energy_balance_error", r.final_energy_balance_error, H5T_FLOAT);
  c.scalar("/solver/control_ticks", double(r.control_ticks), H5T_INTEGER);
  c.scalar("/solver/stiffness_index", r.stiffness_index, H5T_FLOAT);
  c.scalar("/solver/stiffness_hint", r.stiffness_hint);
  // CPU time: exact when this process wrote the file; from another process, only plausible
  c.scalar("/solver/cpu_seconds", same_process ? r.cpu_seconds : 30.0, H5T_FLOAT, same_process ? 0.0 : 1.0);
  c.text("/solver/t_reached", "units", "s");
  c.text("/solver/cpu_seconds", "units", "s");
  for (const char* n : {"steps", "rhs_evals", "jac_evals", "error_test_failures", "nonlinear_iterations",
                        "max_energy_balance_error", "final_energy_balance_error", "control_ticks", "stiffness_index"})
    c.text(std::string("/solver/") + n, "units", "1");

  // /samples holds every number of the chosen groups, named and with units; the series are views
  std::vector<std::vector<double>> rows(T);
  std::vector<std::string> names{"time"}, units{"s"};
  auto columns = [&](const std::string& prefix, const std::vector<std::string>& n, const std::vector<std::string>& u,
                     const std::function<double(size_t, int)>& value) {
    for (size_t j = 0; j < n.size(); ++j) {
      names.push_back(prefix + n[j]);
      units.push_back(u[j]);
      for (size_t k = 0; k < T; ++k) rows[k].push_back(value(k, int(j)));
    }
  };
  for (size_t k = 0; k < T; ++k) rows[k].push_back(x[k].t);
  std::vector<std::string> qdd_units;
  for (const auto& u : vu) qdd_units.push_back(u + "^2");
  if (g.state) {
    columns("q.", m.q_names(), qu, [&](size_t k, int j) { return x[k].q(j); });
    columns("qd.", m.v_names(), vu, [&](size_t k, int j) { return x[k].qd(j); });
    columns("qdd.", m.v_names(), qdd_units, [&](size_t k, int j) { return x[k].qdd(j); });
  }
  if (g.energy)
    columns("energy.", {"kinetic", "potential", "total", "work_inputs", "dissipated"}, std::vector<std::string>(5, "J"),
            [&](size_t k, int j) {
              const double e[] = {x[k].kinetic, x[k].potential, x[k].total, x[k].work_inputs, x[k].dissipated};
              return e[j];
            });
  if (g.momentum) {
    columns("momentum.linear.", {"x", "y", "z"}, std::vector<std::string>(3, "kg m/s"), [&](size_t k, int j) { return x[k].linear(j); });
    columns("momentum.angular.", {"x", "y", "z"}, std::vector<std::string>(3, "kg m^2/s"),
            [&](size_t k, int j) { return x[k].angular(j); });
  }
  if (g.bodies) {
    for (int i = 0; i < N; ++i)
      columns("bodies.position." + m.body_names[i] + ".", {"x", "y", "z"}, std::vector<std::string>(3, "m"),
              [&](size_t k, int j) { return x[k].body_position(j, i); });
    for (int i = 0; i < N; ++i)
      columns("bodies.orientation." + m.body_names[i] + ".", {"w", "x", "y", "z"}, std::vector<std::string>(4, "1"),
              [&](size_t k, int j) { return x[k].body_orientation(j, i); });
    for (int i = 0; i < N; ++i)
      columns("bodies.com." + m.body_names[i] + ".", {"x", "y", "z"}, std::vector<std::string>(3, "m"),
              [&](size_t k, int j) { return x[k].body_com(j, i); });
  }
  const int W = int(names.size());
  EXPECT_EQ(W, 1 + (g.state ? m.nq + 2 * m.nv : 0) + (g.energy ? 5 : 0) + (g.momentum ? 6 : 0) + (g.bodies ? 10 * N : 0));
  EXPECT_EQ(row_bytes(m, g), 8u * unsigned(W));
  c.series("/samples", T, W, [&](size_t k, int j) { return rows[k][size_t(j)]; });
  c.texts("/samples", "column_names", names);
  c.texts("/samples", "column_units", units);
  c.series("/time", T, 0, [&](size_t k, int) { return x[k].t; });
  c.text("/time", "units", "s");
  if (g.state) {
    c.series("/q", T, m.nq, [&](size_t k, int j) { return x[k].q(j); });
    c.series("/qd", T, m.nv, [&](size_t k, int j) { return x[k].qd(j); });
    c.series("/qdd", T, m.nv, [&](size_t k, int j) { return x[k].qdd(j); });
    c.units("/q", qu);
    c.units("/qd", vu);
    c.units("/qdd", qdd_units);
  }
  if (g.energy) {
    c.object("/energy");
    c.series("/energy/kinetic", T, 0, [&](size_t k, int) { return x[k].kinetic; });
    c.series("/energy/potential", T, 0, [&](size_t k, int) { return x[k].potential; });
    c.series("/energy/total", T, 0, [&](size_t k, int) { return x[k].total; });
    c.series("/energy/work_inputs", T, 0, [&](size_t k, int) { return x[k].work_inputs; });
    c.series("/energy/dissipated", T, 0, [&](size_t k, int) { return x[k].dissipated; });
    for (const char* e : {"kinetic", "potential", "total", "work_inputs", "dissipated"})
      c.text(std::string("/energy/") + e, "units", "J");
  }
  if (g.momentum) {
    c.object("/momentum");
    c.series("/momentum/linear", T, 3, [&](size_t k, int j) { return x[k].linear(j); });
    c.series("/momentum/angular", T, 3, [&](size_t k, int j) { return x[k].angular(j); });
    c.text("/momentum/linear", "units", "kg m/s");
    c.text("/momentum/angular", "units", "kg m^2/s");
  }
  if (g.bodies) {
    c.object("/bodies");
    c.mentions("/bodies", "description", {"fixed joints are merged", "w >= 0", "inertial"});
    c.strings("/bodies/names", m.body_names);
    c.series3("/bodies/position", T, N, 3, [&](size_t k, int j) { return x[k].body_position(j % 3, j / 3); });
    c.series3("/bodies/orientation", T, N, 4, [&](size_t k, int j) { return x[k].body_orientation(j % 4, j / 4); });
    c.series3("/bodies/com", T, N, 3, [&](size_t k, int j) { return x[k].body_com(j % 3, j / 3); });
    c.text("/bodies/position", "units", "m");
    c.text("/bodies/orientation", "units", "1");
    c.text("/bodies/com", "units", "m");
  }
  c.complete();
}

struct Case {
  const char* scenario;
  const char* method;
  double t_end, output_dt;
  const char* groups = "all";
};

// in this process: simulate() with the HDF5 log as its observer, then the file against what the
// same run returned
TEST(Hdf5, EveryDatasetAndAttributeMatchesTheRunThatWroteIt) {
  for (const Case& k : {Case{"satellite_two_arrays", "cvode-bdf", 2.0, 0.05}, Case{"double_pendulum", "rk4", 1.0, 0.0125},
                        Case{"three_link_arm", "cvode-adams", 1.5, 0.1},
                        Case{"stiff_arm", "cvode-bdf", 0.5, 0.05, "energy,state"}, Case{"heavy_top", "rk4", 0.5, 0.05, "bodies"}}) {
    SCOPED_TRACE(k.scenario);
    const Scenario sc = load_scenario(kDir + k.scenario + ".yaml");
    SimulationSettings s = sc.simulation;
    s.method = parse_method(k.method);
    s.t_end = k.t_end;
    s.output_dt = k.output_dt;
    const std::string out = tmp(std::string(k.scenario) + ".h5");
    std::vector<Sample> samples;
    RunSummary r;
    {
      H5Log log(out, sc, s, "test-version 1.2", LogGroups::parse(k.groups));
      r = simulate(sc, s, &log, &samples);
    }
    ASSERT_TRUE(r.completed) << r.status;
    ASSERT_GE(samples.size(), 10u);
    H5File f(out);
    ASSERT_GE(f.id, 0);
    FileCheck c(f.id, 0.0);
    check_run_file(c, sc, s, samples, r, "test-version 1.2", true, LogGroups::parse(k.groups));
    std::filesystem::remove(out);
  }
}

// `soadyn run` in its own process against simulate() here: the same numbers to 1e-12
TEST(Hdf5, FileWrittenByRunMatchesTheInMemoryRun) {
  const std::string out = tmp("run.h5");
  const std::string cmd = std::string(SOADYN_CLI) + " run " + kDir + "double_pendulum.yaml --t-end 2 -q -o " + out;
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const Scenario sc = load_scenario(kDir + "double_pendulum.yaml");
  SimulationSettings s = sc.simulation;
  s.t_end = 2;
  std::vector<Sample> mem;
  const RunSummary r = simulate(sc, s, nullptr, &mem);
  ASSERT_TRUE(r.completed);
  H5File f(out);
  ASSERT_GE(f.id, 0);
  const std::string version = string_attribute(f.id, "/", "soadyn_version");
  EXPECT_FALSE(version.empty() || version == "(missing)");
  FileCheck c(f.id, 1e-12);
  check_run_file(c, sc, s, mem, r, version, false);
  std::filesystem::remove(out);
}

}  // namespace
