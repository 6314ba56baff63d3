#pragma once
// The free surface of a layer seen from above, and the spikes on it: a
// height field (the highest point of the material over each cell of a
// horizontal grid) and its peaks, for measuring the Rosensweig pattern
// (docs/ferrofluid.md): how many spikes, how far apart, how tall.
#include <cstddef>
#include <vector>

#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace mpm {

/// Heights z (m) over the cells of a horizontal grid: cell (i, j) covers
/// [x0 + i h, x0 + (i + 1) h) x [y0 + j h, y0 + (j + 1) h).
struct SurfaceHeightField {
  double x0 = 0, y0 = 0;  ///< lower corner, m
  double h = 0;           ///< cell size, m
  int nx = 0, ny = 0;
  std::vector<double> z;  ///< highest point per cell, m; NaN over a cell with no point

  double at(int i, int j) const { return z[std::size_t(j) * std::size_t(nx) + std::size_t(i)]; }
  /// Largest minus smallest height over the cells with points, m (0 if none).
  double range() const;
  /// Mean height over the cells with points, m.
  double mean() const;
  /// Root-mean-square deviation of the heights from their mean, m: the
  /// surface's amplitude (a flying droplet moves it little, unlike range()).
  double rms() const;
};

/// The height field of `points` over [x0, x1) x [y0, y1) in whole cells of
/// size h (m): floor((x1 - x0) / h) of them along x from x0 (a remainder
/// narrower than a cell is left out, as are points outside). Throws InvalidArgument for
/// a cell size that is not positive and finite or an empty rectangle.
SurfaceHeightField surfaceHeight(const std::vector<Vec3d>& points, double x0, double y0, double x1, double y1,
                                 double h);

struct SurfacePeak {
  Vec3d tip;          ///< the peak's place (a parabola's top through its cell and each pair of neighbours) and height, m
  double prominence;  ///< height above the lowest cell within the search radius, m
};

/// Peaks of a height field: cells not on its border, higher than every
/// other cell within `radius` (m; ties go to the first in row order) and at
/// least `minProminence` (m) above the lowest cell within it (a bump cut by
/// the border is not a peak: its top may lie outside). Throws
/// InvalidArgument for a radius not positive and finite or a negative
/// prominence.
std::vector<SurfacePeak> findSurfacePeaks(const SurfaceHeightField& field, double radius, double minProminence);

/// Mean distance (m) from each peak at least `margin` (m) inside the
/// field's rectangle to its nearest other peak (any peak); NaN when no
/// peak qualifies or there is only one.
double meanNearestPeakDistance(const SurfaceHeightField& field, const std::vector<SurfacePeak>& peaks,
                               double margin);

}  // namespace mpm
}  // namespace lodestone
