// libFuzzer target: URDF text → model → mass matrix.
#include "soadyn/algorithms.hpp"
#include "soadyn/kinematics.hpp"
#include "soadyn/scenario.hpp"

#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string xml(reinterpret_cast<const char*>(data), size);
  for (bool free_root : {false, true}) {
    try {
      const soadyn::Model m = soadyn::parse_urdf(xml, "fuzz.urdf", free_root, soadyn::Vec3(0, 0, -9.81));
      if (m.nbodies > 64) continue;
      soadyn::Data d(m);
      soadyn::update_kinematics(m, d, m.neutral_configuration());
      soadyn::mass_matrix(m, d);
    } catch (const soadyn::Error&) {
    }
  }
  return 0;
}
