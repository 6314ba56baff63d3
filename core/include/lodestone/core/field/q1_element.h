#pragma once
// The trilinear (Q1) hexahedral element on one grid cell, integrated with
// 2x2x2 Gauss points. This is the discrete gradient of the field solve
// (docs/physics.md, "Discretization"): grad(phi) at a Gauss point couples all
// eight corners of the cell, so the operator has no checkerboard null modes.
//
// Corner c = a + 2b + 4d sits at node (i+a, j+b, k+d) of the cell's base node
// (i,j,k); Gauss point q = qa + 2qb + 4qd sits at reference coordinates
// (g[qa], g[qb], g[qd]) with g = 1/2 -+ 1/(2 sqrt 3). Every Gauss point
// carries weight dx^3/8.
#include "lodestone/core/base/hostdev.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace field {
namespace q1 {

constexpr int kCorners = 8;
constexpr int kGaussPoints = 8;

/// Reference coordinate of Gauss abscissa s (0 or 1) in [0,1].
LODESTONE_HOSTDEV constexpr double gaussAbscissa(int s) {
  // 0.5 -+ 0.5/sqrt(3)
  return s == 0 ? 0.21132486540518711775 : 0.78867513459481288225;
}

/// 1D linear shape value of corner bit `a` at reference coordinate t.
LODESTONE_HOSTDEV constexpr double shape1(int a, double t) { return a ? t : 1.0 - t; }
/// 1D derivative (in reference units) of corner bit `a`.
LODESTONE_HOSTDEV constexpr double dshape1(int a) { return a ? 1.0 : -1.0; }

/// Shape value N_c at Gauss point q.
LODESTONE_HOSTDEV constexpr double shapeAtGauss(int q, int c) {
  return shape1(c & 1, gaussAbscissa(q & 1)) * shape1((c >> 1) & 1, gaussAbscissa((q >> 1) & 1)) *
         shape1((c >> 2) & 1, gaussAbscissa((q >> 2) & 1));
}

/// Reference gradient of N_c at Gauss point q (multiply by 1/dx for 1/m).
LODESTONE_HOSTDEV constexpr Vec3d shapeGradientAtGauss(int q, int c) {
  const double tx = gaussAbscissa(q & 1), ty = gaussAbscissa((q >> 1) & 1), tz = gaussAbscissa((q >> 2) & 1);
  const int a = c & 1, b = (c >> 1) & 1, d = (c >> 2) & 1;
  return {dshape1(a) * shape1(b, ty) * shape1(d, tz), shape1(a, tx) * dshape1(b) * shape1(d, tz),
          shape1(a, tx) * shape1(b, ty) * dshape1(d)};
}

/// Tables of the shape functions and reference gradients at the Gauss points.
struct Tables {
  double N[kGaussPoints][kCorners];
  Vec3d dN[kGaussPoints][kCorners];
};

LODESTONE_HOSTDEV constexpr Tables makeTables() {
  Tables t{};
  for (int q = 0; q < kGaussPoints; ++q)
    for (int c = 0; c < kCorners; ++c) {
      t.N[q][c] = shapeAtGauss(q, c);
      t.dN[q][c] = shapeGradientAtGauss(q, c);
    }
  return t;
}

/// Reference gradient sum_c dN[q][c] v[c] (divide by dx for the physical gradient).
LODESTONE_HOSTDEV inline Vec3d referenceGradient(const Tables& t, int q, const double v[kCorners]) {
  Vec3d g{};
  for (int c = 0; c < kCorners; ++c) g += v[c] * t.dN[q][c];
  return g;
}

/// Interpolated value sum_c N[q][c] v[c].
LODESTONE_HOSTDEV inline double interpolate(const Tables& t, int q, const double v[kCorners]) {
  double s = 0;
  for (int c = 0; c < kCorners; ++c) s += t.N[q][c] * v[c];
  return s;
}

/// Reference gradients sum_c dN[q][c] v[c] at all 8 Gauss points at once,
/// by sum factorization (the Q1 x-derivative is the x edge difference
/// interpolated bilinearly in y and z, and so on): 60 operations instead of
/// 8 x 24. Equal to referenceGradient up to round-off.
LODESTONE_HOSTDEV inline void gaussGradients(const double v[kCorners], double out[kGaussPoints][3]) {
  const double g0 = gaussAbscissa(0), g1 = gaussAbscissa(1);
  // Linear interpolation of (u0, u1) at abscissa s: s = 0 -> g1 u0 + g0 u1.
  const auto at = [g0, g1](int s, double u0, double u1) { return s ? g0 * u0 + g1 * u1 : g1 * u0 + g0 * u1; };
  for (int axis = 0; axis < 3; ++axis) {
    // The two other axes p < r, and the corner stride of each axis.
    const int p = axis == 0 ? 1 : 0, r = axis == 2 ? 1 : 2;
    const int sa = 1 << axis, sp = 1 << p, sr = 1 << r;
    double d[2][2];  // edge differences along `axis`, indexed by the p and r bits
    for (int bp = 0; bp < 2; ++bp)
      for (int br = 0; br < 2; ++br) {
        const int c = bp * sp + br * sr;
        d[bp][br] = v[c + sa] - v[c];
      }
    for (int qp = 0; qp < 2; ++qp) {
      const double e0 = at(qp, d[0][0], d[1][0]), e1 = at(qp, d[0][1], d[1][1]);
      for (int qr = 0; qr < 2; ++qr) {
        const double value = at(qr, e0, e1);
        const int q = qp * sp + qr * sr;
        out[q][axis] = value;
        out[q + sa][axis] = value;
      }
    }
  }
}

/// The transpose of gaussGradients: out[c] = sum_q dN[q][c] . f[q] for a
/// vector f at each Gauss point (the weak divergence of f, reference units).
LODESTONE_HOSTDEV inline void gaussDivergenceTranspose(const double f[kGaussPoints][3], double out[kCorners]) {
  const double g0 = gaussAbscissa(0), g1 = gaussAbscissa(1);
  for (int c = 0; c < kCorners; ++c) out[c] = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const int p = axis == 0 ? 1 : 0, r = axis == 2 ? 1 : 2;
    const int sa = 1 << axis, sp = 1 << p, sr = 1 << r;
    // Sum over the abscissa along `axis` (the derivative does not depend on it).
    double t[2][2];
    for (int qp = 0; qp < 2; ++qp)
      for (int qr = 0; qr < 2; ++qr) {
        const int q = qp * sp + qr * sr;
        t[qp][qr] = f[q][axis] + f[q + sa][axis];
      }
    // Transposed interpolation in r, then in p: weight of corner bit b at
    // abscissa s is g1 when b == s, g0 otherwise.
    double u[2][2];  // [qp][br]
    for (int qp = 0; qp < 2; ++qp) {
      u[qp][0] = g1 * t[qp][0] + g0 * t[qp][1];
      u[qp][1] = g0 * t[qp][0] + g1 * t[qp][1];
    }
    for (int bp = 0; bp < 2; ++bp)
      for (int br = 0; br < 2; ++br) {
        const double value = bp ? g0 * u[0][br] + g1 * u[1][br] : g1 * u[0][br] + g0 * u[1][br];
        const int c = bp * sp + br * sr;
        out[c + sa] += value;
        out[c] -= value;
      }
  }
}

/// The Gauss-integrated products of the reference gradients of corners c and
/// d: s = (1/8) sum_q (x x, y y, z z, x y + y x, x z + z x, y z + z y) of
/// dN_qc and dN_qd. The unit cell's element matrices of d_a N . d_b N
/// (symmetrized for a != b): E(D) = dx sum_ab D_ab s_ab (the multigrid's
/// coarse levels, on the host and the device).
LODESTONE_HOSTDEV inline void gradientProducts(const Tables& t, int c, int d, double s[6]) {
  for (int a = 0; a < 6; ++a) s[a] = 0;
  for (int q = 0; q < kGaussPoints; ++q) {
    const Vec3d& u = t.dN[q][c];
    const Vec3d& v = t.dN[q][d];
    s[0] += u.x * v.x;
    s[1] += u.y * v.y;
    s[2] += u.z * v.z;
    s[3] += u.x * v.y + u.y * v.x;
    s[4] += u.x * v.z + u.z * v.x;
    s[5] += u.y * v.z + u.z * v.y;
  }
  for (int a = 0; a < 6; ++a) s[a] /= 8;
}

}  // namespace q1
}  // namespace field
}  // namespace lodestone
