#pragma once
// Where the open wall's far field is summed exactly and how the other wall
// nodes get theirs (magnetostatic_problem.h, and dist/'s solve): the
// potential is smooth on the wall on the scale of the material's clearance
// d, so it is summed on a lattice of wall nodes with spacing s (a power of 2
// <= d/6, at least 2) and interpolated (bi)linearly in between: relative
// error about (s/d)^2/8 <= 0.4%, below the blocks' truncated octupole. The
// lattice is counted from both ends of each axis (and holds the middle node,
// or the two middle nodes of an even count), so that it and the
// interpolation between its nodes are mirror-symmetric about the grid's
// mid-planes.
#include <algorithm>

#include "lodestone/core/base/grid.h"

namespace lodestone {
inline namespace field {

class OpenWallLattice {
 public:
  /// `wallClearance`: the material's clearance to the wall, in cells.
  OpenWallLattice(const GridSpec& grid, int wallClearance) : dims_(grid.dims) {
    while (spacing_ < 16 && 6 * (2 * spacing_) <= wallClearance) spacing_ *= 2;
  }
  int spacing() const { return spacing_; }
  /// Coordinate c of an axis with `count` nodes is on the lattice.
  bool onLattice(int c, int count) const {
    const int fromEnd = std::min(c, count - 1 - c);
    return fromEnd % spacing_ == 0 || fromEnd == (count - 1) / 2;
  }
  bool onLattice(int i, int j, int k) const {
    return onLattice(i, dims_.i) && onLattice(j, dims_.j) && onLattice(k, dims_.k);
  }
  /// The value at wall node (i, j, k) interpolated from latticeValue(p, q, r)
  /// at the lattice nodes around it (the node's own value when it is on the
  /// lattice). The wall's normal coordinate is always on the lattice.
  template <typename LatticeValue>
  double interpolate(int i, int j, int k, const LatticeValue& latticeValue) const {
    const int c[3] = {i, j, k}, count[3] = {dims_.i, dims_.j, dims_.k};
    int lo[3], hi[3];
    double t[3];
    for (int a = 0; a < 3; ++a) {
      if (onLattice(c[a], count[a])) {
        lo[a] = hi[a] = c[a];
        t[a] = 0;
      } else {
        lo[a] = c[a];
        while (!onLattice(lo[a], count[a])) --lo[a];
        hi[a] = c[a];
        while (!onLattice(hi[a], count[a])) ++hi[a];
        t[a] = double(c[a] - lo[a]) / double(hi[a] - lo[a]);
      }
    }
    double v = 0;
    for (int corner = 0; corner < 8; ++corner) {
      double w = 1;
      int p[3];
      for (int a = 0; a < 3; ++a) {
        const bool up = (corner >> a) & 1;
        if (lo[a] == hi[a] && up) {
          w = 0;
          break;
        }
        p[a] = up ? hi[a] : lo[a];
        w *= lo[a] == hi[a] ? 1.0 : (up ? t[a] : 1.0 - t[a]);
      }
      if (w != 0) v += w * latticeValue(p[0], p[1], p[2]);
    }
    return v;
  }

 private:
  Index3 dims_;
  int spacing_ = 2;
};

}  // namespace field
}  // namespace lodestone
