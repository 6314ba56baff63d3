// Shapes to a density grid by sub-sampled volume fractions (density_raster.h).
#include "lodestone/core/stage/density_raster.h"

#include <tbb/parallel_for.h>

#include <cmath>

#include "lodestone/core/base/error.h"

namespace lodestone {

DenseGrid<double> rasterizeDensity(const GridSpec& grid, double n0, const std::function<bool(const Vec3d&)>& inside,
                                   int samplesPerAxis) {
  grid.validate("rasterizeDensity: grid");
  require(std::isfinite(n0) && n0 >= 0, "rasterizeDensity: number density n0 must be finite and >= 0 (1/m^3), got ",
          n0);
  require(samplesPerAxis >= 1 && samplesPerAxis <= 64, "rasterizeDensity: samplesPerAxis must be in 1..64, got ",
          samplesPerAxis);
  require(bool(inside), "rasterizeDensity: no inside test given");
  const int S = samplesPerAxis;
  DenseGrid<double> n(grid, 0.0);
  tbb::parallel_for(0, grid.dims.k, [&](int k) {
    for (int j = 0; j < grid.dims.j; ++j)
      for (int i = 0; i < grid.dims.i; ++i) {
        const Vec3d x = grid.nodePosition(i, j, k);
        int in = 0;
        for (int c = 0; c < S; ++c)
          for (int b = 0; b < S; ++b)
            for (int a = 0; a < S; ++a)
              in += inside(x + grid.dx * Vec3d{(a + 0.5) / S - 0.5, (b + 0.5) / S - 0.5, (c + 0.5) / S - 0.5});
        n(i, j, k) = n0 * in / double(S * S * S);
      }
  });
  return n;
}

}  // namespace lodestone
