// The forward-dynamics routes by name, and forward_dynamics choosing one (algorithms.hpp); the
// routes themselves: rnea.cpp (bias), mass_matrix.cpp, ltdl.cpp, articulated.cpp.
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"

#include "dynamics_routes.hpp"

namespace soadyn {

const std::vector<FdMethodInfo>& fd_methods() {
  static const std::vector<FdMethodInfo> table = {
      {FdMethod::Dense, "dense", "composite mass matrix, then Cholesky"},
      {FdMethod::Sparse, "sparse", "composite mass matrix, tree-sparse LᵀDL"},
      {FdMethod::ArticulatedBody, "aba", "O(N) articulated-body recursion"},
  };
  return table;
}

std::vector<std::string> fd_method_names() {
  std::vector<std::string> names;
  for (const auto& m : fd_methods()) names.emplace_back(m.name);
  return names;
}

std::string_view to_string(FdMethod m) {
  for (const auto& info : fd_methods())
    if (info.method == m) return info.name;
  return "?";
}

FdMethod parse_fd_method(std::string_view s) {
  for (const auto& info : fd_methods())
    if (info.name == s) return info.method;
  if (s == kFdMethodAliasOn) return FdMethod::ArticulatedBody;
  std::string all;
  for (const auto& n : fd_method_names()) all += (all.empty() ? "" : ", ") + n;
  throw Error("forward-dynamics method: expected one of " + all + "; got '" + std::string(s) + "'");
}

void forward_dynamics(const Model& model, Data& data, const VecX& tau, FdMethod method) {
  data.check(model, "forward_dynamics", "tau", tau.size(), model.nv);
  data.require("forward_dynamics", true);
  switch (method) {
    case FdMethod::Dense:
      mass_matrix(model, data);
      bias_forces(model, data);
      data.work.factor.llt.compute(data.M);
      if (data.work.factor.llt.info() != Eigen::Success) throw Error("forward dynamics: the mass matrix is not positive definite");
      data.qdd = tau - data.bias;
      data.work.factor.llt.solveInPlace(data.qdd);
      return;
    case FdMethod::Sparse:
      mass_matrix(model, data);
      bias_forces(model, data);
      ltdl_factor(model, data);
      data.qdd = tau - data.bias;
      ltdl_solve(model, data, data.qdd);
      return;
    case FdMethod::ArticulatedBody:
      detail::aba(model, data, tau);
      return;
  }
}

const VecX& forward_dynamics(const Model& model, Data& data, const VecX& q, const VecX& v, const VecX& tau,
                             FdMethod method) {
  data.check(model, "forward_dynamics", "v", v.size(), model.nv);  // every size before any work
  data.check(model, "forward_dynamics", "tau", tau.size(), model.nv);
  update_kinematics(model, data, q);
  update_velocities(model, data, v);
  forward_dynamics(model, data, tau, method);
  return data.qdd;
}

}  // namespace soadyn
