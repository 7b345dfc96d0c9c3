// soadyn's version and the versions of the libraries it was built with.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace soadyn {

std::string version();  // e.g. "0.1.0"

// {name, version} of each library soadyn was built against: Eigen, SUNDIALS, HDF5, urdfdom,
// yaml-cpp, tinyxml2
std::vector<std::pair<std::string, std::string>> dependency_versions();

}  // namespace soadyn
