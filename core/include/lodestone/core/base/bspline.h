#pragma once
// Quadratic B-spline weights for particle <-> grid transfers on the
// node-centred grid of grid.h (node i at origin + dx*i).
//
// Per axis, a particle at world coordinate x has grid coordinate
// u = (x - origin)/dx (dimensionless, in node spacings). It touches the three
// nodes base, base+1, base+2 with base = floor(u - 1/2), and with the
// fractional offset f = u - base (in [1/2, 3/2)) the weights are
//
//   w0 = 1/2 (3/2 - f)^2,   w1 = 3/4 - (f - 1)^2,   w2 = 1/2 (f - 1/2)^2.
//
// Identically in f: w0 + w1 + w2 = 1 (partition of unity) and
// w0*base + w1*(base+1) + w2*(base+2) = u (linear reproduction), so grid sums
// of particle deposits conserve the zeroth and first moments and interpolating
// a linear field returns it exactly (up to rounding). The weights are C1 in u:
// at the base switch u = b + 1/2 the old stencil (f -> 3/2) gives (0, 1/2, 1/2)
// on nodes (b-1, b, b+1) and the new one (f = 1/2) gives (1/2, 1/2, 0) on
// (b, b+1, b+2), i.e. the same node weights.
//
// The derivative weights are dw_i = d w_i / d x = (d w_i / d f) / dx, in 1/m
// when dx is in m; they sum to 0 and satisfy sum_i dw_i x_i = 1.
//
// One-axis weights combine into the 3-D tensor-product weight
// w_abc = wx[a] wy[b] wz[c] and gradient (dwx[a] wy[b] wz[c], ...).
#include <cmath>
#include <type_traits>

#include "lodestone/core/base/hostdev.h"

namespace lodestone {
inline namespace base {

/// One axis of a quadratic B-spline stencil.
template <typename T>
struct QuadraticWeights {
  int base;  ///< index of the first of the three nodes touched (base, base+1, base+2)
  T w[3];    ///< weights of those nodes (dimensionless), sum to 1
  T dw[3];   ///< their derivatives d w / d x, in 1/(unit of dx): 1/m for dx in m
};

/// floor(u - 1/2) as a T: the stencil's first node for grid coordinate u.
/// Kept in floating point so callers can range-check it before converting to
/// int (u may be huge or out of range). Computed as floor(u), less one when
/// the fraction is below 1/2, because u - 1/2 itself rounds once the spacing
/// of T at u reaches 1 (float from 2^23): floor(u - 1/2) then gave base = u,
/// f = 0 and a negative middle weight.
template <typename T>
LODESTONE_HOSTDEV inline T quadraticBaseFloor(T u) {
  static_assert(std::is_floating_point_v<T>, "floating-point argument expected");
  using std::floor;
  const T b = floor(u);
  return u - b < T(0.5) ? b - T(1) : b;
}

/// Weights for grid coordinate u (in node spacings) with a given first node
/// `base`. Normally base = quadraticBaseFloor(u); passing the base explicitly
/// lets a caller that already binned the particle by base use exactly that
/// stencil. invDx = 1/dx scales the derivative weights (pass 1 for d/du).
template <typename T>
LODESTONE_HOSTDEV inline QuadraticWeights<T> quadraticWeightsAt(T u, int base, T invDx = T(1)) {
  static_assert(std::is_floating_point_v<T>, "floating-point argument expected");
  const T f = u - static_cast<T>(base);  // in [1/2, 3/2) for the canonical base
  const T d0 = T(1.5) - f;
  const T d1 = f - T(1);
  const T d2 = f - T(0.5);
  QuadraticWeights<T> q;
  q.base = base;
  q.w[0] = T(0.5) * d0 * d0;
  q.w[1] = T(0.75) - d1 * d1;
  q.w[2] = T(0.5) * d2 * d2;
  q.dw[0] = -d0 * invDx;
  q.dw[1] = T(-2) * d1 * invDx;
  q.dw[2] = d2 * invDx;
  return q;
}

/// Weights for grid coordinate u = (x - origin)/dx (dimensionless). Requires u
/// finite with |u| < 2^31 - 2 so that the base fits an int (in float, |u| <
/// 2^24 - 2, so that the base is a float as well); range-check
/// quadraticBaseFloor(u) first when u is untrusted.
template <typename T>
LODESTONE_HOSTDEV inline QuadraticWeights<T> quadraticWeights(T u, T invDx = T(1)) {
  return quadraticWeightsAt(u, static_cast<int>(quadraticBaseFloor(u)), invDx);
}

}  // namespace base
}  // namespace lodestone
