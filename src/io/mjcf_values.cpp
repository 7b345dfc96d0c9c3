// MJCF values MuJoCo takes without a word (mjcf_values.hpp).  MuJoCo 2.2 reads a `nan` in a
// position as 0 and keeps one in a stiffness or the gravity, prints "XML contains a 'NaN'" on
// stdout and appends it to ./MUJOCO_LOG.TXT (following a link there), and compiles a negative
// damping; soadyn refuses each, at the file's line.
#include "mjcf_values.hpp"

#include "soadyn/io/scenario_file.hpp"
#include "soadyn/multibody/text.hpp"

#include <tinyxml2.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <set>

namespace soadyn::mjcf_detail {

namespace {

std::mutex handlers_mutex;                  // MuJoCo's handlers are process-wide
std::vector<std::string>* kept = nullptr;  // the live MujocoMessages' warnings

void on_warning(const char* message) {
  if (!kept || !message) return;
  const std::string m(message);
  if (std::find(kept->begin(), kept->end(), m) == kept->end()) kept->push_back(m);
}

[[noreturn]] void on_error(const char* message) { throw MujocoError{message ? message : "(no message)"}; }

std::vector<std::string> warnings_store;

}  // namespace

MujocoMessages::MujocoMessages()
    : lock_(handlers_mutex), saved_error_(mju_user_error), saved_warning_(mju_user_warning) {
  warnings_store.clear();
  kept = &warnings_store;
  mju_user_warning = on_warning;
  mju_user_error = on_error;
}

MujocoMessages::~MujocoMessages() {
  mju_user_warning = saved_warning_;
  mju_user_error = saved_error_;
  kept = nullptr;
}

std::vector<std::string> MujocoMessages::warnings() const { return warnings_store; }

namespace {

namespace fs = std::filesystem;

// attributes that hold names or files, never numbers (a joint named "nan" is a name)
bool is_name_attribute(const char* a) {
  static const std::set<std::string> names = {
      "name",   "class",   "childclass", "joint",  "joint1",  "joint2",    "body",     "body1",      "body2",
      "site",   "site1",   "site2",      "geom",   "geom1",   "geom2",     "tendon",   "tendon1",    "tendon2",
      "actuator", "mesh",  "hfield",     "material", "texture", "target",  "objname",  "refname",    "objtype",
      "reftype", "camera", "light",      "cranksite", "slidersite", "jointinparent", "prefix", "content_type",
      "meshdir", "texturedir", "assetdir", "model", "modelname", "plugin", "instance", "key", "type", "refsite", "skin"};
  return std::strncmp(a, "file", 4) == 0 || names.count(a) > 0;
}

// the numbers of an attribute's value; false when any word is not a number
bool numbers_of(const char* value, std::vector<double>& out) {
  out.clear();
  const char* p = value;
  while (*p) {
    while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r') ++p;
    if (!*p) break;
    char* end = nullptr;
    const double x = std::strtod(p, &end);
    if (end == p || (*end && *end != ' ' && *end != '\t' && *end != '\n' && *end != '\r')) return false;
    out.push_back(x);
    p = end;
  }
  return !out.empty();
}

struct Scan {
  fs::path base;  // the main file's folder: MuJoCo resolves <include file> against it
  bool from_disk = false;
  std::set<std::string> seen;

  [[noreturn]] static void refuse(const std::string& path, const tinyxml2::XMLElement* e, const tinyxml2::XMLAttribute* a,
                                  const std::string& what, const std::string& why) {
    throw Error(path + ":" + std::to_string(a->GetLineNum()) + ": " + printable(e->Name()) + ": attribute '" +
                printable(a->Name()) + "': " + what + ", got '" + excerpt(a->Value()) + "' (" + why + ")");
  }

  void element(const tinyxml2::XMLElement* e, const std::string& path, int depth) {
    std::vector<double> xs;
    for (; e; e = e->NextSiblingElement()) {
      const std::string tag = e->Name();
      for (const tinyxml2::XMLAttribute* a = e->FirstAttribute(); a; a = a->Next()) {
        if (tag == "include" && std::strcmp(a->Name(), "file") == 0) {
          include(a->Value(), depth);
          continue;
        }
        if (is_name_attribute(a->Name()) || !numbers_of(a->Value(), xs)) continue;
        if (!std::all_of(xs.begin(), xs.end(), [](double x) { return std::isfinite(x); }))
          refuse(path, e, a, "expected finite numbers", "MuJoCo reads a NaN as 0 in some places and keeps it in others");
        // a joint's (or a default class's joint's) passive terms: negative is no damper, spring, friction or rotor
        static const char* const non_negative[] = {"damping", "stiffness", "frictionloss", "armature"};
        if (tag == "joint" && std::any_of(std::begin(non_negative), std::end(non_negative),
                                          [&](const char* k) { return std::strcmp(a->Name(), k) == 0; }))
          if (std::any_of(xs.begin(), xs.end(), [](double x) { return x < 0; }))
            refuse(path, e, a, "expected a number >= 0", "MuJoCo would take a negative one");
      }
      element(e->FirstChildElement(), path, depth);
    }
  }

  void include(const std::string& file, int depth) {
    if (!from_disk || depth > 32) return;  // the text alone has no includes to read; a loop MuJoCo refuses
    const fs::path p = fs::path(file).is_absolute() ? fs::path(file) : base / file;
    if (!seen.insert(p.lexically_normal().string()).second) return;
    std::string text;
    try {
      text = read_text_file(p.string());
    } catch (const Error&) {
      return;  // missing or not a regular file: the compiler (or the file checks) says so, located
    }
    document(text, p.string(), depth + 1);
  }

  void document(const std::string& text, const std::string& path, int depth) {
    tinyxml2::XMLDocument doc;
    if (doc.Parse(text.data(), text.size()) != tinyxml2::XML_SUCCESS) return;  // MuJoCo's parser says where
    element(doc.FirstChildElement(), path, depth);
  }
};

}  // namespace

void check_file_values(const std::string& xml, const std::string& path, bool from_disk) {
  Scan s;
  s.base = fs::path(path).parent_path();
  s.from_disk = from_disk;
  s.seen.insert(fs::path(path).lexically_normal().string());
  s.document(xml, path, 0);
}

void check_compiled_values(const mjModel* m, const std::string& path) {
  auto named = [&](int type, int id, const char* kind) {
    const char* n = mj_id2name(m, type, id);
    return std::string(kind) + " '" + (n && *n ? printable(n) : "#" + std::to_string(id)) + "'";
  };
  auto finite = [&](const mjtNum* x, int n, const std::string& who, const char* what) {
    for (int k = 0; k < n; ++k)
      if (!std::isfinite(x[k]))
        throw Error(path + ": MJCF: " + who + ": its " + what + " holds a NaN or an infinity (in the file or an <include>)");
  };
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(m->opt.gravity[k])) throw Error(path + ": MJCF: <option gravity>: expected finite numbers");
  for (int b = 0; b < m->nbody; ++b) {
    const std::string who = named(mjOBJ_BODY, b, "body");
    finite(m->body_pos + 3 * b, 3, who, "pos");
    finite(m->body_quat + 4 * b, 4, who, "orientation");
    finite(m->body_ipos + 3 * b, 3, who, "centre of mass");
    finite(m->body_iquat + 4 * b, 4, who, "principal axes");
    finite(m->body_mass + b, 1, who, "mass");
    finite(m->body_inertia + 3 * b, 3, who, "inertia");
  }
  for (int j = 0; j < m->njnt; ++j) {
    const std::string who = named(mjOBJ_JOINT, j, "joint");
    finite(m->jnt_pos + 3 * j, 3, who, "pos");
    finite(m->jnt_axis + 3 * j, 3, who, "axis");
    finite(m->jnt_range + 2 * j, 2, who, "range");
    finite(m->jnt_stiffness + j, 1, who, "stiffness");
    const int nq = m->jnt_type[j] == mjJNT_FREE ? 7 : m->jnt_type[j] == mjJNT_BALL ? 4 : 1;
    finite(m->qpos0 + m->jnt_qposadr[j], nq, who, "ref");
    finite(m->qpos_spring + m->jnt_qposadr[j], nq, who, "springref");
    if (m->jnt_stiffness[j] < 0) throw Error(path + ": MJCF: " + who + ": expected a stiffness >= 0, got " + short_number(m->jnt_stiffness[j]));
  }
  for (int k = 0; k < m->nv; ++k) {
    const std::string who = named(mjOBJ_JOINT, m->dof_jntid[k], "joint");
    finite(m->dof_damping + k, 1, who, "damping");
    finite(m->dof_frictionloss + k, 1, who, "frictionloss");
    finite(m->dof_armature + k, 1, who, "armature");
    if (m->dof_damping[k] < 0) throw Error(path + ": MJCF: " + who + ": expected a damping >= 0, got " + short_number(m->dof_damping[k]));
  }
  for (int s = 0; s < m->nsite; ++s) {
    finite(m->site_pos + 3 * s, 3, named(mjOBJ_SITE, s, "site"), "pos");
    finite(m->site_quat + 4 * s, 4, named(mjOBJ_SITE, s, "site"), "orientation");
  }
  for (int g = 0; g < m->ngeom; ++g) {
    finite(m->geom_pos + 3 * g, 3, named(mjOBJ_GEOM, g, "geom"), "pos");
    finite(m->geom_quat + 4 * g, 4, named(mjOBJ_GEOM, g, "geom"), "orientation");
    finite(m->geom_size + 3 * g, 3, named(mjOBJ_GEOM, g, "geom"), "size");
  }
}

std::vector<std::string> unmodelled_values(const mjModel* m) {
  std::vector<std::string> kinds;
  auto count = [&](int n, const char* one, const char* many) {
    if (n > 0) kinds.push_back(std::to_string(n) + " " + (n == 1 ? one : many));
  };
  int friction = 0, damping = 0, stiffness = 0;
  for (int j = 0; j < m->njnt; ++j) {
    const int type = m->jnt_type[j], dof = m->jnt_dofadr[j];
    const int nv = type == mjJNT_FREE ? 6 : type == mjJNT_BALL ? 3 : 1;
    bool f = false, d = false;
    for (int k = dof; k < dof + nv; ++k) f = f || m->dof_frictionloss[k] != 0.0, d = d || m->dof_damping[k] != 0.0;
    friction += f ? 1 : 0;
    if (type == mjJNT_FREE || type == mjJNT_BALL) {
      damping += d ? 1 : 0;
      stiffness += m->jnt_stiffness[j] != 0.0 ? 1 : 0;
    }
  }
  // what MuJoCo's flags switch off, MuJoCo does not apply either
  if (m->opt.disableflags & mjDSBL_FRICTIONLOSS) friction = 0;
  if (m->opt.disableflags & mjDSBL_PASSIVE) damping = stiffness = 0;
  count(friction, "joint frictionloss (dry friction)", "joint frictionlosses (dry friction)");
  count(damping, "ball- or free-joint damping", "ball- or free-joint dampings");
  count(stiffness, "ball- or free-joint stiffness", "ball- or free-joint stiffnesses");
  std::string fluid;
  if (m->opt.wind[0] != 0.0 || m->opt.wind[1] != 0.0 || m->opt.wind[2] != 0.0) fluid += " wind";
  if (m->opt.density != 0.0) fluid += " density";
  if (m->opt.viscosity != 0.0) fluid += " viscosity";
  if (!fluid.empty() && !(m->opt.disableflags & mjDSBL_PASSIVE)) kinds.push_back("<option" + fluid + "> (fluid forces)");
  return kinds;
}

}  // namespace soadyn::mjcf_detail
