#include "lodestone/core/field/hull_stencil.h"

#include <algorithm>
#include <array>
#include <cstring>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lodestone/core/base/cpu_features.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/kept_capacity.h"

namespace lodestone {
inline namespace field {

template <typename T>
void HullStencil<T>::build(const GridSpec& grid, const std::size_t* cellBase, std::size_t cells) {
  grid.validate("hull stencil grid");
  grid_ = grid;
  const std::size_t nx = std::size_t(grid.dims.i), ny = std::size_t(grid.dims.j), nz = std::size_t(grid.dims.k);
  const std::size_t rows = ny * nz;
  lo_.assign(rows, grid.dims.i);
  hi_.assign(rows, 0);
  for (std::size_t s = 0; s < cells; ++s) {
    const std::size_t b = cellBase[s];
    const int i = int(b % nx);
    const std::size_t j = (b / nx) % ny, k = b / (nx * ny);
    require(i + 1 < grid.dims.i && j + 1 < ny && k + 1 < nz, "hull stencil: cell base node ", b,
            " has no cell on a grid of ", grid.dims.i, " x ", grid.dims.j, " x ", grid.dims.k, " nodes");
    for (std::size_t dk = 0; dk < 2; ++dk)
      for (std::size_t dj = 0; dj < 2; ++dj) {
        const std::size_t row = (j + dj) + ny * (k + dk);
        lo_[row] = std::min(lo_[row], std::int32_t(i));
        hi_[row] = std::max(hi_[row], std::int32_t(i + 2));
      }
  }
  // Slots with blocks of 4, 8 and 16: the largest block whose padding
  // stays within a fifth of the smallest's slots.
  const auto padded = [&](std::size_t row, std::size_t B) {
    return (std::size_t(hi_[row] - lo_[row]) + B - 1) / B * B;
  };
  std::size_t slots[3] = {0, 0, 0};
  for (std::size_t row = 0; row < rows; ++row) {
    if (lo_[row] >= hi_[row]) lo_[row] = hi_[row] = 0;
    for (int b = 0; b < 3; ++b) slots[b] += padded(row, std::size_t(kMaxBlock >> (2 - b)));
  }
  int shift = 2;
  for (int b = 2; b > 0; --b)
    if (5 * slots[b] <= 6 * slots[0]) {
      shift = b + 2;
      break;
    }
  blockShift_ = shift;
  rowStart_.assign(rows + 1, 0);
  for (std::size_t row = 0; row < rows; ++row) rowStart_[row + 1] = rowStart_[row] + padded(row, std::size_t(block()));
  resizeKeepingCapacity(corner_, cells * 8);  // every corner is written below
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t s = r.begin(); s != r.end(); ++s) {
      const std::size_t b = cellBase[s];
      const int i = int(b % nx);
      const std::size_t j = (b / nx) % ny, k = b / (nx * ny);
      for (int c = 0; c < 8; ++c) {
        const std::size_t row = (j + std::size_t((c >> 1) & 1)) + ny * (k + std::size_t(c >> 2));
        corner_[s * 8 + std::size_t(c)] = std::uint32_t(rowStart_[row] + std::size_t(i + (c & 1) - lo_[row]));
      }
    }
  });
  cellBase_.assign(cellBase, cellBase + cells);
  assignKeepingCapacity(cellSlot_, grid.cellCount(), std::int32_t(-1));
  for (std::size_t s = 0; s < cells; ++s) {
    const std::size_t b = cellBase[s];
    cellSlot_[grid.cellIndex(int(b % nx), int((b / nx) % ny), int(b / (nx * ny)))] = std::int32_t(s);
  }
  // Rebuilt as the material moves: the coefficients keep their storage.
  resizeKeepingCapacity(values_, std::size_t(kTaps) * size());
}

template <typename T>
void HullStencil<T>::assemble(const double* packed) {
  // Per corner c of a cell: the taps its row of E feeds and where that row
  // sits in the packed upper triangle.
  struct Tables {
    int tap[8][8], pos[8][8];
  };
  static const Tables tables = [] {
    Tables t{};
    int p[8][8];
    for (int c = 0, e = 0; c < 8; ++c)
      for (int d = c; d < 8; ++d, ++e) p[c][d] = p[d][c] = e;
    for (int c = 0; c < 8; ++c)
      for (int d = 0; d < 8; ++d) {
        t.tap[c][d] = tap(c, d);
        t.pos[c][d] = p[c][d];
      }
    return t;
  }();
  const Index3 d = grid_.dims;
  const Index3 cd = grid_.cellDims();
  const std::size_t B = std::size_t(block());
  T* out = values_.data();
  tbb::parallel_for(tbb::blocked_range<int>(0, d.k, 1), [&](const tbb::blocked_range<int>& kr) {
    for (int k = kr.begin(); k != kr.end(); ++k)
      for (int j = 0; j < d.j; ++j) {
        const int a0 = lo(j, k), a1 = hi(j, k);
        if (a0 >= a1) continue;
        const std::size_t r = std::size_t(j) + std::size_t(d.j) * std::size_t(k), row = rowStart_[r];
        // The row's slots, padding included, are kTaps * (its slot count) values from at(row, 0).
        std::fill(out + at(row, 0), out + at(row, 0) + kTaps * (rowStart_[r + 1] - row), T(0));
        // The row's nodes are corner c = a + 2b + 4e of the cells based at
        // (i - a, j - b, k - e): one cell row per (b, e), in a fixed order.
        for (int c = 0; c < 8; ++c) {
          const int a = c & 1, cj = j - ((c >> 1) & 1), ck = k - (c >> 2);
          if (cj < 0 || ck < 0 || cj >= cd.j || ck >= cd.k) continue;
          const std::int32_t* slots = cellSlot_.data() + grid_.cellIndex(0, cj, ck);
          const int* taps = tables.tap[c];
          const int* pos = tables.pos[c];
          for (int i = std::max(a0, a); i < std::min(a1, cd.i + a); ++i) {
            const std::int32_t slot = slots[i - a];
            if (slot < 0) continue;
            const double* E = packed + std::size_t(slot) * 36;
            const std::size_t node = row + std::size_t(i - a0);
            T* o = out + at(node, 0);
            for (int e = 0; e < 8; ++e) o[std::size_t(taps[e]) * B] += T(E[pos[e]]);
          }
        }
      }
  });
}

template <typename T>
bool HullStencil<T>::sameCells(const GridSpec& grid, const std::size_t* cellBase, std::size_t cells) const {
  return grid == grid_ && cells == cellBase_.size() && std::equal(cellBase, cellBase + cells, cellBase_.begin());
}

template <typename T>
template <typename U>
void HullStencil<T>::assignConverted(const HullStencil<U>& other) {
  grid_ = other.grid_;
  lo_ = other.lo_;
  hi_ = other.hi_;
  rowStart_ = other.rowStart_;
  blockShift_ = other.blockShift_;
  corner_.clear();
  cellBase_.clear();
  cellSlot_.clear();
  resizeKeepingCapacity(values_, other.values_.size());
  const U* src = other.values_.data();
  T* dst = values_.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, values_.size(), 1 << 15),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t m = r.begin(); m != r.end(); ++m) dst[m] = T(src[m]);
                    });
}

template <typename T>
void HullStencil<T>::clear() {
  T* v = values_.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, values_.size(), 1 << 15),
                    [&](const tbb::blocked_range<std::size_t>& r) { std::fill(v + r.begin(), v + r.end(), T(0)); });
}

template <typename T>
void HullStencil<T>::addProduct(const T* v, T* out) const {
  const Index3 d = grid_.dims;
  tbb::parallel_for(tbb::blocked_range<int>(0, d.k, 1), [&](const tbb::blocked_range<int>& kr) {
    for (int k = kr.begin(); k != kr.end(); ++k)
      for (int j = 0; j < d.j; ++j) {
        const std::size_t row = grid_.index(0, j, k);
        addRow(j, k, lo(j, k), hi(j, k), v + row, out + row);
      }
  });
}

template <typename T>
void HullStencil<T>::addDiagonal(T* out) const {
  const Index3 d = grid_.dims;
  tbb::parallel_for(0, d.k, [&](int k) {
    for (int j = 0; j < d.j; ++j) {
      const int a = lo(j, k), b = hi(j, k);
      const std::size_t row = rowStart(j, k);
      T* o = out + grid_.index(a, j, k);
      for (int i = 0; i < b - a; ++i) o[i] += values_[at(row + std::size_t(i), 13)];
    }
  });
}

namespace {

// Blocks of B slots, as vectors of up to 32 bytes, N vectors of L lanes
// (GCC and Clang vector extensions): the portable variant runs a 32-byte
// vector as two SSE2 operations, the AVX2 variant as one.
template <typename T, int B>
__attribute__((always_inline)) inline void addBlocksKernel(const T* c, const T* x, T* o, std::size_t blocks, int first,
                                                           int last, std::ptrdiff_t sy, std::ptrdiff_t sz) {
  constexpr int taps = HullStencil<T>::kTaps;
  constexpr int L = B * int(sizeof(T)) < 32 ? B : 32 / int(sizeof(T)), N = B / L;
  typedef T W __attribute__((vector_size(L * sizeof(T))));
  static_assert(B % L == 0, "a block is whole vectors");
  for (std::size_t b = 0; b < blocks; ++b, c += taps * B, x += B, o += B) {
    const int q0 = b == 0 ? first : 0, q1 = b + 1 == blocks ? last : B;
    if (q0 == 0 && q1 == B) {
      W acc[N];
      for (int n = 0; n < N; ++n) std::memcpy(&acc[n], o + n * L, sizeof(W));
      for (int t = 0; t < taps; ++t) {
        const T* xt = x + (t % 3 - 1) + sy * ((t / 3) % 3 - 1) + sz * (t / 9 - 1);
        const T* ct = c + t * B;
        for (int n = 0; n < N; ++n) {
          W cv, xv;
          std::memcpy(&cv, ct + n * L, sizeof(W));
          std::memcpy(&xv, xt + n * L, sizeof(W));
          acc[n] += cv * xv;
        }
      }
      for (int n = 0; n < N; ++n) std::memcpy(o + n * L, &acc[n], sizeof(W));
    } else {
      T acc[B];
      for (int q = q0; q < q1; ++q) acc[q] = o[q];
      for (int t = 0; t < taps; ++t) {
        const T* xt = x + (t % 3 - 1) + sy * ((t / 3) % 3 - 1) + sz * (t / 9 - 1);
        const T* ct = c + t * B;
        for (int q = q0; q < q1; ++q) acc[q] += ct[q] * xt[q];
      }
      for (int q = q0; q < q1; ++q) o[q] = acc[q];
    }
  }
}

template <typename T, int B>
void addBlocksOf(const T* c, const T* x, T* o, std::size_t blocks, int first, int last, std::ptrdiff_t sy,
                 std::ptrdiff_t sz) {
  // AVX2 without FMA: a multiply and an add round as in the portable variant.
  runWidest<FusedMultiplyAdd::Forbidden>(
      [](auto&&... args) __attribute__((always_inline)) { addBlocksKernel<T, B>(args...); }, c, x, o, blocks, first,
      last, sy, sz);
}

}  // namespace

template <typename T>
void HullStencil<T>::addBlocks(const T* c, const T* x, T* o, std::size_t blocks, int first, int last, std::ptrdiff_t sy,
                               std::ptrdiff_t sz) const {
  switch (block()) {
    case kMaxBlock:
      addBlocksOf<T, kMaxBlock>(c, x, o, blocks, first, last, sy, sz);
      break;
    case kMaxBlock / 2:
      addBlocksOf<T, kMaxBlock / 2>(c, x, o, blocks, first, last, sy, sz);
      break;
    default:
      addBlocksOf<T, kMaxBlock / 4>(c, x, o, blocks, first, last, sy, sz);
      break;
  }
}

template class HullStencil<double>;
template class HullStencil<float>;
template void HullStencil<float>::assignConverted<double>(const HullStencil<double>&);
template void HullStencil<double>::assignConverted<double>(const HullStencil<double>&);

}  // namespace field
}  // namespace lodestone
