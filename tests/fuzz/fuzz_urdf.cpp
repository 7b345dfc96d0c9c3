// libFuzzer target: URDF text → model → mass matrix.  A crash, leak, hang or an exception other
// than soadyn::Error is a finding; so is an accepted model whose mass matrix is not finite or not
// positive definite (fuzz_check.hpp).
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/io/scenario_file.hpp"

#include "fuzz_check.hpp"

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
      soadyn::fuzz::check_mass_matrix(m, soadyn::fuzz::seed_of(data, size));
    } catch (const soadyn::Error&) {
    }
  }
  return 0;
}
