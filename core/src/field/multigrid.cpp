#include "lodestone/core/field/multigrid.h"

#include "lodestone/core/field/v_cycle.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lodestone/core/base/coloured_scatter.h"  // cornerOffsets
#include "lodestone/core/base/error.h"
#include "lodestone/core/field/hull_stencil.h"
#include "lodestone/core/field/magnetostatic_problem.h"
#include "lodestone/core/base/parallel.h"
#include "lodestone/core/field/q1_element.h"
#include "lodestone/core/field/q1_stencil.h"

namespace lodestone {
inline namespace field {

namespace {

constexpr int kPacked = MagnetostaticProblem::kPacked;  // upper triangle of a symmetric 8x8 element matrix

// Packed unit-cell element matrices of d_a N . d_b N (symmetrized for a != b),
// integrated with 2x2x2 Gauss points: E(D) = dx * sum_ab D_ab basis_ab.
struct ElementBasis {
  double xx[kPacked], yy[kPacked], zz[kPacked], xy[kPacked], xz[kPacked], yz[kPacked];
  ElementBasis() {
    const q1::Tables t = q1::makeTables();
    for (int c = 0, e = 0; c < 8; ++c)
      for (int d = c; d < 8; ++d, ++e) {
        double s[6];
        q1::gradientProducts(t, c, d, s);
        xx[e] = s[0];
        yy[e] = s[1];
        zz[e] = s[2];
        xy[e] = s[3];
        xz[e] = s[4];
        yz[e] = s[5];
      }
  }
};
const ElementBasis& elementBasis() {
  static const ElementBasis basis;
  return basis;
}

template <typename Fn>
void forEach(std::size_t n, const Fn& fn) {
  parallelForEach(n, fn);
}

constexpr int kFull = 64;  // a full 8x8 element matrix

// Packed upper triangle -> full symmetric 8x8 (column-major) in T.
template <typename T>
void unpack(const double* packed, T* full) {
  for (int c = 0, e = 0; c < 8; ++c)
    for (int d = c; d < 8; ++d, ++e) full[8 * d + c] = full[8 * c + d] = T(packed[e]);
}

// diag(K) at one node, the same value q1LaplacianDiagonalAll gives there.
inline double laplacianDiagonalAt(const GridSpec& grid, int i, int j, int k) {
  return grid.isBoundaryNode(i, j, k) ? q1LaplacianDiagonal(grid, i, j, k) : grid.dx * 8.0 / 3.0;
}

bool sameGrid(const GridSpec& a, const GridSpec& b) {
  return a.dx == b.dx && a.origin.x == b.origin.x && a.origin.y == b.origin.y && a.origin.z == b.origin.z &&
         a.dims == b.dims;
}

// fn(j, k) for every node row of the grid, one z plane per task.
template <typename Fn>
void forEachRow(const GridSpec& grid, const Fn& fn) {
  tbb::parallel_for(tbb::blocked_range<int>(0, grid.dims.k, 1), [&](const tbb::blocked_range<int>& kr) {
    for (int k = kr.begin(); k != kr.end(); ++k)
      for (int j = 0; j < grid.dims.j; ++j) fn(j, k);
  });
}

// Full weighting of one fine line of fn values onto cn coarse ones (R = P^T
// of the trilinear prolongation along that line).
template <typename T>
inline T restrictPoint(const T* src, std::size_t stride, int c, int fn) {
  T v = 0;
  if (2 * c < fn) v += src[std::size_t(2 * c) * stride];
  if (2 * c - 1 >= 0 && 2 * c - 1 < fn) v += T(0.5) * src[std::size_t(2 * c - 1) * stride];
  if (2 * c + 1 < fn) v += T(0.5) * src[std::size_t(2 * c + 1) * stride];
  return v;
}

// local += E v for a full 8x8 element matrix E (column-major) and the cell's
// corners v[offsets[d]]. Written row by row over stack arrays, which alias
// nothing, so that the compiler vectorizes it across rows.
template <typename T>
inline void elementProduct(const T* E, const T* v, const std::size_t offsets[8], T local[8]) {
  T corner[8];
  for (int d = 0; d < 8; ++d) corner[d] = v[offsets[d]];
  T sum[8];
  for (int c = 0; c < 8; ++c) {
    T s = 0;
    for (int d = 0; d < 8; ++d) s += E[8 * d + c] * corner[d];
    sum[c] = s;
  }
  for (int c = 0; c < 8; ++c) local[c] += sum[c];
}

// An array whose elements are left uninitialized (unlike std::vector's
// resize, which zeroes them on one thread): every array below is written in
// parallel before it is read, so its pages are faulted in by the threads that
// use them, and pages that are never used (off the hulls) never are.
// setSize() keeps the storage (and the values) when the size shrinks or grows
// within it, and otherwise allocates anew without copying.
template <typename V>
class Buffer {
 public:
  void setSize(std::size_t n) {
    if (n > capacity_) {
      data_.reset(new V[n]);
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

}  // namespace

template <typename T>
class MultigridPreconditioner::Hierarchy {
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
bool MultigridPreconditioner::Hierarchy<T>::sameStructure(const MagnetostaticProblem& problem) const {
  if (levels_.empty()) return false;
  const Level& F = *levels_.front();
  if (!sameGrid(F.grid, problem.grid()) || F.boundary != problem.boundary()) return false;
  // Same count and every kept cell still at the problem's slot it was
  // copied from (distinct cells, so the same set and the same permutation).
  if (F.cellBase.size() != problem.materialCellCount()) return false;
  for (std::size_t s = 0; s < F.cellBase.size(); ++s)
    if (F.cellBase[s] != problem.materialCellBase(std::size_t(F.problemSlot[s]))) return false;
  return true;
}

template <typename T>
void MultigridPreconditioner::Hierarchy<T>::buildStructure(const MagnetostaticProblem& problem) {
  // On the same grid (a new material set, as after every setMaterial() of a
  // simulation) the levels, their node arrays and their storage are kept:
  // only the cell lists change, and no page is freed and faulted in again.
  const bool reuse = !levels_.empty() && sameGrid(levels_.front()->grid, problem.grid()) &&
                     levels_.front()->boundary == problem.boundary();
  if (reuse) {
    for (auto& level : levels_) {
      Level& L = *level;
      // The diagonal back to the vacuum one on the old hulls (elsewhere it is).
      forEachHullNode(L, [&](std::size_t m, int i, int j, int k) {
        L.diagonal[m] = laplacianDiagonalAt(L.grid, i, j, k);
        setInverseDiagonal(L, m, i, j, k);
      });
      L.cellBase.clear();
      L.slabStart.clear();
      L.problemSlot.clear();
      L.children.clear();
      L.childCount.clear();
    }
  } else {
    levels_.clear();
    auto fine = std::make_unique<Level>();
    fine->grid = problem.grid();
    fine->boundary = problem.boundary();
    levels_.push_back(std::move(fine));
  }
  const std::size_t keptLevels = reuse ? levels_.size() : 0;

  Level& fine = *levels_.front();
  const std::size_t materialCells = problem.materialCellCount();
  require(materialCells < std::size_t(INT32_MAX), "multigrid: too many material cells (", materialCells, ")");
  // Slot of every cell of the current finest level (-1: none), alternating
  // between two maps; on level 0 the problem's slot, whose tensor seeds level 1.
  Buffer<std::int32_t>* slotOfCell = &slotMaps_[0];
  {
    slotOfCell->setSize(fine.grid.cellCount());
    std::int32_t* map = slotOfCell->data();
    forEach(fine.grid.cellCount(), [&](std::size_t m) { map[m] = -1; });
    const Index3 cd = fine.grid.cellDims();
    const std::size_t nx = std::size_t(fine.grid.dims.i), ny = std::size_t(fine.grid.dims.j);
    forEach(materialCells, [&](std::size_t s) {
      const std::size_t b = problem.materialCellBase(s);
      const int i = int(b % nx), j = int((b / nx) % ny), k = int(b / (nx * ny));
      map[std::size_t(i) + std::size_t(cd.i) * (std::size_t(j) + std::size_t(cd.j) * k)] = std::int32_t(s);
    });
    // Grid order, one slab per task.
    std::vector<std::vector<std::size_t>> slabBase(std::size_t(cd.k));
    std::vector<std::vector<std::int32_t>> slabSlot(std::size_t(cd.k));
    tbb::parallel_for(0, cd.k, [&](int k) {
      for (int j = 0; j < cd.j; ++j)
        for (int i = 0; i < cd.i; ++i) {
          const std::int32_t s = map[std::size_t(i) + std::size_t(cd.i) * (std::size_t(j) + std::size_t(cd.j) * k)];
          if (s < 0) continue;
          slabBase[std::size_t(k)].push_back(fine.grid.index(i, j, k));
          slabSlot[std::size_t(k)].push_back(s);
        }
    });
    fine.cellBase.reserve(materialCells);
    fine.problemSlot.reserve(materialCells);
    fine.slabStart.assign(1, 0);
    for (int k = 0; k < cd.k; ++k) {
      fine.cellBase.insert(fine.cellBase.end(), slabBase[std::size_t(k)].begin(), slabBase[std::size_t(k)].end());
      fine.problemSlot.insert(fine.problemSlot.end(), slabSlot[std::size_t(k)].begin(), slabSlot[std::size_t(k)].end());
      fine.slabStart.push_back(fine.cellBase.size());
    }
    require(fine.cellBase.size() == materialCells, "multigrid: ", materialCells, " material cells listed but ",
            fine.cellBase.size(), " distinct ones found");
  }

  for (std::size_t l = 1;; ++l) {
    const Level& f = *levels_[l - 1];
    const Index3 fd = f.grid.dims;
    if (std::min({fd.i, fd.j, fd.k}) <= settings_.coarsestNodes) break;
    if (l == levels_.size()) {
      auto created = std::make_unique<Level>();
      created->boundary = f.boundary;
      created->grid.origin = f.grid.origin;
      created->grid.dx = 2 * f.grid.dx;
      created->grid.dims = {(fd.i - 1 + 1) / 2 + 1, (fd.j - 1 + 1) / 2 + 1, (fd.k - 1 + 1) / 2 + 1};
      levels_.push_back(std::move(created));
    }
    Level& c = *levels_[l];
    const Index3 fcd = f.grid.cellDims(), ccd = c.grid.cellDims();
    const std::int32_t* finer = slotOfCell->data();
    // A coarse cell carries a correction when any child does; grid order.
    std::vector<std::vector<std::size_t>> slabBase(std::size_t(ccd.k));
    std::vector<std::vector<std::array<std::int32_t, 8>>> slabChildren(std::size_t(ccd.k));
    std::vector<std::vector<std::uint8_t>> slabCount(std::size_t(ccd.k));
    tbb::parallel_for(0, ccd.k, [&](int K) {
      for (int J = 0; J < ccd.j; ++J)
        for (int I = 0; I < ccd.i; ++I) {
          std::array<std::int32_t, 8> kids;
          kids.fill(-1);
          int children = 0, material = 0;
          for (int d = 0; d < 2; ++d)
            for (int b = 0; b < 2; ++b)
              for (int a = 0; a < 2; ++a) {
                const int i = 2 * I + a, j = 2 * J + b, k = 2 * K + d;
                if (i >= fcd.i || j >= fcd.j || k >= fcd.k) continue;
                ++children;
                const std::int32_t s =
                    finer[std::size_t(i) + std::size_t(fcd.i) * (std::size_t(j) + std::size_t(fcd.j) * k)];
                if (s >= 0) kids[std::size_t(material++)] = s;
              }
          if (material == 0) continue;
          const std::size_t slab = std::size_t(K);
          slabBase[slab].push_back(c.grid.index(I, J, K));
          slabChildren[slab].push_back(kids);
          slabCount[slab].push_back(std::uint8_t(children));
        }
    });
    c.slabStart.assign(1, 0);
    for (std::size_t slab = 0; slab < slabBase.size(); ++slab) {
      c.cellBase.insert(c.cellBase.end(), slabBase[slab].begin(), slabBase[slab].end());
      c.children.insert(c.children.end(), slabChildren[slab].begin(), slabChildren[slab].end());
      c.childCount.insert(c.childCount.end(), slabCount[slab].begin(), slabCount[slab].end());
      c.slabStart.push_back(c.cellBase.size());
    }
    slotOfCell = &slotMaps_[l % 2];
    slotOfCell->setSize(c.grid.cellCount());
    std::int32_t* map = slotOfCell->data();
    forEach(c.grid.cellCount(), [&](std::size_t m) { map[m] = -1; });
    const std::size_t cnx = std::size_t(c.grid.dims.i), cny = std::size_t(c.grid.dims.j);
    forEach(c.cellBase.size(), [&](std::size_t s) {
      const std::size_t b = c.cellBase[s];
      const int i = int(b % cnx), j = int((b / cnx) % cny), k = int(b / (cnx * cny));
      map[std::size_t(i) + std::size_t(ccd.i) * (std::size_t(j) + std::size_t(ccd.j) * k)] = std::int32_t(s);
    });
    c.tensor.resize(c.cellBase.size());
  }
  require(!reuse || keptLevels == levels_.size(), "multigrid: ", levels_.size(), " levels on a grid that had ",
          keptLevels);

  for (std::size_t l = 0; l < levels_.size(); ++l) {
    Level& L = *levels_[l];
    const GridSpec& g = L.grid;
    const std::size_t nodes = g.nodeCount();
    L.elem.setSize(l == 0 ? 0 : L.cellBase.size() * kFull);
    // Hull of the correction nodes on each row.
    const int nx = g.dims.i, ny = g.dims.j;
    std::vector<std::int32_t> lo(std::size_t(ny) * std::size_t(g.dims.k), nx), hi(lo.size(), 0);
    for (const std::size_t b : L.cellBase) {
      const int i = int(b % std::size_t(nx)), j = int((b / std::size_t(nx)) % std::size_t(ny)),
                k = int(b / (std::size_t(nx) * std::size_t(ny)));
      for (int dk = 0; dk < 2; ++dk)
        for (int dj = 0; dj < 2; ++dj) {
          const std::size_t row = std::size_t(j + dj) + std::size_t(ny) * std::size_t(k + dk);
          lo[row] = std::min(lo[row], std::int32_t(i));
          hi[row] = std::max(hi[row], std::int32_t(i + 2));
        }
    }
    L.hull.resize(2 * lo.size());
    for (std::size_t row = 0; row < lo.size(); ++row) {
      const bool any = lo[row] < hi[row];
      L.hull[2 * row] = any ? lo[row] : 0;
      L.hull[2 * row + 1] = any ? hi[row] : 0;
    }
    if (reuse) continue;
    cornerOffsets(g, L.offsets);
    // Inverse of the vacuum diagonal everywhere; refreshValues() updates the
    // hull nodes (and only there writes `diagonal`).
    L.diagonal.setSize(nodes);
    L.invDiagonal.setSize(nodes);
    forEachRow(g, [&](int j, int k) {
      for (int i = 0; i < nx; ++i) {
        const std::size_t m = g.index(i, j, k);
        const double d = laplacianDiagonalAt(g, i, j, k);
        L.invDiagonal[m] =
            (L.boundary == BoundaryKind::Open && g.isBoundaryNode(i, j, k)) ? T(0) : (d > 0 ? T(1.0 / d) : T(0));
      }
    });
    L.vacuumInvDiagonal = T(1.0 / (g.dx * 8.0 / 3.0));  // laplacianDiagonalAt off the walls
    // Work vectors persist with the grid (no page faults in the Newton loop).
    Work& w = L.work;
    w.x.setSize(nodes);
    w.b.setSize(nodes);
    if (l + 1 < levels_.size()) {
      w.x2.setSize(nodes);
      w.acc.setSize(l == 0 ? 0 : nodes);  // level 0 reads assembled rows instead
      T* acc = w.acc.data();
      forEach(w.acc.size(), [&](std::size_t m) { acc[m] = T(0); });
      w.half.setSize(std::size_t(levels_[l + 1]->grid.dims.i) * std::size_t(g.dims.j) * std::size_t(g.dims.k));
    } else {
      w.t1.setSize(nodes);
      w.t2.setSize(nodes);
    }
  }
  coarseIn_.resize(levels_.back()->grid.nodeCount());
  coarseOut_.resize(levels_.back()->grid.nodeCount());
}

template <typename T>
template <typename Fn>
void MultigridPreconditioner::Hierarchy<T>::forEachHullNode(const Level& L, const Fn& fn) {
  const GridSpec& g = L.grid;
  forEachRow(g, [&](int j, int k) {
    const std::size_t row = std::size_t(j) + std::size_t(g.dims.j) * std::size_t(k);
    for (int i = L.hull[2 * row]; i < L.hull[2 * row + 1]; ++i) fn(g.index(i, j, k), i, j, k);
  });
}

template <typename T>
void MultigridPreconditioner::Hierarchy<T>::setInverseDiagonal(Level& L, std::size_t m, int i, int j, int k) {
  const double d = L.diagonal[m];
  L.invDiagonal[m] =
      (L.boundary == BoundaryKind::Open && L.grid.isBoundaryNode(i, j, k)) ? T(0) : (d > 0 ? T(1.0 / d) : T(0));
}

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

template <typename T>
template <typename CellDiagonal>
void MultigridPreconditioner::Hierarchy<T>::refreshDiagonal(Level& L, const CellDiagonal& cellDiagonal) {
  // Only the hull nodes differ from the vacuum diagonal: reset them, add the
  // element diagonals (slab by slab; cellDiagonal is called once per cell, so
  // it also refreshes the cell's other values) and invert.
  forEachHullNode(L, [&](std::size_t m, int i, int j, int k) { L.diagonal[m] = laplacianDiagonalAt(L.grid, i, j, k); });
  scatterBySlab(L, L.diagonal.data(), cellDiagonal);
  forEachHullNode(L, [&](std::size_t m, int i, int j, int k) { setInverseDiagonal(L, m, i, j, k); });
}

template <typename T>
void MultigridPreconditioner::Hierarchy<T>::refreshValues(const MagnetostaticProblem& problem) {
  const ElementBasis& basis = elementBasis();
  // Level 0: the problem's assembled rows in T, and the diagonal from their
  // centre taps (the same hull: both are made from the material cells).
  Level& F = *levels_.front();
  const HullStencil<double>& P = problem.materialStencil();
  F.stencil.assignConverted(P);
  const double* centre = P.values() + std::size_t(13) * P.size();
  forEachHullNode(F, [&](std::size_t m, int i, int j, int k) {
    F.diagonal[m] = laplacianDiagonalAt(F.grid, i, j, k) + centre[P.rowStart(j, k) + std::size_t(i - P.lo(j, k))];
    setInverseDiagonal(F, m, i, j, k);
  });
  // Coarse levels: coefficient D = mean of the children's D (the problem's
  // cell tensors under level 1), element matrices rediscretized with it.
  for (std::size_t l = 1; l < levels_.size(); ++l) {
    Level& C = *levels_[l];
    const Level& f = *levels_[l - 1];
    const double h = C.grid.dx;
    refreshDiagonal(C, [&](std::size_t s, double local[8]) {
      SymMat3d sum;
      for (const std::int32_t child : C.children[s]) {
        if (child < 0) break;
        sum += l == 1 ? problem.materialCellTensor(std::size_t(child)) : f.tensor[std::size_t(child)];
      }
      sum *= 1.0 / C.childCount[s];
      C.tensor[s] = sum;
      double E[kPacked];
      for (int e = 0; e < kPacked; ++e)
        E[e] = h * (sum.xx * basis.xx[e] + sum.yy * basis.yy[e] + sum.zz * basis.zz[e] + sum.xy * basis.xy[e] +
                    sum.xz * basis.xz[e] + sum.yz * basis.yz[e]);
      unpack(E, &C.elem[s * kFull]);
      for (int q = 0, e = 0; q < 8; e += 8 - q, ++q) local[q] += E[e];
    });
  }
}

template <typename T>
void MultigridPreconditioner::Hierarchy<T>::update(const MagnetostaticProblem& problem) {
  // The grid and the material cell set change only with setMaterial(); in a
  // Newton loop only the values do, so the structure (cell lists, slabs,
  // hulls, storage) is kept and refilled.
  if (!sameStructure(problem)) buildStructure(problem);
  refreshValues(problem);
}

template <typename T>
void MultigridPreconditioner::Hierarchy<T>::applyLevel(std::size_t level, const T* v, T* out) const {
  const Level& L = *levels_[level];
  applyQ1Laplacian(L.grid, L.boundary, v, out);
  if (level == 0) {
    L.stencil.addProduct(v, out);
  } else {
    scatterBySlab(L, out, [&](std::size_t s, T local[8]) {
      elementProduct(&L.elem[s * kFull], v + L.cellBase[s], L.offsets, local);
    });
  }
  zeroFixedNodes(L.grid, L.boundary, out);
}

template <typename T>
template <typename RowFn>
void MultigridPreconditioner::Hierarchy<T>::product(const Level& L, const T* v, const RowFn& rowFn) const {
  // y = A v row by row, handed to rowFn(j, k, first node, y) with y = 0 on
  // fixed rows, so the caller's pointwise update streams the vectors once.
  // The material part is scattered first (slab by slab: deterministic) into
  // acc, which the rows consume and clear within their hulls.
  // Level 0 reads its assembled material rows instead (no scatter, no acc).
  const bool rows = &L == levels_.front().get();
  T* acc = L.work.acc.data();
  if (!rows)
    scatterBySlab(L, acc, [&](std::size_t s, T local[8]) {
      elementProduct(&L.elem[s * kFull], v + L.cellBase[s], L.offsets, local);
    });
  const GridSpec& g = L.grid;
  const int nx = g.dims.i, ny = g.dims.j, nz = g.dims.k;
  const std::ptrdiff_t sy = nx, sz = std::ptrdiff_t(nx) * ny;
  const T h = T(g.dx), cC = h * T(8.0 / 3.0), cE = -h / T(6), cK = -h / T(12);
  const bool shield = L.boundary == BoundaryKind::Shield;
  forEachRow(g, [&](int j, int k) {
    thread_local std::vector<T> Y;
    Y.resize(std::size_t(nx));
    T* y = Y.data();
    const std::size_t row = g.index(0, j, k);
    const bool wallRow = k == 0 || k == nz - 1 || j == 0 || j == ny - 1;
    if (wallRow) {
      for (int i = 0; i < nx; ++i) y[i] = shield ? T(q1LaplacianRow(g, i, j, k, v)) : T(0);
    } else {
      y[0] = shield ? T(q1LaplacianRow(g, 0, j, k, v)) : T(0);
      y[nx - 1] = shield ? T(q1LaplacianRow(g, nx - 1, j, k, v)) : T(0);
      // As applyQ1Laplacian: per x position the 4 in-plane face neighbours A
      // and the 4 diagonal ones D in (y, z); edges(i) = A(i-1) + A(i+1) + D(i),
      // corners(i) = D(i-1) + D(i+1); face neighbours weigh 0. A and D live
      // on the stack, in chunks, so that the compiler sees they alias nothing
      // and vectorizes their loop.
      constexpr int kChunk = 256;
      T A[kChunk + 2], D[kChunk + 2];
      for (int i0 = 1; i0 < nx - 1; i0 += kChunk) {
        const int count = std::min(kChunk, nx - 1 - i0);
        const T* c = v + row + std::size_t(i0 - 1);  // A[t], D[t] belong to node i0 - 1 + t
        for (int t = 0; t < count + 2; ++t) {
          A[t] = c[t + sy] + c[t - sy] + c[t + sz] + c[t - sz];
          D[t] = c[t + sy + sz] + c[t + sy - sz] + c[t - sy + sz] + c[t - sy - sz];
        }
        T* yc = y + (i0 - 1);
        for (int t = 1; t <= count; ++t) {
          const T edges = A[t - 1] + A[t + 1] + D[t];
          const T corners = D[t - 1] + D[t + 1];
          yc[t] = cC * c[t] + cE * edges + cK * corners;
        }
      }
    }
    const std::size_t hullRow = 2 * (std::size_t(j) + std::size_t(ny) * std::size_t(k));
    const int lo = L.hull[hullRow], hi = L.hull[hullRow + 1];
    if (lo < hi) {
      // Open: the wall nodes are fixed, their rows stay 0.
      const int from = shield ? lo : std::max(lo, 1), to = shield ? hi : std::min(hi, nx - 1);
      if (rows) {
        if (shield || !wallRow) L.stencil.addRow(j, k, from, to, v + row, y);
      } else {
        T* a = acc + row;
        if (shield || !wallRow)
          for (int i = from; i < to; ++i) y[i] += a[i];
        std::fill(a + lo, a + hi, T(0));
      }
    }
    rowFn(j, k, row, static_cast<const T*>(y));
  });
}

template <typename T>
template <typename Fn>
void MultigridPreconditioner::Hierarchy<T>::forEachSegment(const Level& L, int j, int k, const Fn& fn) const {
  // Splits row (j, k) into runs that read the inverse diagonal (walls and
  // hull) and runs of free vacuum nodes where it is the constant
  // vacuumInvDiagonal: fn(from, to, true) / fn(from, to, false). Skipping
  // the array off the hulls saves a stream per pass.
  const int nx = L.grid.dims.i;
  if (j == 0 || k == 0 || j == L.grid.dims.j - 1 || k == L.grid.dims.k - 1) {
    fn(0, nx, true);
    return;
  }
  const std::size_t hullRow = 2 * (std::size_t(j) + std::size_t(L.grid.dims.j) * std::size_t(k));
  int lo = std::max(L.hull[hullRow], 1), hi = std::min(L.hull[hullRow + 1], nx - 1);
  if (lo >= hi) lo = hi = 1;
  fn(0, 1, true);
  fn(1, lo, false);
  fn(lo, hi, true);
  fn(hi, nx - 1, false);
  fn(nx - 1, nx, true);
}

template <typename T>
template <typename U>
void MultigridPreconditioner::Hierarchy<T>::sweep(const Level& L, const T* x, const T* b, U* out,
                                                  const double* dotWith, double* rowDot) const {
  // One damped-Jacobi sweep out = x + w D^-1 (b - A x), in one pass; with
  // dotWith, also each row's sum of dotWith . out into rowDot[j + ny k].
  const T w = T(settings_.jacobiWeight);
  const T wv = w * L.vacuumInvDiagonal;
  const T* dinv = L.invDiagonal.data();
  product(L, x, [&](int j, int k, std::size_t row, const T* y) {
    forEachSegment(L, j, k, [&](int from, int to, bool diagonalArray) {
      const T* xr = x + row;
      const T* br = b + row;
      U* o = out + row;
      if (diagonalArray) {
        const T* dr = dinv + row;
        for (int i = from; i < to; ++i) o[i] = U(xr[i] + w * dr[i] * (br[i] - y[i]));
      } else {
        for (int i = from; i < to; ++i) o[i] = U(xr[i] + wv * (br[i] - y[i]));
      }
    });
    if (dotWith) {
      const double* d = dotWith + row;
      const U* o = out + row;
      double sum = 0;
      for (int i = 0; i < L.grid.dims.i; ++i) sum += d[i] * double(o[i]);
      rowDot[std::size_t(j) + std::size_t(L.grid.dims.j) * std::size_t(k)] = sum;
    }
  });
}

template <typename T>
void MultigridPreconditioner::Hierarchy<T>::restrictResidual(const Level& L, const Level& C, const T* x,
                                                             const T* b) const {
  // Residual b - A x restricted along x as its rows are made (it is never
  // stored whole), then along y and z together into C's right-hand side.
  const Index3 fd = L.grid.dims, cd = C.grid.dims;
  T* half = L.work.half.data();
  product(L, x, [&](int j, int k, std::size_t row, const T* y) {
    thread_local std::vector<T> R;
    R.resize(std::size_t(fd.i));
    for (int i = 0; i < fd.i; ++i) R[std::size_t(i)] = b[row + std::size_t(i)] - y[i];
    T* dst = half + std::size_t(cd.i) * (std::size_t(j) + std::size_t(fd.j) * std::size_t(k));
    // Interior points (all three fine neighbours present) in a loop free of
    // branches, which vectorizes; the same sums as restrictPoint.
    const T* r = R.data();
    const int inner = fd.i / 2;  // c < inner <=> 2c + 1 < fd.i
    dst[0] = restrictPoint(r, 1, 0, fd.i);
    for (int c = 1; c < inner; ++c) dst[c] = r[2 * c] + T(0.5) * r[2 * c - 1] + T(0.5) * r[2 * c + 1];
    for (int c = std::max(inner, 1); c < cd.i; ++c) dst[c] = restrictPoint(r, 1, c, fd.i);
  });
  T* cb = C.work.b.data();
  const std::size_t lineY = std::size_t(cd.i), planeY = std::size_t(cd.i) * std::size_t(fd.j);
  forEachRow(C.grid, [&](int J, int K) {
    // The y-restricted lines at fine z = 2K, 2K-1, 2K+1, then their z weighting
    // (the order of the separate axis passes).
    thread_local std::vector<T> Z;
    Z.resize(3 * std::size_t(cd.i));
    const int zs[3] = {2 * K, 2 * K - 1, 2 * K + 1};
    bool valid[3];
    for (int q = 0; q < 3; ++q) {
      valid[q] = zs[q] >= 0 && zs[q] < fd.k;
      if (!valid[q]) continue;
      const T* src = half + planeY * std::size_t(zs[q]);
      T* t = Z.data() + std::size_t(q) * std::size_t(cd.i);
      for (int ci = 0; ci < cd.i; ++ci) t[ci] = restrictPoint(src + ci, lineY, J, fd.j);
    }
    T* dst = cb + C.grid.index(0, J, K);
    const T* t0 = Z.data();
    const T* t1 = t0 + cd.i;
    const T* t2 = t1 + cd.i;
    for (int ci = 0; ci < cd.i; ++ci) {
      T v = 0;
      if (valid[0]) v += t0[ci];
      if (valid[1]) v += T(0.5) * t1[ci];
      if (valid[2]) v += T(0.5) * t2[ci];
      dst[ci] = v;
    }
  });
  zeroFixedNodes(C.grid, C.boundary, cb);
}

template <typename T>
void MultigridPreconditioner::Hierarchy<T>::prolongAdd(const Level& L, const Level& C, T* x) const {
  // x += P e (e = C's solution) on the free nodes, one pass over the fine
  // grid: each fine row interpolates its coarse lines in z, y, then x.
  const Index3 fd = L.grid.dims, cd = C.grid.dims;
  const T* e = C.work.x.data();
  const bool open = L.boundary == BoundaryKind::Open;
  forEachRow(L.grid, [&](int j, int k) {
    if (open && (j == 0 || j == fd.j - 1 || k == 0 || k == fd.k - 1)) return;
    thread_local std::vector<T> Zb;
    Zb.resize(3 * std::size_t(cd.i));
    T* z0 = Zb.data();
    T* z1 = z0 + cd.i;
    T* line = z1 + cd.i;
    // Line (J, fine z = k) interpolated in z from the coarse lines.
    auto zLine = [&](int J, T* out) {
      const T* c0 = e + C.grid.index(0, J, k / 2);
      if (k % 2 == 0) {
        std::copy(c0, c0 + cd.i, out);
      } else {
        const T* c1 = e + C.grid.index(0, J, k / 2 + 1);
        for (int ci = 0; ci < cd.i; ++ci) out[ci] = T(0.5) * (c0[ci] + c1[ci]);
      }
    };
    if (j % 2 == 0) {
      zLine(j / 2, line);
    } else {
      zLine(j / 2, z0);
      zLine(j / 2 + 1, z1);
      for (int ci = 0; ci < cd.i; ++ci) line[ci] = T(0.5) * (z0[ci] + z1[ci]);
    }
    T* xr = x + L.grid.index(0, j, k);
    const int from = open ? 1 : 0, to = open ? fd.i - 1 : fd.i;
    auto single = [&](int i) {
      const int c = i / 2;
      xr[i] += (i % 2 == 0) ? line[c] : T(0.5) * (line[c] + line[c + 1]);
    };
    // Pairs (2c, 2c + 1) inside [from, to) without branches; the ends alone.
    const int first = (from + 1) / 2, last = to / 2;
    for (int i = from; i < 2 * first; ++i) single(i);
    for (int c = first; c < last; ++c) {
      xr[2 * c] += line[c];
      xr[2 * c + 1] += T(0.5) * (line[c] + line[c + 1]);
    }
    for (int i = std::max(2 * last, from); i < to; ++i) single(i);
  });
}

template <typename T>
void MultigridPreconditioner::Hierarchy<T>::solveCoarsest(std::size_t level, const double* in, double* out) const {
  // CG to a tight tolerance (a few hundred unknowns), in double; b = work.b
  // (or `in`, converted into it), x = work.x (and `out`).
  const Level& L = *levels_[level];
  Work& W = L.work;
  const std::size_t n = L.grid.nodeCount();
  const T* dinv = L.invDiagonal.data();
  T* b = W.b.data();
  struct Diagonal final : Preconditioner {
    const T* d;
    std::size_t n;
    void update(const MagnetostaticProblem&) override {}
    void apply(const double* in, double* out) const override {
      for (std::size_t m = 0; m < n; ++m) out[m] = double(d[m]) * in[m];
    }
    std::string name() const override { return "diagonal"; }
  } diag;
  diag.d = dinv;
  diag.n = n;
  std::function<void(double*)> project;
  if (L.boundary == BoundaryKind::Shield)
    project = [n](double* v) {
      double mean = 0;
      for (std::size_t m = 0; m < n; ++m) mean += v[m];
      mean /= double(n);
      for (std::size_t m = 0; m < n; ++m) v[m] -= mean;
    };
  if (in)
    for (std::size_t m = 0; m < n; ++m) b[m] = T(in[m]);
  for (std::size_t m = 0; m < n; ++m) coarseIn_[m] = double(b[m]);
  T* tv = W.t1.data();
  T* tout = W.t2.data();
  solvePcg(
      n,
      [&](const double* v, double* o) {
        for (std::size_t m = 0; m < n; ++m) tv[m] = T(v[m]);
        applyLevel(level, tv, tout);
        for (std::size_t m = 0; m < n; ++m) o[m] = double(tout[m]);
      },
      diag, coarseIn_.data(), coarseOut_.data(), 1e-10, 10 * int(n), project);
  T* x = W.x.data();
  for (std::size_t m = 0; m < n; ++m) x[m] = T(coarseOut_[m]);
  if (out)
    for (std::size_t m = 0; m < n; ++m) out[m] = double(x[m]);
}

// The level operations of the V-cycle (v_cycle.h). Each level's sweeps
// alternate between its x and x2; `in` and `out` (double) are level 0's
// right-hand side and result, converted in the first and the last sweep.
template <typename T>
class MultigridPreconditioner::Hierarchy<T>::CycleOps {
 public:
  CycleOps(const Hierarchy& h, const double* in, double* out) : h_(h), in_(in), out_(out) {}

  bool coarsest(int level) const { return std::size_t(level) + 1 == h_.levels_.size(); }
  void solveCoarsest(int level) const {
    h_.solveCoarsest(std::size_t(level), level == 0 ? in_ : nullptr, level == 0 ? out_ : nullptr);
  }
  void smoothFromZero(int level) {
    const Level& L = *h_.levels_[std::size_t(level)];
    Work& W = L.work;
    const T* dinv = L.invDiagonal.data();
    T* b = W.b.data();
    const double* in = level == 0 ? in_ : nullptr;
    // Start where the last sweep lands in x.
    const int sweeps = h_.settings_.preSmoothing - 1 + h_.settings_.postSmoothing;
    T* cur = cur_[level] = sweeps % 2 == 0 ? W.x.data() : W.x2.data();
    other_[level] = sweeps % 2 == 0 ? W.x2.data() : W.x.data();
    const T w = T(h_.settings_.jacobiWeight);
    const T wv = w * L.vacuumInvDiagonal;
    forEachRow(L.grid, [&](int j, int k) {
      const std::size_t row = L.grid.index(0, j, k);
      T* br = b + row;
      T* xr = cur + row;
      if (in) {
        const double* ir = in + row;
        for (int i = 0; i < L.grid.dims.i; ++i) br[i] = T(ir[i]);
      }
      h_.forEachSegment(L, j, k, [&](int from, int to, bool diagonalArray) {
        if (diagonalArray) {
          const T* dr = dinv + row;
          for (int i = from; i < to; ++i) xr[i] = w * dr[i] * br[i];
        } else {
          for (int i = from; i < to; ++i) xr[i] = wv * br[i];
        }
      });
    });
  }
  // The last sweep of level 0 writes the double result directly (with
  // applyDot's r . z summed row by row).
  void smooth(int level, bool last) {
    const Level& L = *h_.levels_[std::size_t(level)];
    const T* b = L.work.b.data();
    if (last && level == 0 && out_) {
      if (h_.dotWith_) {
        h_.rowDot_.resize(std::size_t(L.grid.dims.j) * std::size_t(L.grid.dims.k));
        h_.sweep(L, cur_[level], b, out_, h_.dotWith_, h_.rowDot_.data());
      } else {
        h_.sweep(L, cur_[level], b, out_);
      }
      return;
    }
    h_.sweep(L, cur_[level], b, other_[level]);
    std::swap(cur_[level], other_[level]);
  }
  void restrictResidual(int level) const {
    const Level& L = *h_.levels_[std::size_t(level)];
    h_.restrictResidual(L, *h_.levels_[std::size_t(level) + 1], cur_[level], L.work.b.data());
  }
  void prolongAdd(int level) const {
    h_.prolongAdd(*h_.levels_[std::size_t(level)], *h_.levels_[std::size_t(level) + 1], cur_[level]);
  }

 private:
  const Hierarchy& h_;
  const double* in_;
  double* out_;
  std::array<T*, 64> cur_{}, other_{};
};

template <typename T>
void MultigridPreconditioner::Hierarchy<T>::cycle(const double* in, double* out) const {
  CycleOps ops(*this, in, out);
  vCycle(ops, 0, settings_.preSmoothing, settings_.postSmoothing);
}

template <typename T>
void MultigridPreconditioner::Hierarchy<T>::apply(const double* r, double* z) const {
  require(!levels_.empty(), "multigrid: apply() before update()");
  cycle(r, z);
}

template <typename T>
double MultigridPreconditioner::Hierarchy<T>::applyDot(const double* r, double* z) const {
  require(!levels_.empty(), "multigrid: apply() before update()");
  if (levels_.size() == 1) {  // the coarsest-grid solve alone: no sweep to fuse into
    cycle(r, z);
    return deterministicDot(r, z, levels_.front()->grid.nodeCount());
  }
  dotWith_ = r;
  cycle(r, z);
  dotWith_ = nullptr;
  double total = 0;
  for (const double d : rowDot_) total += d;
  return total;
}

MultigridPreconditioner::MultigridPreconditioner(const MultigridSettings& settings) : settings_(settings) {
  settings_.validate();
}
MultigridPreconditioner::~MultigridPreconditioner() = default;

void MultigridPreconditioner::update(const MagnetostaticProblem& problem) {
  if (settings_.singlePrecision) {
    if (!single_) single_ = std::make_unique<Hierarchy<float>>(settings_);
    single_->update(problem);
  } else {
    if (!double_) double_ = std::make_unique<Hierarchy<double>>(settings_);
    double_->update(problem);
  }
}

void MultigridPreconditioner::apply(const double* r, double* z) const {
  if (settings_.singlePrecision) {
    require(bool(single_), "multigrid: apply() before update()");
    single_->apply(r, z);
  } else {
    require(bool(double_), "multigrid: apply() before update()");
    double_->apply(r, z);
  }
}

double MultigridPreconditioner::applyDot(std::size_t, const double* r, double* z) const {
  if (settings_.singlePrecision) {
    require(bool(single_), "multigrid: apply() before update()");
    return single_->applyDot(r, z);
  }
  require(bool(double_), "multigrid: apply() before update()");
  return double_->applyDot(r, z);
}

int MultigridPreconditioner::levelCount() const {
  if (settings_.singlePrecision) return single_ ? single_->levelCount() : 0;
  return double_ ? double_->levelCount() : 0;
}

}  // namespace field
}  // namespace lodestone
