// Reading a run file back with the plain HDF5 C API, for tests: datasets and attributes by
// value, and an inventory of every object and attribute the file holds.  A second route to the
// file's contents beside the library's reader (run_file.hpp); its ids are held by the library's
// one owner of HDF5 ids, h5::Id.
#pragma once

#include "../src/io/h5_util.hpp"

#include <hdf5.h>

#include <algorithm>
#include <limits>
#include <set>
#include <string>
#include <vector>

namespace soadyn::test {

// an id held by h5::Id, closed on scope exit; an empty Id (ok() false) when the call failed
inline h5::Id own(hid_t id, herr_t (*close)(hid_t)) { return id < 0 ? h5::Id() : h5::Id(id, close, "test"); }

// A read-only HDF5 file, closed on scope exit (id < 0 when it could not be opened).
struct H5File {
  explicit H5File(const std::string& path) : file(open(path)), id(file) {}
  static h5::Id open(const std::string& path) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    return own(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  }
  const h5::Id file;
  const hid_t id;
};

// a numeric dataset as doubles, row-major, with its shape (cols = 0 for one dimension; for three,
// cols = the product of the last two, given in dims); empty if absent
struct Table {
  std::vector<double> values;
  hsize_t rows = 0, cols = 0;
  int rank = 0;
  hsize_t dims[3] = {0, 0, 0};
  bool found = false;
  double at(hsize_t r, hsize_t c = 0) const { return values[r * (cols ? cols : 1) + c]; }
};

inline Table read_table(hid_t file, const std::string& path) {
  Table t;
  const h5::Id d = own(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose);
  if (!d.ok()) return t;
  const h5::Id space = own(H5Dget_space(d), H5Sclose);
  hsize_t* dims = t.dims;
  const int rank = H5Sget_simple_extent_ndims(space);
  if (rank < 1 || rank > 3) return t;
  H5Sget_simple_extent_dims(space, dims, nullptr);
  t.rank = rank;
  t.rows = dims[0];
  t.cols = rank == 3 ? dims[1] * dims[2] : rank == 2 ? dims[1] : 0;
  t.values.resize(t.rows * (t.cols ? t.cols : 1));
  t.found = t.values.empty() || H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, t.values.data()) >= 0;
  return t;
}

// a one-dimensional dataset of fixed-length strings
inline std::vector<std::string> read_strings(hid_t file, const std::string& path) {
  std::vector<std::string> out;
  const h5::Id d = own(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose);
  if (!d.ok()) return out;
  const h5::Id type = own(H5Dget_type(d), H5Tclose), space = own(H5Dget_space(d), H5Sclose);
  hsize_t n = 0;
  H5Sget_simple_extent_dims(space, &n, nullptr);
  const size_t width = H5Tget_size(type);
  std::vector<char> buf(width * n);
  if (n > 0 && H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) >= 0)
    for (hsize_t i = 0; i < n; ++i) {
      const std::string s(buf.data() + i * width, width);
      out.push_back(s.substr(0, s.find('\0')));
    }
  return out;
}

// a one-dimensional dataset or attribute of fixed-length strings (layout 5: nothing in the
// global heap; older layouts' variable-length ones read too, only when `variable`); {"(missing)"}
// if absent
inline std::vector<std::string> read_vlen_strings(hid_t obj, bool attribute, bool variable = false) {
  const h5::Id type = own(attribute ? H5Aget_type(obj) : H5Dget_type(obj), H5Tclose);
  const h5::Id space = own(attribute ? H5Aget_space(obj) : H5Dget_space(obj), H5Sclose);
  std::vector<std::string> out;
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  if (H5Tget_class(type) == H5T_STRING && H5Tis_variable_str(type) <= 0 && H5Sget_simple_extent_ndims(space) == 1) {
    const size_t width = H5Tget_size(type);
    std::vector<char> buf(width * size_t(n));
    const herr_t ok = n == 0 ? 0 : attribute ? H5Aread(obj, type, buf.data()) : H5Dread(obj, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data());
    for (hssize_t i = 0; i < n && ok >= 0; ++i) {
      const char* s = buf.data() + size_t(i) * width;
      out.emplace_back(s, std::find(s, s + width, '\0'));
    }
  } else if (variable && H5Tget_class(type) == H5T_STRING && H5Tis_variable_str(type) > 0 &&
             H5Sget_simple_extent_ndims(space) == 1) {
    const h5::Id mem = own(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(mem, H5T_VARIABLE);
    H5Tset_cset(mem, H5Tget_cset(type));
    std::vector<char*> p(size_t(n), nullptr);
    const herr_t ok = n == 0 ? 0 : attribute ? H5Aread(obj, mem, p.data()) : H5Dread(obj, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, p.data());
    for (char* c : p) {
      if (ok >= 0) out.push_back(c ? c : "");
      H5free_memory(c);
    }
  } else {
    out.push_back("(not a list of fixed-length strings)");
  }
  return out;
}

inline std::vector<std::string> string_list_attribute(hid_t file, const std::string& path, const std::string& name) {
  const h5::Id a = own(H5Aopen_by_name(file, path.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!a.ok()) return {"(missing)"};
  return read_vlen_strings(a, true);
}

inline std::vector<std::string> string_list_dataset(hid_t file, const std::string& path) {
  const h5::Id d = own(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose);
  if (!d.ok()) return {"(missing)"};
  return read_vlen_strings(d, false);
}

// a one-dimensional numeric attribute; empty if absent
inline std::vector<double> numbers_attribute(hid_t file, const std::string& path, const std::string& name) {
  const h5::Id a = own(H5Aopen_by_name(file, path.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!a.ok()) return {};
  const h5::Id space = own(H5Aget_space(a), H5Sclose);
  std::vector<double> out(size_t(H5Sget_simple_extent_npoints(space)));
  if (!out.empty()) H5Aread(a, H5T_NATIVE_DOUBLE, out.data());
  return out;
}

// a scalar dataset: a string (fixed length, null-padded) or a number; "(missing)" / NaN if absent
inline std::string scalar_text(hid_t file, const std::string& path) {
  const h5::Id d = own(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose);
  if (!d.ok()) return "(missing)";
  const h5::Id type = own(H5Dget_type(d), H5Tclose);
  std::string s = "(not a string)";
  if (H5Tget_class(type) == H5T_STRING && H5Tis_variable_str(type) <= 0) {
    s.assign(H5Tget_size(type), '\0');
    H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, s.data());
    s = s.substr(0, s.find('\0'));
  }
  return s;
}

inline double scalar_number(hid_t file, const std::string& path) {
  double x = std::numeric_limits<double>::quiet_NaN();
  const h5::Id d = own(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose);
  if (d.ok()) H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, &x);
  return x;
}

// the type class of a dataset (H5T_INTEGER, H5T_FLOAT, H5T_STRING; H5T_NO_CLASS if absent)
inline H5T_class_t dataset_class(hid_t file, const std::string& path) {
  const h5::Id d = own(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose);
  if (!d.ok()) return H5T_NO_CLASS;
  return H5Tget_class(own(H5Dget_type(d), H5Tclose));
}

// attribute `name` of the object at `path`: a string, or a number; "(missing)" / NaN if absent
inline std::string string_attribute(hid_t file, const std::string& path, const std::string& name) {
  const h5::Id a = own(H5Aopen_by_name(file, path.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!a.ok()) return "(missing)";
  const h5::Id type = own(H5Aget_type(a), H5Tclose);
  const bool scalar = H5Sget_simple_extent_type(own(H5Aget_space(a), H5Sclose)) == H5S_SCALAR;
  std::string s = "(not a string)";
  if (H5Tget_class(type) == H5T_STRING && scalar) {
    if (H5Tis_variable_str(type) > 0) {
      char* p = nullptr;
      if (H5Aread(a, type, &p) >= 0 && p) s = p;
      H5free_memory(p);
    } else {
      s.assign(H5Tget_size(type), '\0');
      H5Aread(a, type, s.data());
      s = s.substr(0, s.find('\0'));
    }
  }
  return s;
}

inline double number_attribute(hid_t file, const std::string& path, const std::string& name) {
  double x = std::numeric_limits<double>::quiet_NaN();
  const h5::Id a = own(H5Aopen_by_name(file, path.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!a.ok()) return x;
  const H5T_class_t c = H5Tget_class(own(H5Aget_type(a), H5Tclose));
  if (c == H5T_INTEGER || c == H5T_FLOAT) H5Aread(a, H5T_NATIVE_DOUBLE, &x);
  return x;
}

// the class of a numeric attribute: H5T_INTEGER or H5T_FLOAT (H5T_NO_CLASS if absent)
inline H5T_class_t attribute_class(hid_t file, const std::string& path, const std::string& name) {
  const h5::Id a = own(H5Aopen_by_name(file, path.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!a.ok()) return H5T_NO_CLASS;
  return H5Tget_class(own(H5Aget_type(a), H5Tclose));
}

// every object ("/q", "/energy", …) and every attribute ("/solver@rtol", "/@scenario") in the file
inline std::set<std::string> inventory(hid_t file) {
  struct Walk {
    std::set<std::string> found;
    std::string path;
    void attributes_of(hid_t obj, const std::string& p) {
      found.insert(p);
      path = p;
      hsize_t idx = 0;
      H5Aiterate2(obj, H5_INDEX_NAME, H5_ITER_INC, &idx, &Walk::attribute, this);
    }
    static herr_t attribute(hid_t, const char* name, const H5A_info_t*, void* op) {
      auto* w = static_cast<Walk*>(op);
      w->found.insert(w->path + "@" + name);
      return 0;
    }
    static herr_t link(hid_t group, const char* name, const H5L_info_t*, void* op) {
      const h5::Id o = own(H5Oopen(group, name, H5P_DEFAULT), H5Oclose);
      if (o.ok()) static_cast<Walk*>(op)->attributes_of(o, "/" + std::string(name));
      return 0;
    }
  } walk;
  walk.attributes_of(file, "/");
  H5Lvisit(file, H5_INDEX_NAME, H5_ITER_INC, &Walk::link, &walk);
  return walk.found;
}

}  // namespace soadyn::test
