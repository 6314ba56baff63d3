#pragma once
// How close the material comes to the grid's outer wall, in cells: the
// open wall's decisions (multipole block size, wall prediction, the
// residual's wall correction) depend on it.
#include <algorithm>
#include <cstddef>

#include "lodestone/core/base/grid.h"

namespace lodestone {
inline namespace field {

/// Smallest number of cells between a material cell and the wall (0: a
/// material cell touches it), over the cells whose base nodes (lowest
/// corner, node index) are cellBase[0..count); 2^30 when count is 0.
inline int materialWallClearance(const GridSpec& grid, const std::size_t* cellBase, std::size_t count) {
  const Index3 cd = grid.cellDims();
  const std::size_t nx = std::size_t(grid.dims.i), ny = std::size_t(grid.dims.j);
  int clearance = 1 << 30;
  for (std::size_t s = 0; s < count; ++s) {
    const std::size_t b = cellBase[s];
    const int i = int(b % nx), j = int((b / nx) % ny), k = int(b / (nx * ny));
    clearance = std::min({clearance, i, j, k, cd.i - 1 - i, cd.j - 1 - j, cd.k - 1 - k});
  }
  return clearance;
}

}  // namespace field
}  // namespace lodestone
