#include "h5_util.hpp"

#include "soadyn/io/input_file.hpp"
#include "soadyn/multibody/text.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>

namespace soadyn::h5 {

int last_errno = 0;
std::string last_cause;

namespace {

herr_t find_errno(unsigned, const H5E_error2_t* e, void* found) {
  const char* at = e->desc ? std::strstr(e->desc, "errno = ") : nullptr;
  if (at && *static_cast<int*>(found) == 0) *static_cast<int*>(found) = std::atoi(at + 8);
  return 0;
}

bool all_utf8(const std::vector<std::string>& values) {
  return std::all_of(values.begin(), values.end(), [](const std::string& s) { return is_valid_utf8(s); });
}

// the strings side by side, each null-padded to the longest (at least one byte): a fixed-length
// string array's bytes
std::string packed(const std::vector<std::string>& values, size_t& width) {
  width = 1;
  for (const auto& s : values) width = std::max(width, s.size());
  std::string out;
  for (const auto& s : values) out += s + std::string(width - s.size(), '\0');
  return out;
}

}  // namespace

void record_cause() {
  int err = 0;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, find_errno, &err);
  last_errno = err;
  last_cause = err ? std::strerror(err) : "";
}

void fail(const std::string& what) {
  record_cause();
  throw Failure("HDF5: " + what + " failed", last_cause);
}

Id group(hid_t parent, const char* name) {
  return Id(H5Gcreate2(parent, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, std::string("creating group ") + name);
}

Id string_type(size_t size, bool utf8) {
  Id type(H5Tcopy(H5T_C_S1), H5Tclose, "H5Tcopy");
  check(H5Tset_size(type, std::max<size_t>(1, size)), "H5Tset_size");
  check(H5Tset_strpad(type, H5T_STR_NULLPAD), "H5Tset_strpad");
  check(H5Tset_cset(type, utf8 ? H5T_CSET_UTF8 : H5T_CSET_ASCII), "H5Tset_cset");
  return type;
}

namespace {
template <class T>
void scalar_attribute(hid_t obj, const char* name, hid_t type, const T& value) {
  Id space(H5Screate(H5S_SCALAR), H5Sclose, "H5Screate");
  Id attr(H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, std::string("attribute ") + name);
  check(H5Awrite(attr, type, &value), std::string("writing attribute ") + name);
}
}  // namespace

void attribute(hid_t obj, const char* name, double value) { scalar_attribute(obj, name, H5T_NATIVE_DOUBLE, value); }
void attribute(hid_t obj, const char* name, long value) { scalar_attribute(obj, name, H5T_NATIVE_LONG, value); }

void attribute(hid_t obj, const char* name, const std::string& value) {
  Id type = string_type(value.size(), is_valid_utf8(value));
  Id space(H5Screate(H5S_SCALAR), H5Sclose, "H5Screate");
  Id attr(H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, std::string("attribute ") + name);
  const std::string padded = value.empty() ? std::string(1, '\0') : value;
  check(H5Awrite(attr, type, padded.data()), std::string("writing attribute ") + name);
}

void attribute(hid_t obj, const char* name, const std::vector<std::string>& values) {
  size_t width = 1;
  const std::string bytes = packed(values, width);
  Id type = string_type(width, all_utf8(values));
  const hsize_t n = values.size();
  Id space(H5Screate_simple(1, &n, nullptr), H5Sclose, "H5Screate_simple");
  Id attr(H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, std::string("attribute ") + name);
  if (n > 0) check(H5Awrite(attr, type, bytes.data()), std::string("writing attribute ") + name);
}

void attribute(hid_t obj, const char* name, const std::vector<double>& values) {
  const hsize_t n = values.size();
  Id space(H5Screate_simple(1, &n, nullptr), H5Sclose, "H5Screate_simple");
  Id attr(H5Acreate2(obj, name, H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
          std::string("attribute ") + name);
  if (n > 0) check(H5Awrite(attr, H5T_NATIVE_DOUBLE, values.data()), std::string("writing attribute ") + name);
}

Id text_dataset(hid_t parent, const char* name, const std::string& text) {
  Id type = string_type(text.size(), is_valid_utf8(text));
  Id space(H5Screate(H5S_SCALAR), H5Sclose, "H5Screate");
  Id d(H5Dcreate2(parent, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose, std::string("creating /") + name);
  const std::string padded = text.empty() ? std::string(1, '\0') : text;
  check(H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, padded.data()), std::string("writing /") + name);
  return d;
}

void int_dataset(hid_t parent, const char* name, const std::vector<int>& values, const std::string& units) {
  const hsize_t n = values.size();
  Id space(H5Screate_simple(1, &n, nullptr), H5Sclose, "H5Screate_simple");
  Id d(H5Dcreate2(parent, name, H5T_NATIVE_INT, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose,
       std::string("creating ") + name);
  if (n > 0) check(H5Dwrite(d, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), std::string("writing ") + name);
  attribute(d, "units", units);
}

void string_dataset(hid_t parent, const char* name, const std::vector<std::string>& values) {
  size_t width = 1;
  const std::string bytes = packed(values, width);
  Id type = string_type(width, all_utf8(values));
  const hsize_t n = values.size();
  Id space(H5Screate_simple(1, &n, nullptr), H5Sclose, "H5Screate_simple");
  Id d(H5Dcreate2(parent, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose,
       std::string("creating ") + name);
  if (n > 0) check(H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data()), std::string("writing ") + name);
}

Id byte_dataset(hid_t parent, const char* name, const std::string& bytes) {
  const hsize_t n = bytes.size();
  Id space(H5Screate_simple(1, &n, nullptr), H5Sclose, "H5Screate_simple");
  Id d(H5Dcreate2(parent, name, H5T_STD_U8LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose,
       std::string("creating ") + name);
  if (n > 0) check(H5Dwrite(d, H5T_NATIVE_UCHAR, H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data()), std::string("writing ") + name);
  return d;
}

Scalar::Scalar(hid_t parent, const char* name, hid_t mem_type, Id file_type) {
  Id space(H5Screate(H5S_SCALAR), H5Sclose, "H5Screate");
  Id props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "H5Pcreate");
  check(H5Pset_alloc_time(props, H5D_ALLOC_TIME_EARLY), "H5Pset_alloc_time");
  type = std::move(file_type);
  const hid_t t = type >= 0 ? hid_t(type) : mem_type;
  if (type >= 0) size = H5Tget_size(type);
  dset = Id(H5Dcreate2(parent, name, t, space, H5P_DEFAULT, props, H5P_DEFAULT), H5Dclose, std::string("creating ") + name);
}

void Scalar::write(double x) { check(H5Dwrite(dset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, &x), "writing /solver"); }
void Scalar::write(long x) { check(H5Dwrite(dset, H5T_NATIVE_LONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, &x), "writing /solver"); }

void Scalar::write(std::string s) {
  if (s.size() > size) {  // cut at a character boundary
    size_t n = size - 3;
    while (n > 0 && (static_cast<unsigned char>(s[n]) & 0xC0) == 0x80) --n;
    s = s.substr(0, n) + "...";
  }
  s.resize(size, '\0');
  check(H5Dwrite(dset, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, s.data()), "writing /solver");
}

Scalar string_scalar(hid_t parent, const char* name, size_t size) { return Scalar(parent, name, -1, string_type(size, true)); }

Id open_run_file(const std::string& path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // our messages, not HDF5's stack dumps
  // a regular file (never a FIFO or device: input_file.hpp), and HDF5 opens the very file checked
  const InputFile in(path, "a run file (HDF5, from soadyn run)", kNoSizeLimit);
  const std::string name = in.name_for_library();
  if (H5Fis_hdf5(name.c_str()) <= 0) throw Error(path + ": not a run file: not an HDF5 file (expected one from soadyn run)");
  // a closed file has no writer to wait for: one read of each piece of metadata, so a checksum that
  // fails (a changed byte) refuses at once instead of after retries; a file still open for writing
  // (a running or killed run) opens SWMR-read, whose retries ride out a write in progress
  Id plain(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, path + ": file-access properties");
  H5Pset_metadata_read_attempts(plain, 1);
  hid_t f = H5Fopen(name.c_str(), H5F_ACC_RDONLY, plain);
  Id fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, path + ": file-access properties");
  H5Pset_metadata_read_attempts(fapl, kMetadataReadAttempts);
  if (f < 0) f = H5Fopen(name.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, fapl);
  if (f < 0) throw Error(path + ": cannot open the HDF5 file (corrupt or truncated?)");
  return Id(f, H5Fclose, path);
}

bool exists(hid_t file, const std::string& path) {
  // each link of the path must exist before the next is asked about
  for (size_t from = 1;;) {
    const size_t slash = path.find('/', from);
    if (H5Lexists(file, path.substr(0, slash).c_str(), H5P_DEFAULT) <= 0) return false;
    if (slash == std::string::npos) return true;
    from = slash + 1;
  }
}

bool has_attribute(hid_t obj, const char* name) { return H5Aexists(obj, name) > 0; }

namespace {

// an attribute or a dataset opened for reading, with its type and space
struct Readable {
  Id obj, type, space;
  bool attribute;
  std::string where;
  Readable(hid_t parent, const char* name, bool attr, const std::string& at) : attribute(attr), where(at + ": " + name) {
    const bool there = attr ? H5Aexists(parent, name) > 0 : H5Lexists(parent, name, H5P_DEFAULT) > 0;
    if (!there) throw Error(where + " is missing");
    const hid_t id = attr ? H5Aopen(parent, name, H5P_DEFAULT) : H5Dopen2(parent, name, H5P_DEFAULT);
    if (id < 0) throw Error(where + ": cannot be opened (corrupt or truncated file?)");
    obj = Id(id, attr ? H5Aclose : H5Dclose, where);
    const hid_t t = attr ? H5Aget_type(obj) : H5Dget_type(obj), s = attr ? H5Aget_space(obj) : H5Dget_space(obj);
    if (t < 0 || s < 0) throw Error(where + ": cannot be read (corrupt or truncated file?)");
    type = Id(t, H5Tclose, where), space = Id(s, H5Sclose, where);
  }
  void read(hid_t mem, void* buf) const {
    const herr_t r = attribute ? H5Aread(obj, mem, buf) : H5Dread(obj, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf);
    if (r < 0) throw Error(where + ": cannot be read (corrupt or truncated file?)");
  }
};

}  // namespace

namespace {
// text tagged UTF-8 that is not: a changed byte (the writer tags text that is not UTF-8 as ASCII)
void check_utf8(const Readable& r, const std::vector<std::string>& out) {
  if (H5Tget_cset(r.type) != H5T_CSET_UTF8) return;
  for (size_t k = 0; k < out.size(); ++k)
    if (!is_valid_utf8(out[k]))
      throw Error(r.where + (out.size() > 1 ? " [" + std::to_string(k) + "]" : std::string()) +
                  ": tagged UTF-8 but not valid UTF-8 (a corrupt file?)");
}
}  // namespace

std::vector<std::string> strings(hid_t obj, const char* name, bool attribute, const std::string& where, bool variable) {
  const Readable r(obj, name, attribute, where);
  if (H5Tget_class(r.type) != H5T_STRING) throw Error(r.where + ": expected strings");
  // variable-length strings live in the global heap, which HDF5 reads unchecked: never followed in
  // a file whose layout has none
  if (H5Tis_variable_str(r.type) > 0 && !variable)
    throw Error(r.where + ": variable-length strings, which this file's layout never writes (a corrupt or crafted file)");
  const size_t width = H5Tget_size(r.type);
  const hssize_t n = H5Sget_simple_extent_npoints(r.space);
  std::vector<std::string> out;
  if (n <= 0) return out;
  if (H5Tis_variable_str(r.type) <= 0 && (width == 0 || size_t(n) > (std::size_t(1) << 31) / width))
    throw Error(r.where + ": " + std::to_string(n) + " strings of " + std::to_string(width) + " bytes (a corrupt file?)");
  if (H5Tis_variable_str(r.type) > 0) {
    Id mem(H5Tcopy(H5T_C_S1), H5Tclose, "H5Tcopy");
    check(H5Tset_size(mem, H5T_VARIABLE), "H5Tset_size");
    check(H5Tset_cset(mem, H5Tget_cset(r.type)), "H5Tset_cset");  // HDF5 converts no string between character sets
    std::vector<char*> p(size_t(n), nullptr);
    r.read(mem, p.data());
    for (char* s : p) {
      out.emplace_back(s ? s : "");
      H5free_memory(s);
    }
    check_utf8(r, out);
    return out;
  }
  // fixed-length: n × width bytes, each null-padded or null-terminated
  std::vector<char> buf(width * size_t(n));
  r.read(r.type, buf.data());
  for (hssize_t i = 0; i < n; ++i) {
    const char* s = buf.data() + size_t(i) * width;
    out.emplace_back(s, std::find(s, s + width, '\0'));
  }
  check_utf8(r, out);
  return out;
}

std::string one_string(hid_t obj, const char* name, bool attribute, const std::string& where, bool variable) {
  std::vector<std::string> s = strings(obj, name, attribute, where, variable);
  if (s.size() != 1) throw Error(where + ": " + name + ": expected one string, got " + std::to_string(s.size()));
  return std::move(s[0]);
}

RowMatrix numbers(hid_t obj, const char* name, bool attribute, const std::string& where, std::vector<hsize_t>* shape) {
  const Readable r(obj, name, attribute, where);
  const H5T_class_t c = H5Tget_class(r.type);
  if (c != H5T_FLOAT && c != H5T_INTEGER) throw Error(r.where + ": expected numbers");
  const int rank = H5Sget_simple_extent_ndims(r.space);
  std::vector<hsize_t> dims(size_t(std::max(rank, 0)));
  if (rank < 0 || H5Sget_simple_extent_dims(r.space, dims.data(), nullptr) < 0) throw Error(r.where + ": cannot be read");
  hsize_t rows = rank == 0 ? 1 : dims[0], cols = 1;
  for (size_t k = 1; k < dims.size(); ++k) cols *= dims[k];
  RowMatrix m(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols));
  if (m.size() > 0) r.read(H5T_NATIVE_DOUBLE, m.data());
  if (shape) *shape = std::move(dims);
  return m;
}

std::vector<hsize_t> dims(hid_t obj, const char* name, const std::string& where) {
  const Readable r(obj, name, false, where);
  const int rank = H5Sget_simple_extent_ndims(r.space);
  std::vector<hsize_t> d(size_t(std::max(rank, 0)));
  if (rank < 0 || H5Sget_simple_extent_dims(r.space, d.data(), nullptr) < 0) throw Error(r.where + ": cannot be read");
  return d;
}

void read_rows(hid_t dset, hsize_t first, hsize_t count, hsize_t width, double* out, const std::string& where) {
  const hid_t fs = H5Dget_space(dset);
  if (fs < 0) throw Error(where + ": cannot be read (corrupt or truncated file?)");
  Id file_space(fs, H5Sclose, where);
  hsize_t start[2] = {first, 0}, n[2] = {count, width};
  const hid_t ms = H5Screate_simple(2, n, nullptr);
  if (ms < 0) throw Error(where + ": cannot make a memory space");
  Id mem_space(ms, H5Sclose, where);
  if (H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start, nullptr, n, nullptr) < 0 ||
      H5Dread(dset, H5T_NATIVE_DOUBLE, mem_space, file_space, H5P_DEFAULT, out) < 0)
    throw Error(where + ": rows " + std::to_string(first) + " to " + std::to_string(first + count - 1) +
                " cannot be read (corrupt or truncated file?)");
}

std::string bytes(hid_t obj, const char* name, std::uint64_t max_bytes, const std::string& where) {
  const std::string at = where + ": " + name;
  if (H5Lexists(obj, name, H5P_DEFAULT) <= 0) throw Error(at + ": missing");
  const Id d(H5Dopen2(obj, name, H5P_DEFAULT), H5Dclose, at + ": cannot be opened");
  const Id type(H5Dget_type(d), H5Tclose, at + ": its type cannot be read");
  if (H5Tget_class(type) != H5T_INTEGER || H5Tget_size(type) != 1) throw Error(at + ": expected bytes (1-byte integers)");
  const Id space(H5Dget_space(d), H5Sclose, at + ": its shape cannot be read");
  if (H5Sget_simple_extent_ndims(space) != 1) throw Error(at + ": expected a 1-D dataset of bytes");
  hsize_t n = 0;
  H5Sget_simple_extent_dims(space, &n, nullptr);
  if (n > max_bytes) throw Error(at + ": " + std::to_string(n) + " bytes, more than the " + std::to_string(max_bytes) + " allowed");
  std::string out(size_t(n), '\0');
  if (n > 0) check(H5Dread(d, H5T_NATIVE_UCHAR, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), at + ": reading");
  return out;
}

}  // namespace soadyn::h5
