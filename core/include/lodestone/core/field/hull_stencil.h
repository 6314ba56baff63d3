#pragma once
// The material cells' part of a trilinear-element operator, assembled into
// 27-point rows at the nodes those cells touch (the "hull": per grid row, the
// run of nodes from the first to the last touched one).
//
// An element-by-element product gathers 8 corners, multiplies an 8x8 matrix
// and scatters 8 sums per cell, in colour passes that sweep the material 8
// times; the assembled rows are read in grid order, which vectorizes along x
// and touches each node once. Both give the same sums up to the order of
// additions.
//
// Hull slots are numbered row by row (row j + ny k), along x within a row,
// and each row's hull is padded to whole blocks of block() slots (the
// padding's coefficients are 0). Coefficient t of slot a multiplies the
// neighbour at offset (di, dj, dk) = (t % 3 - 1, (t / 3) % 3 - 1, t / 9 - 1)
// and lives at values()[at(a, t)]: block by block, the block's 27 taps one
// after the other, block() slots each, so that a product reads one stream of
// coefficients. (With one array per tap, 27 streams 1.2 MB apart for a
// sphere of radius 32 cells, the double product took about twice as long.)
// build() takes blocks of 16 slots, or 8 or 4 where the rows are short
// (thin bodies across x): the largest whose padding adds at most a fifth to
// the slots that blocks of 4 need.
#include <algorithm>
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
  /// The largest block build() takes; it takes kMaxBlock, kMaxBlock / 2 or
  /// kMaxBlock / 4.
  static constexpr int kMaxBlock = 16;

  /// Slots per block (16, 8 or 4; chosen by build()).
  int block() const { return 1 << blockShift_; }
  /// Position in values() of coefficient t of hull slot a.
  std::size_t at(std::size_t a, int t) const {
    const std::size_t b = blockShift_;
    return (((a >> b) * kTaps + std::size_t(t)) << b) + (a & ((std::size_t(1) << b) - 1));
  }

  /// Builds the hull of the cells with base nodes `cellBase[0..cells)` on
  /// `grid` and, for every cell, the hull numbers of its 8 corners (corner c
  /// = a + 2b + 4d at base + (a, b, d)). Values are left undefined.
  void build(const GridSpec& grid, const std::size_t* cellBase, std::size_t cells);
  /// Same grid and the same cells in the same order as the last build().
  bool sameCells(const GridSpec& grid, const std::size_t* cellBase, std::size_t cells) const;

  const GridSpec& grid() const { return grid_; }
  /// Number of hull slots: the hull nodes and each row's padding to whole
  /// blocks; values() holds kTaps * size() coefficients.
  std::size_t size() const { return rowStart_.empty() ? 0 : rowStart_.back(); }
  /// Hull slot of corner c of cell `slot` (as given to build()).
  std::uint32_t corner(std::size_t slot, int c) const { return corner_[slot * 8 + std::size_t(c)]; }
  /// Tap of the neighbour at corner d seen from corner c of one cell.
  static int tap(int c, int d) {
    return ((d & 1) - (c & 1) + 1) + 3 * (((d >> 1) & 1) - ((c >> 1) & 1) + 1) + 9 * ((d >> 2) - (c >> 2) + 1);
  }
  /// Row (j, k)'s hull [lo, hi) in i; lo == hi when the row has none.
  int lo(int j, int k) const { return lo_[std::size_t(j) + std::size_t(grid_.dims.j) * std::size_t(k)]; }
  int hi(int j, int k) const { return hi_[std::size_t(j) + std::size_t(grid_.dims.j) * std::size_t(k)]; }
  /// Hull slot of node (lo(j, k), j, k); a multiple of block().
  std::size_t rowStart(int j, int k) const {
    return rowStart_[std::size_t(j) + std::size_t(grid_.dims.j) * std::size_t(k)];
  }
  /// Coefficient t of node (i, j, k), i in [lo(j, k), hi(j, k)).
  T value(int i, int j, int k, int t) const { return values_[at(rowStart(j, k) + std::size_t(i - lo(j, k)), t)]; }

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
  void addRow(int j, int k, int from, int to, const T* v, T* out) const;
  /// out += (assembled rows) v on every hull node (row-parallel).
  void addProduct(const T* v, T* out) const;
  /// out += the rows' diagonal (tap 13) on every hull node.
  void addDiagonal(T* out) const;

 private:
  /// Adds the rows of `blocks` consecutive blocks times x to o: lanes
  /// [first, block()) of the first block, every lane of the middle ones and
  /// lanes [0, last) of the last (0 < last <= block()). c points at the first
  /// block's coefficients, x and o at its lane 0; every neighbour exists.
  /// Compiled for AVX2 too, chosen at run time; without FMA, so that both
  /// give the same bits.
  void addBlocks(const T* c, const T* x, T* o, std::size_t blocks, int first, int last, std::ptrdiff_t sy,
                 std::ptrdiff_t sz) const;

  GridSpec grid_;
  std::vector<std::int32_t> lo_, hi_;
  std::vector<std::size_t> rowStart_;  // per row, then the total
  std::vector<std::uint32_t> corner_;  // 8 per cell
  std::vector<std::size_t> cellBase_;  // what build() was given
  std::vector<std::int32_t> cellSlot_; // slot of each grid cell (-1: none)
  std::vector<T> values_;
  int blockShift_ = 4;  // log2 of block()

  template <typename>
  friend class HullStencil;
};

template <typename T>
void HullStencil<T>::addRow(int j, int k, int from, int to, const T* v, T* out) const {
  if (from >= to) return;
  const int rowLo = lo(j, k);
  const std::size_t start = rowStart(j, k);
  const Index3 d = grid_.dims;
  const std::ptrdiff_t sy = d.i, sz = std::ptrdiff_t(d.i) * d.j;
  // Interior part of the run (every neighbour exists), by blocks: each
  // node's taps are summed in order onto out[i].
  const bool interiorRow = j > 0 && j < d.j - 1 && k > 0 && k < d.k - 1;
  const int in0 = interiorRow ? std::max(from, 1) : to, in1 = interiorRow ? std::min(to, d.i - 1) : to;
  if (in0 < in1) {
    const std::size_t a0 = start + std::size_t(in0 - rowLo), a1 = start + std::size_t(in1 - rowLo);
    const std::size_t B = std::size_t(block());
    const std::size_t blocks = (a1 - 1) / B - a0 / B + 1;
    const int first = int(a0 % B), last = int(a1 - ((a1 - 1) / B) * B);
    const int i0 = in0 - first;  // the node of the first block's lane 0
    addBlocks(values_.data() + at(a0 - std::size_t(first), 0), v + i0, out + i0, blocks, first, last, sy, sz);
  }
  // Nodes next to the grid's faces: neighbour by neighbour, in range only.
  for (int i = from; i < to; ++i) {
    if (i >= in0 && i < in1) continue;
    const std::size_t a = start + std::size_t(i - rowLo);
    T s = out[i];
    for (int t = 0; t < kTaps; ++t) {
      const int di = t % 3 - 1, dj = (t / 3) % 3 - 1, dk = t / 9 - 1;
      if (i + di < 0 || i + di >= d.i || j + dj < 0 || j + dj >= d.j || k + dk < 0 || k + dk >= d.k) continue;
      s += values_[at(a, t)] * v[std::ptrdiff_t(i) + di + sy * dj + sz * dk];
    }
    out[i] = s;
  }
}

}  // namespace field
}  // namespace lodestone
