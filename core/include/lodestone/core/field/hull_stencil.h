#pragma once
// The material cells' part of a trilinear-element operator, assembled into
// 27-point rows at the nodes those cells touch (the "hull": per grid row, the
// run of nodes from the first to the last touched one).
//
// An element-by-element product gathers 8 corners, multiplies an 8x8 matrix
// and scatters 8 sums per cell, in colour passes that sweep the material 8
// times; the assembled rows are read in grid order, one coefficient stream per
// neighbour offset, which vectorizes along x and touches each node once. Both
// give the same sums up to the order of additions.
//
// Coefficient t of hull node a multiplies the neighbour at offset
// (di, dj, dk) = (t % 3 - 1, (t / 3) % 3 - 1, t / 9 - 1) and lives at
// values[t * size() + a]; hull nodes are numbered row by row (row j + ny k),
// along x within a row.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "lodestone/core/base/grid.h"

namespace lodestone {
inline namespace field {

template <typename T>
class HullStencil {
 public:
  static constexpr int kTaps = 27;

  /// Builds the hull of the cells with base nodes `cellBase[0..cells)` on
  /// `grid` and, for every cell, the hull numbers of its 8 corners (corner c
  /// = a + 2b + 4d at base + (a, b, d)). Values are left undefined.
  void build(const GridSpec& grid, const std::size_t* cellBase, std::size_t cells);
  /// Same grid and the same cells in the same order as the last build().
  bool sameCells(const GridSpec& grid, const std::size_t* cellBase, std::size_t cells) const;

  const GridSpec& grid() const { return grid_; }
  /// Number of hull nodes.
  std::size_t size() const { return rowStart_.empty() ? 0 : rowStart_.back(); }
  /// Hull number of corner c of cell `slot` (as given to build()).
  std::uint32_t corner(std::size_t slot, int c) const { return corner_[slot * 8 + std::size_t(c)]; }
  /// Tap of the neighbour at corner d seen from corner c of one cell.
  static int tap(int c, int d) {
    return ((d & 1) - (c & 1) + 1) + 3 * (((d >> 1) & 1) - ((c >> 1) & 1) + 1) + 9 * ((d >> 2) - (c >> 2) + 1);
  }
  /// Row (j, k)'s hull [lo, hi) in i; lo == hi when the row has none.
  int lo(int j, int k) const { return lo_[std::size_t(j) + std::size_t(grid_.dims.j) * std::size_t(k)]; }
  int hi(int j, int k) const { return hi_[std::size_t(j) + std::size_t(grid_.dims.j) * std::size_t(k)]; }
  /// Hull number of node (lo(j, k), j, k).
  std::size_t rowStart(int j, int k) const {
    return rowStart_[std::size_t(j) + std::size_t(grid_.dims.j) * std::size_t(k)];
  }

  T* values() { return values_.data(); }
  const T* values() const { return values_.data(); }
  /// Sets every coefficient to 0 (in parallel).
  void clear();
  /// Writes every coefficient from the cells' packed element matrices
  /// (the upper triangle, row by row, 36 values per cell, in the order given
  /// to build()): each hull node gathers its 8 cells in a fixed order, so
  /// every coefficient is written once, deterministically, in parallel.
  void assemble(const double* packed);
  /// Takes the hulls and coefficients of `other` (values converted to T),
  /// without its cell lists: enough for products and diagonals, not for
  /// assemble().
  template <typename U>
  void assignConverted(const HullStencil<U>& other);
  /// out[row node i] += (assembled rows) v on row (j, k), for i in [from, to)
  /// within the row's hull; v and out point at node (0, j, k) of their grids.
  /// Neighbours outside the grid are skipped (their coefficients are 0).
  template <typename V>
  void addRow(int j, int k, int from, int to, const V* v, V* out) const;
  /// out += (assembled rows) v on every hull node (row-parallel).
  template <typename V>
  void addProduct(const V* v, V* out) const;
  /// out += the rows' diagonal (tap 13) on every hull node.
  template <typename V>
  void addDiagonal(V* out) const;

 private:
  GridSpec grid_;
  std::vector<std::int32_t> lo_, hi_;
  std::vector<std::size_t> rowStart_;  // per row, then the total
  std::vector<std::uint32_t> corner_;  // 8 per cell
  std::vector<std::size_t> cellBase_;  // what build() was given
  std::vector<std::int32_t> cellSlot_; // slot of each grid cell (-1: none)
  std::vector<T> values_;

  template <typename>
  friend class HullStencil;
};

template <typename T>
template <typename V>
void HullStencil<T>::addRow(int j, int k, int from, int to, const V* v, V* out) const {
  const int rowLo = lo(j, k);
  if (from >= to) return;
  const std::size_t n = size(), base = rowStart(j, k) + std::size_t(from - rowLo);
  const Index3 d = grid_.dims;
  const std::ptrdiff_t sy = d.i, sz = std::ptrdiff_t(d.i) * d.j;
  // Interior part of the run: every neighbour exists, one stream per tap.
  const bool interiorRow = j > 0 && j < d.j - 1 && k > 0 && k < d.k - 1;
  const int in0 = interiorRow ? std::max(from, 1) : to, in1 = interiorRow ? std::min(to, d.i - 1) : to;
  if (in0 < in1) {
    const std::size_t b = base + std::size_t(in0 - from);
    const int count = in1 - in0;
    V* o = out + in0;
    for (int t = 0; t < kTaps; ++t) {
      const std::ptrdiff_t off = (t % 3 - 1) + sy * ((t / 3) % 3 - 1) + sz * (t / 9 - 1);
      const T* c = values_.data() + std::size_t(t) * n + b;
      const V* x = v + in0 + off;
      for (int q = 0; q < count; ++q) o[q] += V(c[q]) * x[q];
    }
  }
  // Nodes next to the grid's faces: neighbour by neighbour, in range only.
  for (int i = from; i < to; ++i) {
    if (i >= in0 && i < in1) continue;
    const std::size_t a = base + std::size_t(i - from);
    V s = 0;
    for (int t = 0; t < kTaps; ++t) {
      const int di = t % 3 - 1, dj = (t / 3) % 3 - 1, dk = t / 9 - 1;
      if (i + di < 0 || i + di >= d.i || j + dj < 0 || j + dj >= d.j || k + dk < 0 || k + dk >= d.k) continue;
      s += V(values_[std::size_t(t) * n + a]) * v[std::ptrdiff_t(i) + di + sy * dj + sz * dk];
    }
    out[i] += s;
  }
}

}  // namespace field
}  // namespace lodestone
