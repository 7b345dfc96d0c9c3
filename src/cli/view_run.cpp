// soadyn view: a run file read back, and the model rebuilt from the scenario stored in it.
#include "h5id.hpp"
#include "view.hpp"

#include "soadyn/h5log.hpp"
#include "soadyn/mjcf.hpp"
#include "soadyn/scenario.hpp"

#include <hdf5.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <memory>

namespace soadyn::cli::view {

namespace {

using h5::Id;

bool exists(hid_t file, const std::string& name) {
  // each link of the path must exist before the next is asked about
  std::string at;
  size_t from = 1;
  while (true) {
    const size_t slash = name.find('/', from);
    at = name.substr(0, slash);
    if (H5Lexists(file, at.c_str(), H5P_DEFAULT) <= 0) return false;
    if (slash == std::string::npos) return true;
    from = slash + 1;
  }
}

// a string held by an attribute or a dataset, fixed-length or variable-length
std::string read_string(hid_t obj, bool attribute, const std::string& where) {
  Id type(attribute ? H5Aget_type(obj) : H5Dget_type(obj), H5Tclose);
  if (!type.ok() || H5Tget_class(type) != H5T_STRING) throw Error(where + ": expected a string");
  Id space(attribute ? H5Aget_space(obj) : H5Dget_space(obj), H5Sclose);
  if (H5Sget_simple_extent_npoints(space) != 1) throw Error(where + ": expected one string");
  auto read = [&](hid_t mem, void* buf) {
    return attribute ? H5Aread(obj, mem, buf) : H5Dread(obj, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf);
  };
  if (H5Tis_variable_str(type) > 0) {
    Id mem(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(mem, H5T_VARIABLE);
    H5Tset_cset(mem, H5Tget_cset(type));  // HDF5 converts no string between character sets
    char* text = nullptr;
    if (read(mem, &text) < 0) throw Error(where + ": cannot be read (corrupt or truncated file?)");
    std::unique_ptr<char, herr_t (*)(void*)> owner(text, H5free_memory);
    return text ? std::string(text) : std::string();
  }
  const size_t n = H5Tget_size(type);
  std::string text(n, '\0');
  if (read(type, text.data()) < 0) throw Error(where + ": cannot be read (corrupt or truncated file?)");
  return text.substr(0, text.find('\0'));
}

std::string string_attribute(hid_t obj, const char* name, const std::string& where) {
  if (H5Aexists(obj, name) <= 0) return {};
  Id a(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
  return read_string(a, true, where + ": attribute '" + name + "'");
}

// the strings of an attribute of variable-length strings (empty if the object or the attribute is
// absent, or it holds anything else)
std::vector<std::string> string_list_attribute(hid_t file, const char* object, const char* name) {
  std::vector<std::string> out;
  if (!exists(file, object) || H5Aexists_by_name(file, object, name, H5P_DEFAULT) <= 0) return out;
  Id a(H5Aopen_by_name(file, object, name, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!a.ok()) return out;
  Id type(H5Aget_type(a), H5Tclose);
  Id space(H5Aget_space(a), H5Sclose);
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  if (H5Tget_class(type) != H5T_STRING || H5Tis_variable_str(type) <= 0 || n <= 0) return out;
  Id mem(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(mem, H5T_VARIABLE);
  H5Tset_cset(mem, H5Tget_cset(type));
  std::vector<char*> names(size_t(n), nullptr);
  if (H5Aread(a, mem, names.data()) < 0) return out;
  for (char* p : names) {
    out.push_back(p ? p : "");
    H5free_memory(p);
  }
  return out;
}

// a T or T×cols dataset of numbers, as a row-major T×cols matrix
MatX read_matrix(hid_t file, const std::string& name, const std::string& path) {
  const std::string where = path + ": dataset " + name;
  Id d(H5Dopen2(file, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!d.ok()) throw Error(where + ": cannot be opened (corrupt or truncated file?)");
  Id space(H5Dget_space(d), H5Sclose);
  hsize_t dims[2] = {0, 1};
  const int rank = H5Sget_simple_extent_ndims(space);
  if (rank < 1 || rank > 2) throw Error(where + ": expected 1 or 2 dimensions, got " + std::to_string(rank));
  H5Sget_simple_extent_dims(space, dims, nullptr);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> m(dims[0], rank == 2 ? dims[1] : 1);
  if (m.size() > 0 && H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, m.data()) < 0)
    throw Error(where + ": cannot be read (corrupt or truncated file?)");
  return m;
}

}  // namespace

RunFile read_run(const std::string& path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // our messages, not HDF5's stack dumps
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw Error(path + ": no such run file");
  Id file(hid_t(open_run_file(path)), H5Fclose);

  RunFile r;
  r.path = path;
  // the scenario's text: a dataset /scenario, or (files written before it) a root attribute
  if (H5Aexists(file, "scenario") > 0) {
    r.scenario_text = string_attribute(file, "scenario", path);
  } else if (exists(file, "/scenario")) {
    Id d(H5Dopen2(file, "/scenario", H5P_DEFAULT), H5Dclose);
    r.scenario_text = read_string(d, false, path + ": dataset /scenario");
  }
  if (r.scenario_text.empty()) throw Error(path + ": no scenario stored in the file (not a run file from soadyn run?)");
  r.scenario_path = string_attribute(file, "scenario_path", path);
  r.version = string_attribute(file, "soadyn_version", path);
  if (exists(file, "/solver")) {
    Id g(H5Gopen2(file, "/solver", H5P_DEFAULT), H5Gclose);
    r.method = string_attribute(g, "method", path + ": /solver");
    r.status = string_attribute(g, "status", path + ": /solver");
  }
  if (r.status.empty() && exists(file, "/solver/status")) {  // a dataset, rewritten at every flush
    Id d(H5Dopen2(file, "/solver/status", H5P_DEFAULT), H5Dclose);
    r.status = read_string(d, false, path + ": /solver/status");
  }
  for (const char* name : {"/time", "/q"})
    if (!exists(file, name)) throw Error(path + ": dataset " + name + " is missing (a run logged without the state group, --log, or not a run file from soadyn run)");
  r.time = read_matrix(file, "/time", path).col(0);
  r.q = read_matrix(file, "/q", path);
  if (exists(file, "/energy/kinetic")) r.kinetic = read_matrix(file, "/energy/kinetic", path).col(0);
  if (exists(file, "/energy/total")) r.total = read_matrix(file, "/energy/total", path).col(0);
  if (exists(file, "/energy/work_inputs")) r.work = read_matrix(file, "/energy/work_inputs", path).col(0);
  if (exists(file, "/energy/impact_loss")) r.impact_loss = read_matrix(file, "/energy/impact_loss", path).col(0);

  // rows: as many as every series has (a run stopped mid-write keeps whole rows only)
  Eigen::Index rows = std::min(r.time.size(), r.q.rows());
  for (const VecX* s : {&r.kinetic, &r.total, &r.work, &r.impact_loss})
    if (s->size()) rows = std::min(rows, s->size());
  if (rows == 0) throw Error(path + ": the run logged no samples");
  keep_rows(r, rows);
  for (Eigen::Index k = 1; k < rows; ++k)
    if (!(r.time(k) >= r.time(k - 1))) throw Error(path + ": /time decreases at row " + std::to_string(k));

  if (exists(file, "/model") && H5Aexists_by_name(file, "/model", "joint_names", H5P_DEFAULT) > 0) {
    // layout 3: an attribute of variable-length strings
    r.joint_names = string_list_attribute(file, "/model", "joint_names");
  } else if (exists(file, "/model/joint_names")) {  // layout 2: a dataset of fixed-length strings
    Id d(H5Dopen2(file, "/model/joint_names", H5P_DEFAULT), H5Dclose);
    Id type(H5Dget_type(d), H5Tclose);
    Id space(H5Dget_space(d), H5Sclose);
    const hssize_t n = H5Sget_simple_extent_npoints(space);
    if (H5Tget_class(type) == H5T_STRING && H5Tis_variable_str(type) <= 0 && n > 0) {
      const size_t width = H5Tget_size(type);
      std::vector<char> buf(width * size_t(n));
      if (H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) >= 0)
        for (hssize_t i = 0; i < n; ++i) {
          std::string s(buf.data() + i * width, width);
          r.joint_names.push_back(s.substr(0, s.find('\0')));
        }
    }
  }
  r.v_names = string_list_attribute(file, "/model", "v_names");
  if (exists(file, "/events")) {  // E×7: t, dof, side, kind, v_before, v_after, energy_lost
    const MatX e = read_matrix(file, "/events", path);
    if (e.rows() > 0 && e.cols() != 7)
      throw Error(path + ": dataset /events: expected 7 columns, got " + std::to_string(e.cols()));
    for (Eigen::Index k = 0; k < e.rows(); ++k) {
      const bool dof_ok = std::isfinite(e(k, 1)) && e(k, 1) >= 0 && (r.v_names.empty() || e(k, 1) < double(r.v_names.size()));
      if (!std::isfinite(e(k, 0)) || !dof_ok)
        throw Error(path + ": dataset /events: row " + std::to_string(k) + " names no time or joint of the model");
      r.events.push_back({e(k, 0), int(e(k, 1)), e(k, 2) < 0 ? -1 : 1, std::isfinite(e(k, 3)) ? int(e(k, 3)) : -1, e(k, 4),
                          e(k, 5), e(k, 6)});
    }
  }
  if (exists(file, "/frames/names")) {  // a dataset of variable-length strings (h5log.cpp)
    const std::string where = path + ": dataset /frames/names";
    Id d(H5Dopen2(file, "/frames/names", H5P_DEFAULT), H5Dclose);
    Id type(H5Dget_type(d), H5Tclose);
    Id space(H5Dget_space(d), H5Sclose);
    const hssize_t n = H5Sget_simple_extent_npoints(space);
    if (!type.ok() || H5Tget_class(type) != H5T_STRING || H5Tis_variable_str(type) <= 0)
      throw Error(where + ": expected variable-length strings");
    if (n > 0) {
      Id mem(H5Tcopy(H5T_C_S1), H5Tclose);
      H5Tset_size(mem, H5T_VARIABLE);
      H5Tset_cset(mem, H5Tget_cset(type));
      std::vector<char*> names(size_t(n), nullptr);
      if (H5Dread(d, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, names.data()) < 0)
        throw Error(where + ": cannot be read (corrupt or truncated file?)");
      for (char* p : names) {
        r.frame_names.push_back(p ? p : "");
        H5free_memory(p);
      }
    }
  }
  return r;
}

void keep_rows(RunFile& run, Eigen::Index rows) {
  run.time.conservativeResize(rows);
  run.q.conservativeResize(rows, Eigen::NoChange);
  for (VecX* s : {&run.kinetic, &run.total, &run.work, &run.impact_loss})
    if (s->size()) s->conservativeResize(rows);
}

RunModel rebuild_model(const RunFile& run) {
  const std::string label = run.scenario_path.empty() ? run.path + ":scenario" : run.scenario_path;
  RunModel out;
  try {
    const std::string ext = std::filesystem::path(label).extension().string();
    if (ext == ".xml" && is_mjcf_text(run.scenario_text)) {
      // `soadyn run robot.xml`: an MJCF model, compiled from its file when it is still the one the
      // run used (so its <include>s resolve), else from the stored text
      std::error_code ec;
      const bool same = std::filesystem::is_regular_file(label, ec) && read_text_file(label) == run.scenario_text;
      MjcfOptions mo;
      mo.inertia_check = InertiaCheck::Balance;
      out.model = parse_mjcf(run.scenario_text, label, same, mo).model;
      if (run.q.cols() == out.model.nq + 7) {  // run with --free-root
        mo.free_root = true;
        out.model = parse_mjcf(run.scenario_text, label, same, mo).model;
      }
      out.name = std::filesystem::path(label).stem().string();
      out.urdf_text = run.scenario_text;  // its geoms are drawn (view_scene.cpp)
      out.urdf_path = label;
    } else if (ext == ".urdf" || ext == ".URDF" || ext == ".xml") {
      // `soadyn run robot.urdf [--free-root]`: the stored text is the URDF, run with the default
      // gravity; a free root shows as the 7 more columns of q its free joint has.  (The view draws
      // poses only: inertias are balanced rather than refused whatever the run was told.)
      const InertiaCheck any = InertiaCheck::Balance;
      out.model = parse_urdf(run.scenario_text, label, false, Vec3(0, 0, -9.81), any);
      if (run.q.cols() == out.model.nq + 7) out.model = parse_urdf(run.scenario_text, label, true, Vec3(0, 0, -9.81), any);
      out.name = std::filesystem::path(label).stem().string();
      out.urdf_text = run.scenario_text;
      out.urdf_path = label;
    } else {
      const Scenario sc = parse_scenario(run.scenario_text, label, false, InertiaCheck::Balance);
      out.model = sc.model;
      out.name = sc.name;
      out.description = sc.description;
      out.has_work_inputs = !sc.inputs.torques.empty() || !sc.inputs.dampers.empty();
      // the URDF a scenario names, relative to the scenario file (parse_scenario has just read it)
      const YAML::Node root = YAML::Load(sc.text);
      if (const YAML::Node robot = root["model"] ? root["model"] : root["urdf"]) {
        const std::filesystem::path p = std::filesystem::path(label).parent_path() / robot.as<std::string>();
        std::error_code ec;
        if (std::filesystem::is_regular_file(p, ec)) {
          out.urdf_text = read_text_file(p.string());
          out.urdf_path = p.string();
        }
      }
    }
  } catch (const Error& e) {
    throw Error(run.path + ": cannot rebuild the run's model from the scenario stored in it (" + e.what() +
                "); run soadyn view from the directory the run was made in, with the scenario's files in place");
  }
  const Model& m = out.model;
  if (run.q.cols() != m.nq)
    throw Error(run.path + ": /q has " + std::to_string(run.q.cols()) + " columns but the scenario's model has nq = " +
                std::to_string(m.nq) + " (did " + label + " or its URDF change since the run?)");
  if (!run.joint_names.empty() && run.joint_names != m.joint_names)
    throw Error(run.path + ": the joints logged in /model/joint_names differ from the rebuilt model's (did " + label +
                " or its URDF change since the run?)");
  for (const std::string& f : run.frame_names)
    if (m.frame_index(f) < 0)
      throw Error(run.path + ": /frames/names has '" + f + "', a frame the rebuilt model does not have (did " + label +
                  " or its URDF change since the run?)");
  return out;
}

}  // namespace soadyn::cli::view
