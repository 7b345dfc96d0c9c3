#include "soadyn/io/version.hpp"

#include <Eigen/Core>
#include <H5public.h>
#include <sundials/sundials_config.h>
#include <tinyxml2.h>

namespace soadyn {

std::string version() { return SOADYN_VERSION; }

std::vector<std::pair<std::string, std::string>> dependency_versions() {
  const auto v3 = [](int a, int b, int c) {
    return std::to_string(a) + "." + std::to_string(b) + "." + std::to_string(c);
  };
  return {
      {"Eigen", v3(EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION)},
      {"SUNDIALS", SUNDIALS_VERSION},
      {"HDF5", v3(H5_VERS_MAJOR, H5_VERS_MINOR, H5_VERS_RELEASE)},
      {"urdfdom", SOADYN_URDFDOM_VERSION},
      {"yaml-cpp", SOADYN_YAML_CPP_VERSION},
      {"tinyxml2", v3(TIXML2_MAJOR_VERSION, TIXML2_MINOR_VERSION, TIXML2_PATCH_VERSION)},
  };
}

}  // namespace soadyn
