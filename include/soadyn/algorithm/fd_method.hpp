// The forward-dynamics routes q̈ = 𝓜⁻¹ (τ − bias) can take (algorithms.hpp: forward_dynamics), and
// their words: the enum a setting holds (settings.hpp) without the algorithms that run it.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace soadyn {

enum class FdMethod {
  Dense,           // "dense": composite 𝓜, then Cholesky
  Sparse,          // "sparse": composite 𝓜 factored in place as LᵀDL along the tree (no fill-in off
                   //   ancestor chains)
  ArticulatedBody  // "aba": the O(N) articulated-body recursion (the factored inverse mass matrix);
                   //   𝓜 never formed
};

// The one registry of forward-dynamics routes: the word users write for each, and a line about it.
struct FdMethodInfo {
  FdMethod method;
  std::string_view name;
  std::string_view description;
};
const std::vector<FdMethodInfo>& fd_methods();
std::vector<std::string> fd_method_names();  // {"dense", "sparse", "aba"}
std::string_view to_string(FdMethod m);
// "on", the O(N) route's word before "aba" (YAML 1.1 and PyYAML read a bare on as true): still taken
inline constexpr std::string_view kFdMethodAliasOn = "on";
FdMethod parse_fd_method(std::string_view s);  // a name of fd_methods() or "on"; throws soadyn::Error

}  // namespace soadyn
