// libFuzzer target: scenario text → model → mass matrix and bias.  Any exception other than
// soadyn::Error, any crash, leak or hang is a finding; so is an accepted model whose mass matrix
// is not finite or not positive definite (fuzz_check.hpp).
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/io/scenario_file.hpp"

#include "fuzz_check.hpp"

#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const soadyn::Scenario sc = soadyn::parse_scenario(text, "fuzz.yaml");
    if (sc.model.nbodies > 64) return 0;
    soadyn::Data d(sc.model);
    soadyn::update_kinematics(sc.model, d, sc.q0);
    soadyn::mass_matrix(sc.model, d);
    soadyn::update_velocities(sc.model, d, sc.v0);
    soadyn::bias_forces(sc.model, d);
    soadyn::fuzz::check_mass_matrix(sc.model, soadyn::fuzz::seed_of(data, size));
  } catch (const soadyn::Error&) {
  }
  return 0;
}
