// A signed-distance function on a dense node grid. See sampled_sdf.h.
#include "lodestone/core/mpm/sampled_sdf.h"

#include <utility>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace mpm {

SampledSdf::SampledSdf(const GridSpec& spec, std::vector<float> values, std::string description)
    : spec_(spec), values_(std::move(values)), description_(std::move(description)) {
  const std::string who = description_.empty() ? std::string("sampled signed-distance grid") : description_;
  spec_.validate(who.c_str());
  require(values_.size() == spec_.nodeCount(), who, ": ", values_.size(), " values for ", spec_.dims.i, " x ",
          spec_.dims.j, " x ", spec_.dims.k, " = ", spec_.nodeCount(), " nodes");
  hi_ = spec_.maxCorner();
  invDx_ = 1.0 / spec_.dx;
  Index3 lo{spec_.dims.i, spec_.dims.j, spec_.dims.k}, hi{-1, -1, -1};
  for (int k = 0; k < spec_.dims.k; ++k)
    for (int j = 0; j < spec_.dims.j; ++j)
      for (int i = 0; i < spec_.dims.i; ++i) {
        const float v = values_[spec_.index(i, j, k)];
        require(std::isfinite(v), who, ": value at node (", i, ", ", j, ", ", k, ") is not finite (", v, ")");
        if (v <= 0) {
          lo = {std::min(lo.i, i), std::min(lo.j, j), std::min(lo.k, k)};
          hi = {std::max(hi.i, i), std::max(hi.j, j), std::max(hi.k, k)};
        }
      }
  require(hi.i >= 0, who, ": no node is inside the shape (every value is > 0 m)");
  interiorLo_ = spec_.nodePosition(std::max(lo.i - 1, 0), std::max(lo.j - 1, 0), std::max(lo.k - 1, 0));
  interiorHi_ = spec_.nodePosition(std::min(hi.i + 1, spec_.dims.i - 1), std::min(hi.j + 1, spec_.dims.j - 1),
                                   std::min(hi.k + 1, spec_.dims.k - 1));
}

double SampledSdf::volume() const {
  // V = sum_i (1 - H_eps(phi_i)) h^3 with the smoothed Heaviside
  // H_eps(phi) = 1/2 + phi / (2 eps) + sin(pi phi / eps) / (2 pi), |phi| <= eps.
  const double h = spec_.dx, eps = 1.5 * h;
  double inside = 0;
  for (const float f : values_) {
    const double phi = f;
    if (phi <= -eps) {
      inside += 1;
    } else if (phi < eps) {
      inside += 0.5 - phi / (2 * eps) - std::sin(kPi * phi / eps) / (2 * kPi);
    }
  }
  return inside * h * h * h;
}

void SampledSdf::interiorBounds(Vec3d& lo, Vec3d& hi) const {
  lo = interiorLo_;
  hi = interiorHi_;
}

}  // namespace mpm
}  // namespace lodestone
