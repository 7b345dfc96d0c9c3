// The refusal a URDF text meets, as its one-line message ("(accepted)" if none), read as robot.urdf.
#pragma once

#include "soadyn/io/scenario_file.hpp"

#include <string>

namespace soadyn::test {

inline std::string urdf_error(const std::string& xml, bool free_root = false) {
  try {
    parse_urdf(xml, "robot.urdf", free_root, urdf_gravity());
  } catch (const Error& e) {
    return e.what();
  }
  return "(accepted)";
}

}  // namespace soadyn::test
