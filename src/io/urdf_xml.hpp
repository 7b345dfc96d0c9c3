// The document side of URDF import: tinyxml2 reads the file once for what urdfdom does not keep —
// the line of every link and joint and of their child elements, and the joints' document order —
// checks the link graph is one tree, and keeps for urdfdom only what soadyn reads: links with their
// <inertial>, and joints.  Geometry, materials, transmissions and simulator blocks never reach
// urdfdom, so a duplicated material or a malformed mesh (common in composed xacro output) cannot
// refuse a robot whose dynamics they do not touch.  Internal to soadyn.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace soadyn::urdf_xml {

// One <link> or <joint>: its line and the line of the first child element of each tag.
struct Element {
  int line = 0;
  std::map<std::string, int> child;
};

struct Index {
  std::string path;                        // the file, for messages
  int robot_line = 1;
  std::vector<std::string> joint_order;    // joints in document order
  std::map<std::string, Element> joints, links;
  std::string dynamics;                    // the document with only what soadyn reads, for urdfdom

  // "path:line: joint 'name'" / "path:line: link 'name'"
  std::string at_joint(const std::string& name) const;
  std::string at_link(const std::string& name) const;
};

// Parses the document and checks names and the tree: every joint names a parent and a child link
// that exist, no link has two parents, there is no cycle and there is one root.  Throws
// soadyn::Error naming file:line.  Fills `dynamics`.
Index index(const std::string& xml, const std::string& path);

// urdfdom's messages when it refuses the robot name the joint or link they are about; returns
// "path:line: joint 'name': URDF: message; message" with the line of that element, or of its child
// element the messages speak of (<limit>, <inertial>, ...).  Falls back to the <robot> line.
std::string locate(const Index& idx, const std::vector<std::string>& messages);

}  // namespace soadyn::urdf_xml
