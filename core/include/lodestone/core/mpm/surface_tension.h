#pragma once
// Surface tension of the MPM fluids as a continuum surface stress (Lafaurie,
// Nardone, Scardovelli, Zaleski and Zanetti 1994; the conservative, stress form
// of Brackbill, Kothe and Zemach's CSF, 1992). Written once for host and
// device: no exceptions, no allocation.
//
// A colour field c (the liquid's volume fraction, 1 inside, 0 outside, smooth
// over about two cells) has the gradient g = grad c (1/m), which is
// concentrated on the interface (|g| ~ a delta function of the surface) and
// points into the liquid. The capillary stress
//   T = sigma |g| (I - n n^T),   n = g / |g|,
// (Pa, sigma the surface tension coefficient in N/m) is a tension along the
// interface. It is added to the Cauchy stress, so the force density is
//   div T = -sigma (div n) |g| n = sigma kappa |g| n,   kappa = -div n,
// (using grad |g| = (n . grad) g) Brackbill's CSF force towards the centre of
// curvature, whose integral across the interface is the Laplace pressure jump
// sigma kappa (2 sigma / R for a sphere of radius R). Entering like a
// symmetric stress, it conserves linear and angular momentum exactly.
#include <cmath>
#include <limits>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/hostdev.h"
#include "lodestone/core/base/mat3.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace mpm {

/// The capillary (Cauchy) stress sigma |g| (I - n n^T) (Pa) from the colour
/// gradient g (1/m) and the surface tension sigma (N/m): sigma (|g| I - g g^T
/// / |g|), zero where |g| <= minGradient (1/m; no interface there).
template <typename T>
LODESTONE_HOSTDEV inline Mat3<T> capillaryStress(const Vec3<T>& g, T sigma, T minGradient) {
  using std::sqrt;
  Mat3<T> s;
  const T g2 = g.x * g.x + g.y * g.y + g.z * g.z;
  if (!(g2 > minGradient * minGradient) || !(sigma > T(0))) return s;
  const T len = sqrt(g2);
  const T k = sigma / len;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s(i, j) = (i == j ? sigma * len : T(0)) - k * g[i] * g[j];
  return s;
}

/// The MPM particles carry the stress only where the liquid is: they sample
/// the liquid half (c > 1/2) of the smoothed interface, which holds half of
/// the integral of |g| across it (the colour field is symmetric about the
/// surface, c(s) + c(-s) = 1 across a flat one): on a flat interface seeded
/// with 1 to 4 particles per cell and axis, sum_p V_p |g_p| per unit area is
/// 0.50 on average over the lattice's offsets from the surface (0.45 ..
/// 0.55). The particles' stress is therefore twice the continuum one.
constexpr double kLiquidSideWeight = 2.0;

/// The capillary stress a liquid particle carries (Pa) from the colour
/// gradient g (1/m) at the particle: capillaryStress with sigma scaled by
/// kLiquidSideWeight.
template <typename T>
LODESTONE_HOSTDEV inline Mat3<T> particleCapillaryStress(const Vec3<T>& g, T sigma, T minGradient) {
  return capillaryStress(g, T(kLiquidSideWeight) * sigma, minGradient);
}

/// The explicit capillary time-step limit sqrt(rho dx^3 / (2 pi sigma)) (s)
/// of Brackbill et al. 1992: the period of the shortest capillary wave the
/// grid resolves, for density rho (kg/m^3), cell size dx (m) and surface
/// tension sigma (N/m); infinite for sigma <= 0.
inline double capillaryTimeStep(double density, double dx, double sigma) {
  if (!(sigma > 0)) return std::numeric_limits<double>::infinity();
  return std::sqrt(density * dx * dx * dx / (2 * kPi * sigma));
}

}  // namespace mpm
}  // namespace lodestone
