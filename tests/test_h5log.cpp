// The HDF5 run file read back with the HDF5 C API: every dataset and every attribute, by value,
// against the samples, summary, model and settings of the run that wrote it in this process; the
// file must hold nothing the test does not check.  And the file `soadyn run` writes against an
// in-memory run of the same scenario.
#include "soadyn/h5log.hpp"
#include "soadyn/simulate.hpp"

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

  void strings(const std::string& path, const std::vector<std::string>& expected) {
    seen_.insert(path);
    EXPECT_EQ(read_strings(f_, path), expected) << path;
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

// the whole layout of a run file (h5log.hpp, layout_version 2) against the run's samples, summary
// and settings
void check_run_file(FileCheck& c, const Scenario& sc, const SimulationSettings& s, const std::vector<Sample>& x,
                    const RunSummary& r, const std::string& version, bool same_process) {
  const Model& m = sc.model;
  const size_t T = x.size();
  c.object("/");
  c.text("/", "scenario_path", sc.path);
  c.text("/", "soadyn_version", version);
  c.number("/", "layout_version", 2, H5T_INTEGER);
  c.scalar("/scenario", sc.text);

  c.object("/model");
  c.number("/model", "nq", m.nq, H5T_INTEGER);
  c.number("/model", "nv", m.nv, H5T_INTEGER);
  c.strings("/model/joint_names", m.joint_names);
  c.series("/model/parents", size_t(m.nbodies), 0, [&](size_t i, int) { return double(m.parent[i]); });

  // fixed at the start: attributes
  c.object("/solver");
  c.text("/solver", "method", s.method);
  c.text("/solver", "dynamics", s.dynamics);
  c.number("/solver", "rtol", s.rtol, H5T_FLOAT);
  c.number("/solver", "atol", s.atol, H5T_FLOAT);
  c.number("/solver", "dt", s.dt, H5T_FLOAT);
  c.number("/solver", "t_end", s.t_end, H5T_FLOAT);
  c.number("/solver", "output_dt", r.output_dt, H5T_FLOAT);
  // rewritten at every flush: scalar datasets, here as the run ended
  c.scalar("/solver/status", r.status);
  c.scalar("/solver/quaternion_handling", r.quaternion_handling);
  c.scalar("/solver/t_reached", r.t_reached, H5T_FLOAT);
  c.scalar("/solver/steps", double(r.stats.steps), H5T_INTEGER);
  c.scalar("/solver/rhs_evals", double(r.stats.rhs_evals), H5T_INTEGER);
  c.scalar("/solver/jac_evals", double(r.stats.jac_evals), H5T_INTEGER);
  c.scalar("/solver/error_test_failures", double(r.stats.error_test_failures), H5T_INTEGER);
  c.scalar("/solver/nonlinear_iterations", double(r.stats.nonlinear_iterations), H5T_INTEGER);
  // CPU time: exact when this process wrote the file; from another process, only plausible
  c.scalar("/solver/cpu_seconds", same_process ? r.cpu_seconds : 30.0, H5T_FLOAT, same_process ? 0.0 : 1.0);

  // /samples holds every number; the series are views of its columns
  std::vector<std::vector<double>> rows;
  for (const Sample& k : x) {
    std::vector<double> row{k.t};
    for (const VecX* v : {&k.q, &k.qd, &k.qdd}) row.insert(row.end(), v->data(), v->data() + v->size());
    row.insert(row.end(), {k.kinetic, k.potential, k.total});
    row.insert(row.end(), k.linear.data(), k.linear.data() + 3);
    row.insert(row.end(), k.angular.data(), k.angular.data() + 3);
    rows.push_back(row);
  }
  const int W = 1 + m.nq + 2 * m.nv + 3 + 6;
  c.series("/samples", T, W, [&](size_t k, int j) { return rows[k][size_t(j)]; });
  c.text("/samples", "columns",
         "time 1, q " + std::to_string(m.nq) + ", qd " + std::to_string(m.nv) + ", qdd " + std::to_string(m.nv) +
             ", energy/kinetic 1, energy/potential 1, energy/total 1, momentum/linear 3, momentum/angular 3");
  c.series("/time", T, 0, [&](size_t k, int) { return x[k].t; });
  c.series("/q", T, m.nq, [&](size_t k, int j) { return x[k].q(j); });
  c.series("/qd", T, m.nv, [&](size_t k, int j) { return x[k].qd(j); });
  c.series("/qdd", T, m.nv, [&](size_t k, int j) { return x[k].qdd(j); });
  c.object("/energy");
  c.series("/energy/kinetic", T, 0, [&](size_t k, int) { return x[k].kinetic; });
  c.series("/energy/potential", T, 0, [&](size_t k, int) { return x[k].potential; });
  c.series("/energy/total", T, 0, [&](size_t k, int) { return x[k].total; });
  c.object("/momentum");
  c.series("/momentum/linear", T, 3, [&](size_t k, int j) { return x[k].linear(j); });
  c.series("/momentum/angular", T, 3, [&](size_t k, int j) { return x[k].angular(j); });
  c.complete();
}

struct Case {
  const char* scenario;
  const char* method;
  double t_end, output_dt;
};

// in this process: simulate() with the HDF5 log as its observer, then the file against what the
// same run returned
TEST(Hdf5, EveryDatasetAndAttributeMatchesTheRunThatWroteIt) {
  for (const Case& k : {Case{"satellite_two_arrays", "cvode-bdf", 2.0, 0.05}, Case{"double_pendulum", "rk4", 1.0, 0.0125},
                        Case{"three_link_arm", "cvode-adams", 1.5, 0.1}}) {
    SCOPED_TRACE(k.scenario);
    const Scenario sc = load_scenario(kDir + k.scenario + ".yaml");
    SimulationSettings s = sc.simulation;
    s.method = k.method;
    s.t_end = k.t_end;
    s.output_dt = k.output_dt;
    const std::string out = tmp(std::string(k.scenario) + ".h5");
    std::vector<Sample> samples;
    RunSummary r;
    {
      H5Log log(out, sc, s, "test-version 1.2");
      r = simulate(sc, s, &log, &samples);
    }
    ASSERT_TRUE(r.completed) << r.status;
    ASSERT_GE(samples.size(), 10u);
    H5File f(out);
    ASSERT_GE(f.id, 0);
    FileCheck c(f.id, 0.0);
    check_run_file(c, sc, s, samples, r, "test-version 1.2", true);
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
