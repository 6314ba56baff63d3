// Height field and peak finding (mpm/surface_peaks.h) on surfaces with known
// spikes: a hexagonal array of bumps at the capillary wavelength, found
// where they are and spaced as laid out, and a rough flat surface with none.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/surface_peaks.h"

using namespace lodestone;

namespace {

constexpr double kLambda = 9.156e-3;  // m: lambda_c of a ferrofluid of 1200 kg/m^3 and 0.025 N/m
constexpr double kSide = 0.04;        // m, the square sampled

/// Lattice points of a hexagonal array of spacing kLambda covering the square.
std::vector<Vec3d> hexagonalLattice() {
  std::vector<Vec3d> out;
  const double row = kLambda * std::sqrt(3.0) / 2;
  for (int j = -2; j * row < kSide + kLambda; ++j)
    for (int i = -2; i * kLambda < kSide + kLambda; ++i) {
      const double x = 0.002 + i * kLambda + (j % 2 ? 0.5 * kLambda : 0.0), y = 0.003 + j * row;
      out.push_back({x, y, 0});
    }
  return out;
}

/// A layer 5 mm deep with a Gaussian bump (2 mm tall, 1.5 mm wide) at each
/// lattice point, sampled at points `spacing` apart (jittered by `jitter` of it).
std::vector<Vec3d> bumpySurface(const std::vector<Vec3d>& lattice, double spacing, double jitter, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<Vec3d> pts;
  for (double y = 0.5 * spacing; y < kSide; y += spacing)
    for (double x = 0.5 * spacing; x < kSide; x += spacing) {
      const double px = x + jitter * spacing * u(rng), py = y + jitter * spacing * u(rng);
      double z = 0.005;
      for (const Vec3d& c : lattice) {
        const double d2 = (px - c.x) * (px - c.x) + (py - c.y) * (py - c.y);
        z += 0.002 * std::exp(-d2 / (2 * 1.5e-3 * 1.5e-3));
      }
      pts.push_back({px, py, z});
      pts.push_back({px, py, 0.5 * z});  // material below the surface does not count
    }
  return pts;
}

}  // namespace

TEST(SurfacePeaks, AHexagonalArrayIsFoundWhereItIsAndSpacedAsLaidOut) {
  const std::vector<Vec3d> lattice = hexagonalLattice();
  // Fine sampling (0.25 mm, regular) and particle-like sampling (0.6 mm,
  // jittered by half a spacing) with a coarser height field.
  struct Case {
    double spacing, jitter, cell, tolerance;
  };
  for (const Case& k : {Case{0.25e-3, 0.0, 0.5e-3, 0.01}, Case{0.6e-3, 0.5, 1.2e-3, 0.03}}) {
    const SurfaceHeightField f = surfaceHeight(bumpySurface(lattice, k.spacing, k.jitter, 7), 0, 0, kSide, kSide, k.cell);
    const std::vector<SurfacePeak> peaks = findSurfacePeaks(f, 0.4 * kLambda, 5e-4);
    // Every lattice point 1.5 mm inside the square is found, within a cell
    // and a half; every peak is one of them (or one cut by the edge).
    std::size_t inside = 0, found = 0;
    for (const Vec3d& c : lattice) {
      if (c.x < 1.5e-3 || c.y < 1.5e-3 || c.x > kSide - 1.5e-3 || c.y > kSide - 1.5e-3) continue;
      ++inside;
      for (const SurfacePeak& p : peaks)
        if (std::hypot(p.tip.x - c.x, p.tip.y - c.y) < 1.5 * k.cell) {
          ++found;
          break;
        }
    }
    for (const SurfacePeak& p : peaks) {
      double nearest = 1;
      for (const Vec3d& c : lattice) nearest = std::min(nearest, std::hypot(p.tip.x - c.x, p.tip.y - c.y));
      EXPECT_LT(nearest, 1.5 * k.cell) << "a peak at (" << p.tip.x << ", " << p.tip.y << ") is no bump";
    }
    const double spacing = meanNearestPeakDistance(f, peaks, kLambda);
    std::printf("sampled every %.2f mm (jitter %.1f), cells %.1f mm: %zu peaks, %zu of %zu lattice points found, "
                "mean nearest distance %.3f mm (laid out %.3f mm), range %.2f mm\n",
                1e3 * k.spacing, k.jitter, 1e3 * k.cell, peaks.size(), found, inside, 1e3 * spacing, 1e3 * kLambda,
                1e3 * f.range());
    EXPECT_EQ(found, inside);
    EXPECT_GT(f.rms(), 2e-4);  // the bumps: well above the flat case's roughness
    EXPECT_NEAR(spacing / kLambda, 1.0, k.tolerance);
  }
}

TEST(SurfacePeaks, ARoughFlatSurfaceHasNoPeaks) {
  // A flat layer with +-0.1 mm of roughness: no peak 0.5 mm prominent, and
  // its range is the roughness.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1e-4, 1e-4);
  std::vector<Vec3d> pts;
  for (double y = 2.5e-4; y < kSide; y += 5e-4)
    for (double x = 2.5e-4; x < kSide; x += 5e-4) pts.push_back({x, y, 0.005 + u(rng)});
  const SurfaceHeightField f = surfaceHeight(pts, 0, 0, kSide, kSide, 1e-3);
  EXPECT_TRUE(findSurfacePeaks(f, 0.4 * kLambda, 5e-4).empty());
  EXPECT_LT(f.range(), 2e-4);
  EXPECT_LT(f.rms(), 1e-4);
  EXPECT_NEAR(f.mean(), 0.005, 1e-4);  // the highest of the points over each cell
  EXPECT_FALSE(findSurfacePeaks(f, 0.4 * kLambda, 0).empty());  // without a prominence, roughness peaks
}

TEST(SurfacePeaks, BadSettingsAreRefused) {
  EXPECT_THROW(surfaceHeight({}, 0, 0, 1, 1, 0), InvalidArgument);
  EXPECT_THROW(surfaceHeight({}, 0, 0, 0, 1, 0.1), InvalidArgument);
  const SurfaceHeightField f = surfaceHeight({{0.5, 0.5, 1}}, 0, 0, 1, 1, 0.1);
  EXPECT_THROW(findSurfacePeaks(f, -1, 0), InvalidArgument);
  EXPECT_THROW(findSurfacePeaks(f, 0.2, std::nan("")), InvalidArgument);
  EXPECT_TRUE(std::isnan(meanNearestPeakDistance(f, findSurfacePeaks(f, 0.2, 0), 0)));  // one peak: no neighbour
}
