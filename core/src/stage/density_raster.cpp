// Shapes to a density grid by sub-sampled volume fractions (density_raster.h).
#include "lodestone/core/stage/density_raster.h"

#include <tbb/parallel_for.h>

#include <cmath>

#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace stage {

namespace {

void checkArguments(const GridSpec& grid, double n0, int samplesPerAxis) {
  grid.validate("rasterizeDensity: grid");
  require(std::isfinite(n0) && n0 >= 0, "rasterizeDensity: number density n0 must be finite and >= 0 (1/m^3), got ",
          n0);
  require(samplesPerAxis >= 1 && samplesPerAxis <= 64, "rasterizeDensity: samplesPerAxis must be in 1..64, got ",
          samplesPerAxis);
}

// n0 times the fraction of the S^3 sub-samples of node (i, j, k)'s dual cell
// that `inside` accepts; `classify(x)` may decide the whole cell first
// (+1 inside, -1 outside, 0 sample it).
template <typename Inside, typename Classify>
DenseGrid<double> rasterize(const GridSpec& grid, double n0, int S, const Inside& inside, const Classify& classify) {
  const int all = S * S * S;
  DenseGrid<double> n(grid, 0.0);
  tbb::parallel_for(0, grid.dims.k, [&](int k) {
    for (int j = 0; j < grid.dims.j; ++j)
      for (int i = 0; i < grid.dims.i; ++i) {
        const Vec3d x = grid.nodePosition(i, j, k);
        const int side = classify(x);
        int in = side > 0 ? all : 0;
        if (side == 0)
          for (int c = 0; c < S; ++c)
            for (int b = 0; b < S; ++b)
              for (int a = 0; a < S; ++a)
                in += inside(x + grid.dx * Vec3d{(a + 0.5) / S - 0.5, (b + 0.5) / S - 0.5, (c + 0.5) / S - 0.5});
        n(i, j, k) = n0 * in / double(all);
      }
  });
  return n;
}

}  // namespace

DenseGrid<double> rasterizeDensity(const GridSpec& grid, double n0, const std::function<bool(const Vec3d&)>& inside,
                                   int samplesPerAxis) {
  checkArguments(grid, n0, samplesPerAxis);
  require(bool(inside), "rasterizeDensity: no inside test given");
  return rasterize(grid, n0, samplesPerAxis, inside, [](const Vec3d&) { return 0; });
}

DenseGrid<double> rasterizeDensityFromDistance(const GridSpec& grid, double n0,
                                               const std::function<double(const Vec3d&)>& signedDistance,
                                               int samplesPerAxis) {
  checkArguments(grid, n0, samplesPerAxis);
  require(bool(signedDistance), "rasterizeDensityFromDistance: no signed distance given");
  // Every sub-sample lies within half the cell's diagonal of the node.
  const double half = 0.5 * std::sqrt(3.0) * grid.dx;
  return rasterize(
      grid, n0, samplesPerAxis, [&](const Vec3d& p) { return signedDistance(p) < 0; },
      [&](const Vec3d& x) {
        const double phi = signedDistance(x);
        require(!std::isnan(phi), "rasterizeDensityFromDistance: the signed distance at (", x.x, ", ", x.y, ", ",
                x.z, ") is NaN");
        return phi > half ? -1 : (phi < -half ? 1 : 0);
      });
}

}  // namespace stage
}  // namespace lodestone
