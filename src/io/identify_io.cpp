// Identification's inputs and outputs (identify.hpp): a run file's samples checked against the
// scene, the unidentifiable directions as text, and the fitted scene's YAML.
#include "soadyn/sim/identify.hpp"
#include "soadyn/io/table_file.hpp"

#include "soadyn/io/output_file.hpp"
#include "soadyn/multibody/text.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

namespace soadyn {

namespace fs = std::filesystem;

namespace {

std::string join_names(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + printable(n);
  return out;
}

}  // namespace

Measurements read_measurements(const std::string& path, const Model& model) {
  const RunState s = read_run_state(path);
  const std::vector<std::string> names = model.q_names();
  if (s.q_names != names)
    throw Error(path + ": /q: the run's joints (" + join_names(s.q_names) + ") are not the scene's (" + join_names(names) + ")");
  if (s.qd.size() == 0) throw Error(path + ": dataset /qd is missing (a run logged without the state group?)");
  Measurements d;
  d.path = path;
  d.t = s.time;
  d.q = s.q;
  d.v = s.qd;
  d.qdd = s.qdd;
  return d;
}

std::string describe_direction(const IdentifyResult& r, int k) {
  const auto n = r.unidentifiable.col(k);
  const double top = n.cwiseAbs().maxCoeff();
  std::string out;
  for (Eigen::Index j = 0; j < n.size(); ++j) {
    if (std::abs(n(j)) <= 1e-6 * top) continue;
    char c[32];
    std::snprintf(c, sizeof c, "%.4g", std::abs(n(j)));
    out += out.empty() ? (n(j) < 0 ? "-" : "") : (n(j) < 0 ? " - " : " + ");
    if (std::string(c) != "1") out += std::string(c) + " ";
    out += r.names[size_t(j)];
  }
  return out;
}

namespace {

YAML::Node flow_list(std::initializer_list<double> xs) {
  YAML::Node n(YAML::NodeType::Sequence);
  n.SetStyle(YAML::EmitterStyle::Flow);
  for (double x : xs) n.push_back(exact_number(x));  // %.17g: the double itself when read back
  return n;
}

}  // namespace

std::string fitted_scenario_text(const Scenario& sc, const IdentifyResult& r, const std::string& output) {
  const bool robot_file = [&] {
    const std::string ext = fs::path(sc.path).extension().string();
    return ext == ".urdf" || ext == ".URDF" || ext == ".xml";
  }();
  // the robot file's path as seen from the output's directory
  const fs::path out_dir = fs::absolute(fs::path(output)).parent_path();
  const auto relocated = [&](const std::string& rel) {
    const fs::path from = fs::absolute(fs::path(sc.path)).parent_path() / rel;
    return fs::path(rel).is_absolute() ? rel : fs::relative(from, out_dir).lexically_normal().string();
  };
  YAML::Node root;
  if (robot_file) {
    root["urdf"] = relocated(fs::path(sc.path).filename().string());
    if (!sc.model.parent.empty() && sc.model.joint_type[0] == JointType::Free) root["free_root"] = true;
  } else {
    root = YAML::Load(sc.text);
    for (const char* key : {"urdf", "model"})
      if (root[key]) root[key] = relocated(root[key].Scalar());
  }
  YAML::Node inertial = root["inertial"] ? root["inertial"] : YAML::Node(YAML::NodeType::Map);
  for (const int i : r.bodies) {
    const Model& m = r.model;
    YAML::Node b(YAML::NodeType::Map);
    b.SetStyle(YAML::EmitterStyle::Flow);
    const Vec3& c = m.com[size_t(i)];
    const Mat3& I = m.inertia[size_t(i)];
    b["mass"] = exact_number(m.mass[size_t(i)]);
    b["com"] = flow_list({c.x(), c.y(), c.z()});
    YAML::Node rows(YAML::NodeType::Sequence);
    rows.SetStyle(YAML::EmitterStyle::Flow);
    for (int k = 0; k < 3; ++k) rows.push_back(flow_list({I(k, 0), I(k, 1), I(k, 2)}));
    b["inertia"] = rows;
    inertial[m.body_names[size_t(i)]] = b;
  }
  root["inertial"] = inertial;
  YAML::Emitter e;
  e << root;
  std::string head = std::string(kFittedScenarioHeader) + " (" + r.method + ") from " + sc.path + "\n" +
                     "# mass, com and inertia about the com of the fitted bodies in `inertial:`; comments of the scene are not kept\n";
  return head + e.c_str() + "\n";
}

}  // namespace soadyn
