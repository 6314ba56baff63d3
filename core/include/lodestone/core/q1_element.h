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
#include "lodestone/core/hostdev.h"
#include "lodestone/core/vec3.h"

namespace lodestone {
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

}  // namespace q1
}  // namespace lodestone
