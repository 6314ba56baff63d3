#pragma once
// A body given as a shape, turned into the micro-particle number density n
// (1/m^3) on a grid, for MagneticForceStage::runOnDensity when a host has a
// shape rather than material points.
//
// n_i = n0 * (volume fraction of the body in the dual cell of node i), the
// cube [x_i - dx/2, x_i + dx/2]^3. The fraction is estimated with S^3
// sub-samples at the centres of an S x S x S split of that cube (a cell wholly
// outside gets 0, one wholly inside n0 up to one rounding); the total count
// sum_i n_i dx^3 approaches n0 times the body's volume as O(dx / (S size)).
//
// An emitter shape (mpm/emitter.h) is a body too:
//   rasterizeDensity(grid, n0, [&](const Vec3d& x) { return shape.containsBody(shape.pose.toLocal(x)); });
#include <functional>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace stage {

/// The density of a body of bulk number density n0 (1/m^3, >= 0, finite):
/// `inside(x)` tells whether the world point x (m) is inside. `inside` is
/// called concurrently from several threads (oneTBB), so it must be safe to
/// call at once; the result does not depend on the thread count. Throws
/// InvalidArgument on a bad grid, n0 or samplesPerAxis (1..64), naming the
/// value.
DenseGrid<double> rasterizeDensity(const GridSpec& grid, double n0, const std::function<bool(const Vec3d&)>& inside,
                                   int samplesPerAxis = 6);

/// The same for a body given by its signed distance phi(x) (m, negative
/// inside; outside the body a lower bound of the distance to it suffices,
/// inside one of the depth): a node whose dual cell lies wholly on one side
/// (|phi| above half the cell's diagonal) is decided by phi at the node alone,
/// the others are sampled with phi < 0 as the inside test, so the result is
/// rasterizeDensity's with that test at a fraction of the calls. Also throws
/// InvalidArgument when phi at a node is NaN.
DenseGrid<double> rasterizeDensityFromDistance(const GridSpec& grid, double n0,
                                               const std::function<double(const Vec3d&)>& signedDistance,
                                               int samplesPerAxis = 6);

}  // namespace stage
}  // namespace lodestone
