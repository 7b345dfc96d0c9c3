// URDF import: urdfdom reads the robot, tinyxml2 the document order of the joints and the line of
// every link and joint, so that errors name file:line and q keeps the URDF's own order.
#include "soadyn/scenario.hpp"

#include <console_bridge/console.h>
#include <tinyxml2.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

namespace soadyn {

namespace {

// Collects urdfdom's console messages instead of printing them.
class CaptureConsole : public console_bridge::OutputHandler {
 public:
  CaptureConsole() { console_bridge::useOutputHandler(this); }
  ~CaptureConsole() override { console_bridge::restorePreviousOutputHandler(); }
  CaptureConsole(const CaptureConsole&) = delete;
  CaptureConsole& operator=(const CaptureConsole&) = delete;
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) messages += (messages.empty() ? "" : "; ") + text;
  }
  std::string messages;
};

struct XmlIndex {
  std::vector<std::string> joint_order;   // joints in document order
  std::map<std::string, int> joint_line, link_line;
};

// The link graph must be a tree before urdfdom sees it: urdfdom leaks the shared_ptr cycle it
// builds for a cyclic graph, and its message names no line.
void check_tree(const tinyxml2::XMLElement* robot, const std::string& path) {
  std::map<std::string, std::pair<std::string, int>> parent_of;  // child link → (parent link, line)
  for (auto* e = robot->FirstChildElement("joint"); e; e = e->NextSiblingElement("joint")) {
    const auto* p = e->FirstChildElement("parent");
    const auto* c = e->FirstChildElement("child");
    const char* pl = p ? p->Attribute("link") : nullptr;
    const char* cl = c ? c->Attribute("link") : nullptr;
    const std::string at = path + ":" + std::to_string(e->GetLineNum()) + ": joint '" + e->Attribute("name") + "'";
    if (!pl) throw Error(at + ": expected <parent link=\"...\"/>");
    if (!cl) throw Error(at + ": expected <child link=\"...\"/>");
    if (std::string(pl) == cl) throw Error(at + ": link '" + std::string(cl) + "' is its own parent");
    if (parent_of.count(cl))
      throw Error(at + ": link '" + std::string(cl) + "' already has a parent joint (line " +
                  std::to_string(parent_of[cl].second) + "); a URDF is a tree");
    parent_of[cl] = {pl, e->GetLineNum()};
  }
  for (const auto& [link, pl] : parent_of) {
    std::string at = link, chain = link;
    for (size_t steps = 0; parent_of.count(at); ++steps) {
      at = parent_of[at].first;
      chain += " <- " + at;
      if (at == link || steps > parent_of.size())
        throw Error(path + ":" + std::to_string(pl.second) + ": URDF: cycle in the links: " + chain);
    }
  }
}

XmlIndex index_xml(const std::string& xml, const std::string& path) {
  tinyxml2::XMLDocument doc;
  // entity declarations: a URDF needs none, and nested ones expand without bound (an XML bomb)
  if (const size_t at = xml.find("<!ENTITY"); at != std::string::npos)
    throw Error(path + ":" + std::to_string(1 + std::count(xml.begin(), xml.begin() + long(at), '\n')) +
                ": XML: entity declarations (<!ENTITY ...>) are refused: a URDF needs none, and nested ones expand "
                "without bound (an XML bomb)");
  if (doc.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS)
    throw Error(path + ":" + std::to_string(doc.ErrorLineNum()) + ": XML: " + doc.ErrorStr());
  const tinyxml2::XMLElement* robot = doc.FirstChildElement("robot");
  if (!robot) throw Error(path + ":1: URDF: expected a <robot> element at the top");
  XmlIndex idx;
  for (auto* e = robot->FirstChildElement(); e; e = e->NextSiblingElement()) {
    const char* name = e->Attribute("name");
    const std::string tag = e->Name();
    if (!name) {
      if (tag == "link" || tag == "joint")
        throw Error(path + ":" + std::to_string(e->GetLineNum()) + ": <" + tag + ">: missing attribute 'name'");
      continue;
    }
    if (tag == "joint") {
      if (idx.joint_line.count(name))
        throw Error(path + ":" + std::to_string(e->GetLineNum()) + ": joint '" + name + "': duplicate joint name");
      idx.joint_order.push_back(name);
      idx.joint_line[name] = e->GetLineNum();
    } else if (tag == "link") {
      if (idx.link_line.count(name))
        throw Error(path + ":" + std::to_string(e->GetLineNum()) + ": link '" + name + "': duplicate link name");
      idx.link_line[name] = e->GetLineNum();
    }
  }
  check_tree(robot, path);
  return idx;
}

Placement to_placement(const urdf::Pose& p) {
  Placement X;
  X.p = Vec3(p.position.x, p.position.y, p.position.z);
  X.R = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).normalized().toRotationMatrix();
  return X;
}

void mass_properties(const urdf::Link& link, BodySpec& s) {
  if (!link.inertial) return;  // massless; allowed only where merged by a fixed joint
  const urdf::Inertial& in = *link.inertial;
  const Placement X = to_placement(in.origin);
  Mat3 I;
  I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  s.mass = in.mass;
  s.com = X.p;
  s.inertia = X.R * I * X.R.transpose();
}

}  // namespace

Model parse_urdf(const std::string& xml, const std::string& path, bool free_root, const Vec3& gravity) {
  const XmlIndex idx = index_xml(xml, path);
  urdf::ModelInterfaceSharedPtr robot;
  std::string messages;
  {
    CaptureConsole console;
    robot = urdf::parseURDF(xml);
    messages = console.messages;
  }
  if (!robot) throw Error(path + ": URDF: " + (messages.empty() ? "urdfdom could not read the robot" : messages));
  const urdf::LinkConstSharedPtr root = robot->getRoot();
  if (!root) throw Error(path + ": URDF: no root link");

  auto at_link = [&](const std::string& link) {
    auto it = idx.link_line.find(link);
    return path + (it != idx.link_line.end() ? ":" + std::to_string(it->second) : std::string()) + ": link '" + link + "'";
  };
  auto at_joint = [&](const std::string& joint) {
    auto it = idx.joint_line.find(joint);
    return path + (it != idx.joint_line.end() ? ":" + std::to_string(it->second) : std::string()) + ": joint '" + joint + "'";
  };

  // parent-first order: the URDF's own joint order when it already is, else depth-first from the root
  std::vector<std::string> order;
  {
    std::set<std::string> placed{root->name};
    bool parent_first = true;
    for (const auto& jn : idx.joint_order) {
      const auto j = robot->getJoint(jn);
      if (!j || !placed.count(j->parent_link_name)) {
        parent_first = false;
        break;
      }
      placed.insert(j->child_link_name);
      order.push_back(jn);
    }
    if (!parent_first) {
      order.clear();
      std::vector<std::string> stack{root->name};
      while (!stack.empty()) {
        const std::string link = stack.back();
        stack.pop_back();
        std::vector<std::string> children;  // in document order
        for (const auto& jn : idx.joint_order) {
          const auto j = robot->getJoint(jn);
          if (j && j->parent_link_name == link) children.push_back(jn);
        }
        for (auto it = children.rbegin(); it != children.rend(); ++it) stack.push_back(robot->getJoint(*it)->child_link_name);
        for (const auto& jn : children) order.push_back(jn);  // a joint follows its parent link's joint
      }
    }
  }

  std::vector<BodySpec> specs;
  std::vector<std::string> where;  // location of each spec, for messages
  std::map<std::string, int> link_index;
  {
    BodySpec s;
    s.name = root->name;
    s.joint = free_root ? JointType::Free : JointType::Fixed;
    s.joint_name = free_root ? root->name + "_free" : root->name;
    mass_properties(*root, s);
    link_index[root->name] = 0;
    specs.push_back(s);
    where.push_back(at_link(root->name));
  }
  for (const auto& jn : order) {
    const auto j = robot->getJoint(jn);
    const auto link = robot->getLink(j->child_link_name);
    BodySpec s;
    s.name = link->name;
    s.joint_name = j->name;
    s.parent = link_index.at(j->parent_link_name);
    s.placement = to_placement(j->parent_to_joint_origin_transform);
    s.axis = Vec3(j->axis.x, j->axis.y, j->axis.z);
    switch (j->type) {
      case urdf::Joint::REVOLUTE:
      case urdf::Joint::CONTINUOUS: s.joint = JointType::Revolute; break;
      case urdf::Joint::PRISMATIC: s.joint = JointType::Prismatic; break;
      case urdf::Joint::FIXED: s.joint = JointType::Fixed; break;
      case urdf::Joint::FLOATING: {
        // a floating joint frees a body hung on the world-welded root: its q is the pose in the world
        if (s.parent != 0 || free_root)
          throw Error(at_joint(jn) + ": floating joints are supported only on a child of the root link, "
                                     "with the root welded to the world (no --free-root)");
        if (!s.placement.R.isIdentity(1e-12) || !s.placement.p.isZero(0.0))
          throw Error(at_joint(jn) + ": origin: expected none for a floating joint (its q is the body's pose in the world)");
        s.joint = JointType::Free;
        s.parent = -1;
        s.placement = Placement{};
        break;
      }
      default:
        throw Error(at_joint(jn) + ": type: expected revolute, continuous, prismatic, fixed or floating; "
                                   "planar joints are not supported");
    }
    if (s.joint == JointType::Revolute || s.joint == JointType::Prismatic) {
      if (!(s.axis.norm() > 1e-12) || !std::isfinite(s.axis.squaredNorm())) {
        char got[96];
        std::snprintf(got, sizeof got, "[%g, %g, %g]", s.axis.x(), s.axis.y(), s.axis.z());
        throw Error(at_joint(jn) + ": axis: expected a non-zero axis of norm between 1e-12 and 1e150, got " + got);
      }
      s.axis.normalize();
    }
    mass_properties(*link, s);
    if (s.joint != JointType::Fixed && !link->inertial)
      throw Error(at_link(link->name) + ": inertial: expected mass properties for a link that moves (joint '" +
                  jn + "' is " + std::string(to_string(s.joint)) + ")");
    link_index[link->name] = int(specs.size());
    specs.push_back(s);
    where.push_back(at_link(link->name));
  }
  if (free_root && !root->inertial)
    throw Error(at_link(root->name) + ": inertial: expected mass properties for a free root (--free-root)");
  try {
    return Model::build(specs, gravity);
  } catch (const ModelError& e) {
    throw Error(where.at(e.spec) + ": " + e.detail);
  }
}

}  // namespace soadyn
