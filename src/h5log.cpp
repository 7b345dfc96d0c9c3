#include "soadyn/h5log.hpp"

#include <hdf5.h>

#include <filesystem>
#include <type_traits>
#include <vector>

namespace soadyn {

namespace {

// A move-only owner of one HDF5 id, closed with the function for its kind.
class Id {
 public:
  Id() = default;
  Id(hid_t id, herr_t (*close)(hid_t), const std::string& what) : id_(id), close_(close) {
    if (id < 0) throw Error("HDF5: " + what + " failed");
  }
  Id(Id&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = -1; }
  Id& operator=(Id&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = o.id_;
      close_ = o.close_;
      o.id_ = -1;
    }
    return *this;
  }
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  ~Id() { reset(); }
  void reset() {
    if (id_ >= 0 && close_) close_(id_);
    id_ = -1;
  }
  operator hid_t() const { return id_; }

 private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

void check(herr_t status, const std::string& what) {
  if (status < 0) throw Error("HDF5: " + what + " failed");
}

Id group(hid_t parent, const char* name) {
  return Id(H5Gcreate2(parent, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, std::string("creating group ") + name);
}

// a scalar numeric attribute (double or long), replaced if it exists
template <class T>
void set_attribute(hid_t obj, const char* name, T value) {
  static_assert(std::is_same_v<T, double> || std::is_same_v<T, long>);
  const hid_t type = std::is_same_v<T, double> ? H5T_NATIVE_DOUBLE : H5T_NATIVE_LONG;
  if (H5Aexists(obj, name) > 0) H5Adelete(obj, name);
  Id space(H5Screate(H5S_SCALAR), H5Sclose, "H5Screate");
  Id attr(H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, std::string("attribute ") + name);
  check(H5Awrite(attr, type, &value), std::string("writing attribute ") + name);
}

void set_attribute(hid_t obj, const char* name, const std::string& value) {
  if (H5Aexists(obj, name) > 0) H5Adelete(obj, name);
  Id type(H5Tcopy(H5T_C_S1), H5Tclose, "H5Tcopy");
  check(H5Tset_size(type, std::max<size_t>(1, value.size())), "H5Tset_size");
  check(H5Tset_cset(type, H5T_CSET_UTF8), "H5Tset_cset");
  Id space(H5Screate(H5S_SCALAR), H5Sclose, "H5Screate");
  Id attr(H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, std::string("attribute ") + name);
  const std::string padded = value.empty() ? std::string(1, '\0') : value;
  check(H5Awrite(attr, type, padded.data()), std::string("writing attribute ") + name);
}

// A chunked, extendable T×cols dataset of doubles (cols = 0: one-dimensional).
struct Series {
  Id dset;
  int cols = 0;
  std::vector<double> buffer;  // rows not yet written
  hsize_t rows = 0;            // rows in the file

  Series(hid_t parent, const char* name, int columns) : cols(columns) {
    const int rank = cols > 0 ? 2 : 1;
    hsize_t dims[2] = {0, hsize_t(cols)}, maxdims[2] = {H5S_UNLIMITED, hsize_t(cols)};
    hsize_t chunk[2] = {hsize_t(std::max(1, 4096 / std::max(1, cols))), hsize_t(std::max(1, cols))};
    Id space(H5Screate_simple(rank, dims, maxdims), H5Sclose, "H5Screate_simple");
    Id props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "H5Pcreate");
    check(H5Pset_chunk(props, rank, chunk), "H5Pset_chunk");
    dset = Id(H5Dcreate2(parent, name, H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, props, H5P_DEFAULT), H5Dclose,
              std::string("creating dataset ") + name);
  }

  void append(const double* row) { buffer.insert(buffer.end(), row, row + std::max(1, cols)); }

  void write() {
    const hsize_t width = hsize_t(std::max(1, cols));
    const hsize_t n = buffer.size() / width;
    if (n == 0) return;
    const int rank = cols > 0 ? 2 : 1;
    hsize_t size[2] = {rows + n, width};
    check(H5Dset_extent(dset, size), "extending a dataset");
    Id file_space(H5Dget_space(dset), H5Sclose, "H5Dget_space");
    hsize_t start[2] = {rows, 0}, count[2] = {n, width};
    check(H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start, nullptr, count, nullptr), "H5Sselect_hyperslab");
    Id mem_space(H5Screate_simple(rank, count, nullptr), H5Sclose, "H5Screate_simple");
    check(H5Dwrite(dset, H5T_NATIVE_DOUBLE, mem_space, file_space, H5P_DEFAULT, buffer.data()), "writing a dataset");
    rows += n;
    buffer.clear();
  }
};

}  // namespace

struct H5Log::Impl {
  Id file, g_energy, g_momentum, g_model, g_solver;
  std::vector<std::unique_ptr<Series>> series;  // time, q, qd, qdd, kinetic, potential, total, linear, angular
  std::chrono::steady_clock::time_point last_flush;
  bool finished = false;
};

H5Log::H5Log(const std::string& path, const Scenario& sc, const SimulationSettings& settings, const std::string& version)
    : impl_(std::make_unique<Impl>()) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // our messages, not HDF5's stack dumps
  const std::filesystem::path p(path);
  std::error_code ec;
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path(), ec);
  if (std::filesystem::is_directory(p, ec)) throw Error(path + ": is a directory, expected an output file");
  const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (f < 0) throw Error(path + ": cannot create the output file (is the directory writable?)");
  Impl& im = *impl_;
  im.file = Id(f, H5Fclose, "H5Fcreate");
  const Model& m = sc.model;

  set_attribute(im.file, "scenario", sc.text);
  set_attribute(im.file, "soadyn_version", version);
  set_attribute(im.file, "scenario_path", sc.path);

  im.g_model = group(im.file, "model");
  set_attribute(im.g_model, "nq", long(m.nq));
  set_attribute(im.g_model, "nv", long(m.nv));
  {
    // joint_names: fixed-length strings; parents: ints (-1 = world)
    size_t width = 1;
    for (const auto& n : m.joint_names) width = std::max(width, n.size());
    std::vector<char> names(width * m.nbodies, '\0');
    for (int i = 0; i < m.nbodies; ++i) std::copy(m.joint_names[i].begin(), m.joint_names[i].end(), names.begin() + i * width);
    Id type(H5Tcopy(H5T_C_S1), H5Tclose, "H5Tcopy");
    check(H5Tset_size(type, width), "H5Tset_size");
    hsize_t n = hsize_t(m.nbodies);
    Id space(H5Screate_simple(1, &n, nullptr), H5Sclose, "H5Screate_simple");
    Id d(H5Dcreate2(im.g_model, "joint_names", type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose, "joint_names");
    check(H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, names.data()), "writing joint_names");
    std::vector<int> parents(m.parent.begin(), m.parent.end());
    Id dp(H5Dcreate2(im.g_model, "parents", H5T_NATIVE_INT, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose, "parents");
    check(H5Dwrite(dp, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, parents.data()), "writing parents");
  }

  im.g_solver = group(im.file, "solver");
  set_attribute(im.g_solver, "method", settings.method);
  set_attribute(im.g_solver, "rtol", settings.rtol);
  set_attribute(im.g_solver, "atol", settings.atol);
  set_attribute(im.g_solver, "dt", settings.dt);
  set_attribute(im.g_solver, "output_dt", settings.output_dt);
  set_attribute(im.g_solver, "t_end", settings.t_end);
  set_attribute(im.g_solver, "dynamics", settings.dynamics);
  set_attribute(im.g_solver, "status", std::string("running"));
  set_attribute(im.g_solver, "t_reached", 0.0);

  im.g_energy = group(im.file, "energy");
  im.g_momentum = group(im.file, "momentum");
  im.series.push_back(std::make_unique<Series>(im.file, "time", 0));
  im.series.push_back(std::make_unique<Series>(im.file, "q", m.nq));
  im.series.push_back(std::make_unique<Series>(im.file, "qd", m.nv));
  im.series.push_back(std::make_unique<Series>(im.file, "qdd", m.nv));
  im.series.push_back(std::make_unique<Series>(im.g_energy, "kinetic", 0));
  im.series.push_back(std::make_unique<Series>(im.g_energy, "potential", 0));
  im.series.push_back(std::make_unique<Series>(im.g_energy, "total", 0));
  im.series.push_back(std::make_unique<Series>(im.g_momentum, "linear", 3));
  im.series.push_back(std::make_unique<Series>(im.g_momentum, "angular", 3));
  check(H5Fflush(im.file, H5F_SCOPE_GLOBAL), "H5Fflush");
  im.last_flush = std::chrono::steady_clock::now();
}

H5Log::~H5Log() {
  if (!impl_->finished) {
    try {
      flush();
    } catch (...) {
    }
  }
}

void H5Log::on_sample(const Sample& s) {
  auto& sr = impl_->series;
  sr[0]->append(&s.t);
  sr[1]->append(s.q.data());
  sr[2]->append(s.qd.data());
  sr[3]->append(s.qdd.data());
  sr[4]->append(&s.kinetic);
  sr[5]->append(&s.potential);
  sr[6]->append(&s.total);
  sr[7]->append(s.linear.data());
  sr[8]->append(s.angular.data());
}

void H5Log::flush(const RunSummary* summary) {
  Impl& im = *impl_;
  for (auto& s : im.series) s->write();
  if (summary) {
    set_attribute(im.g_solver, "status", summary->status);
    set_attribute(im.g_solver, "t_reached", summary->t_reached);
    set_attribute(im.g_solver, "steps", summary->stats.steps);
    set_attribute(im.g_solver, "rhs_evals", summary->stats.rhs_evals);
    set_attribute(im.g_solver, "jac_evals", summary->stats.jac_evals);
    set_attribute(im.g_solver, "error_test_failures", summary->stats.error_test_failures);
    set_attribute(im.g_solver, "nonlinear_iterations", summary->stats.nonlinear_iterations);
    set_attribute(im.g_solver, "cpu_seconds", summary->cpu_seconds);
    set_attribute(im.g_solver, "quaternion_handling", summary->quaternion_handling);
    set_attribute(im.g_solver, "output_dt", summary->output_dt);
  }
  check(H5Fflush(im.file, H5F_SCOPE_GLOBAL), "H5Fflush");
  im.last_flush = std::chrono::steady_clock::now();
}

void H5Log::on_progress(const RunSummary& summary) {
  // at least once per second of wall time
  if (std::chrono::steady_clock::now() - impl_->last_flush >= std::chrono::milliseconds(500)) flush(&summary);
}

void H5Log::on_finish(const RunSummary& summary) {
  flush(&summary);
  impl_->finished = true;
}

}  // namespace soadyn
