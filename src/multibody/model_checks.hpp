// The checks Model::build runs (model_checks.cpp): each refuses with one ModelError naming the
// body (its index among the given specs) and the field, what was expected and what it got.
#pragma once

#include "soadyn/multibody/model.hpp"

#include <string>
#include <vector>

namespace soadyn::model_checks {

std::string fmt(double x);                 // 10 significant digits
std::string fmt(const Eigen::MatrixXd& m);  // [a b; c d]

[[noreturn]] void refuse(const BodySpec& b, int i, const std::string& field, const std::string& expected,
                         const std::string& got);

// every number of a user-supplied body finite, its mass, inertia, placement, axis, limits sound
void validate(const BodySpec& b, int i);
// mass properties of a body or a merged one: symmetric, positive semidefinite (up to round-off)
void check_inertia(const BodySpec& b, int i, double mass, const Mat3& I);
// the triangle inequality over every body part: warned of, balanced or refused as `check` says;
// returns the specs with any balanced inertias
std::vector<BodySpec> triangle_inequality(const std::vector<BodySpec>& specs, InertiaCheck check,
                                          std::vector<std::string>& warnings);
// 𝓜 positive definite and resolvable in doubles at the neutral configuration (spec_of: the spec
// each model body came from)
void check_mass_matrix(const Model& m, const std::vector<BodySpec>& specs, const std::vector<int>& spec_of);

}  // namespace soadyn::model_checks
