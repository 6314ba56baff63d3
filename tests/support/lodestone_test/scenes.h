#pragma once
// Test scenes with closed-form answers: bodies (inside tests for
// rasterizeDensity), applied fields, and the sphere closed forms of
// PHYSICS.md section 6.
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "lodestone/core/sources/field_source.h"
#include "lodestone/core/base/grid.h"
#include "lodestone/core/field/langevin.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone::test {

/// A cube grid of N nodes per axis spanning [-halfWidth, halfWidth]^3 (m).
inline GridSpec cubeGrid(int N, double halfWidth) {
  GridSpec g;
  g.dx = 2 * halfWidth / (N - 1);
  g.origin = {-halfWidth, -halfWidth, -halfWidth};
  g.dims = {N, N, N};
  return g;
}

/// The inside test of a ball (centre and radius in m), for rasterizeDensity
/// (lodestone/core/stage/density_raster.h).
inline std::function<bool(const Vec3d&)> ball(const Vec3d& centre, double radius) {
  return [=](const Vec3d& x) { return norm2(x - centre) < radius * radius; };
}

/// A FieldSource given by a lambda (tests only).
class LambdaField final : public FieldSource {
 public:
  explicit LambdaField(std::function<Vec3d(const Vec3d&)> fn, bool uniform = false)
      : fn_(std::move(fn)), uniform_(uniform) {}
  Vec3d field(const Vec3d& x, double) const override { return fn_(x); }
  bool isUniform() const override { return uniform_; }
  std::string describe() const override { return "test field"; }
  std::unique_ptr<FieldSource> clone() const override { return std::make_unique<LambdaField>(*this); }

 private:
  std::function<Vec3d(const Vec3d&)> fn_;
  bool uniform_;
};

/// Interior field (A/m) of a sphere of `material` (bulk density) in a
/// uniform applied field of magnitude H0 (A/m): H + M(H)/3 = H0.
inline double sphereInteriorField(const MagneticMaterial& material, double H0) {
  if (material.law.kind == LawKind::Linear) return 3 * H0 / (3 + material.lowFieldSusceptibility());
  const double Ms = material.saturation(), k2 = material.law.k2;
  double lo = 0, hi = H0;
  for (int it = 0; it < 200; ++it) {
    const double m = 0.5 * (lo + hi);
    (m + Ms * langevin(k2 * m) / 3 - H0 > 0 ? hi : lo) = m;
  }
  return 0.5 * (lo + hi);
}

/// Least-squares slope of log(err) against log(h): the observed order.
inline double observedOrder(const std::vector<double>& h, const std::vector<double>& err) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = double(h.size());
  for (std::size_t m = 0; m < h.size(); ++m) {
    const double x = std::log(h[m]), y = std::log(err[m]);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

}  // namespace lodestone::test
