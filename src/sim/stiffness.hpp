// Whether a run was stiff for its method: the stiffness hint in RunSummary (simulate.hpp).
#pragma once

#include "soadyn/sim/integrators.hpp"
#include "soadyn/sim/system.hpp"

namespace soadyn::detail {

// ρ(∂f/∂y) at (t, y): the largest |λ| of the Jacobian of the system's right-hand side, by forward
// differences of System::rhs (its inputs and continuous controllers included: 1 + n more
// evaluations).  NaN for a state of more than kMaxStiffnessStates numbers, or when an evaluation
// fails or is not finite.
inline constexpr int kMaxStiffnessStates = 400;
double spectral_radius(System& sys, double t, const VecX& y);

// After a cvode-adams run of at least kStiffSteps steps: h̄ ρ, the mean step times the larger ρ at
// the start and the end.  An explicit-type method keeps h ρ inside its stability region whatever
// the accuracy asks, so h̄ ρ ≳ kStiffIndex over many steps says the steps were spent on stability:
// a stiff run, for which BDF's steps follow the accuracy alone.
inline constexpr long kStiffSteps = 2000;
inline constexpr double kStiffIndex = 0.2;

}  // namespace soadyn::detail
