#pragma once
// Where the open wall's far field is summed exactly and how the other wall
// nodes get theirs (magnetostatic_problem.h, and dist/'s solve): the
// potential is smooth on the wall on the scale of the material's clearance
// d, so it is summed on a lattice of wall nodes with spacing s (a power of 2
// <= 0.4 d, at least 2, at most 16) and interpolated in between by cubic
// Lagrange polynomials through the 4 nearest lattice nodes of each axis
// (fewer where an axis has fewer). For the worst source, a point dipole at
// the clearance, the error is within 0.6 (s/d)^3 of the wall's peak value
// (measured: 3.6% at s = 0.4 d, 0.36% at s = 0.2 d; test_open_wall_sum);
// bilinear interpolation errs by about 0.8 (s/d)^2 and needed s <= d/6 for
// 2%, a 4x denser lattice. In the solve, H and the force on an active
// region differ from the full box's by what they did with the denser
// bilinear lattice (docs/benchmarks.md). The lattice is counted from both
// ends of each axis (and holds the middle node, or the two middle nodes of
// an even count), so that it and the interpolation between its nodes are
// mirror-symmetric about the grid's mid-planes.
#include <algorithm>
#include <cstddef>
#include <vector>

#include "lodestone/core/base/grid.h"

namespace lodestone {
inline namespace field {

class OpenWallLattice {
 public:
  /// `wallClearance`: the material's clearance to the wall, in cells.
  OpenWallLattice(const GridSpec& grid, int wallClearance) : dims_(grid.dims) {
    while (spacing_ < 16 && 5 * (2 * spacing_) <= 2 * wallClearance) spacing_ *= 2;
    const int count[3] = {dims_.i, dims_.j, dims_.k};
    for (int a = 0; a < 3; ++a) {
      stencil_[a].resize(std::size_t(std::max(count[a], 0)));
      for (int c = 0; c < count[a]; ++c) stencil_[a][std::size_t(c)] = axisStencil(c, count[a]);
    }
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
    const Stencil &x = stencil_[0][std::size_t(i)], &y = stencil_[1][std::size_t(j)], &z = stencil_[2][std::size_t(k)];
    double v = 0;
    for (int r = 0; r < z.n; ++r)
      for (int q = 0; q < y.n; ++q)
        for (int p = 0; p < x.n; ++p) v += x.w[p] * y.w[q] * z.w[r] * latticeValue(x.at[p], y.at[q], z.at[r]);
    return v;
  }

 private:
  /// The lattice coordinates (ascending) and Lagrange weights that
  /// interpolate one coordinate of an axis, and how many there are.
  struct Stencil {
    int n = 0;
    int at[4] = {0, 0, 0, 0};
    double w[4] = {0, 0, 0, 0};
  };

  /// Coordinate c of an axis with `count` nodes: c itself when it is on the
  /// lattice, else the 4 nearest lattice coordinates, two on each side where
  /// the axis has them.
  Stencil axisStencil(int c, int count) const {
    Stencil st;
    if (onLattice(c, count)) {
      st.n = 1;
      st.at[0] = c;
      st.w[0] = 1.0;
      return st;
    }
    const auto below = [&](int x) {
      do --x;
      while (!onLattice(x, count));
      return x;
    };
    const auto above = [&](int x) {
      do ++x;
      while (!onLattice(x, count));
      return x;
    };
    int lo = below(c), hi = above(c), first = lo, last = hi;
    if (first > 0) first = below(first);
    if (last < count - 1) last = above(last);
    if (first == lo && last < count - 1) last = above(last);
    if (last == hi && first > 0) first = below(first);
    for (int x = first; x <= last; x = x == last ? last + 1 : above(x)) st.at[st.n++] = x;
    for (int p = 0; p < st.n; ++p) {
      st.w[p] = 1.0;
      for (int q = 0; q < st.n; ++q)
        if (q != p) st.w[p] *= double(c - st.at[q]) / double(st.at[p] - st.at[q]);
    }
    return st;
  }

  Index3 dims_;
  int spacing_ = 2;
  std::vector<Stencil> stencil_[3];  // per axis, per coordinate
};

}  // namespace field
}  // namespace lodestone
