#pragma once
// Independent references for the applied-field sources' tests: Gauss-Legendre
// quadrature of the surface-charge Coulomb integral over rectangles, discs and
// boxes, the point-dipole formula, rotations, central-difference div and curl,
// and the distance to a box surface.
#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <random>
#include <string>
#include <vector>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/gauss_legendre.h"
#include "lodestone/core/base/mat3.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone::test {

// ---------------------------------------------------------------- helpers --

// Message of the InvalidArgument thrown by f, or a marker when none is thrown.
template <typename F>
inline std::string thrownMessage(F&& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "<no InvalidArgument thrown>";
}

inline void expectContains(const std::string& msg, std::initializer_list<const char*> parts) {
  for (const char* p : parts)
    EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
}

inline double relErr(const Vec3d& a, const Vec3d& ref) { return norm(a - ref) / norm(ref); }

// Gauss-Legendre nodes and weights on [-1, 1] (base/gauss_legendre.h).
struct Rule {
  std::vector<double> x, w;
};
inline Rule gaussLegendre(int n) {
  Rule r;
  gaussLegendreRule(n, r.x, r.w);
  return r;
}

// Composite Gauss-Legendre rule on [lo, hi]: `panels` panels of `order` points.
inline Rule composite(double lo, double hi, int panels, int order) {
  const Rule g = gaussLegendre(order);
  Rule r;
  const double h = (hi - lo) / panels;
  for (int p = 0; p < panels; ++p)
    for (int i = 0; i < order; ++i) {
      r.x.push_back(lo + h * (p + 0.5 * (g.x[i] + 1)));
      r.w.push_back(0.5 * h * g.w[i]);
    }
  return r;
}

// Coulomb field (A/m) at x of the rectangle centre + s e1 + t e2 (|s| <= a,
// |t| <= b) carrying surface charge sigma (A/m): sigma/(4 pi) int (x-y)/|x-y|^3 dA.
inline Vec3d rectangleQuadrature(const Vec3d& x, const Vec3d& centre, const Vec3d& e1, double a,
                          const Vec3d& e2, double b, double sigma) {
  const Rule rs = composite(-a, a, 24, 10), rt = composite(-b, b, 24, 10);
  Vec3d H;
  for (std::size_t i = 0; i < rs.x.size(); ++i)
    for (std::size_t j = 0; j < rt.x.size(); ++j) {
      const Vec3d d = x - (centre + rs.x[i] * e1 + rt.x[j] * e2);
      const double r = norm(d);
      H += d * (rs.w[i] * rt.w[j] / (r * r * r));
    }
  return H * (sigma / (4 * kPi));
}

// Field of a cuboid (half-sizes h, body magnetization M) placed with rotation
// R (columns = body axes in world) at p: the six charged faces, sigma = M.n.
inline Vec3d cuboidQuadrature(const Vec3d& h, const Vec3d& M, const Mat3d& R, const Vec3d& p,
                       const Vec3d& x) {
  Vec3d axis[3];
  for (int k = 0; k < 3; ++k) axis[k] = {R(0, k), R(1, k), R(2, k)};
  Vec3d H;
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    for (int s = -1; s <= 1; s += 2)
      H += rectangleQuadrature(x, p + (s * h[k]) * axis[k], axis[i], h[i], axis[j], h[j], s * M[k]);
  }
  return H;
}

// Field of a disc of radius a in the plane z = zc (axis e_z) with charge sigma.
inline Vec3d discQuadrature(const Vec3d& x, double zc, double a, double sigma) {
  const Rule rr = composite(0, a, 16, 8);
  const int nphi = 512;  // trapezoid: spectrally accurate for the periodic angle
  Vec3d H;
  for (std::size_t i = 0; i < rr.x.size(); ++i)
    for (int k = 0; k < nphi; ++k) {
      const double phi = 2 * kPi * k / nphi;
      const Vec3d y{rr.x[i] * std::cos(phi), rr.x[i] * std::sin(phi), zc};
      const Vec3d d = x - y;
      const double r = norm(d);
      H += d * (rr.w[i] * rr.x[i] * (2 * kPi / nphi) / (r * r * r));
    }
  return H * (sigma / (4 * kPi));
}

// Axial cylinder: charges +M on z = +L and -M on z = -L.
inline Vec3d cylinderQuadrature(double R, double L, double M, const Vec3d& x) {
  return discQuadrature(x, L, R, M) + discQuadrature(x, -L, R, -M);
}

// Independent dipole formula (no unit vector): 3 (m.r) r / r^5 - m / r^3, / 4 pi.
inline Vec3d dipoleReference(const Vec3d& m, const Vec3d& r) {
  const double d2 = norm2(r), d = std::sqrt(d2);
  return (r * (3 * dot(m, r) / (d2 * d2 * d)) - m / (d2 * d)) / (4 * kPi);
}

// Rodrigues rotation matrix about a unit axis.
inline Mat3d rotation(Vec3d axis, double angle) {
  axis = axis / norm(axis);
  const double c = std::cos(angle), s = std::sin(angle);
  const Mat3d K = Mat3d::cross(axis);
  Mat3d R = Mat3d::identity();
  const Mat3d K2 = K * K;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R(i, j) += s * K(i, j) + (1 - c) * K2(i, j);
  return R;
}

// Central-difference divergence and curl of a field at x with step s (m).
struct DivCurl {
  double div;
  Vec3d curl;
};
template <typename F>
inline DivCurl divCurl(F&& H, const Vec3d& x, double s) {
  Vec3d d[3];  // d[j] = dH/dx_j
  for (int j = 0; j < 3; ++j) {
    Vec3d e;
    e[j] = s;
    d[j] = (H(x + e) - H(x - e)) / (2 * s);
  }
  return {d[0].x + d[1].y + d[2].z, {d[1].z - d[2].y, d[2].x - d[0].z, d[0].y - d[1].x}};
}

inline Vec3d randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> g;
  Vec3d v{g(rng), g(rng), g(rng)};
  return v / norm(v);
}

// Signed distance from x to the surface of an axis-aligned box of half-sizes
// h: positive outside, negative inside.
inline double boxSurfaceDistance(const Vec3d& x, const Vec3d& h) {
  Vec3d out;
  double inside = 1e300;
  for (int k = 0; k < 3; ++k) {
    const double q = std::fabs(x[k]) - h[k];
    out[k] = std::fmax(q, 0.0);
    inside = std::fmin(inside, -q);
  }
  const double o = norm(out);
  return o > 0 ? o : -inside;
}

// The sample magnets the tests share.
inline const Vec3d kCuboidHalf{0.01, 0.015, 0.006};      // m
inline const Vec3d kCuboidM{3.0e5, -1.2e5, 8.0e5};       // A/m, body frame
inline constexpr double kCylR = 0.01, kCylL = 0.015, kCylM = 9e5;  // m, m, A/m

}  // namespace lodestone::test
