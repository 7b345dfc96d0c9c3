#include "urdf_xml.hpp"

#include "soadyn/multibody/types.hpp"
#include "soadyn/multibody/text.hpp"

#include <tinyxml2.h>

#include <algorithm>
#include <cctype>
#include <set>

namespace soadyn::urdf_xml {

namespace {

std::string line_of(const std::string& path, int line) { return path + ":" + std::to_string(line); }

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

Element element(const tinyxml2::XMLElement* e) {
  Element out{e->GetLineNum(), {}};
  for (auto* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) out.child.emplace(c->Name(), c->GetLineNum());
  return out;
}

// Links and joints by name, refusing nameless and duplicate ones.
void read_elements(const tinyxml2::XMLElement* robot, Index& idx) {
  for (auto* e = robot->FirstChildElement(); e; e = e->NextSiblingElement()) {
    const std::string tag = e->Name();
    auto* table = tag == "joint" ? &idx.joints : tag == "link" ? &idx.links : nullptr;
    if (!table) continue;
    const char* name = e->Attribute("name");
    const std::string at = line_of(idx.path, e->GetLineNum());
    if (!name) throw Error(at + ": <" + tag + ">: missing attribute 'name'");
    if (table->count(name))
      throw Error(at + ": " + tag + " '" + printable(name) + "': duplicate " + tag + " name (the first is at line " +
                  std::to_string(table->at(name).line) + ")");
    table->emplace(name, element(e));
    if (tag == "joint") idx.joint_order.push_back(name);
  }
}

// What urdfdom is given: <robot> with its links, each keeping only <inertial>, and its joints.
std::string dynamics_only(tinyxml2::XMLDocument& doc, tinyxml2::XMLElement* robot) {
  for (auto* e = robot->FirstChildElement(); e;) {
    auto* next = e->NextSiblingElement();
    const std::string tag = e->Name();
    if (tag == "link") {
      for (auto* c = e->FirstChildElement(); c;) {
        auto* cn = c->NextSiblingElement();
        if (std::string(c->Name()) != "inertial") e->DeleteChild(c);
        c = cn;
      }
    } else if (tag != "joint") {
      robot->DeleteChild(e);  // <material>, <transmission>, <gazebo>, extensions
    }
    e = next;
  }
  tinyxml2::XMLPrinter printer(nullptr, true);
  doc.Print(&printer);
  return printer.CStr();
}

// urdfdom 3.0 logs some malformed values (an <origin>'s xyz or rpy, a <mass> value) by handing
// a message that quotes them to console_bridge as its printf format, so a '%' there is read as a
// conversion ("%n" writes through a pointer that is not there: a crash).  No value urdfdom reads
// holds a '%', names aside, which it always logs through "%s": any other attribute with one is
// refused here, before urdfdom sees the document
void check_no_percent(const tinyxml2::XMLElement* e, const std::string& path) {
  for (const auto* a = e->FirstAttribute(); a; a = a->Next()) {
    const std::string name = a->Name(), value = a->Value();
    if (name == "name" || name == "link" || name == "joint" || value.find('%') == std::string::npos) continue;
    throw Error(line_of(path, e->GetLineNum()) + ": <" + e->Name() + "> " + name + ": expected a URDF value, got '" +
                value + "' (a '%' is part of no number, axis or type)");
  }
  for (const auto* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) check_no_percent(c, path);
}

// The link graph must be one tree before urdfdom sees it: urdfdom leaks the shared_ptr cycle it
// builds for a cyclic graph, and its messages name no line.
void check_tree(const tinyxml2::XMLElement* robot, const Index& idx) {
  std::map<std::string, std::pair<std::string, int>> parent_of;  // child link → (parent link, line)
  for (auto* e = robot->FirstChildElement("joint"); e; e = e->NextSiblingElement("joint")) {
    const std::string at = idx.at_joint(e->Attribute("name"));
    std::string end[2];
    for (int k = 0; k < 2; ++k) {
      const char* tag = k == 0 ? "parent" : "child";
      const auto* x = e->FirstChildElement(tag);
      const char* link = x ? x->Attribute("link") : nullptr;
      if (!link) throw Error(at + ": expected <" + tag + " link=\"...\"/>");
      if (!idx.links.count(link))
        throw Error(line_of(idx.path, x->GetLineNum()) + ": joint '" + e->Attribute("name") + "': " + tag +
                    ": no link named '" + link + "'");
      end[k] = link;
    }
    if (end[0] == end[1]) throw Error(at + ": link '" + end[1] + "' is its own parent");
    if (parent_of.count(end[1]))
      throw Error(at + ": link '" + end[1] + "' already has a parent joint (line " +
                  std::to_string(parent_of[end[1]].second) + "); a URDF is a tree: drop this joint and close the loop "
                  "from a scenario's loops: (scenarios/README.md, Closed loops)");
    parent_of[end[1]] = {end[0], e->GetLineNum()};
  }
  // no cycle: walk up from every link until a link known to reach a root; O(N) walks in all
  std::set<std::string> reaches_root;
  for (const auto& [link, pl] : parent_of) {
    std::vector<std::string> path{link};
    std::set<std::string> on_path{link};
    for (auto up = parent_of.find(link); up != parent_of.end() && !reaches_root.count(up->second.first);
         up = parent_of.find(up->second.first)) {
      const std::string& p = up->second.first;
      if (!on_path.insert(p).second) {
        std::string chain = p;  // p <- its parent <- ... <- p
        for (auto it = std::find(path.begin(), path.end(), p) + 1; it != path.end(); ++it) chain += " <- " + *it;
        chain += " <- " + p;
        throw Error(line_of(idx.path, parent_of.at(p).second) + ": URDF: cycle in the links: " + chain);
      }
      path.push_back(p);
    }
    reaches_root.insert(path.begin(), path.end());
  }
  // one root: every other link hangs from a joint
  std::vector<std::pair<int, std::string>> roots;
  for (const auto& [name, e] : idx.links)
    if (!parent_of.count(name)) roots.emplace_back(e.line, name);
  std::sort(roots.begin(), roots.end());
  if (roots.size() > 1)
    throw Error(idx.at_link(roots[1].second) + ": a second root link (the first is '" + roots[0].second + "', line " +
                std::to_string(roots[0].first) + "); a URDF is one tree: connect it by a joint");
}

// The element a message names, as "joint [name]" or "link 'name'"; console_bridge cuts messages at
// 1023 characters, so a name left open at the end is matched as the start of one.  A plain scan:
// a regex would recurse once per character of a long name.
struct Named {
  std::string kind, name;
  const Element* element = nullptr;
};
Named named(const Index& idx, const std::string& message) {
  const std::string text = lower(message);
  for (const std::string kind : {"joint", "link"}) {
    const auto& table = kind == "joint" ? idx.joints : idx.links;
    for (size_t at = text.find(kind); at != std::string::npos; at = text.find(kind, at + 1)) {
      size_t open = at + kind.size();
      while (open < text.size() && text[open] == ' ') ++open;
      if (open >= text.size() || (text[open] != '[' && text[open] != '\'')) continue;
      const size_t close = message.find(text[open] == '[' ? ']' : '\'', open + 1);
      const std::string name = message.substr(open + 1, close == std::string::npos ? close : close - open - 1);
      auto e = table.find(name);
      if (e == table.end() && close == std::string::npos && !name.empty()) {
        e = table.lower_bound(name);
        if (e != table.end() && !e->first.starts_with(name)) e = table.end();
      }
      if (e != table.end()) return {kind, e->first, &e->second};
    }
  }
  return {};
}

// UTF-8 only: urdfdom's TinyXML steps a multi-byte lead byte's whole length, past the end of the
// text when the sequence is cut short.  The first bad attribute, text or comment is named at its
// line (tinyxml2's values, entities decoded); any other bad byte (a declaration, a DOCTYPE) at its
// line of the text.  Messages are formed only for a refusal.
void check_utf8(const tinyxml2::XMLDocument& doc, const std::string& xml, const std::string& path) {
  for (const tinyxml2::XMLNode* n = doc.FirstChild(); n;) {
    if (const tinyxml2::XMLElement* e = n->ToElement()) {
      if (!is_valid_utf8(e->Name()))
        throw Error(line_of(path, n->GetLineNum()) + ": <" + printable(e->Name()) + ">: expected a UTF-8 tag");
      for (const tinyxml2::XMLAttribute* a = e->FirstAttribute(); a; a = a->Next()) {
        if (is_valid_utf8(a->Name()) && is_valid_utf8(a->Value())) continue;
        const char* name = e->Attribute("name");
        const std::string field = printable(a->Name());
        throw Error(line_of(path, n->GetLineNum()) + ": " + e->Name() + (name ? " '" + printable(name) + "'" : "") +
                    ": " + field + ": expected a valid UTF-8 " + (field == "name" ? "name" : "value") + ", got '" +
                    printable(a->Value()) + "'");
      }
    } else if (n->Value() && !is_valid_utf8(n->Value())) {
      throw Error(line_of(path, n->GetLineNum()) + ": XML: expected UTF-8 text, got '" +
                  printable(std::string(n->Value()).substr(0, 60)) + "'");
    }
    // next node in document order, without recursion (the nesting is the file's)
    if (n->FirstChild()) { n = n->FirstChild(); continue; }
    while (n && !n->NextSibling()) n = n->Parent();
    if (n) n = n->NextSibling();
  }
  if (is_valid_utf8(xml)) return;  // the lines below only locate what the whole text holds
  for (size_t start = 0, line = 1; start < xml.size(); ++line) {  // a UTF-8 sequence never holds '\n'
    const size_t end = std::min(xml.find('\n', start), xml.size());
    if (!is_valid_utf8(xml.substr(start, end - start)))
      throw Error(line_of(path, int(line)) + ": XML: expected UTF-8 text, got '" +
                  printable(xml.substr(start, std::min<size_t>(end - start, 60))) + "'");
    start = end + 1;
  }
}

}  // namespace

std::string Index::at_joint(const std::string& name) const {
  auto it = joints.find(name);
  return (it != joints.end() ? line_of(path, it->second.line) : path) + ": joint '" + printable(name) + "'";
}

std::string Index::at_link(const std::string& name) const {
  auto it = links.find(name);
  return (it != links.end() ? line_of(path, it->second.line) : path) + ": link '" + printable(name) + "'";
}

Index index(const std::string& xml, const std::string& path) {
  // entity declarations: a URDF needs none, and nested ones expand without bound (an XML bomb)
  if (const size_t at = xml.find("<!ENTITY"); at != std::string::npos)
    throw Error(path + ":" + std::to_string(1 + std::count(xml.begin(), xml.begin() + long(at), '\n')) +
                ": XML: entity declarations (<!ENTITY ...>) are refused: a URDF needs none, and nested ones expand "
                "without bound (an XML bomb)");
  tinyxml2::XMLDocument doc;
  if (doc.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS)
    throw Error(line_of(path, doc.ErrorLineNum()) + ": XML: " + doc.ErrorStr());
  check_utf8(doc, xml, path);
  tinyxml2::XMLElement* robot = doc.FirstChildElement("robot");
  if (!robot) throw Error(path + ":1: URDF: expected a <robot> element at the top");
  Index idx;
  idx.path = path;
  idx.robot_line = robot->GetLineNum();
  read_elements(robot, idx);
  if (idx.links.empty()) throw Error(line_of(path, idx.robot_line) + ": URDF: expected at least one <link>");
  check_tree(robot, idx);
  idx.dynamics = dynamics_only(doc, robot);
  check_no_percent(robot, path);  // what is left of it: what urdfdom reads
  return idx;
}

std::string locate(const Index& idx, const std::vector<std::string>& messages) {
  // the child element a message speaks of, most specific first
  static const std::vector<std::pair<std::string, std::string>> children = {
      {"safety", "safety_controller"}, {"soft_", "safety_controller"}, {"k_velocity", "safety_controller"},
      {"k_position", "safety_controller"}, {"calibration", "calibration"}, {"rising", "calibration"},
      {"falling", "calibration"}, {"mimic", "mimic"}, {"multiplier", "mimic"}, {"dynamics", "dynamics"},
      {"damping", "dynamics"}, {"friction", "dynamics"}, {"limit", "limit"}, {"effort", "limit"},
      {"velocity", "limit"}, {"axis", "axis"}, {"origin", "origin"}, {"inertia", "inertial"},
      {"mass", "inertial"}};
  std::string all;
  for (const auto& m : messages) all += (all.empty() ? "" : "; ") + m;
  Named e;
  for (size_t k = 0; k < messages.size() && !e.element; ++k) e = named(idx, messages[k]);
  if (!e.element) return line_of(idx.path, idx.robot_line) + ": URDF: " + all;
  const std::string text = lower(all);
  int line = e.element->line;
  for (const auto& [word, tag] : children) {
    const auto c = e.element->child.find(tag);
    if (text.find(word) != std::string::npos && c != e.element->child.end()) {
      line = c->second;
      break;
    }
  }
  return line_of(idx.path, line) + ": " + e.kind + " '" + e.name + "': URDF: " + all;
}

}  // namespace soadyn::urdf_xml
