// The library's reader of run files (run_file.hpp) against the run that wrote the file in this
// process: every logged double back to the bit, every column of /samples in exactly one series,
// the scenario's and the robot file's text, the model, the summary; RunReader's blocks against the
// whole read; and one line naming the file for a truncated, foreign or inconsistent file.
#include "soadyn/io/h5log.hpp"
#include "soadyn/io/run_file.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/sim/simulate.hpp"

#include "../../src/io/h5_util.hpp"
#include "test_util.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>

using namespace soadyn;
using soadyn::test::message_of;

namespace {

namespace fs = std::filesystem;

std::string tmp(const std::string& name) {
  return (fs::temp_directory_path() / ("soadyn_rf_" + std::to_string(getpid()) + "_" + name)).string();
}

// row k of a series holds the n doubles at `want`, bit for bit (a stored double is not rounded)
::testing::AssertionResult same_bits(const MatX& values, Eigen::Index k, const double* want, Eigen::Index n) {
  if (values.cols() != n) return ::testing::AssertionFailure() << values.cols() << " columns, expected " << n;
  for (Eigen::Index c = 0; c < n; ++c) {
    const double got = values(k, c);
    if (std::memcmp(&got, want + c, sizeof(double)) != 0)
      return ::testing::AssertionFailure() << "row " << k << " column " << c << ": " << got << ", logged " << want[c];
  }
  return ::testing::AssertionSuccess();
}

struct Written {
  Scenario sc;
  std::vector<Sample> samples;
  RunSummary summary;
  std::string path;
};

// a URDF arm with logged frames (tests/data/view_visuals.yaml), every group, 0.5 s by rk4
Written write_run(const std::string& name) {
  Written w{load_scenario(SOADYN_SOURCE_DIR "/tests/data/view_visuals.yaml"), {}, {}, tmp(name)};
  SimulationSettings s = w.sc.simulation;
  s.method = Method::Rk4;
  s.t_end = 0.5;
  s.output_dt = 0.01;
  {
    H5Log log(w.path, w.sc, s, "test-version", LogGroups{});
    w.summary = simulate(w.sc, s, &log, &w.samples);
  }
  return w;
}

TEST(RunFile, ReadsBackEveryLoggedDoubleToTheBit) {
  const Written w = write_run("round.h5");
  ASSERT_TRUE(w.summary.completed) << w.summary.status;
  const RunContents r = read_run_file(w.path);
  const Model& m = w.sc.model;
  const Eigen::Index T = Eigen::Index(w.samples.size());
  ASSERT_EQ(r.rows(), T);
  for (Eigen::Index k = 0; k < T; ++k) {
    const Sample& x = w.samples[size_t(k)];
    SCOPED_TRACE("row " + std::to_string(k));
    EXPECT_TRUE(same_bits(r.values("/time"), k, &x.t, 1));
    EXPECT_TRUE(same_bits(r.values("/q"), k, x.q.data(), m.nq));
    EXPECT_TRUE(same_bits(r.values("/qd"), k, x.qd.data(), m.nv));
    EXPECT_TRUE(same_bits(r.values("/qdd"), k, x.qdd.data(), m.nv));
    EXPECT_TRUE(same_bits(r.values("/energy/kinetic"), k, &x.kinetic, 1));
    EXPECT_TRUE(same_bits(r.values("/energy/potential"), k, &x.potential, 1));
    EXPECT_TRUE(same_bits(r.values("/energy/total"), k, &x.total, 1));
    EXPECT_TRUE(same_bits(r.values("/energy/work_inputs"), k, &x.work_inputs, 1));
    EXPECT_TRUE(same_bits(r.values("/energy/dissipated"), k, &x.dissipated, 1));
    EXPECT_TRUE(same_bits(r.values("/momentum/linear"), k, x.linear.data(), 3));
    EXPECT_TRUE(same_bits(r.values("/momentum/angular"), k, x.angular.data(), 3));
    EXPECT_TRUE(same_bits(r.values("/bodies/position"), k, x.body_position.data(), 3 * m.nbodies));
    EXPECT_TRUE(same_bits(r.values("/bodies/orientation"), k, x.body_orientation.data(), 4 * m.nbodies));
    EXPECT_TRUE(same_bits(r.values("/bodies/com"), k, x.body_com.data(), 3 * m.nbodies));
  }
  // the views' shapes, and every column of /samples in exactly one series, in order
  EXPECT_EQ(r.find("/q")->shape, std::vector<Eigen::Index>{m.nq});
  EXPECT_TRUE(r.find("/time")->shape.empty());
  EXPECT_EQ(r.find("/bodies/orientation")->shape, (std::vector<Eigen::Index>{m.nbodies, 4}));
  EXPECT_EQ(r.find("/frames/position")->shape, (std::vector<Eigen::Index>{2, 3}));
  EXPECT_EQ(r.frame_names, (std::vector<std::string>{"tool", "tip"}));
  std::vector<std::string> claimed;
  for (const RunSeries& s : r.series) claimed.insert(claimed.end(), s.columns.begin(), s.columns.end());
  EXPECT_EQ(claimed, r.column_names);
  EXPECT_EQ(r.find("/q")->units[0], "rad");
  EXPECT_EQ(r.find("/control"), nullptr);
  EXPECT_EQ(message_of([&] { r.values("/control"); }), w.path + ": dataset /control is missing (a run logged without it: soadyn run --log)");

  // what the run was made from: the scenario's text and the URDF's, as read
  EXPECT_EQ(r.scenario_text, w.sc.text);
  EXPECT_EQ(r.robot_text, read_text_file(SOADYN_SOURCE_DIR "/tests/data/view_visuals.urdf"));
  EXPECT_EQ(r.robot_path, w.sc.robot_path);
  EXPECT_EQ(r.layout_version, kLayoutVersion);
  EXPECT_EQ(r.soadyn_version, "test-version");
  EXPECT_EQ(r.nq, m.nq);
  EXPECT_EQ(r.q_names, m.q_names());
  EXPECT_EQ(r.joint_names, m.joint_names);
  EXPECT_EQ(r.parents, std::vector<int>(m.parent.begin(), m.parent.end()));
  EXPECT_EQ(r.solver.method, "rk4");
  EXPECT_EQ(r.solver.status, "completed");
  EXPECT_EQ(r.solver.steps, w.summary.stats.steps);
  EXPECT_EQ(r.solver.t_reached, w.summary.t_reached);  // a stored double: the same bits
  fs::remove(w.path);
}

TEST(RunFile, ReaderBlocksAreTheWholeRead) {
  const Written w = write_run("blocks.h5");
  const RunReader reader(w.path);
  const RunContents r = reader.read();
  const std::uint64_t W = reader.column_names().size(), T = reader.rows();
  ASSERT_EQ(T, w.samples.size());
  std::vector<double> rows(size_t(T * W));
  for (std::uint64_t r0 = 0; r0 < T; r0 += 7) reader.read_rows(r0, std::min<std::uint64_t>(7, T - r0), rows.data() + r0 * W);
  size_t first = 0;
  for (const RunSeries& s : r.series) {
    for (Eigen::Index k = 0; k < Eigen::Index(T); ++k) EXPECT_TRUE(same_bits(s.values, k, rows.data() + size_t(k) * W + first, s.values.cols())) << s.path;
    first += size_t(s.values.cols());
  }
  EXPECT_EQ(first, W);
  EXPECT_EQ(message_of([&] { reader.read_rows(T - 1, 2, rows.data()); }),
            w.path + ": /samples: rows " + std::to_string(T - 1) + " to " + std::to_string(T) + " asked for, it has " +
                std::to_string(T));
  fs::remove(w.path);
}

// one line, naming the file first
void expect_one_line(const std::string& message, const std::string& path, const std::string& says) {
  EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  EXPECT_NE(message.find(says), std::string::npos) << message;
}

TEST(RunFile, TruncatedForeignAndInconsistentFilesGiveOneLine) {
  const Written w = write_run("whole.h5");
  // cut at several points: an error naming the file, never a crash or a hang
  const auto size = fs::file_size(w.path);
  for (const double part : {0.9, 0.5, 0.1, 0.01}) {
    const std::string cut = tmp("cut.h5");
    fs::copy_file(w.path, cut, fs::copy_options::overwrite_existing);
    fs::resize_file(cut, std::uintmax_t(double(size) * part));
    const std::string msg = message_of([&] { read_run_file(cut); });
    SCOPED_TRACE(part);
    EXPECT_NE(msg, "(no error)");
    expect_one_line(msg, cut, "");
    fs::remove(cut);
  }
  const std::string text = tmp("notes.h5");
  std::ofstream(text) << "not a run\n";
  expect_one_line(message_of([&] { read_run_file(text); }), text, "not a run file: not an HDF5 file");
  fs::remove(text);

  // HDF5 files soadyn did not write, made with the library's own helpers
  auto make = [](const std::string& path, const std::function<void(hid_t)>& fill) {
    h5::Id f(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose, path);
    fill(f);
  };
  auto table = [](hid_t f, hsize_t rows, hsize_t cols) {
    hsize_t dims[2] = {rows, cols};
    h5::Id space(H5Screate_simple(2, dims, nullptr), H5Sclose, "space");
    h5::Id d(H5Dcreate2(f, "samples", H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose, "samples");
    std::vector<double> zeros(size_t(rows * cols), 0.0);
    h5::check(H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, zeros.data()), "write");
    return d;
  };
  const std::string other = tmp("other.h5");
  make(other, [](hid_t f) { h5::int_dataset(f, "x", {1, 2, 3}, "1"); });
  expect_one_line(message_of([&] { read_run_file(other); }), other, "not a soadyn run file (no /samples, no /time)");
  make(other, [&](hid_t f) { table(f, 3, 2); });
  expect_one_line(message_of([&] { read_run_file(other); }), other, "/samples: column_names is missing");
  make(other, [&](hid_t f) {
    h5::Id d = table(f, 3, 2);
    h5::attribute(d, "column_names", std::vector<std::string>{"time", "q.a"});
    h5::attribute(d, "column_units", std::vector<std::string>{"s"});
  });
  expect_one_line(message_of([&] { read_run_file(other); }), other, "/samples has 2 columns but 1 column_units");
  make(other, [&](hid_t f) {
    h5::Id d = table(f, 3, 2);
    h5::attribute(d, "column_names", std::vector<std::string>{"time", "q.a"});
    h5::attribute(d, "column_units", std::vector<std::string>{"s", "rad"});
    h5::Id g = h5::group(f, "model");
    h5::attribute(g, "q_names", std::vector<std::string>{"a", "b"});
  });
  expect_one_line(message_of([&] { read_run_file(other); }), other, "/q: expected 2 columns (/model q_names), the file has 1");
  fs::remove(other);
  fs::remove(w.path);
}

}  // namespace
