// A scenario's `bodies:` list: each body's name, parent, joint, origin and mass properties as a
// BodySpec, then the model, with Model::build's refusals located at the offending body's line.
#include "scenario_reader.hpp"

#include "soadyn/multibody/text.hpp"

#include <map>
#include <numbers>
#include <set>

namespace soadyn::scenario_detail {

namespace {

JointType joint_type(const Reader& rd, const YAML::Node& n, const std::string& field) {
  const std::string t = rd.string(n, field);
  std::vector<std::string> names;
  for (const JointTraits& tr : joint_traits_table()) {
    if (tr.name == t) return tr.type;
    names.emplace_back(tr.name);
  }
  rd.fail(n, field, "unknown joint type '" + excerpt(t) + "'" + did_you_mean(t, names));
}

// Every body's declared parent, to tell a cycle from a parent listed too late.
std::map<std::string, std::string> declared_parents(const YAML::Node& list) {
  std::map<std::string, std::string> declared;
  for (size_t k = 0; k < list.size(); ++k) {
    const YAML::Node& b = list[k];
    if (b.IsMap() && b["name"] && b["name"].IsScalar())
      declared[b["name"].Scalar()] = b["parent"] && b["parent"].IsScalar() ? b["parent"].Scalar() : "world";
  }
  return declared;
}

// body.parent: the index of a body listed before this one, or -1 for the world
int read_parent(const Reader& rd, const YAML::Node& b, const std::string& name, const std::string& fb,
                const std::map<std::string, int>& index, const std::map<std::string, std::string>& declared) {
  const std::string parent = b["parent"] ? rd.string(b["parent"], fb + ".parent") : "world";
  if (parent == "world") return -1;
  if (auto it = index.find(parent); it != index.end()) return it->second;
  if (declared.count(parent)) {
    // follow the declared parents from `parent`: back to this body means a cycle
    std::string chain = name + " -> " + parent, at = parent;
    std::set<std::string> visited{name};
    bool cycle = false;
    while (declared.count(at) && !visited.count(at)) {
      visited.insert(at);
      at = declared.at(at);
      chain += " -> " + at;
      if (at == name) {
        cycle = true;
        break;
      }
    }
    if (cycle || parent == name) rd.fail(b["parent"], fb + ".parent", "cycle in the tree: " + chain);
    rd.fail(b["parent"], fb + ".parent",
            "parent '" + excerpt(parent) + "' is listed after '" + excerpt(name) + "'; list every parent before its children");
  }
  std::vector<std::string> names{"world"};
  for (auto& [n, i] : index) names.push_back(n);
  rd.fail(b["parent"], fb + ".parent", "no body named '" + excerpt(parent) + "'" + did_you_mean(parent, names));
}

// body.joint {type, name, axis, pitch} and body.origin {xyz, rpy}
void read_joint(const Reader& rd, const YAML::Node& b, const std::string& fb, std::set<std::string>& joint_names,
                BodySpec& s) {
  const YAML::Node j = rd.require(b, "joint", fb);
  rd.keys(j, fb + ".joint", {"type", "name", "axis", "pitch"});
  s.joint = joint_type(rd, rd.require(j, "type", fb + ".joint"), fb + ".joint.type");
  const JointTraits& tr = joint_traits(s.joint);
  s.joint_name = j["name"] ? rd.string(j["name"], fb + ".joint.name") : s.name;
  if (s.joint != JointType::Fixed && !joint_names.insert(s.joint_name).second)
    rd.fail(j["name"] ? j["name"] : b["name"], fb + ".joint.name", "duplicate joint name '" + excerpt(s.joint_name) + "'");
  if (tr.has_axis) {
    s.axis = rd.vec3(rd.require(j, "axis", fb + ".joint"), fb + ".joint.axis");
    if (!(s.axis.norm() > 1e-12) || !std::isfinite(s.axis.squaredNorm())) {
      char got[96];
      std::snprintf(got, sizeof got, "[%g, %g, %g]", s.axis.x(), s.axis.y(), s.axis.z());
      rd.fail(j["axis"], fb + ".joint.axis", std::string("expected a non-zero axis of norm between 1e-12 and 1e150, got ") + got);
    }
  } else if (j["axis"]) {
    rd.fail(j["axis"], fb + ".joint.axis", "a " + std::string(tr.name) + " joint has no axis");
  }
  // a helical joint's pitch h (m/rad): it slides h θ along its axis as it turns by θ
  if (s.joint == JointType::Helical)
    s.pitch = rd.number(rd.require(j, "pitch", fb + ".joint"), fb + ".joint.pitch");
  else if (j["pitch"])
    rd.fail(j["pitch"], fb + ".joint.pitch", "a " + std::string(tr.name) + " joint has no pitch (a helical one has)");
  if (const YAML::Node o = b["origin"]) {
    if (tr.root_only)
      rd.fail(o, fb + ".origin", "a free joint has no origin: its q is the body's pose in the world");
    rd.keys(o, fb + ".origin", {"xyz", "rpy"});
    if (o["xyz"]) s.placement.p = rd.vec3(o["xyz"], fb + ".origin.xyz");
    if (o["rpy"]) s.placement.R = Reader::rpy(rd.vec3(o["rpy"], fb + ".origin.rpy"));
  }
}

// body.mass, body.com, body.inertia and body.inertia_rpy
void read_mass_properties(const Reader& rd, const YAML::Node& b, const std::string& fb, BodySpec& s) {
  const YAML::Node mass = rd.require(b, "mass", fb);
  s.mass = rd.number(mass, fb + ".mass");
  const bool massless_weld = s.joint == JointType::Fixed && s.mass == 0.0;
  if (!(s.mass > 0) && !massless_weld) rd.fail(mass, fb + ".mass", "expected a positive mass, got " + Reader::show(mass));
  if (b["com"]) s.com = rd.vec3(b["com"], fb + ".com");
  if (!massless_weld) s.inertia = rd.inertia(rd.require(b, "inertia", fb), fb + ".inertia");
  else if (b["inertia"]) s.inertia = rd.inertia(b["inertia"], fb + ".inertia");
  if (b["inertia_rpy"]) {
    // the inertia was given in axes turned by rpy from the body frame: I_body = R I Rᵀ
    const Mat3 R = Reader::rpy(rd.vec3(b["inertia_rpy"], fb + ".inertia_rpy"));
    s.inertia = R * s.inertia * R.transpose();
  }
}

}  // namespace

BodyNodes read_bodies(const Reader& rd, const YAML::Node& list) {
  if (!list.IsSequence() || list.size() == 0) rd.fail(list, "bodies", "expected a non-empty list of bodies");
  BodyNodes out;
  std::map<std::string, int> index;
  const std::map<std::string, std::string> declared = declared_parents(list);
  std::set<std::string> joint_names;
  for (size_t k = 0; k < list.size(); ++k) {
    const YAML::Node& b = list[k];
    const std::string f = "bodies[" + std::to_string(k) + "]";
    rd.keys(b, f, {"name", "parent", "joint", "origin", "mass", "com", "inertia", "inertia_rpy"});
    BodySpec s;
    s.name = rd.string(rd.require(b, "name", f), f + ".name");
    const std::string fb = "body '" + printable(s.name) + "'";
    if (index.count(s.name) || s.name == "world") rd.fail(b["name"], fb + ".name", "duplicate body name '" + excerpt(s.name) + "'");
    s.parent = read_parent(rd, b, s.name, fb, index, declared);
    read_joint(rd, b, fb, joint_names, s);
    read_mass_properties(rd, b, fb, s);
    index[s.name] = int(k);
    out.specs.push_back(s);
    out.nodes.push_back(b);
  }
  return out;
}

// Model::build's refusals, located at the offending body's line
Model build_located(const Reader& rd, const BodyNodes& bodies, const Vec3& gravity, InertiaCheck inertia_check) {
  try {
    return Model::build(bodies.specs, gravity, inertia_check);
  } catch (const ModelError& e) {
    const int k = e.spec >= 0 && e.spec < int(bodies.nodes.size()) ? e.spec : 0;
    rd.fail(bodies.nodes[k], "body '" + printable(bodies.specs[k].name) + "'", e.detail);
  }
}

}  // namespace soadyn::scenario_detail
