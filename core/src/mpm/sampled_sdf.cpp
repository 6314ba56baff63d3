// A signed-distance function on a dense node grid. See sampled_sdf.h.
#include "lodestone/core/mpm/sampled_sdf.h"

#include <algorithm>
#include <cmath>
#include <limits>
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
  findRidges();
}

void SampledSdf::findRidges() {
  // A thin part of a solid shows in its signed distance as a ridge: along
  // some axis a node lies no higher than its two neighbours, and the
  // surfaces on either side face opposite ways (the unit gradients at the two
  // neighbours meet at more than 120 degrees: n_l . n_r <= -1/2). The medial
  // surfaces that run from convex edges and corners into a solid are not such
  // ridges (their two sides' normals are perpendicular), nor is the flat
  // interior of a narrow band (no gradient). Where the inside has no ridge,
  // its deepest value stands in (a band's half width); where the outside has
  // none, it has no far side (infinite).
  constexpr double kOpposite = -0.5;
  const Index3 d = spec_.dims;
  const auto unitGradient = [&](int i, int j, int k) {
    const int idx[3] = {i, j, k}, dim[3] = {d.i, d.j, d.k};
    Vec3d g;
    for (int ax = 0; ax < 3; ++ax) {
      int lo[3] = {i, j, k}, hi[3] = {i, j, k};
      lo[ax] = std::max(idx[ax] - 1, 0);
      hi[ax] = std::min(idx[ax] + 1, dim[ax] - 1);
      const int span = hi[ax] - lo[ax];
      g[ax] = span > 0 ? (at(hi[0], hi[1], hi[2]) - at(lo[0], lo[1], lo[2])) / span : 0.0;
    }
    const double len = norm(g);
    return len > 0 ? g / len : Vec3d{};
  };
  const auto ridge = [&](double sign) {
    double ridgeDepth = std::numeric_limits<double>::infinity(), deepest = 0;
    for (int k = 1; k + 1 < d.k; ++k)
      for (int j = 1; j + 1 < d.j; ++j)
        for (int i = 1; i + 1 < d.i; ++i) {
          const double psi = sign * at(i, j, k);  // negative in the solid
          if (!(psi < 0)) continue;
          deepest = std::max(deepest, -psi);
          if (-psi >= ridgeDepth) continue;
          for (int axis = 0; axis < 3; ++axis) {
            const int o[3] = {axis == 0, axis == 1, axis == 2};
            const int il = i - o[0], jl = j - o[1], kl = k - o[2], ir = i + o[0], jr = j + o[1], kr = k + o[2];
            if (sign * at(il, jl, kl) < psi || sign * at(ir, jr, kr) < psi) continue;
            if (dot(unitGradient(il, jl, kl), unitGradient(ir, jr, kr)) <= kOpposite) {
              ridgeDepth = -psi;
              break;
            }
          }
        }
    if (std::isfinite(ridgeDepth) || sign < 0) return ridgeDepth;
    return deepest > 0 ? deepest : std::numeric_limits<double>::infinity();
  };
  insideRidge_ = ridge(1.0);
  outsideRidge_ = ridge(-1.0);
}

double SampledSdf::volume() const {
  // V = sum_i (1 - H_eps(phi_i)) h^3, eps = 1.5 h.
  const double h = spec_.dx, eps = 1.5 * h;
  double inside = 0;
  for (const float f : values_) inside += smoothedInsideFraction(f, eps);
  return inside * h * h * h;
}

void SampledSdf::interiorBounds(Vec3d& lo, Vec3d& hi) const {
  lo = interiorLo_;
  hi = interiorHi_;
}

}  // namespace mpm
}  // namespace lodestone
