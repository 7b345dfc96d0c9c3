// The fuzz targets' check of every accepted model (fuzz_check.hpp).
#include "fuzz_check.hpp"

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <random>

namespace soadyn::fuzz {

// FNV-1a of the input: the seed of the configurations tried
std::uint64_t seed_of(const std::uint8_t* data, std::size_t size) {
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t k = 0; k < size; ++k) h = (h ^ data[k]) * 1099511628211ull;
  return h;
}

namespace {

[[noreturn]] void trap(const char* what, int config, const MatX& M) {
  std::fprintf(stderr, "fuzz: accepted model, configuration %d: the mass matrix is %s\n", config, what);
  for (Eigen::Index r = 0; r < std::min<Eigen::Index>(M.rows(), 8); ++r) {
    for (Eigen::Index c = 0; c < std::min<Eigen::Index>(M.cols(), 8); ++c) std::fprintf(stderr, " %.6g", M(r, c));
    std::fprintf(stderr, "\n");
  }
  std::abort();
}

}  // namespace

void check_mass_matrix(const Model& m, std::uint64_t seed) {
  Data d(m);
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> step(-3.14159, 3.14159);
  for (int config = 0; config < 4; ++config) {
    VecX q = m.neutral_configuration();
    if (config > 0) {
      for (Eigen::Index k = 0; k < q.size(); ++k) q(k) += step(gen);
      m.normalize(q);
    }
    update_kinematics(m, d, q);
    mass_matrix(m, d);
    const MatX& M = d.M;
    if (!M.allFinite()) trap("not finite", config, M);
    if (!M.isApprox(M.transpose(), 1e-12)) trap("not symmetric", config, M);
    // positive definite up to rounding: a Cholesky factor, or else no eigenvalue below −1e-9 λ_max
    // (a model with absurd scales, a 1e62 m offset, may be singular to working precision — a
    // validation matter — but never indefinite)
    if (Eigen::LLT<MatX>(M).info() == Eigen::Success) continue;
    const Eigen::VectorXd l = Eigen::SelfAdjointEigenSolver<MatX>(M, Eigen::EigenvaluesOnly).eigenvalues();
    if (!(l.minCoeff() >= -1e-9 * std::max(l.maxCoeff(), 0.0)) || !(l.maxCoeff() > 0))
      trap("not positive definite (an eigenvalue below -1e-9 of the largest)", config, M);
  }
}

}  // namespace soadyn::fuzz
