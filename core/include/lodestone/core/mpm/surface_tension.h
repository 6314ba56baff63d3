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

#include <cstddef>

#include "lodestone/core/base/bspline.h"
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

/// Colour gradients at or below this (1/m, for cell size 1/invDx) carry no
/// capillary stress: no interface there.
template <typename T>
LODESTONE_HOSTDEV inline T minColourGradient(T invDx) {
  return T(1e-9) * invDx;
}

/// The colour gradient at a particle, g_p = sum_i c_i grad w_ip (1/m), from
/// the colour field on a node-centred grid (x fastest; `corner` the node at
/// the stencil's base, sj and sk the strides of j and k) and the particle's
/// quadratic weights with derivatives (quadraticWeightsAt with invDx).
template <typename T>
LODESTONE_HOSTDEV inline Vec3<T> colourGradient(const T* corner, std::size_t sj, std::size_t sk,
                                                const QuadraticWeights<T>& wx, const QuadraticWeights<T>& wy,
                                                const QuadraticWeights<T>& wz) {
  Vec3<T> g;
  for (int c = 0; c < 3; ++c)
    for (int b = 0; b < 3; ++b) {
      const T* line = corner + std::size_t(b) * sj + std::size_t(c) * sk;
      for (int a = 0; a < 3; ++a) {
        const T ci = line[a];
        g.x += ci * wx.dw[a] * wy.w[b] * wz.w[c];
        g.y += ci * wx.w[a] * wy.dw[b] * wz.w[c];
        g.z += ci * wx.w[a] * wy.w[b] * wz.dw[c];
      }
    }
  return g;
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
