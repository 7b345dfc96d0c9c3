// Reading a run file back with the plain HDF5 C API, for tests: datasets and attributes by
// value, and an inventory of every object and attribute the file holds.
#pragma once

#include <hdf5.h>

#include <limits>
#include <set>
#include <string>
#include <vector>

namespace soadyn::test {

// A read-only HDF5 file, closed on scope exit.
class H5File {
 public:
  explicit H5File(const std::string& path) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    id = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  }
  ~H5File() {
    if (id >= 0) H5Fclose(id);
  }
  H5File(const H5File&) = delete;
  H5File& operator=(const H5File&) = delete;
  hid_t id = -1;
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
  const hid_t d = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  if (d < 0) return t;
  const hid_t space = H5Dget_space(d);
  hsize_t* dims = t.dims;
  const int rank = H5Sget_simple_extent_ndims(space);
  if (rank < 1 || rank > 3) {
    H5Sclose(space);
    H5Dclose(d);
    return t;
  }
  H5Sget_simple_extent_dims(space, dims, nullptr);
  t.rank = rank;
  t.rows = dims[0];
  t.cols = rank == 3 ? dims[1] * dims[2] : rank == 2 ? dims[1] : 0;
  t.values.resize(t.rows * (t.cols ? t.cols : 1));
  t.found = t.values.empty() || H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, t.values.data()) >= 0;
  H5Sclose(space);
  H5Dclose(d);
  return t;
}

// a one-dimensional dataset of fixed-length strings
inline std::vector<std::string> read_strings(hid_t file, const std::string& path) {
  std::vector<std::string> out;
  const hid_t d = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  if (d < 0) return out;
  const hid_t type = H5Dget_type(d), space = H5Dget_space(d);
  hsize_t n = 0;
  H5Sget_simple_extent_dims(space, &n, nullptr);
  const size_t width = H5Tget_size(type);
  std::vector<char> buf(width * n);
  if (n > 0 && H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) >= 0)
    for (hsize_t i = 0; i < n; ++i) {
      const std::string s(buf.data() + i * width, width);
      out.push_back(s.substr(0, s.find('\0')));
    }
  H5Sclose(space);
  H5Tclose(type);
  H5Dclose(d);
  return out;
}

// a one-dimensional dataset or attribute of variable-length strings; {"(missing)"} if absent
inline std::vector<std::string> read_vlen_strings(hid_t obj, bool attribute) {
  const hid_t type = attribute ? H5Aget_type(obj) : H5Dget_type(obj);
  const hid_t space = attribute ? H5Aget_space(obj) : H5Dget_space(obj);
  std::vector<std::string> out;
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  if (H5Tget_class(type) == H5T_STRING && H5Tis_variable_str(type) > 0 && H5Sget_simple_extent_ndims(space) == 1) {
    const hid_t mem = H5Tcopy(H5T_C_S1);
    H5Tset_size(mem, H5T_VARIABLE);
    H5Tset_cset(mem, H5Tget_cset(type));
    std::vector<char*> p(size_t(n), nullptr);
    const herr_t ok = n == 0 ? 0 : attribute ? H5Aread(obj, mem, p.data()) : H5Dread(obj, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, p.data());
    for (char* c : p) {
      if (ok >= 0) out.push_back(c ? c : "");
      H5free_memory(c);
    }
    H5Tclose(mem);
  } else {
    out.push_back("(not a list of variable-length strings)");
  }
  H5Sclose(space);
  H5Tclose(type);
  return out;
}

inline std::vector<std::string> string_list_attribute(hid_t file, const std::string& path, const std::string& name) {
  const hid_t a = H5Aopen_by_name(file, path.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
  if (a < 0) return {"(missing)"};
  std::vector<std::string> out = read_vlen_strings(a, true);
  H5Aclose(a);
  return out;
}

inline std::vector<std::string> string_list_dataset(hid_t file, const std::string& path) {
  const hid_t d = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  if (d < 0) return {"(missing)"};
  std::vector<std::string> out = read_vlen_strings(d, false);
  H5Dclose(d);
  return out;
}

// a one-dimensional numeric attribute; empty if absent
inline std::vector<double> numbers_attribute(hid_t file, const std::string& path, const std::string& name) {
  const hid_t a = H5Aopen_by_name(file, path.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
  if (a < 0) return {};
  const hid_t space = H5Aget_space(a);
  std::vector<double> out(size_t(H5Sget_simple_extent_npoints(space)));
  if (!out.empty()) H5Aread(a, H5T_NATIVE_DOUBLE, out.data());
  H5Sclose(space);
  H5Aclose(a);
  return out;
}

// a scalar dataset: a string (fixed length, null-padded) or a number; "(missing)" / NaN if absent
inline std::string scalar_text(hid_t file, const std::string& path) {
  const hid_t d = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  if (d < 0) return "(missing)";
  const hid_t type = H5Dget_type(d);
  std::string s = "(not a string)";
  if (H5Tget_class(type) == H5T_STRING && H5Tis_variable_str(type) <= 0) {
    s.assign(H5Tget_size(type), '\0');
    H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, s.data());
    s = s.substr(0, s.find('\0'));
  }
  H5Tclose(type);
  H5Dclose(d);
  return s;
}

inline double scalar_number(hid_t file, const std::string& path) {
  double x = std::numeric_limits<double>::quiet_NaN();
  const hid_t d = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  if (d < 0) return x;
  H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, &x);
  H5Dclose(d);
  return x;
}

// the type class of a dataset (H5T_INTEGER, H5T_FLOAT, H5T_STRING; H5T_NO_CLASS if absent)
inline H5T_class_t dataset_class(hid_t file, const std::string& path) {
  const hid_t d = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  if (d < 0) return H5T_NO_CLASS;
  const hid_t type = H5Dget_type(d);
  const H5T_class_t c = H5Tget_class(type);
  H5Tclose(type);
  H5Dclose(d);
  return c;
}

// attribute `name` of the object at `path`: a string, or a number; "(missing)" / NaN if absent
inline std::string string_attribute(hid_t file, const std::string& path, const std::string& name) {
  const hid_t a = H5Aopen_by_name(file, path.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
  if (a < 0) return "(missing)";
  const hid_t type = H5Aget_type(a);
  const hid_t space = H5Aget_space(a);
  const bool scalar = H5Sget_simple_extent_type(space) == H5S_SCALAR;
  H5Sclose(space);
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
  H5Tclose(type);
  H5Aclose(a);
  return s;
}

inline double number_attribute(hid_t file, const std::string& path, const std::string& name) {
  double x = std::numeric_limits<double>::quiet_NaN();
  const hid_t a = H5Aopen_by_name(file, path.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
  if (a < 0) return x;
  const hid_t type = H5Aget_type(a);
  if (H5Tget_class(type) == H5T_INTEGER || H5Tget_class(type) == H5T_FLOAT) H5Aread(a, H5T_NATIVE_DOUBLE, &x);
  H5Tclose(type);
  H5Aclose(a);
  return x;
}

// the class of a numeric attribute: H5T_INTEGER or H5T_FLOAT (H5T_NO_CLASS if absent)
inline H5T_class_t attribute_class(hid_t file, const std::string& path, const std::string& name) {
  const hid_t a = H5Aopen_by_name(file, path.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
  if (a < 0) return H5T_NO_CLASS;
  const hid_t type = H5Aget_type(a);
  const H5T_class_t c = H5Tget_class(type);
  H5Tclose(type);
  H5Aclose(a);
  return c;
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
      const hid_t o = H5Oopen(group, name, H5P_DEFAULT);
      if (o >= 0) {
        static_cast<Walk*>(op)->attributes_of(o, "/" + std::string(name));
        H5Oclose(o);
      }
      return 0;
    }
  } walk;
  walk.attributes_of(file, "/");
  H5Lvisit(file, H5_INDEX_NAME, H5_ITER_INC, &Walk::link, &walk);
  return walk.found;
}

}  // namespace soadyn::test
