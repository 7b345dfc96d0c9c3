#include "h5_util.hpp"

#include "soadyn/h5log.hpp"
#include "soadyn/text.hpp"

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

// a variable-length string type: UTF-8, or ASCII when some text is not valid UTF-8
Id vlen_string_type(bool utf8) {
  Id type(H5Tcopy(H5T_C_S1), H5Tclose, "H5Tcopy");
  check(H5Tset_size(type, H5T_VARIABLE), "H5Tset_size");
  check(H5Tset_cset(type, utf8 ? H5T_CSET_UTF8 : H5T_CSET_ASCII), "H5Tset_cset");
  return type;
}

bool all_utf8(const std::vector<std::string>& values) {
  return std::all_of(values.begin(), values.end(), [](const std::string& s) { return is_valid_utf8(s); });
}

std::vector<const char*> pointers(const std::vector<std::string>& values) {
  std::vector<const char*> p;
  for (const auto& s : values) p.push_back(s.c_str());
  return p;
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
  Id type = vlen_string_type(is_valid_utf8(value));
  const char* p = value.c_str();
  scalar_attribute(obj, name, type, p);
}

void attribute(hid_t obj, const char* name, const std::vector<std::string>& values) {
  Id type = vlen_string_type(all_utf8(values));
  const hsize_t n = values.size();
  Id space(H5Screate_simple(1, &n, nullptr), H5Sclose, "H5Screate_simple");
  Id attr(H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, std::string("attribute ") + name);
  const std::vector<const char*> p = pointers(values);
  if (n > 0) check(H5Awrite(attr, type, p.data()), std::string("writing attribute ") + name);
}

void attribute(hid_t obj, const char* name, const std::vector<double>& values) {
  const hsize_t n = values.size();
  Id space(H5Screate_simple(1, &n, nullptr), H5Sclose, "H5Screate_simple");
  Id attr(H5Acreate2(obj, name, H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
          std::string("attribute ") + name);
  if (n > 0) check(H5Awrite(attr, H5T_NATIVE_DOUBLE, values.data()), std::string("writing attribute ") + name);
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
  Id type = vlen_string_type(all_utf8(values));
  const hsize_t n = values.size();
  Id space(H5Screate_simple(1, &n, nullptr), H5Sclose, "H5Screate_simple");
  Id d(H5Dcreate2(parent, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose,
       std::string("creating ") + name);
  const std::vector<const char*> p = pointers(values);
  if (n > 0) check(H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, p.data()), std::string("writing ") + name);
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

}  // namespace soadyn::h5

namespace soadyn {

std::int64_t open_run_file(const std::string& path) {
  static_assert(sizeof(hid_t) == sizeof(std::int64_t));
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // our messages, not HDF5's stack dumps
  if (H5Fis_hdf5(path.c_str()) <= 0) throw Error(path + ": not an HDF5 file (expected a run file from soadyn run)");
  const hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  if (fapl < 0) throw Error(path + ": HDF5 could not make file-access properties");
  H5Pset_metadata_read_attempts(fapl, kMetadataReadAttempts);
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl);
  if (f < 0) f = H5Fopen(path.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, fapl);
  H5Pclose(fapl);
  if (f < 0) throw Error(path + ": cannot open the HDF5 file (corrupt or truncated?)");
  return f;
}

}  // namespace soadyn
