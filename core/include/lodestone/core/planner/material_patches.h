#pragma once
// Separate groups of material and the solve grid of each: the planner's
// patches (effects_planner.h), solved apart and coupled through their far
// fields (stage/magnetic_patches.h).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace planner {

struct MaterialPatches {
  /// One grid per group: the group's box widened by `pad` cells on every
  /// side (clipped to the full grid), nodes on the full grid's lattice. No
  /// two share a node; ordered by each group's first point.
  std::vector<GridSpec> grids;
  std::vector<std::uint32_t> patchOf;  ///< the patch of each point
};

/// Groups points of `grid` (m): points whose cells of edge `pad` cells
/// touch (26 neighbours) are one group, and groups whose widened boxes
/// would share a node are merged, so the material of two patches lies more
/// than 2 pad cells apart. Throws InvalidArgument when pad < 1 or there
/// are no points.
MaterialPatches findMaterialPatches(const GridSpec& grid, const Vec3d* x, std::size_t count, int pad);

}  // namespace planner
}  // namespace lodestone
