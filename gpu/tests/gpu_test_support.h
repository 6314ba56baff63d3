#pragma once
// Helpers of the gpu tests: the skip for machines without a device, relative
// differences, the paper's Langevin law and the closed-form sphere.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "lodestone/core/field/langevin.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/core/base/vec3.h"
#include "lodestone/gpu/backend.h"

/// Skips the current test, saying why, unless a CUDA device is usable.
#define LODESTONE_REQUIRE_DEVICE()                                                   \
  do {                                                                               \
    if (!::lodestone::gpu::deviceAvailable())                                        \
      GTEST_SKIP() << "no usable CUDA device (" << ::lodestone::gpu::backendStatus() \
                   << "): the device kernels are compiled but cannot run here";      \
  } while (0)

namespace lodestone {
namespace gpu {
namespace test {

constexpr double kMu0 = 1.25663706212e-6;    // N/A^2
constexpr double kBoltzmann = 1.380649e-23;  // J/K

/// max |a - b| / max |b| over two arrays (0 when both are zero).
inline double relativeDifference(const double* a, const double* b, std::size_t n) {
  double d = 0, s = 0;
  for (std::size_t m = 0; m < n; ++m) {
    d = std::max(d, std::fabs(a[m] - b[m]));
    s = std::max(s, std::fabs(b[m]));
  }
  return s > 0 ? d / s : d;
}
inline double relativeDifference(const std::vector<double>& a, const std::vector<double>& b) {
  return relativeDifference(a.data(), b.data(), std::min(a.size(), b.size()));
}
inline double relativeDifference(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
  return relativeDifference(&a[0].x, &b[0].x, 3 * std::min(a.size(), b.size()));
}
inline double relativeScalar(double a, double b) { return std::fabs(a - b) / std::max(std::fabs(b), 1e-300); }

/// The paper's material (Table 2): m = 1.09e-19 A m^2, T = 300 K.
inline MagnetizationLaw<double> paperLaw() {
  MagnetizationLaw<double> law;
  law.kind = LawKind::Langevin;
  law.moment = 1.09e-19;
  law.k2 = kMu0 * law.moment / (kBoltzmann * 300.0);
  return law;
}
/// Its bulk density: 3.6e17 micro-particles per cell of 7.8 mm, 1/m^3.
inline double paperDensity() { return 3.6e17 / (7.8e-3 * 7.8e-3 * 7.8e-3); }

/// Interior field of a sphere of the law at density n in a uniform field H0
/// (A/m): the root of H + M(H)/3 = H0 (bisection to round-off).
inline double sphereInteriorField(const MagnetizationLaw<double>& law, double n, double H0) {
  double lo = 0, hi = H0;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    const double M = magnetization(law, n, Vec3d{0, 0, mid}).z;
    (mid + M / 3 > H0 ? hi : lo) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace test
}  // namespace gpu
}  // namespace lodestone
