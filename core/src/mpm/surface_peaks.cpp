// Height field and peaks of a free surface. See mpm/surface_peaks.h.
#include "lodestone/core/mpm/surface_peaks.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace mpm {

double SurfaceHeightField::range() const {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const double v : z)
    if (!std::isnan(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  return hi >= lo ? hi - lo : 0.0;
}

double SurfaceHeightField::mean() const {
  double sum = 0;
  std::size_t n = 0;
  for (const double v : z)
    if (!std::isnan(v)) {
      sum += v;
      ++n;
    }
  return n ? sum / double(n) : std::numeric_limits<double>::quiet_NaN();
}

double SurfaceHeightField::rms() const {
  const double m = mean();
  double sum = 0;
  std::size_t n = 0;
  for (const double v : z)
    if (!std::isnan(v)) {
      sum += (v - m) * (v - m);
      ++n;
    }
  return n ? std::sqrt(sum / double(n)) : 0.0;
}

SurfaceHeightField surfaceHeight(const std::vector<Vec3d>& points, double x0, double y0, double x1, double y1,
                                 double h) {
  require(std::isfinite(h) && h > 0, "surface height: the cell size must be positive and finite, got ", h, " m");
  require(std::isfinite(x0) && std::isfinite(x1) && std::isfinite(y0) && std::isfinite(y1) && x1 > x0 && y1 > y0,
          "surface height: the rectangle [", x0, ", ", x1, ") x [", y0, ", ", y1, ") m is empty or not finite");
  SurfaceHeightField f;
  f.x0 = x0;
  f.y0 = y0;
  f.h = h;
  // Whole cells only: a sliver at the far edge holds too few points for its
  // highest to be on the surface.
  f.nx = std::max(1, int(std::floor((x1 - x0) / h + 1e-9)));
  f.ny = std::max(1, int(std::floor((y1 - y0) / h + 1e-9)));
  f.z.assign(std::size_t(f.nx) * std::size_t(f.ny), std::numeric_limits<double>::quiet_NaN());
  for (const Vec3d& p : points) {
    if (!(p.x >= x0 && p.y >= y0) || !std::isfinite(p.z)) continue;
    const int i = int((p.x - x0) / h), j = int((p.y - y0) / h);
    if (i >= f.nx || j >= f.ny) continue;
    double& z = f.z[std::size_t(j) * std::size_t(f.nx) + std::size_t(i)];
    if (std::isnan(z) || p.z > z) z = p.z;
  }
  return f;
}

std::vector<SurfacePeak> findSurfacePeaks(const SurfaceHeightField& field, double radius, double minProminence) {
  require(std::isfinite(radius) && radius > 0, "surface peaks: the search radius must be positive and finite, got ",
          radius, " m");
  require(std::isfinite(minProminence) && minProminence >= 0,
          "surface peaks: the minimum prominence must be finite and >= 0, got ", minProminence, " m");
  const int r = std::max(1, int(std::floor(radius / field.h)));
  const double r2 = (radius / field.h) * (radius / field.h);
  std::vector<SurfacePeak> out;
  // Parabola through three heights z(-1), z(0), z(1): the offset of its top, in cells.
  const auto vertex = [](double a, double b, double c) {
    const double curvature = a - 2 * b + c;
    if (std::isnan(a) || std::isnan(c) || !(curvature < 0)) return 0.0;
    return std::clamp(0.5 * (a - c) / curvature, -0.5, 0.5);
  };
  for (int j = 1; j + 1 < field.ny; ++j)
    for (int i = 1; i + 1 < field.nx; ++i) {
      const double z = field.at(i, j);
      if (std::isnan(z)) continue;
      bool highest = true;
      double lowest = z;
      for (int dj = -r; dj <= r && highest; ++dj)
        for (int di = -r; di <= r; ++di) {
          if ((di == 0 && dj == 0) || double(di * di + dj * dj) > r2) continue;
          const int a = i + di, b = j + dj;
          if (a < 0 || b < 0 || a >= field.nx || b >= field.ny) continue;
          const double w = field.at(a, b);
          if (std::isnan(w)) continue;
          // Ties: the first cell in row order (b, a) < (j, i) wins.
          if (w > z || (w == z && (b < j || (b == j && a < i)))) {
            highest = false;
            break;
          }
          lowest = std::min(lowest, w);
        }
      if (!highest || z - lowest < minProminence) continue;
      const double dx = vertex(field.at(i - 1, j), z, field.at(i + 1, j));
      const double dy = vertex(field.at(i, j - 1), z, field.at(i, j + 1));
      out.push_back({Vec3d{field.x0 + (i + 0.5 + dx) * field.h, field.y0 + (j + 0.5 + dy) * field.h, z}, z - lowest});
    }
  return out;
}

double meanNearestPeakDistance(const SurfaceHeightField& field, const std::vector<SurfacePeak>& peaks,
                               double margin) {
  const double x1 = field.x0 + field.nx * field.h, y1 = field.y0 + field.ny * field.h;
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t a = 0; a < peaks.size(); ++a) {
    const Vec3d& p = peaks[a].tip;
    if (p.x < field.x0 + margin || p.x > x1 - margin || p.y < field.y0 + margin || p.y > y1 - margin) continue;
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t b = 0; b < peaks.size(); ++b)
      if (b != a) nearest = std::min(nearest, std::hypot(peaks[b].tip.x - p.x, peaks[b].tip.y - p.y));
    if (std::isfinite(nearest)) {
      sum += nearest;
      ++n;
    }
  }
  return n ? sum / double(n) : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace mpm
}  // namespace lodestone
