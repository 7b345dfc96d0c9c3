// URDF import: urdfdom reads the robot; urdf_xml.hpp gives the line of every element, so that
// every error names file:line, and the joints' document order, so that q keeps the URDF's order.
//
// What enters the model: links' <inertial> (mass, inertia, origin), joints' type, <origin>,
// <axis>, <parent>, <child> and <limit lower upper>.  Geometry, materials, transmissions and simulator extensions never
// reach urdfdom; joints reach it whole (it checks their <limit>, <mimic>, ... ), and soadyn ignores
// all but the above: none of it changes rigid-body dynamics.
#include "soadyn/io/scenario_file.hpp"

#include "urdf_xml.hpp"

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <set>

namespace soadyn {

namespace {

// Collects urdfdom's error messages instead of printing them.
class CaptureConsole : public console_bridge::OutputHandler {
 public:
  CaptureConsole() { console_bridge::useOutputHandler(this); }
  ~CaptureConsole() override { console_bridge::restorePreviousOutputHandler(); }
  CaptureConsole(const CaptureConsole&) = delete;
  CaptureConsole& operator=(const CaptureConsole&) = delete;
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    // the last words of every failure, which add nothing to the ones before them
    if (text.find("is not initialized correctly") != std::string::npos) return;
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) messages.push_back(text);
  }
  std::vector<std::string> messages;
};

urdf::ModelInterfaceSharedPtr read_robot(const urdf_xml::Index& idx) {
  urdf::ModelInterfaceSharedPtr robot;
  std::vector<std::string> messages;
  {
    CaptureConsole console;
    robot = urdf::parseURDF(idx.dynamics);
    messages = console.messages;
  }
  // urdfdom 3.0 keeps a link it could not read (a malformed <inertial> becomes zero mass) and
  // only says so: any error it reports refuses the robot
  if (!robot || !messages.empty())
    throw Error(urdf_xml::locate(idx, messages.empty() ? std::vector<std::string>{"urdfdom could not read the robot"}
                                                       : messages));
  if (!robot->getRoot())  // urdf_xml::index checked there is one
    throw Error(idx.path + ":" + std::to_string(idx.robot_line) + ": URDF: no root link");
  return robot;
}

// Parent-first order: the URDF's own joint order when it already is, else depth-first from the
// root with siblings in document order.
std::vector<std::string> parent_first(const urdf::ModelInterface& robot, const urdf_xml::Index& idx) {
  // every joint of the document must have reached urdfdom's model (a name it read differently would not)
  for (const auto& jn : idx.joint_order)
    if (!robot.getJoint(jn)) throw Error(idx.at_joint(jn) + ": urdfdom did not read this joint");
  std::vector<std::string> order;
  std::set<std::string> placed{robot.getRoot()->name};
  for (const auto& jn : idx.joint_order) {
    const auto j = robot.getJoint(jn);
    if (!placed.count(j->parent_link_name)) break;
    placed.insert(j->child_link_name);
    order.push_back(jn);
  }
  if (order.size() == idx.joint_order.size()) return order;

  std::map<std::string, std::vector<std::string>> children;  // link → its child joints, in document order
  for (const auto& jn : idx.joint_order) children[robot.getJoint(jn)->parent_link_name].push_back(jn);
  order.clear();
  std::vector<std::string> stack{robot.getRoot()->name};
  while (!stack.empty()) {
    const std::string link = stack.back();
    stack.pop_back();
    const auto& below = children[link];
    for (auto it = below.rbegin(); it != below.rend(); ++it) stack.push_back(robot.getJoint(*it)->child_link_name);
    order.insert(order.end(), below.begin(), below.end());  // a joint follows its parent link's joint
  }
  return order;
}

// <inertial>: mass, centre of mass and inertia about it, turned from the inertial frame (origin
// rpy) into the link frame: I_link = R I Rᵀ.  No <inertial>: a massless frame.
void mass_properties(const urdf::Link& link, BodySpec& s) {
  if (!link.inertial) return;
  const urdf::Inertial& in = *link.inertial;
  const Placement X = placement_of_pose(in.origin);
  Mat3 I;
  I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  s.mass = in.mass;
  s.com = X.p;
  s.inertia = X.R * I * X.R.transpose();
}

BodySpec root_spec(const urdf::Link& root, bool free_root) {
  BodySpec s;
  s.name = root.name;
  s.joint = free_root ? JointType::Free : JointType::Fixed;
  s.joint_name = free_root ? root.name + "_free" : root.name;
  mass_properties(root, s);
  return s;
}

// The body below joint j: its joint's type, frame and axis, and its link's mass properties.
BodySpec joint_spec(const urdf::Joint& j, const urdf::Link& link, const std::map<std::string, int>& link_index,
                    bool free_root, const urdf_xml::Index& idx) {
  BodySpec s;
  s.name = link.name;
  s.joint_name = j.name;
  s.parent = link_index.at(j.parent_link_name);
  s.placement = placement_of_pose(j.parent_to_joint_origin_transform);
  s.axis = Vec3(j.axis.x, j.axis.y, j.axis.z);
  switch (j.type) {
    case urdf::Joint::REVOLUTE:
    case urdf::Joint::CONTINUOUS: s.joint = JointType::Revolute; break;
    case urdf::Joint::PRISMATIC: s.joint = JointType::Prismatic; break;
    case urdf::Joint::PLANAR: s.joint = JointType::Planar; break;  // the axis is the plane's normal
    case urdf::Joint::FIXED: s.joint = JointType::Fixed; break;  // its <axis>, if any, means nothing
    case urdf::Joint::FLOATING:
      // a floating joint frees a body hung on the world-welded root: its q is the pose in the world
      if (s.parent != 0 || free_root)
        throw Error(idx.at_joint(j.name) + ": floating joints are supported only on a child of the root link, "
                                           "with the root welded to the world (no --free-root)");
      if (!s.placement.R.isIdentity(1e-12) || !s.placement.p.isZero(0.0))
        throw Error(idx.at_joint(j.name) +
                    ": origin: expected none for a floating joint (its q is the body's pose in the world)");
      s.joint = JointType::Free;
      s.parent = -1;
      s.placement = Placement{};
      break;
    default:
      throw Error(idx.at_joint(j.name) + ": type: expected revolute, continuous, prismatic, planar, fixed or floating");
  }
  if (joint_traits(s.joint).has_axis) {
    if (!(s.axis.norm() > 1e-12) || !std::isfinite(s.axis.squaredNorm())) {
      char got[96];
      std::snprintf(got, sizeof got, "[%g, %g, %g]", s.axis.x(), s.axis.y(), s.axis.z());
      throw Error(idx.at_joint(j.name) + ": axis: expected a non-zero axis of norm between 1e-12 and 1e150, got " + got);
    }
    s.axis.normalize();
  }
  // travel: <limit lower upper> on revolute and prismatic joints (continuous ones have none); a
  // <limit> with lower ≥ upper (urdfdom reads absent bounds as 0, 0) bounds nothing
  if ((j.type == urdf::Joint::REVOLUTE || j.type == urdf::Joint::PRISMATIC) && j.limits &&
      j.limits->lower < j.limits->upper) {
    s.lower = j.limits->lower;
    s.upper = j.limits->upper;
  }
  // effort: <limit effort> (required by the URDF spec on revolute and prismatic joints, often 0
  // where the author had no figure: a non-positive effort bounds nothing)
  if ((j.type == urdf::Joint::REVOLUTE || j.type == urdf::Joint::CONTINUOUS || j.type == urdf::Joint::PRISMATIC) &&
      j.limits && j.limits->effort > 0 && std::isfinite(j.limits->effort))
    s.effort = j.limits->effort;
  mass_properties(link, s);
  return s;
}

// A moving body is its link with every link welded to it: it needs mass somewhere in that group
// (the links' own <inertial> may be missing).  Said in the URDF's words before Model::build.
void check_moving_mass(const std::vector<BodySpec>& specs, bool free_root, const urdf_xml::Index& idx) {
  std::vector<int> group(specs.size());  // the moving spec each spec is welded into, -1 = the world
  std::map<int, bool> has_mass;          // (a negative or NaN mass is Model::build's to refuse)
  for (int i = 0; i < int(specs.size()); ++i) {
    const BodySpec& s = specs[i];
    group[i] = s.joint != JointType::Fixed ? i : s.parent < 0 ? -1 : group[s.parent];
    if (group[i] >= 0) has_mass[group[i]] = has_mass[group[i]] || s.mass != 0.0;
  }
  for (const auto& [g, any] : has_mass) {
    if (any) continue;
    const BodySpec& s = specs[g];
    const bool root = g == 0 && free_root;
    throw Error(idx.at_link(s.name) + ": inertial: expected mass properties for " +
                (root ? std::string("a free root (--free-root)")
                      : "a link that moves (joint '" + s.joint_name + "' is " + std::string(to_string(s.joint)) + ")") +
                ", on it or on a link welded to it");
  }
}

// Model::build's refusals, located at the joint's line for what the joint says (axis, placement,
// joint, the mass matrix's DOFs) and at the link's line for mass properties.
Model build_located(const std::vector<BodySpec>& specs, const Vec3& gravity, InertiaCheck inertia_check,
                    const urdf_xml::Index& idx) {
  try {
    return Model::build(specs, gravity, inertia_check);
  } catch (const ModelError& e) {
    const BodySpec& s = specs.at(e.spec);
    const std::string field = e.detail.substr(0, e.detail.find(':'));
    const bool joint_field = field == "axis" || field == "joint" || field.starts_with("placement") ||
                             field == "mass matrix";
    const bool has_joint = idx.joints.count(s.joint_name) > 0;
    throw Error((joint_field && has_joint ? idx.at_joint(s.joint_name) : idx.at_link(s.name)) + ": " + e.detail);
  }
}

}  // namespace

Model parse_urdf(const std::string& xml, const std::string& path, bool free_root, const Vec3& gravity,
                 InertiaCheck inertia_check) {
  const urdf_xml::Index idx = urdf_xml::index(xml, path);
  const urdf::ModelInterfaceSharedPtr robot = read_robot(idx);

  std::vector<BodySpec> specs{root_spec(*robot->getRoot(), free_root)};
  std::map<std::string, int> link_index{{robot->getRoot()->name, 0}};
  for (const auto& jn : parent_first(*robot, idx)) {
    const auto j = robot->getJoint(jn);
    const auto link = robot->getLink(j->child_link_name);
    link_index[link->name] = int(specs.size());
    specs.push_back(joint_spec(*j, *link, link_index, free_root, idx));
  }
  check_moving_mass(specs, free_root, idx);
  return build_located(specs, gravity, inertia_check, idx);
}

}  // namespace soadyn
