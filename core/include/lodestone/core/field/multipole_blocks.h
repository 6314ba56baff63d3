#pragma once
// The cubic blocks of cells whose dipole + quadrupole moments give the open
// wall's far field (magnetostatic_problem.h), shared by core's solve and the
// distributed one (dist/): the block edge, the tiling of the cells into
// blocks and one cell's moments about its block's centre.
#include <cstdint>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/base/vec3.h"
#include "lodestone/core/field/multipole.h"
#include "lodestone/core/field/q1_element.h"

namespace lodestone {
inline namespace field {

/// Edge of the blocks, in cells: 8, doubled while 4 edges fit in the
/// material's clearance to the wall (cells), up to 32, so that edge /
/// clearance stays <= 1/2 beyond 8 cells (the truncated octupole of a block
/// falls as (edge / distance)^3).
inline int multipoleBlockEdgeFor(int wallClearance) {
  int edge = 8;
  while (edge < 32 && 4 * edge <= wallClearance) edge *= 2;
  return edge;
}

/// Cells grouped per axis into runs of `edge` cells counted from both ends
/// towards the middle (a middle cell of an odd count is its own run), so that
/// the tiling, and with it the truncated far field, is mirror-symmetric
/// about the grid's mid-planes. key() numbers the blocks; keys grow with the
/// run index along x, then y, then z.
class MultipoleBlockTiling {
 public:
  MultipoleBlockTiling(const Index3& cellDims, int edge)
      : cd_(cellDims), edge_(edge), hx_(half(cellDims.i)), hy_(half(cellDims.j)), hz_(half(cellDims.k)) {}
  /// Key of the block holding the cell with base node (i, j, k).
  std::uint64_t key(int i, int j, int k) const {
    const std::uint64_t bx = std::uint64_t(2 * hx_ + 1), by = std::uint64_t(2 * hy_ + 1);
    return std::uint64_t(run(i, cd_.i, hx_)) +
           bx * (std::uint64_t(run(j, cd_.j, hy_)) + by * std::uint64_t(run(k, cd_.k, hz_)));
  }
  /// Number of keys (blocks with and without material).
  std::uint64_t keyCount() const {
    return std::uint64_t(2 * hx_ + 1) * std::uint64_t(2 * hy_ + 1) * std::uint64_t(2 * hz_ + 1);
  }

 private:
  int half(int cellCount) const { return (cellCount / 2 + edge_ - 1) / edge_; }
  int run(int c, int cellCount, int h) const {
    const int mirrored = cellCount - 1 - c;
    if (c < cellCount / 2) return c / edge_;
    if (mirrored < cellCount / 2) return 2 * h - mirrored / edge_;
    return h;  // the middle cell of an odd count
  }
  Index3 cd_;
  int edge_, hx_, hy_, hz_;
};

/// A cell's moments about a block centre `rel` away from the cell's origin
/// (rel = origin - centre), from its dipole sum_q w M_q and upper[a], the
/// same sum over the Gauss points with bit a set (the upper abscissa on axis
/// a): the Gauss point at bits (qa, qb, qd) lies at o + dx (g[qa], g[qb],
/// g[qd]), so sum_q w M_q (x_q - c)_a = dipole (o - c)_a + dx (g0 dipole +
/// (g1 - g0) upper[a]). The centre is left unset.
inline Multipole cellMultipole(const Vec3d& dipole, const Vec3d upper[3], const Vec3d& rel, double h) {
  const double g0 = q1::gaussAbscissa(0), g1 = q1::gaussAbscissa(1);
  Multipole m;
  m.dipole = dipole;
  for (int i = 0; i < 3; ++i)
    for (int a = 0; a < 3; ++a) m.quadrupole[i][a] = dipole[i] * (rel[a] + h * g0) + h * (g1 - g0) * upper[a][i];
  return m;
}

}  // namespace field
}  // namespace lodestone
