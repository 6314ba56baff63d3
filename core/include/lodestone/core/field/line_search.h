#pragma once
// The backtracking rule of the Newton line search, shared by core's
// solveField and the gpu module's Newton driver (header-only: the gpu
// module builds without the core library).
#include <algorithm>
#include <cmath>

namespace lodestone {
inline namespace field {

/// Next step length after `lambda` was rejected: the minimizer of the
/// quadratic through E(0), the slope g0 < 0 and the change dE at lambda,
/// kept within [0.1, 0.5] lambda; half of lambda when dE is not finite or
/// the quadratic has no minimum.
inline double backtrackedStep(double dE, double g0, double lambda) {
  double next = 0.5 * lambda;
  if (std::isfinite(dE)) {
    const double denom = 2.0 * (dE - g0 * lambda);
    if (denom > 0) next = -g0 * lambda * lambda / denom;
  }
  return std::clamp(next, 0.1 * lambda, 0.5 * lambda);
}

}  // namespace field
}  // namespace lodestone
