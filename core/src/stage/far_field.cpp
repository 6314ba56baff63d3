// The far field of other patches over a patch's grid. See stage/far_field.h.
#include "lodestone/core/stage/far_field.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace lodestone {
inline namespace stage {

Vec3d farFieldOf(const std::vector<Multipole>& blocks, const Vec3d& x) {
  Vec3d h;
  for (const Multipole& m : blocks) h += m.field(x);
  return h;
}

double distanceToBlocks(const GridSpec& g, const std::vector<Multipole>& blocks) {
  const double inf = std::numeric_limits<double>::infinity();
  Vec3d lo{inf, inf, inf}, hi{-inf, -inf, -inf};
  for (const Multipole& m : blocks)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], m.centre[a]);
      hi[a] = std::max(hi[a], m.centre[a]);
    }
  if (!(lo.x <= hi.x)) return inf;
  const Vec3d gHi = g.maxCorner();
  double d2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double gap = std::max({0.0, lo[a] - gHi[a], g.origin[a] - hi[a]});
    d2 += gap * gap;
  }
  return std::sqrt(d2);
}

SampledFarField::SampledFarField(std::vector<Multipole> blocks, const GridSpec& g) : blocks_(std::move(blocks)) {
  const double d = distanceToBlocks(g, blocks_);
  const int h = std::isfinite(d) ? int(std::floor(d / (16 * g.dx))) : 0;
  if (h < 2) return;
  step_ = h * g.dx;
  for (int a = 0; a < 3; ++a) {
    lo_[a] = g.origin[a] - g.dx;
    n_[a] = int(std::ceil(g.dx * (g.dims[a] + 1) / step_)) + 1;
  }
  samples_.resize(std::size_t(n_[0]) * std::size_t(n_[1]) * std::size_t(n_[2]));
  tbb::parallel_for(0, n_[2], [&](int k) {
    for (int j = 0; j < n_[1]; ++j)
      for (int i = 0; i < n_[0]; ++i)
        samples_[index(i, j, k)] = farFieldOf(blocks_, lo_ + Vec3d{i * step_, j * step_, k * step_});
  });
}

std::size_t SampledFarField::index(int i, int j, int k) const {
  return (std::size_t(k) * std::size_t(n_[1]) + std::size_t(j)) * std::size_t(n_[0]) + std::size_t(i);
}

Vec3d SampledFarField::at(const Vec3d& x) const {
  if (samples_.empty()) return farFieldOf(blocks_, x);
  int c[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    const double u = (x[a] - lo_[a]) / step_;
    if (!(u >= 0 && u <= n_[a] - 1)) return farFieldOf(blocks_, x);
    c[a] = std::min(int(u), n_[a] - 2);
    f[a] = u - c[a];
  }
  Vec3d h;
  for (int corner = 0; corner < 8; ++corner) {
    const int di = corner & 1, dj = (corner >> 1) & 1, dk = corner >> 2;
    const double w = (di ? f[0] : 1 - f[0]) * (dj ? f[1] : 1 - f[1]) * (dk ? f[2] : 1 - f[2]);
    h += w * samples_[index(c[0] + di, c[1] + dj, c[2] + dk)];
  }
  return h;
}

}  // namespace stage
}  // namespace lodestone
