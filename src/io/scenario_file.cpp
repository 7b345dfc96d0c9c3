#include "soadyn/io/scenario_file.hpp"

#include "soadyn/io/input_file.hpp"
#include "soadyn/sim/integrators.hpp"
#include "soadyn/io/mjcf.hpp"
#include "soadyn/multibody/text.hpp"
#include "soadyn/multibody/configuration.hpp"

#include "mjcf_files.hpp"
#include "scenario_reader.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <string_view>

namespace soadyn {

namespace {

using scenario_detail::BodyNodes;
using scenario_detail::build_located;
using scenario_detail::find_joint;
using scenario_detail::read_bodies;
using scenario_detail::Reader;



void read_initial(const Reader& rd, const YAML::Node& n, const Model& m, VecX& q0, VecX& v0) {
  rd.keys(n, "initial", {"q", "qd"});
  for (const char* part : {"q", "qd"}) {
    const YAML::Node values = n[part];
    if (!values) continue;
    const std::string f = std::string("initial.") + part;
    if (!values.IsMap()) rd.fail(values, f, "expected a map from joint name to value, got " + Reader::show(values));
    const bool is_q = std::string(part) == "q";
    for (auto it = values.begin(); it != values.end(); ++it) {
      const int i = find_joint(rd, m, it->first, f);
      const std::string fj = f + "." + it->first.Scalar();
      const int size = is_q ? m.nq_i[i] : m.nv_i[i];
      VecX x = size == 1 && it->second.IsScalar() ? VecX::Constant(1, rd.number(it->second, fj))
                                                   : rd.numbers(it->second, fj, size);
      for (Eigen::Index k = 0; k < x.size(); ++k)
        if (std::abs(x(k)) > kMaxStateMagnitude)
          rd.fail(it->second, fj, "expected |value| <= " + Reader::show_number(kMaxStateMagnitude) + " (m, rad, m/s or rad/s), got " +
                                      Reader::show_number(x(k)) + ": a double resolves no finer than 1e-10 of it there");
      if (const int k = joint_quaternion(m, i); is_q && k >= 0) {
        const double norm = x.segment<4>(k).norm();
        if (std::abs(norm - 1.0) > 1e-6)
          rd.fail(it->second, fj, "expected a unit quaternion [w, x, y, z]" + std::string(k ? " after the position" : "") +
                                      ", got norm " + [&] {
                                        char got[32];
                                        std::snprintf(got, sizeof got, "%g", norm);
                                        return std::string(got);
                                      }());
        x.segment<4>(k) /= norm;
      }
      (is_q ? q0.segment(m.idx_q[i], size) : v0.segment(m.idx_v[i], size)) = x;
    }
  }
}

void read_simulation(const Reader& rd, const YAML::Node& n, const Model& m, SimulationSettings& s) {
  std::vector<std::string> keys;
  for (const SettingInfo& info : setting_table()) keys.emplace_back(info.name);
  keys.emplace_back("sensitivities");
  rd.keys(n, "simulation", keys);
  if (n["sensitivities"]) scenario_detail::read_sensitivities(rd, n["sensitivities"], m, s.sensitivities);
  // every other key by the table: its kind, its range or words (settings.cpp)
  for (const SettingInfo& info : setting_table()) {
    const std::string key(info.name), field = "simulation." + key;
    const YAML::Node v = n[key];
    if (!v) continue;
    switch (info.kind) {
      case SettingKind::Real:
      case SettingKind::Count: {
        const double x = rd.number(v, field);
        if (const std::string p = setting_problem(info, x); !p.empty()) rd.fail(v, field, p + ", got " + Reader::show(v));
        set_setting(s, info, x);
        break;
      }
      case SettingKind::Word: {
        const std::string w = rd.string(v, field);
        if (const std::string p = setting_problem(info, w); !p.empty()) rd.fail(v, field, p);
        set_setting(s, info, w);
        break;
      }
      case SettingKind::Flag: set_setting(s, info, rd.boolean(v, field)); break;
    }
  }
  // control ticks over the file's t_end (or the default): bounded as steps and rows are
  if (const YAML::Node v = n["control_dt"])
    if (const std::string p = control_ticks_problem(s.t_end, s.control_dt); !p.empty()) rd.fail(v, "simulation.control_dt", p);
}

void read_inputs(const Reader& rd, const YAML::Node& n, const Model& m, const VecX& q0, Inputs& in) {
  rd.keys(n, "inputs", {"torques", "springs", "dampers", "controllers"});
  if (n["controllers"]) scenario_detail::read_controllers(rd, n["controllers"], m, q0, in.controllers);
  auto each = [&](const char* part, auto&& read_one) {
    const YAML::Node list = n[part];
    if (!list) return;
    const std::string f = std::string("inputs.") + part;
    if (!list.IsSequence()) rd.fail(list, f, "expected a list, got " + Reader::show(list));
    for (size_t k = 0; k < list.size(); ++k) {
      const std::string fk = f + "[" + std::to_string(k) + "]";
      const YAML::Node e = list[k];
      if (!e.IsMap()) rd.fail(e, fk, "expected a map, got " + Reader::show(e));
      const YAML::Node jn = rd.require(e, "joint", fk);
      const int i = find_joint(rd, m, jn, fk + ".joint");
      if (m.nv_i[i] != 1)
        rd.fail(jn, fk + ".joint", "inputs act on revolute or prismatic joints; '" + excerpt(jn.Scalar()) + "' is " +
                                       std::string(to_string(m.joint_type[i])));
      read_one(e, fk, i);
    }
  };
  each("torques", [&](const YAML::Node& e, const std::string& f, int i) {
    rd.keys(e, f, {"joint", "constant", "amplitude", "frequency", "phase"});
    TorqueInput t{m.joint_names[i], m.idx_v[i]};
    if (e["constant"]) t.constant = rd.number(e["constant"], f + ".constant");
    if (e["amplitude"]) t.amplitude = rd.number(e["amplitude"], f + ".amplitude");
    if (e["frequency"]) t.frequency = rd.number(e["frequency"], f + ".frequency");
    if (e["phase"]) t.phase = rd.number(e["phase"], f + ".phase");
    in.torques.push_back(t);
  });
  each("springs", [&](const YAML::Node& e, const std::string& f, int i) {
    rd.keys(e, f, {"joint", "stiffness", "rest"});
    SpringInput s{m.joint_names[i], m.idx_v[i], m.idx_q[i]};
    s.stiffness = rd.number(rd.require(e, "stiffness", f), f + ".stiffness");
    if (s.stiffness < 0) rd.fail(e["stiffness"], f + ".stiffness", "expected a stiffness >= 0");
    if (e["rest"]) s.rest = rd.number(e["rest"], f + ".rest");
    in.springs.push_back(s);
  });
  each("dampers", [&](const YAML::Node& e, const std::string& f, int i) {
    rd.keys(e, f, {"joint", "damping"});
    DamperInput d{m.joint_names[i], m.idx_v[i]};
    d.damping = rd.number(rd.require(e, "damping", f), f + ".damping");
    if (d.damping < 0) rd.fail(e["damping"], f + ".damping", "expected a damping >= 0");
    in.dampers.push_back(d);
  });
}

// frames: {name: {body, position, rpy}}: a named frame placed on a body, or on any frame the model
// has (a link merged by a fixed joint, an earlier entry), or on the world
void read_frames(const Reader& rd, const YAML::Node& n, Model& m) {
  if (!n.IsMap()) rd.fail(n, "frames", "expected a map from frame name to {body, position, rpy}, got " + Reader::show(n));
  for (auto it = n.begin(); it != n.end(); ++it) {
    const std::string name = rd.string(it->first, "frames");
    const std::string f = "frames." + printable(name);
    rd.keys(it->second, f, {"body", "position", "rpy"});
    const YAML::Node body = rd.require(it->second, "body", f);
    const std::string on = rd.string(body, f + ".body");
    Placement X;
    int b = -1;
    if (on != "world") {
      const int at = m.frame_index(on);
      if (at < 0) {
        std::vector<std::string> names = m.frame_names;
        names.push_back("world");
        rd.fail(body, f + ".body", "no body or frame named '" + excerpt(on) + "'" + did_you_mean(on, names));
      }
      b = m.frame_body[at];
      X = m.frame_placement[at];
    }
    Placement local;
    if (it->second["position"]) local.p = rd.vec3(it->second["position"], f + ".position");
    if (it->second["rpy"]) local.R = Reader::rpy(rd.vec3(it->second["rpy"], f + ".rpy"));
    if (m.frame_index(name) >= 0) rd.fail(it->first, f, "the model already has a frame named '" + excerpt(name) + "' (a body or a merged link)");
    try {
      m.add_frame(name, b, compose(X, local));
    } catch (const Error& e) {
      rd.fail(it->first, f, e.what());
    }
  }
}

// log: {frames: [name, …]}: frames (of the model or of `frames:`) whose poses a run file logs
void read_log_section(const Reader& rd, const YAML::Node& n, const Model& m, std::vector<std::string>& out) {
  rd.keys(n, "log", {"frames"});
  const YAML::Node list = n["frames"];
  if (!list) return;
  if (!list.IsSequence()) rd.fail(list, "log.frames", "expected a list of frame names, got " + Reader::show(list));
  for (size_t k = 0; k < list.size(); ++k) {
    const std::string f = "log.frames[" + std::to_string(k) + "]";
    const std::string name = rd.string(list[k], f);
    if (m.frame_index(name) < 0) rd.fail(list[k], f, "no frame named '" + excerpt(name) + "'" + did_you_mean(name, m.frame_names));
    if (std::find(out.begin(), out.end(), name) != out.end()) rd.fail(list[k], f, "frame '" + excerpt(name) + "' listed twice");
    out.push_back(name);
  }
}

bool is_urdf_path(const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  return ext == ".urdf" || ext == ".URDF" || ext == ".xml";
}

}  // namespace

std::string read_text_file(const std::string& path) {
  // a regular file only, never waited on (input_file.hpp)
  const std::string text = InputFile(path, "a scenario or model file (YAML, URDF or MJCF)", kMaxInputBytes).read();
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) throw Error(path + ": the file is empty");
  if (text.find('\0') != std::string::npos) throw Error(path + ": a binary file, expected text (YAML or URDF)");
  return text;
}

bool mjcf_file_unchanged(const std::string& path, const std::string& stored_text) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  try {
    return read_text_file(path) == stored_text;
  } catch (const Error&) {
    return false;
  }
}

bool is_mjcf_text(const std::string& text) {
  // the first element after the prolog, comments and DOCTYPE
  size_t at = 0;
  while ((at = text.find('<', at)) != std::string::npos) {
    if (text.compare(at, 4, "<!--") == 0) {
      at = text.find("-->", at);
      if (at == std::string::npos) return false;
      continue;
    }
    if (text.compare(at, 2, "<?") == 0 || text.compare(at, 2, "<!") == 0) {
      ++at;
      continue;
    }
    return text.compare(at, 7, "<mujoco") == 0 &&
           (at + 7 >= text.size() || std::string(" \t\r\n>/").find(text[at + 7]) != std::string::npos);
  }
  return false;
}

std::optional<InertiaCheck> parse_inertia_check(const std::string& s) {
  if (s == "warn") return InertiaCheck::Warn;
  if (s == "balance") return InertiaCheck::Balance;
  if (s == "strict") return InertiaCheck::Strict;
  return std::nullopt;
}

namespace {

// A scenario's name: it names the default output, out/<name>.h5, so it must be one plain file-name
// component (no folder, no '.' or '..', no control characters), short enough for the file system
// with the output's ".h5", lock and temporary suffixes.
void check_name(const Reader& rd, const YAML::Node& n, const std::string& name) {
  std::string why;
  if (name.empty() || name == "." || name == "..") why = "it cannot be empty, '.' or '..'";
  else if (name.find_first_of("/\\") != std::string::npos) why = "it cannot hold '/' or '\\' (it would name another folder)";
  else if (std::any_of(name.begin(), name.end(), [](char c) { return (unsigned char)c < 0x20 || c == 0x7f; }))
    why = "it cannot hold control characters";
  else if (name.size() > 200) why = "at most 200 bytes, got " + std::to_string(name.size());
  if (why.empty()) return;
  const std::string shown = printable(name.substr(0, 80)) + (name.size() > 80 ? "..." : "");
  rd.fail(n, "name", "expected a plain file name, as it names the default output out/<name>.h5: " + why + "; got '" +
                         shown + "'");
}

// a scenario's inertia_check: warn | balance | strict (Model::build's InertiaCheck)
InertiaCheck read_inertia_check(const Reader& rd, const YAML::Node& n) {
  const std::string s = rd.string(n, "inertia_check");
  if (const auto c = parse_inertia_check(s)) return *c;
  rd.fail(n, "inertia_check", "expected warn, balance or strict, got '" + excerpt(s) + "'" +
                                  did_you_mean(s, {"warn", "balance", "strict"}));
}

// The scenario's one YAML document, a mapping: a second document, a syntax error, an empty file
// or one that is no mapping (another kind of file, named by mistake) is refused
YAML::Node load_root(const Reader& rd, const std::string& text, const std::string& path) {
  YAML::Node root;
  try {
    // a '---' at column 0 after content always starts another document (YAML 1.2, 9.2); yaml-cpp's
    // LoadAll is not used for this: fuzz_scenario found a 704-byte input it never returns from
    bool content = false;
    int line = 0;
    for (size_t at = 0; at < text.size(); ++line) {
      const size_t end = std::min(text.find('\n', at), text.size());
      const std::string_view l(text.data() + at, end - at);
      const bool marker = l.substr(0, 3) == "---" && (l.size() == 3 || l[3] == ' ' || l[3] == '\t' || l[3] == '\r');
      if (marker && content) {
        YAML::Mark m;
        m.line = line;
        m.column = 0;
        rd.fail(m, "YAML documents", "a second document ('---') would not be read: one scenario per file");
      }
      const size_t first = l.find_first_not_of(" \t\r");
      if (!marker && first != std::string_view::npos && l[first] != '#' && l.substr(0, 3) != "...") content = true;
      at = end + 1;
    }
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    rd.fail(e.mark, "YAML syntax", e.msg);
  }
  if (!root || root.IsNull()) throw Error(path + ": the file is empty");
  // a file that is no mapping (another kind of file, named by mistake) is not quoted back
  if (!root.IsMap())
    rd.fail(root, "scenario", "expected a mapping of a scenario's sections (bodies or model, simulation, …), got " +
                                  (root.IsScalar() ? "plain text (" + std::to_string(text.size()) + " bytes): is this a scenario file?"
                                                   : Reader::show(root)));
  return root;
}

// The robot file `urdf:` or `model:` names (robot_key; robot_text: its text as a run file stored
// it, model_files: an MJCF model's stored files): sc's model, robot text and files; an MJCF
// robot's MjcfModel (its drawn pose, dampers and springs), none for a URDF
std::optional<MjcfModel> read_robot(const Reader& rd, YAML::Node root, const char* robot_key, Scenario& sc,
                                    const Vec3& gravity, InertiaCheck check, bool free_root,
                                    const std::optional<std::string>& robot_text,
                                    const std::vector<ModelFile>* model_files) {
  const YAML::Node robot_node = root[robot_key];
  std::optional<MjcfModel> mjcf;
  const std::string rel = rd.string(robot_node, robot_key);
  const std::filesystem::path p = std::filesystem::path(sc.path).parent_path() / rel;
  const bool free = free_root || (root["free_root"] && rd.boolean(root["free_root"], "free_root"));
  try {
    // a URDF, or an MJCF file (MuJoCo's <mujoco>: its own gravity unless the scenario says one)
    sc.files.push_back(p.string());
    const std::string robot = robot_text ? *robot_text : read_text_file(p.string());
    sc.robot_text = robot;
    sc.robot_path = p.string();
    if (is_mjcf_text(robot)) {
      const std::optional<Vec3> g = root["gravity"] ? std::optional<Vec3>(gravity) : std::nullopt;
      const bool stored = robot_text && model_files && !model_files->empty();
      const bool from_disk = !stored && (!robot_text || mjcf_file_unchanged(p.string(), robot));
      mjcf = stored ? parse_mjcf_files(*model_files, p.string(), {free, g, check})
                    : parse_mjcf(robot, p.string(), from_disk, {free, g, check});
      sc.model_files = mjcf->files;
      if (from_disk)
        for (std::string& f : mjcf_files(robot, p.string())) sc.files.push_back(std::move(f));
      sc.model = mjcf->model;
    } else {
      sc.model = parse_urdf(robot, p.string(), free, gravity, check);
    }
  } catch (const Error& e) {
    rd.fail(robot_node, robot_key, e.what());
  }
  return mjcf;
}

}  // namespace

Scenario parse_scenario(const std::string& text, const std::string& path, bool free_root,
                        std::optional<InertiaCheck> inertia_check, const std::optional<std::string>& robot_text,
                        const std::vector<ModelFile>* model_files) {
  const Reader rd{path, {}};
  YAML::Node root = load_root(rd, text, path);
  rd.keys(root, "scenario", {"name", "description", "gravity", "bodies", "urdf", "model", "free_root", "frames", "log", "inertia_check", "initial", "simulation", "inputs", "limits", "inertial", "prescribed", "loops"});

  Scenario sc;
  sc.path = path;
  sc.text = text;
  sc.name = root["name"] ? rd.string(root["name"], "name") : std::filesystem::path(path).stem().string();
  if (root["name"]) check_name(rd, root["name"], sc.name);
  sc.files.push_back(path);
  if (root["description"]) sc.description = root["description"].as<std::string>("");
  // a URDF robot gets the URDF gravity wherever it enters; bodies written here get none by default
  // the robot file: `urdf:` or `model:` (the same key: a URDF or an MJCF file)
  if (root["urdf"] && root["model"]) rd.fail(root["model"], "model", "give either 'urdf' or 'model' (the same key), not both");
  const char* robot_key = root["model"] ? "model" : "urdf";
  const YAML::Node robot_node = root[robot_key];
  const Vec3 gravity = root["gravity"] ? rd.vec3(root["gravity"], "gravity") : robot_node ? urdf_gravity() : Vec3::Zero();
  // the caller's (--inertia-check) over the file's
  const InertiaCheck check = inertia_check ? *inertia_check
                             : root["inertia_check"] ? read_inertia_check(rd, root["inertia_check"])
                                                     : InertiaCheck::Warn;

  if (robot_node && root["bodies"])
    rd.fail(robot_node, robot_key, "give either 'bodies' or '" + std::string(robot_key) + "', not both");
  std::optional<MjcfModel> mjcf;  // an MJCF robot: its drawn pose, dampers and springs
  if (robot_node) {
    mjcf = read_robot(rd, root, robot_key, sc, gravity, check, free_root, robot_text, model_files);
  } else {
    if (root["free_root"]) rd.fail(root["free_root"], "free_root", "applies to 'urdf' models; give the root a free joint");
    const BodyNodes bodies = read_bodies(rd, rd.require(root, "bodies", "scenario"));
    if (free_root) throw Error(path + ": --free-root applies to URDF models; give the root body a free joint");
    sc.model = build_located(rd, bodies, gravity, check);
  }

  if (root["inertial"]) scenario_detail::read_inertial(rd, root["inertial"], sc.model);
  if (root["limits"]) scenario_detail::read_limits(rd, root["limits"], sc.model);
  if (root["frames"]) read_frames(rd, root["frames"], sc.model);
  if (root["log"]) read_log_section(rd, root["log"], sc.model, sc.log_frames);
  sc.q0 = mjcf ? mjcf->q0 : sc.model.neutral_configuration();
  sc.v0 = VecX::Zero(sc.model.nv);
  if (mjcf) {
    sc.inputs.dampers = mjcf->dampers;
    sc.inputs.springs = mjcf->springs;
    sc.inputs.loops = mjcf->loops;  // its connects and welds, before the scenario's own loops:
  }
  if (root["initial"]) read_initial(rd, root["initial"], sc.model, sc.q0, sc.v0);
  if (root["simulation"]) read_simulation(rd, root["simulation"], sc.model, sc.simulation);
  if (root["prescribed"])
    scenario_detail::read_prescribed(rd, root["prescribed"], root["initial"], sc.model, sc.q0, sc.v0, sc.inputs.prescribed);
  if (root["inputs"]) read_inputs(rd, root["inputs"], sc.model, sc.q0, sc.inputs);
  if (root["loops"]) scenario_detail::read_loops(rd, root["loops"], sc.model, sc.q0, sc.inputs.loops);
  // the initial state assembled onto every loop (the MJCF's and the file's), refused at loops: or
  // at the model that brought them
  if (!sc.inputs.loops.empty()) {
    const bool own = bool(root["loops"]);
    const VecX q_file = sc.q0, v_file = sc.v0;
    scenario_detail::assemble_loops(rd, own ? root["loops"] : robot_node, own ? "loops" : robot_key, root["initial"],
                                    sc.model, sc.inputs.loops, sc.q0, sc.v0);
    if (std::string note = scenario_detail::assembly_note(sc.model, q_file, v_file, sc.q0, sc.v0); !note.empty())
      sc.notes.push_back(std::move(note));
  }
  sc.files.insert(sc.files.end(), rd.files_read.begin(), rd.files_read.end());
  scenario_detail::record_locations(rd, root, sc);
  return sc;
}

Scenario load_scenario(const std::string& path, bool free_root, const std::optional<Vec3>& gravity,
                       std::optional<InertiaCheck> inertia_check) {
  const std::string text = read_text_file(path);
  Scenario sc;
  if (is_urdf_path(path)) {
    sc.path = path;
    sc.text = text;
    sc.name = std::filesystem::path(path).stem().string();
    sc.files.push_back(path);
    if (is_mjcf_text(text)) {
      MjcfModel mj = parse_mjcf(text, path, true, {free_root, gravity, inertia_check.value_or(InertiaCheck::Warn)});
      sc.files = mjcf_files(text, path);
      sc.files.insert(sc.files.begin(), path);
      sc.model_files = std::move(mj.files);
      sc.model = std::move(mj.model);
      sc.q0 = mj.q0;
      sc.inputs.dampers = mj.dampers;
      sc.inputs.springs = mj.springs;
      sc.v0 = VecX::Zero(sc.model.nv);
      // its connects and welds, the drawn pose closed on them (a weld's relpose may open it)
      sc.inputs.loops = std::move(mj.loops);
      if (!sc.inputs.loops.empty()) {
        const std::vector<char> none(size_t(sc.model.nv), 0);
        if (const double e = scenario_detail::close_on_loops(sc.model, sc.inputs.loops, none, none, sc.q0, sc.v0); e > kLoopClosure)
          throw Error(path + ": the drawn pose cannot be closed on the equality constraints (largest closure error " +
                      short_number(e) + " after 50 Newton steps): check their anchors and relpose");
      }
      return sc;
    }
    sc.model = parse_urdf(text, path, free_root, gravity.value_or(urdf_gravity()),
                          inertia_check.value_or(InertiaCheck::Warn));
    sc.q0 = sc.model.neutral_configuration();
    sc.v0 = VecX::Zero(sc.model.nv);
  } else {
    sc = parse_scenario(text, path, free_root, inertia_check);
    if (gravity) sc.model.gravity = *gravity;
  }
  return sc;
}

Model load_urdf(const std::string& path, bool free_root, const Vec3& gravity, InertiaCheck inertia_check) {
  return parse_urdf(read_text_file(path), path, free_root, gravity, inertia_check);
}

}  // namespace soadyn
