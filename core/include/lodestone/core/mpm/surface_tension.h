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
/// with 1, 2 and 3 particles per cell and axis, sum_p V_p |g_p| per unit
/// area is 0.500, 0.483 and 0.486 on average over the lattice's offsets from
/// the surface (0.45 .. 0.55; FlatInterfaceTensionDepth in
/// tests/core/test_surface_tension.cpp). The particles' stress is therefore
/// twice the continuum one.
constexpr double kLiquidSideWeight = 2.0;

/// How far inside the liquid's outline its particles carry the tension, in
/// cells: the first-order term of the pressure error of resting drops
/// without the curvature correction (the pressure is high by about this
/// depth over the radius; tests/core/test_surface_tension.cpp).
constexpr double kTensionDepthCells = 1.0;

/// The colour field's Hessian at a particle (1/m^2), symmetrised: the
/// gradient of the nodes' central-difference colour gradients G_i (one-sided
/// on the grid's faces), H = sym(sum_i grad w_ip G_i^T). `colour` is the
/// whole grid (nx x ny x nz nodes, x fastest; nodes that no particle reaches
/// read 0), (bi, bj, bk) the stencil's base, invDx = 1/dx (1/m).
template <typename T>
LODESTONE_HOSTDEV inline Mat3<T> colourHessian(const T* colour, int nx, int ny, int nz, int bi, int bj, int bk,
                                               const QuadraticWeights<T>& wx, const QuadraticWeights<T>& wy,
                                               const QuadraticWeights<T>& wz, T invDx) {
  const std::size_t sj = std::size_t(nx), sk = sj * std::size_t(ny);
  // Per axis and stencil node: the offsets (in elements) to the lower and
  // upper neighbours, 0 on a face, and 1 / (their distance, m).
  std::size_t lo[3][3], hi[3][3];
  T inv[3][3];
  const int base[3] = {bi, bj, bk}, dims[3] = {nx, ny, nz};
  const std::size_t stride[3] = {1, sj, sk};
  for (int axis = 0; axis < 3; ++axis)
    for (int a = 0; a < 3; ++a) {
      const int i = base[axis] + a;
      const int l = i > 0 ? 1 : 0, h = i < dims[axis] - 1 ? 1 : 0;
      lo[axis][a] = std::size_t(l) * stride[axis];
      hi[axis][a] = std::size_t(h) * stride[axis];
      inv[axis][a] = invDx / T(l + h);
    }
  Mat3<T> H;
  const T* corner = colour + std::size_t(bi) + sj * std::size_t(bj) + sk * std::size_t(bk);
  for (int c = 0; c < 3; ++c)
    for (int b = 0; b < 3; ++b) {
      const T* line = corner + std::size_t(b) * sj + std::size_t(c) * sk;
      const T wyz = wy.w[b] * wz.w[c], dyz = wy.dw[b] * wz.w[c], ydz = wy.w[b] * wz.dw[c];
      for (int a = 0; a < 3; ++a) {
        const T* n = line + a;
        const T G[3] = {(n[hi[0][a]] - *(n - lo[0][a])) * inv[0][a], (n[hi[1][b]] - *(n - lo[1][b])) * inv[1][b],
                        (n[hi[2][c]] - *(n - lo[2][c])) * inv[2][c]};
        const T dw[3] = {wx.dw[a] * wyz, wx.w[a] * dyz, wx.w[a] * ydz};
        for (int r = 0; r < 3; ++r)
          for (int q = 0; q < 3; ++q) H(r, q) += dw[r] * G[q];
      }
    }
  for (int r = 0; r < 3; ++r)
    for (int q = r + 1; q < 3; ++q) H(r, q) = H(q, r) = T(0.5) * (H(r, q) + H(q, r));
  return H;
}

/// The capillary stress (Pa) of a tension carried a distance `depth` (m)
/// inside the surface: the tension sigma |g| along each principal direction
/// of the surface scaled by 1 - depth kappa_k (kappa_k its curvature, 1/m,
/// positive where the liquid is convex), as a line on a parallel surface
/// that far inside is shorter by that factor. From the colour gradient g
/// (1/m) and Hessian H (1/m^2): with P = I - n n^T, the shape operator is
/// -P H P / |g|, so
///   T = sigma (|g| P + depth P H P).
/// A sphere of radius R: sigma |g| (1 - depth / R) P. The correction is kept
/// within half the tension (Frobenius norm of depth P H P at most |g| / 2)
/// where the curvature is of the cell's size (threads, corners, noise).
/// Zero where |g| <= minGradient or sigma <= 0; symmetric.
template <typename T>
LODESTONE_HOSTDEV inline Mat3<T> curvedCapillaryStress(const Vec3<T>& g, const Mat3<T>& H, T sigma, T depth,
                                                       T minGradient) {
  using std::sqrt;
  Mat3<T> s;
  const T g2 = g.x * g.x + g.y * g.y + g.z * g.z;
  if (!(g2 > minGradient * minGradient) || !(sigma > T(0))) return s;
  const T len = sqrt(g2);
  const T n[3] = {g.x / len, g.y / len, g.z / len};
  T P[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) P[i][j] = (i == j ? T(1) : T(0)) - n[i] * n[j];
  T HP[3][3];  // H P
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) HP[i][j] = H(i, 0) * P[0][j] + H(i, 1) * P[1][j] + H(i, 2) * P[2][j];
  T C[3][3];  // depth P H P
  T norm2 = T(0);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      C[i][j] = depth * (P[i][0] * HP[0][j] + P[i][1] * HP[1][j] + P[i][2] * HP[2][j]);
      norm2 += C[i][j] * C[i][j];
    }
  const T limit = T(0.5) * len;
  const T scale = norm2 > limit * limit ? limit / sqrt(norm2) : T(1);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s(i, j) = sigma * (len * P[i][j] + scale * T(0.5) * (C[i][j] + C[j][i]));
  return s;
}

/// The capillary stress (Pa) of a liquid particle of surface tension sigma
/// (N/m) from the colour field on the whole grid (colourHessian's
/// arguments): curvedCapillaryStress of the colour gradient and Hessian at
/// the particle with sigma scaled by kLiquidSideWeight and the depth
/// kTensionDepthCells dx.
template <typename T>
LODESTONE_HOSTDEV inline Mat3<T> particleCapillaryStress(const T* colour, int nx, int ny, int nz, int bi, int bj,
                                                         int bk, const QuadraticWeights<T>& wx,
                                                         const QuadraticWeights<T>& wy, const QuadraticWeights<T>& wz,
                                                         T sigma, T invDx) {
  const std::size_t sj = std::size_t(nx), sk = sj * std::size_t(ny);
  const Vec3<T> g = colourGradient(colour + std::size_t(bi) + sj * std::size_t(bj) + sk * std::size_t(bk), sj, sk,
                                   wx, wy, wz);
  const T minGradient = minColourGradient(invDx);
  // Inside the liquid (|g| dx below 0.01, a fiftieth of |g| dx at the
  // outline) the depth term, at most half of a tension that small, is left out.
  if (!((g.x * g.x + g.y * g.y + g.z * g.z) > T(1e-4) * invDx * invDx))
    return capillaryStress(g, T(kLiquidSideWeight) * sigma, minGradient);
  const Mat3<T> H = colourHessian(colour, nx, ny, nz, bi, bj, bk, wx, wy, wz, invDx);
  return curvedCapillaryStress(g, H, T(kLiquidSideWeight) * sigma, T(kTensionDepthCells) / invDx, minGradient);
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
