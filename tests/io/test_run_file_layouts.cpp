// Run files of every layout the reader takes, and the global heap it never lets libhdf5 fault in:
// layout 5 holds no variable-length data at all (every attribute and dataset walked); layout-4
// files written by soadyn before it (tests/data/run_files/) read back, and one whose global heap
// is broken (an object's size made huge, which crashes libhdf5 1.10's H5HG_read: checked in a
// child process first, so the test can fail for the right reason) is refused in one line while
// this process goes on.
#include "soadyn/io/h5log.hpp"
#include "soadyn/io/run_file.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/sim/simulate.hpp"

#include "h5_reader.hpp"
#include "test_util.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

using namespace soadyn;
using soadyn::test::message_of;

namespace {

namespace fs = std::filesystem;

const std::string kOld = SOADYN_SOURCE_DIR "/tests/data/run_files";

std::string tmp(const std::string& name) {
  return (fs::temp_directory_path() / ("soadyn_rfl_" + std::to_string(getpid()) + "_" + name)).string();
}

std::string bytes_of(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

void write_bytes(const std::string& path, const std::string& b) { std::ofstream(path, std::ios::binary) << b; }

// every attribute and dataset whose type is variable-length, by path
std::vector<std::string> variable_length(hid_t file) {
  struct Walk {
    std::vector<std::string> found;
    static bool vlen(hid_t type) { return H5Tis_variable_str(type) > 0 || H5Tdetect_class(type, H5T_VLEN) > 0; }
    static herr_t attribute(hid_t obj, const char* name, const H5A_info_t*, void* op) {
      const h5::Id a = test::own(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
      const h5::Id t = test::own(H5Aget_type(a), H5Tclose);
      if (vlen(t)) static_cast<Walk*>(op)->found.push_back(std::string("@") + name);
      return 0;
    }
    static herr_t object(hid_t root, const char* name, const H5O_info_t* info, void* op) {
      auto* w = static_cast<Walk*>(op);
      const h5::Id o = test::own(H5Oopen(root, name, H5P_DEFAULT), H5Oclose);
      hsize_t idx = 0;
      const size_t before = w->found.size();
      H5Aiterate2(o, H5_INDEX_NAME, H5_ITER_INC, &idx, &Walk::attribute, w);
      for (size_t k = before; k < w->found.size(); ++k) w->found[k] = std::string("/") + name + w->found[k];
      if (info->type == H5O_TYPE_DATASET) {
        const h5::Id t = test::own(H5Dget_type(o), H5Tclose);
        if (vlen(t)) w->found.push_back(std::string("/") + name);
      }
      return 0;
    }
  } w;
  H5Ovisit(file, H5_INDEX_NAME, H5_ITER_INC, &Walk::object, &w);
  return w.found;
}

std::vector<std::string> old_files() {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(kOld))
    if (e.path().extension() == ".h5") out.push_back(e.path().string());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST(RunFileLayouts, Layout5HoldsNoVariableLengthData) {
  Scenario sc = load_scenario(SOADYN_SOURCE_DIR "/scenarios/arm_control_limits.yaml");
  sc.log_frames = {sc.model.frame_names.front()};
  SimulationSettings s = sc.simulation;
  s.t_end = 0.2;
  const std::string path = tmp("layout5.h5");
  {
    H5Log log(path, sc, s, "test-version", LogGroups{});
    simulate(sc, s, &log);
  }
  const test::H5File f(path);
  ASSERT_GE(f.id, 0);
  EXPECT_EQ(test::number_attribute(f.id, "/", "layout_version"), 5.0);
  const std::set<std::string> all = test::inventory(f.id);
  ASSERT_TRUE(all.count("/events") && all.count("/control") && all.count("/bodies/names") && all.count("/frames/names"));
  EXPECT_EQ(variable_length(f.id), std::vector<std::string>{});
  const RunContents c = read_run_file(path);
  EXPECT_EQ(c.layout_version, 5);
  EXPECT_FALSE(c.events.empty());
  ASSERT_NE(c.find("/bodies/position"), nullptr);
  EXPECT_EQ(c.find("/bodies/position")->shape, (std::vector<Eigen::Index>{sc.model.nbodies, 3}));
  EXPECT_EQ(c.find("/frames/orientation")->shape, (std::vector<Eigen::Index>{1, 4}));
  fs::remove(path);
}

TEST(RunFileLayouts, Layout4FilesReadBack) {
  const std::vector<std::string> files = old_files();
  ASSERT_GE(files.size(), 3u);
  for (const std::string& p : files) {
    SCOPED_TRACE(p);
    const RunContents c = read_run_file(p);
    EXPECT_EQ(c.layout_version, 4);
    EXPECT_GT(c.rows(), 2);
    EXPECT_FALSE(c.q_names.empty());
    ASSERT_NE(c.find("/q"), nullptr);
    EXPECT_EQ(c.find("/q")->values.cols(), c.nq);
    ASSERT_NE(c.find("/bodies/orientation"), nullptr);
    EXPECT_EQ(c.find("/bodies/orientation")->shape.back(), 4);
    const h5::Id f = test::own(H5Fopen(p.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, H5P_DEFAULT), H5Fclose);
    ASSERT_TRUE(f.ok());
    EXPECT_FALSE(variable_length(f).empty()) << "a layout-4 file has variable-length strings";
    const RunReader r(p);
    EXPECT_EQ(r.rows(), std::uint64_t(c.rows()));
  }
}

TEST(RunFileLayouts, Layout4FileWhoseGlobalHeapFaultsIsRefused) {
  const std::string src = old_files().front();
  std::string b = bytes_of(src);
  const size_t at = b.find(std::string("GCOL\x01", 5));
  ASSERT_NE(at, std::string::npos);
  // the collection's first object: index (2), references (2), reserved (4), size (8) after the
  // collection's 16-byte header; a size past the file makes H5HG_read copy past its buffer
  const std::uint64_t huge = std::uint64_t(1) << 46;
  std::memcpy(&b[at + 16 + 8], &huge, 8);
  const std::string path = tmp("faults.h5");
  write_bytes(path, b);
  // libhdf5 itself faults on it: read its strings directly in a child
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const test::H5File f(path);
    for (const char* name : {"q_names", "v_names", "joint_names", "joint_types", "body_names"}) {
      const h5::Id a = test::own(H5Aopen_by_name(f.id, "/model", name, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
      (void)test::read_vlen_strings(a, true, true);
    }
    (void)test::string_attribute(f.id, "/", "soadyn_version");
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFSIGNALED(status)) << "the broken heap should crash libhdf5 (exit " << WEXITSTATUS(status) << ")";
  // the reader refuses it, in one line naming the file, and this process goes on
  const std::string m = message_of([&] { read_run_file(path); });
  EXPECT_EQ(m.rfind(path + ": corrupt run file: the HDF5 library faults reading it", 0), 0u) << m;
  EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  EXPECT_NE(message_of([&] { RunReader r(path); }).find("corrupt run file"), std::string::npos);
  fs::remove(path);
}
