// A scenario's joint limits, built-in controllers and prescribed motion (scenarios/README.md).
#include "scenario_reader.hpp"

#include "soadyn/io/table_file.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <memory>
#include <tuple>

namespace soadyn::scenario_detail {

namespace {

// a 1-DOF joint, or the message why not
int one_dof_joint(const Reader& rd, const Model& m, const YAML::Node& key, const std::string& field) {
  const int i = find_joint(rd, m, key, field);
  if (m.nv_i[i] != 1 || m.nq_i[i] != 1)
    rd.fail(key, field, "acts on 1-DOF joints (revolute, prismatic, helical); '" + excerpt(key.Scalar()) + "' is " + std::string(to_string(m.joint_type[i])));
  return i;
}

// The tables a scenario's targets read (table.hpp), each file read once, its path relative to the
// scenario file's folder.
class Tables {
 public:
  explicit Tables(const Reader& rd) : rd_(rd) {}
  const Table& get(const YAML::Node& n, const std::string& field) {
    const std::string rel = rd_.string(n, field);
    const std::string path = (std::filesystem::path(rd_.file).parent_path() / rel).string();
    auto it = read_.find(path);
    if (it == read_.end()) {
      try {
        rd_.files_read.push_back(path);  // named before it is read: an output may never be it
        it = read_.emplace(path, read_table(path)).first;
      } catch (const Error& e) {
        rd_.fail(n, field, e.what());
      }
    }
    return it->second;
  }
  // the spline through `column` of the table `n` names
  std::shared_ptr<const CubicSpline> spline(const YAML::Node& n, const std::string& field, const std::string& column,
                                            const YAML::Node* column_node) {
    const Table& t = get(n, field);
    const int c = t.column(column);
    if (c < 0)
      rd_.fail(column_node ? *column_node : n, field, t.path + " has no column '" + excerpt(column) + "' (it has " +
                   join(t.columns) + ")" + did_you_mean(column, t.columns));
    return std::make_shared<const CubicSpline>(t.time, t.values.col(c));
  }

 private:
  // the first 20 names, each cut at 60 bytes and shown as text (a CSV header's names are the user's)
  static std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (size_t k = 0; k < v.size() && k < 20; ++k) s += (s.empty() ? "" : ", ") + excerpt(v[k]);
    if (v.size() > 20) s += ", … (" + std::to_string(v.size()) + " in all)";
    return s;
  }
  const Reader& rd_;
  std::map<std::string, Table> read_;
};

// a target: a number (constant), {constant, amplitude, frequency, phase}, or {table: FILE,
// column: NAME} (the column named as the joint unless given)
JointTarget read_target(const Reader& rd, const YAML::Node& n, const std::string& field, const std::string& joint,
                        Tables& tables) {
  JointTarget r;
  if (n.IsScalar()) {
    r.constant = rd.number(n, field);
    return r;
  }
  if (n.IsMap() && n["table"]) {
    rd.keys(n, field, {"table", "column"});
    const std::string column = n["column"] ? rd.string(n["column"], field + ".column") : joint;
    const YAML::Node cn = n["column"];
    r.table = tables.spline(n["table"], field + ".table", column, cn ? &cn : nullptr);
    return r;
  }
  rd.keys(n, field, {"constant", "amplitude", "frequency", "phase", "table"});
  if (n["constant"]) r.constant = rd.number(n["constant"], field + ".constant");
  if (n["amplitude"]) r.amplitude = rd.number(n["amplitude"], field + ".amplitude");
  if (n["frequency"]) r.frequency = rd.number(n["frequency"], field + ".frequency");
  if (n["phase"]) r.phase = rd.number(n["phase"], field + ".phase");
  return r;
}

// a prescribed joint's motion: a target's forms (read_target; `offset` for `constant`), a table of
// at least 4 rows (q̈* from a natural cubic spline needs them), or {slew: {from, to, start, duration}}
JointTarget read_profile(const Reader& rd, const YAML::Node& n, const std::string& field, const std::string& joint,
                         Tables& tables) {
  if (n.IsMap() && n["slew"]) {
    rd.keys(n, field, {"slew"});
    const YAML::Node w = n["slew"];
    const std::string f = field + ".slew";
    if (!w.IsMap()) rd.fail(w, f, "expected a map {from, to, start, duration}, got " + Reader::show(w));
    rd.keys(w, f, {"from", "to", "start", "duration"});
    auto slew = std::make_shared<JointSlew>();
    slew->from = rd.number(rd.require(w, "from", f), f + ".from");
    slew->to = rd.number(rd.require(w, "to", f), f + ".to");
    if (w["start"]) slew->start = rd.number(w["start"], f + ".start");
    slew->duration = rd.positive(rd.require(w, "duration", f), f + ".duration");
    JointTarget r;
    r.slew = std::move(slew);
    return r;
  }
  if (n.IsMap() && n["table"]) {
    const Table& t = tables.get(n["table"], field + ".table");
    if (t.time.size() < 4)
      rd.fail(n["table"], field + ".table", t.path + " has " + std::to_string(t.time.size()) +
                                                " rows; a prescribed motion's q̈ needs a spline through at least 4");
    return read_target(rd, n, field, joint, tables);
  }
  if (n.IsMap()) {
    rd.keys(n, field, {"offset", "constant", "amplitude", "frequency", "phase"});
    if (n["offset"] && n["constant"]) rd.fail(n["constant"], field + ".constant", "give offset or constant, not both");
    JointTarget r;
    if (n["offset"]) r.constant = rd.number(n["offset"], field + ".offset");
    if (n["constant"]) r.constant = rd.number(n["constant"], field + ".constant");
    if (n["amplitude"]) r.amplitude = rd.number(n["amplitude"], field + ".amplitude");
    if (n["frequency"]) r.frequency = rd.number(n["frequency"], field + ".frequency");
    if (n["phase"]) r.phase = rd.number(n["phase"], field + ".phase");
    return r;
  }
  if (!n.IsScalar())
    rd.fail(n, field, "expected a number, {offset, amplitude, frequency, phase}, {table, column} or {slew: {from, to, "
                      "start, duration}}, got " + Reader::show(n));
  return read_target(rd, n, field, joint, tables);
}

double non_negative(const Reader& rd, const YAML::Node& n, const std::string& field) {
  const double x = rd.number(n, field);
  if (x < 0) rd.fail(n, field, "expected a number >= 0, got " + Reader::show(n));
  return x;
}

}  // namespace

void read_limits(const Reader& rd, const YAML::Node& n, Model& m) {
  if (!n.IsMap()) rd.fail(n, "limits", "expected a map from joint name to [lower, upper], got " + Reader::show(n));
  for (auto it = n.begin(); it != n.end(); ++it) {
    const std::string f = "limits." + it->first.Scalar();
    const int i = one_dof_joint(rd, m, it->first, "limits");
    const VecX b = rd.numbers(it->second, f, 2);
    if (!(b(0) < b(1))) rd.fail(it->second, f, "expected lower < upper, got " + Reader::show_number(b(0)) + ", " + Reader::show_number(b(1)));
    m.lower[size_t(m.idx_v[i])] = b(0);
    m.upper[size_t(m.idx_v[i])] = b(1);
  }
}

void read_controllers(const Reader& rd, const YAML::Node& list, const Model& m, const VecX& q0,
                      std::vector<ControllerInput>& out) {
  using Kind = ControllerInput::Kind;
  const std::string f0 = "inputs.controllers";
  if (!list.IsSequence()) rd.fail(list, f0, "expected a list, got " + Reader::show(list));
  Tables tables(rd);
  for (size_t k = 0; k < list.size(); ++k) {
    const std::string f = f0 + "[" + std::to_string(k) + "]";
    const YAML::Node e = list[k];
    if (!e.IsMap()) rd.fail(e, f, "expected a map, got " + Reader::show(e));
    const YAML::Node type = rd.require(e, "type", f);
    const std::string kind = rd.string(type, f + ".type");
    ControllerInput c;
    // max_torque: a number, or `effort`: each DOF's <limit effort>
    if (const YAML::Node mt = e["max_torque"]) {
      if (mt.IsScalar() && mt.Scalar() == "effort") {
        c.at_effort = true;
        if (std::none_of(m.effort.begin(), m.effort.end(), [](double x) { return std::isfinite(x); }))
          rd.fail(mt, f + ".max_torque", "effort: no joint of the model has an effort (a URDF's <limit effort>)");
      } else {
        c.max_torque = rd.positive(mt, f + ".max_torque");
      }
    }
    if (kind == "pd") {
      rd.keys(e, f, {"type", "joint", "kp", "kd", "target", "max_torque"});
      const int i = one_dof_joint(rd, m, rd.require(e, "joint", f), f + ".joint");
      c.kind = Kind::Pd;
      c.dofs = {m.idx_v[i]};
      c.coords = {m.idx_q[i]};
      c.kp = non_negative(rd, rd.require(e, "kp", f), f + ".kp");
      if (e["kd"]) c.kd = non_negative(rd, e["kd"], f + ".kd");
      c.targets = {e["target"] ? read_target(rd, e["target"], f + ".target", m.joint_names[size_t(i)], tables)
                               : JointTarget{}};
      if (c.at_effort && !std::isfinite(m.effort[size_t(m.idx_v[i])]))
        rd.fail(e["max_torque"], f + ".max_torque", "effort: joint '" + m.joint_names[size_t(i)] + "' has no effort (a URDF's <limit effort>)");
    } else if (kind == "gravity_compensation") {
      rd.keys(e, f, {"type", "max_torque"});
      c.kind = Kind::GravityCompensation;
    } else if (kind == "computed_torque") {
      rd.keys(e, f, {"type", "kp", "kd", "targets", "max_torque"});
      if (m.nq != m.nv) rd.fail(type, f + ".type", "computed_torque needs a model of revolute and prismatic joints");
      c.kind = Kind::ComputedTorque;
      c.kp = non_negative(rd, rd.require(e, "kp", f), f + ".kp");
      c.kd = non_negative(rd, rd.require(e, "kd", f), f + ".kd");
      // every DOF: its target, or its initial q held
      for (int d = 0; d < m.nv; ++d) {
        c.dofs.push_back(d);
        c.coords.push_back(d);
        JointTarget r;
        r.constant = q0(d);
        c.targets.push_back(r);
      }
      if (const YAML::Node t = e["targets"]; t && t.IsScalar()) {
        // a table: each joint it has a column for follows that column
        const Table& table = tables.get(t, f + ".targets");
        int found = 0;
        for (int i = 0; i < m.nbodies; ++i)
          if (m.nv_i[i] == 1 && table.column(m.joint_names[size_t(i)]) >= 0) {
            c.targets[size_t(m.idx_v[i])].table = tables.spline(t, f + ".targets", m.joint_names[size_t(i)], nullptr);
            ++found;
            c.actuated.push_back(m.idx_v[i]);
          }
        if (!found)
          rd.fail(t, f + ".targets", table.path + " has no column named as a joint of the model");
      } else if (t) {
        if (!t.IsMap()) rd.fail(t, f + ".targets", "expected a table file or a map from joint name to target, got " + Reader::show(t));
        for (auto it = t.begin(); it != t.end(); ++it) {
          const int i = one_dof_joint(rd, m, it->first, f + ".targets");
          c.targets[size_t(m.idx_v[i])] =
              read_target(rd, it->second, f + ".targets." + it->first.Scalar(), m.joint_names[size_t(i)], tables);
          if (std::find(c.actuated.begin(), c.actuated.end(), m.idx_v[i]) == c.actuated.end()) c.actuated.push_back(m.idx_v[i]);
        }
      }
    } else {
      rd.fail(type, f + ".type",
              "unknown controller '" + excerpt(kind) + "'" + did_you_mean(kind, {"pd", "gravity_compensation", "computed_torque"}));
    }
    out.push_back(std::move(c));
  }
}

void read_prescribed(const Reader& rd, const YAML::Node& n, const YAML::Node& initial, const Model& m, VecX& q0,
                     VecX& v0, std::vector<PrescribedInput>& out) {
  if (!n.IsMap())
    rd.fail(n, "prescribed", "expected a map from joint name to its motion, got " + Reader::show(n));
  Tables tables(rd);
  for (auto it = n.begin(); it != n.end(); ++it) {
    const std::string f = "prescribed." + it->first.Scalar();
    const int i = one_dof_joint(rd, m, it->first, "prescribed");
    PrescribedInput p;
    p.joint = m.joint_names[size_t(i)];
    p.body = i, p.dof = m.idx_v[i], p.coord = m.idx_q[i];
    p.target = read_profile(rd, it->second, f, p.joint, tables);
    // the start is the motion's: an initial value the file gives must agree with it
    double q = 0, qd = 0, qdd = 0;
    p.at(0.0, q, qd, qdd);
    for (const auto& [part, given, value] : {std::tuple{"q", &q0, q}, std::tuple{"qd", &v0, qd}}) {
      const YAML::Node g = initial && initial[part] ? initial[part][p.joint] : YAML::Node();
      if (g && g.IsScalar()) {
        const double x = rd.number(g, std::string("initial.") + part + "." + p.joint);
        if (!(std::abs(x - value) <= 1e-9 * std::max(1.0, std::abs(value))))
          rd.fail(g, std::string("initial.") + part + "." + p.joint,
                  "joint '" + p.joint + "' is prescribed (" + f + "), which starts it at " + Reader::show_number(value) +
                      ", not " + Reader::show_number(x) + "; leave it out of initial: or make them agree");
      }
      (*given)(std::string(part) == "q" ? p.coord : p.dof) = value;
    }
    if (std::any_of(out.begin(), out.end(), [&](const PrescribedInput& o) { return o.body == i; }))
      rd.fail(it->first, f, "joint '" + p.joint + "' is prescribed twice");
    out.push_back(std::move(p));
  }
}

}  // namespace soadyn::scenario_detail
