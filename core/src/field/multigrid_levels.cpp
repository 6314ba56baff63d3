// The multigrid's levels: their structure (cell lists, hulls, storage) built
// from the problem's material cells, and their values (the assembled rows on
// level 0, the rediscretized element matrices and the diagonals) refreshed.
#include "multigrid_hierarchy.h"

#include <algorithm>
#include <array>
#include <cstdint>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lodestone/core/base/coloured_scatter.h"  // cornerOffsets
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/parallel.h"
#include "lodestone/core/field/q1_element.h"
#include "lodestone/core/field/q1_stencil.h"

namespace lodestone {
inline namespace field {

using namespace multigrid_detail;

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

}  // namespace

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
  forEachHullNode(F, [&](std::size_t m, int i, int j, int k) {
    F.diagonal[m] = laplacianDiagonalAt(F.grid, i, j, k) + P.value(i, j, k, 13);
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

template void MultigridPreconditioner::Hierarchy<float>::update(const MagnetostaticProblem&);
template void MultigridPreconditioner::Hierarchy<double>::update(const MagnetostaticProblem&);

}  // namespace field
}  // namespace lodestone
