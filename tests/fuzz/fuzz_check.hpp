// What every model a parser accepts must give: a finite, symmetric positive definite 𝓜 — at the
// neutral configuration and at a few configurations drawn deterministically from the input
// itself (so a finding reproduces from its artifact).  Anything else aborts: libFuzzer reports it.
// Compiled once, in fuzz_check.cpp, for both fuzz targets.
#pragma once

#include "soadyn/multibody/model.hpp"

#include <cstddef>
#include <cstdint>

namespace soadyn::fuzz {

// FNV-1a of the input: the seed of the configurations tried
std::uint64_t seed_of(const std::uint8_t* data, std::size_t size);

// 𝓜 finite, symmetric and positive definite (up to rounding) at neutral and at three
// configurations: each coordinate moved by up to ±π, quaternions renormalized; aborts otherwise
void check_mass_matrix(const Model& m, std::uint64_t seed);

}  // namespace soadyn::fuzz
