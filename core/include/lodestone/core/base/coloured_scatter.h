#pragma once
// Deterministic parallel scatter from grid cells to their 8 corner nodes.
// Cells are grouped by colour (the parity of their base index on each axis);
// two cells of one colour share no node, so each colour is scattered in
// parallel without races, and every node receives its contributions in the
// same order on every run.
#include <cstddef>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lodestone/core/base/grid.h"

namespace lodestone {
inline namespace base {

/// Colour 0..7 of the cell with base node (i, j, k).
inline int cellColour(int i, int j, int k) { return (i & 1) | ((j & 1) << 1) | ((k & 1) << 2); }

/// Flat offsets of the 8 corners of a cell from its base node (corner c = a + 2b + 4d).
inline void cornerOffsets(const GridSpec& grid, std::size_t offsets[8]) {
  for (int c = 0; c < 8; ++c) offsets[c] = grid.index(c & 1, (c >> 1) & 1, (c >> 2) & 1);
}

/// For cells [colourStart[c], colourStart[c+1]) of each colour c in turn,
/// calls cellFn(slot, local[8]) (T local[8]) and adds local to out at the slot's corners.
/// base[slot] is the flat index of the cell's base node.
template <typename T, typename CellFn>
void scatterByColour(const std::size_t* base, const std::size_t colourStart[9], const std::size_t offsets[8],
                     T* out, const CellFn& cellFn) {
  for (int colour = 0; colour < 8; ++colour) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(colourStart[colour], colourStart[colour + 1], 128),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t s = r.begin(); s != r.end(); ++s) {
                          T local[8] = {0, 0, 0, 0, 0, 0, 0, 0};
                          cellFn(s, local);
                          for (int c = 0; c < 8; ++c) out[base[s] + offsets[c]] += local[c];
                        }
                      });
  }
}

}  // namespace base
}  // namespace lodestone
