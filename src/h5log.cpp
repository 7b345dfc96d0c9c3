#include "soadyn/h5log.hpp"
#include "soadyn/text.hpp"

#include <hdf5.h>

#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>

namespace soadyn {

namespace {

// the cause of the last failed HDF5 call: the errno its file driver recorded (0: none) and its text
int last_errno = 0;
std::string last_cause;

herr_t find_errno(unsigned, const H5E_error2_t* e, void* found) {
  const char* at = e->desc ? std::strstr(e->desc, "errno = ") : nullptr;
  if (at && *static_cast<int*>(found) == 0) *static_cast<int*>(found) = std::atoi(at + 8);
  return 0;
}

// Records why the HDF5 call that just failed did so; must run before any other HDF5 call, which
// would clear the library's error stack.
void record_cause() {
  int err = 0;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, find_errno, &err);
  last_errno = err;
  last_cause = err ? std::strerror(err) : "";
}

struct H5Failure : Error {
  H5Failure(const std::string& what, std::string cause) : Error(what), cause(std::move(cause)) {}
  std::string cause;
};

[[noreturn]] void fail(const std::string& what) {
  record_cause();
  throw H5Failure("HDF5: " + what + " failed", last_cause);
}

void check(herr_t status, const std::string& what) {
  if (status < 0) fail(what);
}

// A move-only owner of one HDF5 id, closed with the function for its kind.  release() gives the id
// up without closing it: after a failed write the library must not touch the file again.
class Id {
 public:
  Id() = default;
  Id(hid_t id, herr_t (*close)(hid_t), const std::string& what) : id_(id), close_(close) {
    if (id < 0) fail(what);
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
  void release() { id_ = -1; }
  operator hid_t() const { return id_; }

 private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

Id group(hid_t parent, const char* name) {
  return Id(H5Gcreate2(parent, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, std::string("creating group ") + name);
}

// a fixed-length string type of `size` bytes, UTF-8 when the text is valid UTF-8
Id string_type(size_t size, bool utf8) {
  Id type(H5Tcopy(H5T_C_S1), H5Tclose, "H5Tcopy");
  check(H5Tset_size(type, std::max<size_t>(1, size)), "H5Tset_size");
  check(H5Tset_strpad(type, H5T_STR_NULLPAD), "H5Tset_strpad");
  check(H5Tset_cset(type, utf8 ? H5T_CSET_UTF8 : H5T_CSET_ASCII), "H5Tset_cset");
  return type;
}

// scalar attributes, written once before SWMR writing starts
template <class T>
void attribute(hid_t obj, const char* name, T value) {
  static_assert(std::is_same_v<T, double> || std::is_same_v<T, long>);
  const hid_t type = std::is_same_v<T, double> ? H5T_NATIVE_DOUBLE : H5T_NATIVE_LONG;
  Id space(H5Screate(H5S_SCALAR), H5Sclose, "H5Screate");
  Id attr(H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, std::string("attribute ") + name);
  check(H5Awrite(attr, type, &value), std::string("writing attribute ") + name);
}

void attribute(hid_t obj, const char* name, const std::string& value) {
  Id type = string_type(value.size(), is_valid_utf8(value));
  Id space(H5Screate(H5S_SCALAR), H5Sclose, "H5Screate");
  Id attr(H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, std::string("attribute ") + name);
  const std::string padded = value.empty() ? std::string(1, '\0') : value;
  check(H5Awrite(attr, type, padded.data()), std::string("writing attribute ") + name);
}

// A scalar dataset whose storage is allocated at creation: later writes overwrite its bytes in
// place and change no metadata, which SWMR allows at any time.
struct Scalar {
  Id dset, type;
  size_t size = 0;  // strings: fixed length in bytes
  Scalar() = default;
  Scalar(hid_t parent, const char* name, hid_t mem_type, Id file_type = Id()) {
    Id space(H5Screate(H5S_SCALAR), H5Sclose, "H5Screate");
    Id props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "H5Pcreate");
    check(H5Pset_alloc_time(props, H5D_ALLOC_TIME_EARLY), "H5Pset_alloc_time");
    type = std::move(file_type);
    const hid_t t = type >= 0 ? hid_t(type) : mem_type;
    if (type >= 0) size = H5Tget_size(type);
    dset = Id(H5Dcreate2(parent, name, t, space, H5P_DEFAULT, props, H5P_DEFAULT), H5Dclose, std::string("creating ") + name);
  }
  void write(double x) { check(H5Dwrite(dset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, &x), "writing /solver"); }
  void write(long x) { check(H5Dwrite(dset, H5T_NATIVE_LONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, &x), "writing /solver"); }
  void write(std::string s) {
    if (s.size() > size) {  // cut at a character boundary
      size_t n = size - 3;
      while (n > 0 && (static_cast<unsigned char>(s[n]) & 0xC0) == 0x80) --n;
      s = s.substr(0, n) + "...";
    }
    s.resize(size, '\0');
    check(H5Dwrite(dset, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, s.data()), "writing /solver");
  }
  void release() { dset.release(), type.release(); }
};

Scalar string_scalar(hid_t parent, const char* name, size_t size) {
  return Scalar(parent, name, -1, string_type(size, true));
}

// the bytes of one row: t, q, q̇, q̈, T, V, E, linear and angular momentum
int row_width(const Model& m) { return 1 + m.nq + 2 * m.nv + 3 + 6; }

}  // namespace

std::uint64_t row_bytes(const Model& model) { return std::uint64_t(row_width(model)) * sizeof(double); }

struct H5Log::Impl {
  std::string path, tmp_path;
  bool published = false, closed = false, broken = false;
  Id file, samples;
  int width = 0;
  hsize_t rows = 0;            // rows in the file
  std::vector<double> buffer;  // rows not yet written
  double t_last = 0.0, t_flushed = -1.0;
  Scalar status, quaternion, t_reached, cpu, steps, rhs, jac, etf, nli;
  std::chrono::steady_clock::time_point last_flush;
  std::chrono::duration<double> flush_interval{0.5};
  long flushes = 0;
  double flush_seconds = 0.0;

  // after a failed write: give every id up unclosed, so nothing writes to the file again
  void abandon() {
    broken = true;
    for (Scalar* s : {&status, &quaternion, &t_reached, &cpu, &steps, &rhs, &jac, &etf, &nli}) s->release();
    samples.release();
    file.release();
  }
  [[noreturn]] void io_error(const H5Failure& e) {
    abandon();
    std::string msg = (e.cause.empty() ? std::string(e.what()) : e.cause) + " while writing " + path + " at t = " +
                      number(t_last) + " s";
    if (published)
      msg += t_flushed >= 0 ? " (rows up to t = " + number(t_flushed) + " s are kept)" : " (no rows are kept)";
    else
      msg += " (the output was not written; an existing file there is unchanged)";
    if (!published) std::remove(tmp_path.c_str());
    if (!msg.empty()) msg[0] = char(std::tolower(static_cast<unsigned char>(msg[0])));
    throw IoError(msg);
  }
};

namespace {

// /time, /q, … as views of columns [first, first + cols) of /samples (cols = 0: one column, 1-D)
void view(hid_t parent, const char* name, int first, int cols, int width) {
  const int rank = cols > 0 ? 2 : 1;
  const hsize_t c = hsize_t(std::max(1, cols));
  hsize_t dims[2] = {0, c}, maxdims[2] = {H5S_UNLIMITED, c};
  Id vspace(H5Screate_simple(rank, dims, maxdims), H5Sclose, "H5Screate_simple");
  hsize_t start[2] = {0, 0}, stride[2] = {1, 1}, count[2] = {H5S_UNLIMITED, 1}, block[2] = {1, c};
  check(H5Sselect_hyperslab(vspace, H5S_SELECT_SET, start, stride, count, block), "selecting a view");
  hsize_t sdims[2] = {0, hsize_t(width)}, smax[2] = {H5S_UNLIMITED, hsize_t(width)};
  Id sspace(H5Screate_simple(2, sdims, smax), H5Sclose, "H5Screate_simple");
  hsize_t sstart[2] = {0, hsize_t(first)}, sblock[2] = {1, c};
  check(H5Sselect_hyperslab(sspace, H5S_SELECT_SET, sstart, stride, count, sblock), "selecting a view's source");
  Id props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "H5Pcreate");
  check(H5Pset_virtual(props, vspace, ".", "/samples", sspace), std::string("mapping view ") + name);
  Id d(H5Dcreate2(parent, name, H5T_NATIVE_DOUBLE, vspace, H5P_DEFAULT, props, H5P_DEFAULT), H5Dclose,
       std::string("creating view ") + name);
}

}  // namespace

H5Log::H5Log(const std::string& path, const Scenario& sc, const SimulationSettings& settings, const std::string& version)
    : impl_(std::make_unique<Impl>()) {
  H5dont_atexit();  // no flush at exit of a file a failed write left behind
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // our messages, not HDF5's stack dumps
  Impl& im = *impl_;
  im.path = path;
  im.tmp_path = temporary_path(path);
  const Model& m = sc.model;
  im.width = row_width(m);
  try {
    Id fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "H5Pcreate");
    check(H5Pset_libver_bounds(fapl, H5F_LIBVER_LATEST, H5F_LIBVER_LATEST), "H5Pset_libver_bounds");
    const hid_t f = H5Fcreate(im.tmp_path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
    if (f < 0) {
      record_cause();
      if (last_errno == ENOSPC || last_errno == EDQUOT || last_errno == EIO || last_errno == EFBIG) {
        std::remove(im.tmp_path.c_str());
        throw IoError(std::string(1, char(std::tolower(static_cast<unsigned char>(last_cause[0])))) + last_cause.substr(1) +
                      " while creating " + path + " (the output was not written; an existing file there is unchanged)");
      }
      throw Error(path + ": cannot create the output file " + im.tmp_path +
                  (last_cause.empty() ? std::string() : " (" + last_cause + ")") + "; is the directory writable?");
    }
    im.file = Id(f, H5Fclose, "H5Fcreate");
    attribute(im.file, "soadyn_version", version);
    attribute(im.file, "scenario_path", sc.path);
    attribute(im.file, "layout_version", 2L);
    {
      Id type = string_type(sc.text.size(), is_valid_utf8(sc.text));
      Id space(H5Screate(H5S_SCALAR), H5Sclose, "H5Screate");
      Id d(H5Dcreate2(im.file, "scenario", type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose, "creating /scenario");
      const std::string padded = sc.text.empty() ? std::string(1, '\0') : sc.text;
      check(H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, padded.data()), "writing /scenario");
    }

    Id g_model = group(im.file, "model");
    attribute(g_model, "nq", long(m.nq));
    attribute(g_model, "nv", long(m.nv));
    {
      // joint_names: fixed-length UTF-8 strings; parents: ints (-1 = world)
      size_t width = 1;
      for (const auto& n : m.joint_names) width = std::max(width, n.size());
      std::vector<char> names(width * m.nbodies, '\0');
      for (int i = 0; i < m.nbodies; ++i) std::copy(m.joint_names[i].begin(), m.joint_names[i].end(), names.begin() + i * width);
      Id type = string_type(width, true);
      hsize_t n = hsize_t(m.nbodies);
      Id space(H5Screate_simple(1, &n, nullptr), H5Sclose, "H5Screate_simple");
      Id d(H5Dcreate2(g_model, "joint_names", type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose, "joint_names");
      check(H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, names.data()), "writing joint_names");
      std::vector<int> parents(m.parent.begin(), m.parent.end());
      Id dp(H5Dcreate2(g_model, "parents", H5T_NATIVE_INT, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose, "parents");
      check(H5Dwrite(dp, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, parents.data()), "writing parents");
    }

    Id g_solver = group(im.file, "solver");
    attribute(g_solver, "method", settings.method);
    attribute(g_solver, "rtol", settings.rtol);
    attribute(g_solver, "atol", settings.atol);
    attribute(g_solver, "dt", settings.dt);
    attribute(g_solver, "output_dt", output_interval(settings));
    attribute(g_solver, "t_end", settings.t_end);
    attribute(g_solver, "dynamics", settings.dynamics);
    im.status = string_scalar(g_solver, "status", 1024);
    im.quaternion = string_scalar(g_solver, "quaternion_handling", 256);
    im.t_reached = Scalar(g_solver, "t_reached", H5T_NATIVE_DOUBLE);
    im.cpu = Scalar(g_solver, "cpu_seconds", H5T_NATIVE_DOUBLE);
    im.steps = Scalar(g_solver, "steps", H5T_NATIVE_LONG);
    im.rhs = Scalar(g_solver, "rhs_evals", H5T_NATIVE_LONG);
    im.jac = Scalar(g_solver, "jac_evals", H5T_NATIVE_LONG);
    im.etf = Scalar(g_solver, "error_test_failures", H5T_NATIVE_LONG);
    im.nli = Scalar(g_solver, "nonlinear_iterations", H5T_NATIVE_LONG);
    im.status.write(std::string("running"));
    im.quaternion.write(std::string());
    for (Scalar* s : {&im.t_reached, &im.cpu}) s->write(0.0);
    for (Scalar* s : {&im.steps, &im.rhs, &im.jac, &im.etf, &im.nli}) s->write(0L);

    {
      // the table every series is a view of: chunks of about 64 KiB
      const hsize_t w = hsize_t(im.width);
      hsize_t dims[2] = {0, w}, maxdims[2] = {H5S_UNLIMITED, w}, chunk[2] = {std::max<hsize_t>(1, 8192 / w), w};
      Id space(H5Screate_simple(2, dims, maxdims), H5Sclose, "H5Screate_simple");
      Id props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "H5Pcreate");
      check(H5Pset_chunk(props, 2, chunk), "H5Pset_chunk");
      im.samples = Id(H5Dcreate2(im.file, "samples", H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, props, H5P_DEFAULT), H5Dclose,
                      "creating /samples");
      attribute(im.samples, "columns",
                "time 1, q " + std::to_string(m.nq) + ", qd " + std::to_string(m.nv) + ", qdd " + std::to_string(m.nv) +
                    ", energy/kinetic 1, energy/potential 1, energy/total 1, momentum/linear 3, momentum/angular 3");
    }
    Id g_energy = group(im.file, "energy"), g_momentum = group(im.file, "momentum");
    int col = 0;
    view(im.file, "time", col, 0, im.width), col += 1;
    view(im.file, "q", col, m.nq, im.width), col += m.nq;
    view(im.file, "qd", col, m.nv, im.width), col += m.nv;
    view(im.file, "qdd", col, m.nv, im.width), col += m.nv;
    for (const char* e : {"kinetic", "potential", "total"}) view(g_energy, e, col, 0, im.width), col += 1;
    view(g_momentum, "linear", col, 3, im.width), col += 3;
    view(g_momentum, "angular", col, 3, im.width), col += 3;
    check(H5Fstart_swmr_write(im.file), "H5Fstart_swmr_write");  // writes everything so far
  } catch (const H5Failure& e) {
    im.io_error(e);
  } catch (...) {
    im.abandon();
    std::remove(im.tmp_path.c_str());
    throw;
  }
  im.last_flush = std::chrono::steady_clock::now();
}

H5Log::~H5Log() {
  Impl& im = *impl_;
  if (im.closed || im.broken) return;
  if (!im.published) {  // never reached its first flush: nothing to keep
    im.abandon();
    std::remove(im.tmp_path.c_str());
    return;
  }
  try {
    flush();
  } catch (...) {
  }
}

void H5Log::on_sample(const Sample& s) {
  auto& b = impl_->buffer;
  b.push_back(s.t);
  b.insert(b.end(), s.q.data(), s.q.data() + s.q.size());
  b.insert(b.end(), s.qd.data(), s.qd.data() + s.qd.size());
  b.insert(b.end(), s.qdd.data(), s.qdd.data() + s.qdd.size());
  b.insert(b.end(), {s.kinetic, s.potential, s.total});
  b.insert(b.end(), s.linear.data(), s.linear.data() + 3);
  b.insert(b.end(), s.angular.data(), s.angular.data() + 3);
  impl_->t_last = s.t;
}

void H5Log::flush(const RunSummary* summary) {
  Impl& im = *impl_;
  if (im.broken || im.closed) return;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    const hsize_t w = hsize_t(im.width), n = im.buffer.size() / w;
    if (n > 0) {
      hsize_t size[2] = {im.rows + n, w};
      check(H5Dset_extent(im.samples, size), "extending /samples");
      Id file_space(H5Dget_space(im.samples), H5Sclose, "H5Dget_space");
      hsize_t start[2] = {im.rows, 0}, count[2] = {n, w};
      check(H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start, nullptr, count, nullptr), "H5Sselect_hyperslab");
      Id mem_space(H5Screate_simple(2, count, nullptr), H5Sclose, "H5Screate_simple");
      check(H5Dwrite(im.samples, H5T_NATIVE_DOUBLE, mem_space, file_space, H5P_DEFAULT, im.buffer.data()), "writing /samples");
      check(H5Dflush(im.samples), "H5Dflush");  // the rows, then the extent that shows them
    }
    if (summary) {
      im.status.write(summary->status);
      im.quaternion.write(summary->quaternion_handling);
      im.t_reached.write(summary->t_reached);
      im.cpu.write(summary->cpu_seconds);
      im.steps.write(summary->stats.steps);
      im.rhs.write(summary->stats.rhs_evals);
      im.jac.write(summary->stats.jac_evals);
      im.etf.write(summary->stats.error_test_failures);
      im.nli.write(summary->stats.nonlinear_iterations);
    }
    check(H5Fflush(im.file, H5F_SCOPE_LOCAL), "H5Fflush");
    im.rows += n;
    if (n > 0) im.t_flushed = im.buffer[(n - 1) * w];
    im.buffer.clear();
  } catch (const H5Failure& e) {
    im.io_error(e);
  }
  if (!im.published) {  // the file is whole: put it in place of whatever was there
    if (std::rename(im.tmp_path.c_str(), im.path.c_str()) != 0) {
      const int err = errno;
      im.abandon();
      std::remove(im.tmp_path.c_str());
      throw IoError(std::string(std::strerror(err)) + " while renaming " + im.tmp_path + " to " + im.path);
    }
    im.published = true;
  }
  im.last_flush = std::chrono::steady_clock::now();
  ++im.flushes;
  im.flush_seconds += std::chrono::duration<double>(im.last_flush - t0).count();
}

void H5Log::on_progress(const RunSummary& summary) {
  if (!impl_->published || std::chrono::steady_clock::now() - impl_->last_flush >= impl_->flush_interval)
    flush(&summary);
}

void H5Log::on_finish(const RunSummary& summary) {
  Impl& im = *impl_;
  if (!im.published && summary.status.rfind("interrupted", 0) == 0 && im.buffer.size() <= size_t(im.width)) {
    // interrupted before its first step: an existing file stays as it was
    im.abandon();
    std::remove(im.tmp_path.c_str());
    im.closed = true;
    return;
  }
  flush(&summary);
  if (im.broken) return;
  for (Scalar* s : {&im.status, &im.quaternion, &im.t_reached, &im.cpu, &im.steps, &im.rhs, &im.jac, &im.etf, &im.nli}) {
    s->dset.reset();
    s->type.reset();
  }
  im.samples.reset();
  // closing ends SWMR writing: the file then opens without the SWMR-read flag
  if (H5Fclose(im.file) < 0) {
    record_cause();
    im.file.release();
    im.abandon();
    throw IoError((last_cause.empty() ? std::string("an HDF5 error") : last_cause) + " while closing " + im.path +
                  " (rows up to t = " + number(im.t_flushed) + " s are kept)");
  }
  im.file.release();
  im.closed = true;
}

std::string H5Log::temporary_path(const std::string& path) { return path + "." + std::to_string(getpid()) + ".tmp"; }

void H5Log::set_flush_interval(double seconds) { impl_->flush_interval = std::chrono::duration<double>(seconds); }

const std::string& H5Log::current_path() const { return impl_->published ? impl_->path : impl_->tmp_path; }
bool H5Log::published() const { return impl_->published; }
long H5Log::flushes() const { return impl_->flushes; }
double H5Log::flush_seconds() const { return impl_->flush_seconds; }

}  // namespace soadyn
