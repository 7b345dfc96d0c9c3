// The scenario parser's YAML reader: every mistake as file:line:column: field: message.  Shared by
// scenario.cpp and scenario_control.cpp (limits:, controllers:).  Internal.
#pragma once

#include "soadyn/algorithm/inputs.hpp"
#include "soadyn/multibody/model.hpp"
#include "soadyn/sim/settings.hpp"
#include "soadyn/multibody/text.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

namespace soadyn {
struct Scenario;
}

namespace soadyn::scenario_detail {

// Reads YAML nodes and reports every mistake as file:line:column: field: message.
struct Reader {
  std::string file;
  // the other files read while parsing `file` (target tables), for Scenario::files
  mutable std::vector<std::string> files_read;

  // the field and the message shown as text (control characters as \xHH: a key or value from the
  // file never reaches the terminal raw); a field longer than 80 bytes keeps its ends
  [[noreturn]] void fail(const YAML::Mark& m, const std::string& field, const std::string& msg) const {
    std::string where = file;
    if (m.line >= 0) where += ":" + std::to_string(m.line + 1) + ":" + std::to_string(m.column + 1);
    const std::string f = printable(field);
    const std::string shown_field = f.size() <= 80 ? f : excerpt(field, 45) + " … " + printable(field.substr(field.size() - 30));
    throw Error(where + ": " + shown_field + ": " + printable(msg));
  }
  [[noreturn]] void fail(const YAML::Node& n, const std::string& field, const std::string& msg) const {
    fail(n.Mark(), field, msg);
  }

  static std::string show_number(double x) { return short_number(x); }

  static std::string show(const YAML::Node& n) {
    if (n.IsScalar()) return "'" + excerpt(n.Scalar()) + "'";  // at most 60 bytes of it
    if (n.IsSequence()) return "a list";
    if (n.IsMap()) return "a map";
    return "nothing";
  }

  void keys(const YAML::Node& map, const std::string& field, const std::vector<std::string>& allowed) const {
    if (!map.IsMap()) fail(map, field, "expected a map, got " + show(map));
    std::set<std::string> seen;
    for (auto it = map.begin(); it != map.end(); ++it) {
      const std::string k = it->first.Scalar();
      if (std::find(allowed.begin(), allowed.end(), k) == allowed.end())
        fail(it->first, field, "unknown key '" + excerpt(k) + "'" + did_you_mean(k, allowed));
      if (!seen.insert(k).second) fail(it->first, field, "duplicate key '" + excerpt(k) + "'");
    }
  }

  YAML::Node require(const YAML::Node& map, const std::string& key, const std::string& field) const {
    const YAML::Node n = map[key];
    if (!n || n.IsNull()) fail(map, field, "missing required field '" + key + "'");
    return n;
  }

  double number(const YAML::Node& n, const std::string& field) const {
    if (!n.IsScalar()) fail(n, field, "expected a number, got " + show(n));
    // a quoted or !!str-tagged scalar is a string in YAML, whatever it spells
    if (n.Tag() == "!" || n.Tag() == "tag:yaml.org,2002:str") fail(n, field, "expected a number, got the string " + show(n));
    double x;
    try {
      x = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(n, field, "expected a number, got " + show(n));
    }
    if (!std::isfinite(x)) fail(n, field, "expected a finite number, got " + show(n));
    return x;
  }

  double positive(const YAML::Node& n, const std::string& field) const {
    const double x = number(n, field);
    if (!(x > 0)) fail(n, field, "expected a positive number, got " + show(n));
    return x;
  }

  std::string string(const YAML::Node& n, const std::string& field) const {
    if (!n.IsScalar() || n.Scalar().empty()) fail(n, field, "expected a name, got " + show(n));
    return n.Scalar();
  }

  bool boolean(const YAML::Node& n, const std::string& field) const {
    try {
      if (n.IsScalar()) return n.as<bool>();
    } catch (const YAML::Exception&) {
    }
    fail(n, field, "expected true or false, got " + show(n));
  }

  VecX numbers(const YAML::Node& n, const std::string& field, int size) const {
    if (size == 1 && !n.IsScalar()) fail(n, field, "expected a number, got " + show(n));
    if (!n.IsSequence()) fail(n, field, "expected a list of " + std::to_string(size) + " numbers, got " + show(n));
    if (int(n.size()) != size)
      fail(n, field, "expected " + std::to_string(size) + " numbers, got " + std::to_string(n.size()));
    VecX v(size);
    for (int k = 0; k < size; ++k) v(k) = number(n[k], field + "[" + std::to_string(k) + "]");
    return v;
  }

  Vec3 vec3(const YAML::Node& n, const std::string& field) const { return numbers(n, field, 3); }

  // rpy: R = Rz(yaw) Ry(pitch) Rx(roll)
  static Mat3 rpy(const Vec3& a) {
    return (Eigen::AngleAxisd(a.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(a.y(), Vec3::UnitY()) *
            Eigen::AngleAxisd(a.x(), Vec3::UnitX()))
        .toRotationMatrix();
  }

  // inertia: [ixx, iyy, izz], {ixx, iyy, izz, ixy, ixz, iyz}, or a 3×3 list of rows
  Mat3 inertia(const YAML::Node& n, const std::string& field) const {
    Mat3 I = Mat3::Zero();
    if (n.IsMap()) {
      keys(n, field, {"ixx", "iyy", "izz", "ixy", "ixz", "iyz"});
      I(0, 0) = number(require(n, "ixx", field), field + ".ixx");
      I(1, 1) = number(require(n, "iyy", field), field + ".iyy");
      I(2, 2) = number(require(n, "izz", field), field + ".izz");
      if (n["ixy"]) I(0, 1) = I(1, 0) = number(n["ixy"], field + ".ixy");
      if (n["ixz"]) I(0, 2) = I(2, 0) = number(n["ixz"], field + ".ixz");
      if (n["iyz"]) I(1, 2) = I(2, 1) = number(n["iyz"], field + ".iyz");
      return I;
    }
    if (n.IsSequence() && n.size() == 3 && n[0].IsSequence()) {
      for (int r = 0; r < 3; ++r) I.row(r) = vec3(n[r], field + "[" + std::to_string(r) + "]").transpose();
      return I;
    }
    if (n.IsSequence() && n.size() == 3) return vec3(n, field).asDiagonal();
    fail(n, field,
         "expected [ixx, iyy, izz], a map {ixx, iyy, izz, ixy, ixz, iyz} or a 3x3 list, got " + show(n));
  }
};

// the body index of the joint a key names
inline int find_joint(const Reader& rd, const Model& m, const YAML::Node& key, const std::string& field) {
  const std::string name = rd.string(key, field);
  const int i = m.joint_index(name);
  if (i < 0) rd.fail(key, field, "no joint named '" + excerpt(name) + "'" + did_you_mean(name, m.joint_names));
  return i;
}

// scenario_control.cpp: `limits: {joint: [lower, upper]}` onto the model's travel, and
// `inputs: controllers: [...]` (q0: the initial state, a computed-torque target's default)
// scenario_bodies.cpp: the bodies: list, and the model built from it
struct BodyNodes {
  std::vector<BodySpec> specs;
  std::vector<YAML::Node> nodes;  // each body's node, to locate a refusal
};
BodyNodes read_bodies(const Reader& rd, const YAML::Node& list);
Model build_located(const Reader& rd, const BodyNodes& bodies, const Vec3& gravity, InertiaCheck inertia_check);

void read_limits(const Reader& rd, const YAML::Node& n, Model& m);
void read_controllers(const Reader& rd, const YAML::Node& n, const Model& m, const VecX& q0,
                      std::vector<ControllerInput>& out);
// `prescribed: {joint: motion}` (1-DOF joints): each joint's motion, and its start into q0 and v0,
// where `initial` (the file's initial:, may be undefined) must agree with it
void read_prescribed(const Reader& rd, const YAML::Node& n, const YAML::Node& initial, const Model& m, VecX& q0,
                     VecX& v0, std::vector<PrescribedInput>& out);
// scenario_loops.cpp: `loops: [{type, a, at_a, b, at_b, axis, …}]`, appended to `out` (after an
// MJCF model's own; a distance loop's default length from q0)
void read_loops(const Reader& rd, const YAML::Node& n, const Model& m, const VecX& q0, std::vector<LoopConstraint>& out);
// the DOFs of the joints `initial.part` names (part: q or qd; initial may be undefined)
std::vector<char> held_dofs(const YAML::Node& initial, const char* part, const Model& m);
// The initial state closed on the loops: q0 by Newton on their closure φ over the DOFs hold_q does
// not hold (steps of minimum norm, at most 50), then, once closed, v0 onto K v = 0 over the DOFs
// hold_v does not hold.  Returns the largest |φ| left (≤ kLoopClosure: closed, v0 projected).
double close_on_loops(const Model& m, const std::vector<LoopConstraint>& loops, const std::vector<char>& hold_q,
                      const std::vector<char>& hold_v, VecX& q0, VecX& v0);
// close_on_loops with the joints `initial` names held (q, qd), refused at `where` (field) when q0
// cannot be closed
void assemble_loops(const Reader& rd, const YAML::Node& where, const std::string& field, const YAML::Node& initial,
                    const Model& m, const std::vector<LoopConstraint>& loops, VecX& q0, VecX& v0);
// what the assembly did to the file's initial state (q_file, v_file → q0, v0), in one line for the
// run to say ("" when it moved nothing)
std::string assembly_note(const Model& m, const VecX& q_file, const VecX& v_file, const VecX& q0, const VecX& v0);

// scenario_sensitivity.cpp: `simulation: sensitivities: {initial_state, parameters}`, the bodies
// checked against the model's
void read_sensitivities(const Reader& rd, const YAML::Node& n, const Model& m, SensitivitySettings& out);

// scenario_checks.cpp: where the file gives the fields a run may refuse in combination (limits, a
// joint's start or range, sensitivities), into Scenario::locations
void record_locations(const Reader& rd, const YAML::Node& root, Scenario& sc);

// scenario_inertial.cpp: `inertial: {body: {mass, com, inertia}}` over the model's mass properties
void read_inertial(const Reader& rd, const YAML::Node& n, Model& m);

}  // namespace soadyn::scenario_detail
