#pragma once
// What the multigrid's source files share (multigrid.cpp, multigrid_levels.cpp,
// multigrid_cycle.cpp): the hierarchy of levels in one storage precision, its
// buffers and its row loop. multigrid_levels.cpp builds the levels and
// refreshes their values from the problem; multigrid_cycle.cpp runs the
// V-cycle (smoothing, transfers, coarsest solve).
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lodestone/core/base/kept_capacity.h"
#include "lodestone/core/field/hull_stencil.h"
#include "lodestone/core/field/magnetostatic_problem.h"
#include "lodestone/core/field/multigrid.h"

namespace lodestone {
inline namespace field {

namespace multigrid_detail {

constexpr int kFull = 64;  // a full 8x8 element matrix

// fn(j, k) for every node row of the grid, one z plane per task.
template <typename Fn>
void forEachRow(const GridSpec& grid, const Fn& fn) {
  tbb::parallel_for(tbb::blocked_range<int>(0, grid.dims.k, 1), [&](const tbb::blocked_range<int>& kr) {
    for (int k = kr.begin(); k != kr.end(); ++k)
      for (int j = 0; j < grid.dims.j; ++j) fn(j, k);
  });
}

// An array whose elements are left uninitialized (unlike std::vector's
// resize, which zeroes them on one thread): every array below is written in
// parallel before it is read, so its pages are faulted in by the threads that
// use them, and 4 KiB pages that are never used (off the hulls) never are.
// Storage of several MiB is advised for 2 MiB pages (kept_capacity.h): a
// fault maps 512 times the memory, and the last partly used page is mapped
// whole.
// setSize() keeps the storage (and the values) when the size shrinks or grows
// within it, and otherwise allocates anew without copying.
template <typename V>
class Buffer {
 public:
  void setSize(std::size_t n) {
    if (n > capacity_) {
      data_.reset(new V[n]);
      adviseHugePages(data_.get(), n * sizeof(V));
      capacity_ = n;
    }
    size_ = n;
  }
  std::size_t size() const { return size_; }
  V* data() { return data_.get(); }
  const V* data() const { return data_.get(); }
  V& operator[](std::size_t m) { return data_[m]; }
  const V& operator[](std::size_t m) const { return data_[m]; }

 private:
  std::unique_ptr<V[]> data_;
  std::size_t size_ = 0, capacity_ = 0;
};

}  // namespace multigrid_detail

template <typename T>
class MultigridPreconditioner::Hierarchy {
  template <typename V>
  using Buffer = multigrid_detail::Buffer<V>;


 public:
  explicit Hierarchy(const MultigridSettings& settings) : settings_(settings) {}
  void update(const MagnetostaticProblem& problem);
  void apply(const double* r, double* z) const;
  double applyDot(const double* r, double* z) const;
  int levelCount() const { return int(levels_.size()); }

 private:
  // Vectors of one level that every cycle reuses.
  struct Work {
    Buffer<T> x, x2;   // iterate and its partner (a Jacobi sweep cannot run in place)
    Buffer<T> b;       // right-hand side
    Buffer<T> half;    // residual restricted along x only (coarse.i x fine.j x fine.k)
    Buffer<T> acc;     // material part of A v; all zero between products
    Buffer<T> t1, t2;  // coarsest level: operands of its CG operator
  };
  struct Level {
    GridSpec grid;
    BoundaryKind boundary = BoundaryKind::Open;
    // Correction cells (coefficient I + D with D != 0) in grid order: by z
    // slab ([slabStart[K], slabStart[K + 1]) lie between node planes K and
    // K + 1), then y, then x.
    std::vector<std::size_t> cellBase;
    std::vector<std::size_t> slabStart;
    std::size_t offsets[8] = {};
    std::vector<std::int32_t> problemSlot;  // level 0: the problem's slot of each cell
    // Coarse levels: each cell's children on the finer level that carry
    // material (their slots, then -1) and how many children lie inside the
    // finer grid (the divisor of the mean).
    std::vector<std::array<std::int32_t, 8>> children;
    std::vector<std::uint8_t> childCount;
    std::vector<SymMat3d> tensor;  // coarse levels: D of each correction cell
    Buffer<T> elem;                // element matrices, full 8x8 (column-major) per cell (coarse levels)
    // Level 0: the problem's assembled material rows in T (the problem's
    // hulls, which are this level's); products read them row by row
    // instead of scattering element products.
    HullStencil<T> stencil;
    // Per node row j + ny k: [lo, hi) in i of the nodes the correction cells
    // touch (lo == hi: none). Only there do A and its diagonal differ from the
    // vacuum stencil, so only there are they recomputed or read from acc.
    std::vector<std::int32_t> hull;
    Buffer<double> diagonal;  // diag(A) in double, only ever used at the hull nodes
    Buffer<T> invDiagonal;    // 0 on fixed rows
    T vacuumInvDiagonal = 0;  // its value at free nodes off the hulls and walls
    mutable Work work;
  };
  bool sameStructure(const MagnetostaticProblem& problem) const;
  void buildStructure(const MagnetostaticProblem& problem);
  void refreshValues(const MagnetostaticProblem& problem);
  template <typename CellDiagonal>
  void refreshDiagonal(Level& L, const CellDiagonal& cellDiagonal);
  template <typename V, typename CellFn>
  static void scatterBySlab(const Level& L, V* out, const CellFn& cellFn);
  template <typename Fn>
  static void forEachHullNode(const Level& L, const Fn& fn);
  static void setInverseDiagonal(Level& L, std::size_t m, int i, int j, int k);

  class CycleOps;
  /// One V-cycle from level 0: z = cycle(r), in double at the ends.
  void cycle(const double* in, double* out) const;
  void solveCoarsest(std::size_t level, const double* in, double* out) const;
  void applyLevel(std::size_t level, const T* v, T* out) const;
  template <typename RowFn>
  void product(const Level& L, const T* v, const RowFn& rowFn) const;
  template <typename Fn>
  void forEachSegment(const Level& L, int j, int k, const Fn& fn) const;
  template <typename U>
  void sweep(const Level& L, const T* x, const T* b, U* out, const double* dotWith = nullptr,
             double* rowDot = nullptr) const;
  void restrictResidual(const Level& L, const Level& C, const T* x, const T* b) const;
  void prolongAdd(const Level& L, const Level& C, T* x) const;

  MultigridSettings settings_;
  std::vector<std::unique_ptr<Level>> levels_;
  mutable std::vector<double> coarseIn_, coarseOut_;  // double copies for the coarsest CG
  mutable const double* dotWith_ = nullptr;            // applyDot(): r, for the last fine sweep
  mutable std::vector<double> rowDot_;                 // its per-row sums of r . z
  Buffer<std::int32_t> slotMaps_[2];                  // buildStructure(): cell -> slot on two levels
};

template <typename T>
template <typename V, typename CellFn>
void MultigridPreconditioner::Hierarchy<T>::scatterBySlab(const Level& L, V* out, const CellFn& cellFn) {
  // Adds cellFn(slot, local[8]) (V local[8]) to out at each cell's corners.
  // Slabs of one parity share no node plane, so they run in parallel without
  // races; a slab runs in grid order on one thread, so every node receives
  // its contributions in the same order on every run, and neighbouring cells
  // find their shared corners in cache.
  const int slabs = int(L.slabStart.size()) - 1;
  for (int parity = 0; parity < 2; ++parity)
    tbb::parallel_for(0, (slabs + 1 - parity) / 2, [&](int h) {
      const std::size_t K = std::size_t(2 * h + parity);
      for (std::size_t s = L.slabStart[K]; s != L.slabStart[K + 1]; ++s) {
        V local[8] = {0, 0, 0, 0, 0, 0, 0, 0};
        cellFn(s, local);
        for (int c = 0; c < 8; ++c) out[L.cellBase[s] + L.offsets[c]] += local[c];
      }
    });
}

}  // namespace field
}  // namespace lodestone
