// Every URDF refusal names file:line: urdfdom's own messages located, tree errors, model
// refusals at the joint or the link, and text that is not UTF-8.
#include "test_util.hpp"
#include "urdf_error.hpp"

using namespace soadyn;
using namespace soadyn::test;
using ::testing::HasSubstr;

namespace {

// a two-link robot whose joint (line 4) or moving link (line 3) is given
std::string two_links(const std::string& joint, const std::string& link_b = "") {
  return "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\">" +
         (link_b.empty() ? std::string("<inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\" "
                                       "ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>")
                         : link_b) +
         "</link>\n" + joint + "\n</robot>";
}

TEST(UrdfErrorLines, UrdfdomRefusalsAreLocated) {
  const std::string pc = "<parent link=\"a\"/><child link=\"b\"/>";
  struct Case {
    std::string xml, expect;
  };
  const Case cases[] = {
      {two_links("<joint name=\"j\" type=\"revolute\">" + pc + "</joint>"),
       "robot.urdf:4: joint 'j': URDF: Joint [j] is of type REVOLUTE but it does not specify limits"},
      {two_links("<joint name=\"j\" type=\"prismatic\">" + pc + "</joint>"),
       "robot.urdf:4: joint 'j': URDF: Joint [j] is of type PRISMATIC without limits"},
      {two_links("<joint name=\"j\" type=\"revolute\">" + pc + "\n<limit lower=\"0\" upper=\"1\" velocity=\"1\"/></joint>"),
       "robot.urdf:5: joint 'j': URDF: joint limit: no effort"},
      {two_links("<joint name=\"j\" type=\"continuous\">" + pc + "\n<origin xyz=\"1 2\"/></joint>"),
       "robot.urdf:5: joint 'j': URDF:"},
      {two_links("<joint name=\"j\" type=\"continuous\">" + pc + "\n<axis xyz=\"1 0 zero\"/></joint>"),
       "robot.urdf:5: joint 'j': URDF: Malformed axis element for joint [j]"},
      {two_links("<joint name=\"j\" type=\"continuous\">" + pc + "\n<mimic multiplier=\"2\"/></joint>"),
       "robot.urdf:5: joint 'j': URDF: joint mimic: no mimic joint specified"},
      {two_links("<joint name=\"j\" type=\"ball\">" + pc + "</joint>"),
       "robot.urdf:4: joint 'j': URDF: Joint [j] has no known type [ball]"},
      {two_links("<joint name=\"j\" type=\"continuous\">" + pc + "</joint>",
                 "\n<inertial><inertia ixx=\"1\" iyy=\"1\" izz=\"1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>"),
       "robot.urdf:4: link 'b': URDF: Inertial element must have a mass element"},
      {two_links("<joint name=\"j\" type=\"continuous\">" + pc + "</joint>",
                 "\n<inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>"),
       "robot.urdf:4: link 'b': URDF: Inertial: inertia element missing izz attribute"},
      {"<robot>\n<link name=\"a\"/>\n</robot>", "robot.urdf:1: URDF: No name given for the robot."},
  };
  for (const Case& c : cases) EXPECT_THAT(urdf_error(c.xml), HasSubstr(c.expect)) << c.xml;
}

// a long name in urdfdom's message is found without recursion per character, and when cut short
// urdfdom 3.0 hands some messages quoting a malformed value to printf as its format: a '%' in such
// a value (found by fuzz_urdf: "%n" crashed the process) is refused before urdfdom reads it, with
// the line, element and attribute; '%' in names stays allowed, and parts urdfdom never sees
// (visuals, meshes, extensions) are not read
TEST(UrdfErrorLines, PercentInAValueIsRefusedBeforeUrdfdom) {
  const std::string pc = "<parent link=\"a\"/><child link=\"b\"/>";
  const std::string joint = "<joint name=\"j\" type=\"continuous\">" + pc;
  EXPECT_EQ(urdf_error(two_links(joint + "\n<origin xyz=\"0.06 -n%n 0\"/></joint>")),
            "robot.urdf:5: <origin> xyz: expected a URDF value, got '0.06 -n%n 0' (a '%' is part of no number, axis or type)");
  EXPECT_THAT(urdf_error(two_links(joint + "\n<origin rpy=\"%s%s%s%n\"/></joint>")), HasSubstr("robot.urdf:5: <origin> rpy:"));
  EXPECT_THAT(urdf_error(two_links(joint + "</joint>", "<inertial><mass\nvalue=\"1%n\"/></inertial>")),
              HasSubstr("robot.urdf:3: <mass> value:"));
  EXPECT_THAT(urdf_error(two_links(joint + "\n<axis xyz=\"%n 0 1\"/></joint>")), HasSubstr("robot.urdf:5: <axis> xyz:"));
  // names may hold a '%', and so may what urdfdom is not given
  EXPECT_EQ(urdf_error(two_links("<joint name=\"j%n\" type=\"continuous\">" + pc + "</joint>")), "(accepted)");
  EXPECT_EQ(urdf_error(two_links(joint + "</joint>",
                                 "<visual><geometry><mesh filename=\"package://r/My%20Part.stl\"/></geometry></visual>"
                                 "<inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\" ixy=\"0\" "
                                 "ixz=\"0\" iyz=\"0\"/></inertial>")),
            "(accepted)");
}

TEST(UrdfErrorLines, LongNameInAnUrdfdomMessage) {
  const std::string name(200000, 'j');
  const std::string xml = two_links("<joint name=\"" + name + "\" type=\"revolute\"><parent link=\"a\"/>"
                                    "<child link=\"b\"/></joint>");
  // console_bridge cuts the message short, within the name: the element is still found
  EXPECT_THAT(urdf_error(xml), HasSubstr("robot.urdf:4: joint '" + name + "': URDF: Joint [jjjj"));
}

// what soadyn does not read cannot refuse a robot: a malformed visual, a material defined twice
TEST(UrdfErrorLines, IgnoredElementsAreNotRead) {
  const std::string pc = "<parent link=\"a\"/><child link=\"b\"/>";
  const std::string inertial = "<inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\" ixy=\"0\" "
                               "ixz=\"0\" iyz=\"0\"/></inertial>";
  EXPECT_EQ(urdf_error(two_links("<joint name=\"j\" type=\"continuous\">" + pc + "</joint>",
                                 inertial + "<visual><geometry></geometry></visual><collision/>")),
            "(accepted)");
  const std::string black = "<material name=\"black\"><color rgba=\"0 0 0 1\"/></material>\n";
  EXPECT_EQ(urdf_error(two_links("<joint name=\"j\" type=\"continuous\">" + pc + "</joint>\n" + black + black)),
            "(accepted)");
}

TEST(UrdfErrorLines, TreeErrorsAreLocated) {
  const std::string j = "<joint name=\"j\" type=\"continuous\"><parent link=\"a\"/>\n<child link=\"c\"/></joint>";
  EXPECT_THAT(urdf_error(two_links(j)), HasSubstr("robot.urdf:5: joint 'j': child: no link named 'c'"));
  const std::string p = "<joint name=\"j\" type=\"continuous\">\n<parent link=\"x\"/><child link=\"b\"/></joint>";
  EXPECT_THAT(urdf_error(two_links(p)), HasSubstr("robot.urdf:5: joint 'j': parent: no link named 'x'"));
  auto joint = [](const std::string& n, const std::string& p, const std::string& c) {
    return "<joint name=\"" + n + "\" type=\"fixed\"><parent link=\"" + p + "\"/><child link=\"" + c + "\"/></joint>\n";
  };
  EXPECT_THAT(urdf_error("<robot name=\"r\">\n<link name=\"a\"/><link name=\"b\"/><link name=\"c\"/><link name=\"d\"/>\n" +
                         joint("j1", "b", "c") + joint("j2", "c", "d") + joint("j3", "d", "b") + "</robot>"),
              HasSubstr("robot.urdf:5: URDF: cycle in the links: b <- d <- c <- b"));
  EXPECT_THAT(urdf_error("<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n</robot>"),
              HasSubstr("robot.urdf:3: link 'b': a second root link (the first is 'a', line 2)"));
  EXPECT_THAT(urdf_error("<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"a\"/>\n</robot>"),
              HasSubstr("robot.urdf:3: link 'a': duplicate link name (the first is at line 2)"));
}

// the joint's line for what the joint says, the link's for mass properties
TEST(UrdfErrorLines, ModelRefusalsPointAtTheJointOrTheLink) {
  EXPECT_THAT(urdf_error(two_links("<joint name=\"j\" type=\"continuous\"><parent link=\"a\"/><child link=\"b\"/>"
                                   "<axis xyz=\"0 0 0\"/></joint>")),
              HasSubstr("robot.urdf:4: joint 'j': axis: expected"));
  EXPECT_THAT(urdf_error(two_links("<joint name=\"j\" type=\"continuous\"><parent link=\"a\"/><child link=\"b\"/></joint>",
                                   "<inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"3\" ixy=\"0\" "
                                   "ixz=\"0\" iyz=\"0\"/></inertial>")),
              HasSubstr("robot.urdf:3: link 'b': inertia: expected principal moments obeying the triangle inequality"));
  EXPECT_THAT(urdf_error(two_links("<joint name=\"j\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/></joint>",
                                   "<inertial><mass value=\"0\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\" ixy=\"0\" "
                                   "ixz=\"0\" iyz=\"0\"/></inertial>")),
              HasSubstr("robot.urdf:3: link 'b': mass: expected a positive mass for a body with inertia"));
}

// urdfdom's TinyXML steps over the end of a text cut short inside a UTF-8 sequence: such bytes
// are refused at their line, naming the attribute where one holds them, before urdfdom reads them
// (the fuzzer's heap overflow, here as a test)
TEST(UrdfErrorLines, BytesThatAreNotUtf8) {
  const std::string pc = "<parent link=\"a\"/><child link=\"b\"/>";
  std::string xml = two_links("<joint name=\"j\" type=\"continuous\">" + pc + "</joint>");
  xml.insert(xml.find("</robot>"), "<!-- caf\xe3&&& -->\n");
  EXPECT_THAT(urdf_error(xml), HasSubstr("robot.urdf:5: XML: expected UTF-8 text, got ' caf\\xe3&&& '"));
  xml.replace(xml.find("\xe3"), 1, "\xc3\xa9");  // é, well formed
  EXPECT_EQ(urdf_error(xml), "(accepted)");
  EXPECT_THAT(urdf_error("<robot name=\"r\xff\">\n<link name=\"a\"/>\n</robot>"),
              HasSubstr("robot.urdf:1: robot 'r\\xff': name: expected a valid UTF-8 name, got 'r\\xff'"));
  EXPECT_THAT(urdf_error(two_links("<joint name=\"j\" type=\"continuous\">" + pc + "\n<axis xyz=\"1 0 \xe3\"/></joint>")),
              HasSubstr("robot.urdf:5: axis: xyz: expected a valid UTF-8 value, got '1 0 \\xe3'"));
  // a bad byte outside any node tinyxml2 keeps (here the XML declaration's encoding)
  EXPECT_THAT(urdf_error("<?xml version=\"1.0\" encoding=\"\xe3\"?>\n<robot name=\"r\">\n<link name=\"a\"/>\n</robot>"),
              HasSubstr("robot.urdf:1: XML: expected UTF-8 text, got"));
}

}  // namespace
