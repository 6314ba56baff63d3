#include "lodestone/core/multigrid.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lodestone/core/coloured_scatter.h"
#include "lodestone/core/error.h"
#include "lodestone/core/magnetostatic_problem.h"
#include "lodestone/core/parallel.h"
#include "lodestone/core/q1_element.h"
#include "lodestone/core/q1_stencil.h"

namespace lodestone {

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
        double s[6] = {0, 0, 0, 0, 0, 0};
        for (int q = 0; q < 8; ++q) {
          const Vec3d& u = t.dN[q][c];
          const Vec3d& v = t.dN[q][d];
          s[0] += u.x * v.x;
          s[1] += u.y * v.y;
          s[2] += u.z * v.z;
          s[3] += u.x * v.y + u.y * v.x;
          s[4] += u.x * v.z + u.z * v.x;
          s[5] += u.y * v.z + u.z * v.y;
        }
        xx[e] = s[0] / 8;
        yy[e] = s[1] / 8;
        zz[e] = s[2] / 8;
        xy[e] = s[3] / 8;
        xz[e] = s[4] / 8;
        yz[e] = s[5] / 8;
      }
  }
};
const ElementBasis& elementBasis() {
  static const ElementBasis basis;
  return basis;
}

template <typename Fn>
void forEach(std::size_t n, const Fn& fn) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 13), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t m = r.begin(); m != r.end(); ++m) fn(m);
  });
}

// Trilinear prolongation (prolong = true) or its transpose along one axis
// between grids that differ only in that axis: fine node 2I is coarse node I,
// fine node 2I+1 the mean of coarse I and I+1.
template <typename T>
void resampleAxis(const T* src, const Index3& sd, T* dst, const Index3& dd, int axis, bool prolong) {
  const int n0 = axis == 0 ? dd.j : dd.i;  // the two other axes, same size in src and dst
  const int n1 = axis == 2 ? dd.j : dd.k;
  const std::size_t sStride = axis == 0 ? 1 : (axis == 1 ? std::size_t(sd.i) : std::size_t(sd.i) * sd.j);
  const std::size_t dStride = axis == 0 ? 1 : (axis == 1 ? std::size_t(dd.i) : std::size_t(dd.i) * dd.j);
  const int sn = sd[axis], dn = dd[axis];
  tbb::parallel_for(0, n1, [&](int b) {
    for (int a = 0; a < n0; ++a) {
      // Flat index of (a, b) in the two other axes.
      int ii = 0, jj = 0, kk = 0;
      if (axis == 0) { jj = a; kk = b; }
      else if (axis == 1) { ii = a; kk = b; }
      else { ii = a; jj = b; }
      const std::size_t sBase = std::size_t(ii) + std::size_t(sd.i) * (std::size_t(jj) + std::size_t(sd.j) * kk);
      const std::size_t dBase = std::size_t(ii) + std::size_t(dd.i) * (std::size_t(jj) + std::size_t(dd.j) * kk);
      if (prolong) {
        for (int f = 0; f < dn; ++f) {
          const int c = f / 2;
          dst[dBase + std::size_t(f) * dStride] =
              (f % 2 == 0) ? src[sBase + std::size_t(c) * sStride]
                           : T(0.5) * (src[sBase + std::size_t(c) * sStride] + src[sBase + std::size_t(c + 1) * sStride]);
        }
      } else {
        const int fn = sn;  // restriction: src is the fine axis
        for (int c = 0; c < dn; ++c) {
          T v = 0;
          if (2 * c < fn) v += src[sBase + std::size_t(2 * c) * sStride];
          if (2 * c - 1 >= 0 && 2 * c - 1 < fn) v += T(0.5) * src[sBase + std::size_t(2 * c - 1) * sStride];
          if (2 * c + 1 < fn) v += T(0.5) * src[sBase + std::size_t(2 * c + 1) * sStride];
          dst[dBase + std::size_t(c) * dStride] = v;
        }
      }
    }
  });
}


constexpr int kFull = 64;  // a full 8x8 element matrix

// Packed upper triangle -> full symmetric 8x8 (column-major) in T.
template <typename T>
void unpack(const double* packed, T* full) {
  for (int c = 0, e = 0; c < 8; ++c)
    for (int d = c; d < 8; ++d, ++e) full[8 * d + c] = full[8 * c + d] = T(packed[e]);
}

}  // namespace

template <typename T>
class MultigridPreconditioner::Hierarchy {
 public:
  explicit Hierarchy(const MultigridSettings& settings) : settings_(settings) {}
  void update(const MagnetostaticProblem& problem);
  void apply(const double* r, double* z) const;
  int levelCount() const { return int(levels_.size()); }

 private:
  struct Work {
    std::vector<T> x, b, r, t1, t2;
  };
  struct Level {
    GridSpec grid;
    BoundaryKind boundary = BoundaryKind::Open;
    // Correction cells (coefficient I + D with D != 0), grouped by colour.
    std::vector<std::size_t> cellBase;
    std::size_t colourStart[9] = {};
    std::size_t offsets[8] = {};
    std::vector<SymMat3d> tensor;         // D of each correction cell (to build the next level)
    std::vector<T> elem;                  // element matrices, full 8x8 (column-major) per cell
    std::vector<std::int32_t> slotOfCell; // per grid cell: correction slot or -1
    std::vector<T> invDiagonal;           // 0 on fixed rows
    Work* work = nullptr;
  };
  void cycle(std::size_t level, const T* b, T* x) const;
  void applyLevel(std::size_t level, const T* v, T* out) const;
  void finishLevel(Level& L, const std::vector<double>& diagonal);

  MultigridSettings settings_;
  std::vector<std::unique_ptr<Level>> levels_;
  mutable std::vector<Work> workspace_;
  mutable std::vector<double> coarseIn_, coarseOut_;  // double copies for the coarsest CG
};

template <typename T>
void MultigridPreconditioner::Hierarchy<T>::finishLevel(Level& L, const std::vector<double>& diagonal) {
  const std::size_t nodes = L.grid.nodeCount();
  L.invDiagonal.assign(nodes, T(0));
  forEach(nodes, [&](std::size_t m) { L.invDiagonal[m] = diagonal[m] > 0 ? T(1.0 / diagonal[m]) : T(0); });
  zeroFixedNodes(L.grid, L.boundary, L.invDiagonal.data());
}

template <typename T>
void MultigridPreconditioner::Hierarchy<T>::update(const MagnetostaticProblem& problem) {
  levels_.clear();
  const ElementBasis& basis = elementBasis();

  // Level 0: the fine problem (a copy of its element matrices in T); its cell
  // tensors seed the coarse coefficients.
  auto fine = std::make_unique<Level>();
  fine->grid = problem.grid();
  fine->boundary = problem.boundary();
  const std::size_t materialCells = problem.materialCellCount();
  std::copy(problem.materialColourStart(), problem.materialColourStart() + 9, fine->colourStart);
  cornerOffsets(fine->grid, fine->offsets);
  fine->cellBase.resize(materialCells);
  fine->elem.resize(materialCells * kFull);
  fine->tensor.resize(materialCells);
  fine->slotOfCell.assign(fine->grid.cellCount(), -1);
  {
    const Index3 cd = fine->grid.cellDims();
    const std::size_t nx = std::size_t(fine->grid.dims.i), ny = std::size_t(fine->grid.dims.j);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, materialCells, 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t s = r.begin(); s != r.end(); ++s) {
                          const std::size_t b = problem.materialCellBase(s);
                          fine->cellBase[s] = b;
                          const int i = int(b % nx), j = int((b / nx) % ny), k = int(b / (nx * ny));
                          fine->slotOfCell[std::size_t(i) + std::size_t(cd.i) * (std::size_t(j) + std::size_t(cd.j) * k)] =
                              std::int32_t(s);
                          fine->tensor[s] = problem.materialCellTensor(s);
                          unpack(problem.materialElementMatrix(s), &fine->elem[s * kFull]);
                        }
                      });
  }
  {
    std::vector<double> diagonal(fine->grid.nodeCount());
    problem.jacobianDiagonal(diagonal.data());
    finishLevel(*fine, diagonal);
  }
  levels_.push_back(std::move(fine));

  for (;;) {
    Level& f = *levels_.back();
    const Index3 fd = f.grid.dims;
    if (std::min({fd.i, fd.j, fd.k}) <= settings_.coarsestNodes) break;
    auto c = std::make_unique<Level>();
    c->boundary = f.boundary;
    c->grid.origin = f.grid.origin;
    c->grid.dx = 2 * f.grid.dx;
    c->grid.dims = {(fd.i - 1 + 1) / 2 + 1, (fd.j - 1 + 1) / 2 + 1, (fd.k - 1 + 1) / 2 + 1};
    const Index3 fcd = f.grid.cellDims(), ccd = c->grid.cellDims();
    // Coarse coefficient: mean of the existing children's D.
    std::vector<std::vector<std::size_t>> slabBase(std::size_t(ccd.k) * 8);
    std::vector<std::vector<SymMat3d>> slabTensor(std::size_t(ccd.k) * 8);
    tbb::parallel_for(0, ccd.k, [&](int K) {
      for (int J = 0; J < ccd.j; ++J)
        for (int I = 0; I < ccd.i; ++I) {
          SymMat3d sum;
          int children = 0;
          bool any = false;
          for (int d = 0; d < 2; ++d)
            for (int b = 0; b < 2; ++b)
              for (int a = 0; a < 2; ++a) {
                const int i = 2 * I + a, j = 2 * J + b, k = 2 * K + d;
                if (i >= fcd.i || j >= fcd.j || k >= fcd.k) continue;
                ++children;
                const std::int32_t s =
                    f.slotOfCell[std::size_t(i) + std::size_t(fcd.i) * (std::size_t(j) + std::size_t(fcd.j) * k)];
                if (s >= 0) {
                  sum += f.tensor[std::size_t(s)];
                  any = true;
                }
              }
          if (!any) continue;
          sum *= 1.0 / children;
          const std::size_t slab = std::size_t(K) * 8 + std::size_t(cellColour(I, J, K));
          slabBase[slab].push_back(c->grid.index(I, J, K));
          slabTensor[slab].push_back(sum);
        }
    });
    for (int colour = 0; colour < 8; ++colour) {
      c->colourStart[colour] = c->cellBase.size();
      for (int K = 0; K < ccd.k; ++K) {
        const std::size_t slab = std::size_t(K) * 8 + std::size_t(colour);
        c->cellBase.insert(c->cellBase.end(), slabBase[slab].begin(), slabBase[slab].end());
        c->tensor.insert(c->tensor.end(), slabTensor[slab].begin(), slabTensor[slab].end());
      }
    }
    c->colourStart[8] = c->cellBase.size();
    cornerOffsets(c->grid, c->offsets);
    c->slotOfCell.assign(c->grid.cellCount(), -1);
    c->elem.assign(c->cellBase.size() * kFull, T(0));
    std::vector<double> elemD(c->cellBase.size() * kPacked);
    const double h = c->grid.dx;
    const std::size_t cnx = std::size_t(c->grid.dims.i), cny = std::size_t(c->grid.dims.j);
    tbb::parallel_for(std::size_t(0), c->cellBase.size(), [&](std::size_t s) {
      const std::size_t b = c->cellBase[s];
      const int i = int(b % cnx), j = int((b / cnx) % cny), k = int(b / (cnx * cny));
      c->slotOfCell[std::size_t(i) + std::size_t(ccd.i) * (std::size_t(j) + std::size_t(ccd.j) * k)] =
          std::int32_t(s);
      const SymMat3d& D = c->tensor[s];
      for (int e = 0; e < kPacked; ++e)
        elemD[s * kPacked + std::size_t(e)] = h * (D.xx * basis.xx[e] + D.yy * basis.yy[e] + D.zz * basis.zz[e] +
                                                   D.xy * basis.xy[e] + D.xz * basis.xz[e] + D.yz * basis.yz[e]);
      unpack(&elemD[s * kPacked], &c->elem[s * kFull]);
    });
    // Diagonal (in double, then inverted into T).
    std::vector<double> diagonal(c->grid.nodeCount());
    q1LaplacianDiagonalAll(c->grid, diagonal.data());
    scatterByColour(c->cellBase.data(), c->colourStart, c->offsets, diagonal.data(),
                    [&](std::size_t s, double local[8]) {
                      const double* E = &elemD[s * kPacked];
                      for (int q = 0, e = 0; q < 8; e += 8 - q, ++q) local[q] += E[e];
                    });
    finishLevel(*c, diagonal);
    // The finer level's tensors and map were only needed to build this one.
    f.tensor.clear();
    f.tensor.shrink_to_fit();
    f.slotOfCell.clear();
    f.slotOfCell.shrink_to_fit();
    levels_.push_back(std::move(c));
  }
  // Work vectors persist across updates on the same grid (no page faults
  // in the Newton loop).
  if (workspace_.size() != levels_.size()) workspace_.assign(levels_.size(), {});
  for (std::size_t l = 0; l < levels_.size(); ++l) {
    const std::size_t nodes = levels_[l]->grid.nodeCount();
    auto& w = workspace_[l];
    for (auto* v : {&w.x, &w.b, &w.r, &w.t1, &w.t2}) v->resize(nodes);
    levels_[l]->work = &w;
  }
  coarseIn_.resize(levels_.back()->grid.nodeCount());
  coarseOut_.resize(levels_.back()->grid.nodeCount());
}

template <typename T>
void MultigridPreconditioner::Hierarchy<T>::applyLevel(std::size_t level, const T* v, T* out) const {
  const Level& L = *levels_[level];
  applyQ1Laplacian(L.grid, L.boundary, v, out);
  scatterByColour(L.cellBase.data(), L.colourStart, L.offsets, out, [&](std::size_t s, T local[8]) {
    // Dense 8x8 times 8: column by column, which vectorizes.
    const T* E = &L.elem[s * kFull];
    for (int d = 0; d < 8; ++d) {
      const T vd = v[L.cellBase[s] + L.offsets[d]];
      for (int c = 0; c < 8; ++c) local[c] += E[8 * d + c] * vd;
    }
  });
  zeroFixedNodes(L.grid, L.boundary, out);
}

template <typename T>
void MultigridPreconditioner::Hierarchy<T>::cycle(std::size_t level, const T* b, T* x) const {
  const Level& L = *levels_[level];
  const std::size_t n = L.grid.nodeCount();
  const T* dinv = L.invDiagonal.data();
  T* r = L.work->r.data();
  if (level + 1 == levels_.size()) {
    // Coarsest grid: CG to a tight tolerance (a few hundred unknowns), in double.
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
    for (std::size_t m = 0; m < n; ++m) coarseIn_[m] = double(b[m]);
    T* tv = L.work->t1.data();
    T* tout = L.work->t2.data();
    solvePcg(
        n,
        [&](const double* v, double* out) {
          for (std::size_t m = 0; m < n; ++m) tv[m] = T(v[m]);
          applyLevel(level, tv, tout);
          for (std::size_t m = 0; m < n; ++m) out[m] = double(tout[m]);
        },
        diag, coarseIn_.data(), coarseOut_.data(), 1e-10, 10 * int(n), project);
    for (std::size_t m = 0; m < n; ++m) x[m] = T(coarseOut_[m]);
    return;
  }
  const T w = T(settings_.jacobiWeight);
  // Pre-smoothing from x = 0.
  forEach(n, [&](std::size_t m) { x[m] = w * dinv[m] * b[m]; });
  for (int s = 1; s < settings_.preSmoothing; ++s) {
    applyLevel(level, x, r);
    forEach(n, [&](std::size_t m) { x[m] += w * dinv[m] * (b[m] - r[m]); });
  }
  // Coarse correction.
  applyLevel(level, x, r);
  forEach(n, [&](std::size_t m) { r[m] = b[m] - r[m]; });
  const Level& C = *levels_[level + 1];
  const Index3 fd = L.grid.dims, cd = C.grid.dims;
  const Index3 s1{cd.i, fd.j, fd.k}, s2{cd.i, cd.j, fd.k};
  std::vector<T>& a = L.work->t1;  // sized for the fine grid, large enough for partial shapes
  std::vector<T>& bb = L.work->t2;
  resampleAxis(r, fd, a.data(), s1, 0, false);
  resampleAxis(a.data(), s1, bb.data(), s2, 1, false);
  resampleAxis(bb.data(), s2, C.work->b.data(), cd, 2, false);
  zeroFixedNodes(C.grid, C.boundary, C.work->b.data());
  cycle(level + 1, C.work->b.data(), C.work->x.data());
  resampleAxis(C.work->x.data(), cd, bb.data(), s2, 2, true);
  resampleAxis(bb.data(), s2, a.data(), s1, 1, true);
  resampleAxis(a.data(), s1, r, fd, 0, true);
  zeroFixedNodes(L.grid, L.boundary, r);
  forEach(n, [&](std::size_t m) { x[m] += r[m]; });
  // Post-smoothing.
  for (int s = 0; s < settings_.postSmoothing; ++s) {
    applyLevel(level, x, r);
    forEach(n, [&](std::size_t m) { x[m] += w * dinv[m] * (b[m] - r[m]); });
  }
}

template <typename T>
void MultigridPreconditioner::Hierarchy<T>::apply(const double* r, double* z) const {
  require(!levels_.empty(), "multigrid: apply() before update()");
  const std::size_t n = levels_.front()->grid.nodeCount();
  T* b = levels_.front()->work->b.data();
  T* x = levels_.front()->work->x.data();
  forEach(n, [&](std::size_t m) { b[m] = T(r[m]); });
  cycle(0, b, x);
  forEach(n, [&](std::size_t m) { z[m] = double(x[m]); });
}

void MultigridSettings::validate() const {
  require(preSmoothing >= 1 && preSmoothing <= 20, "multigrid: preSmoothing must be 1..20, got ", preSmoothing);
  require(postSmoothing == preSmoothing, "multigrid: postSmoothing must equal preSmoothing (",
          preSmoothing, ") to keep the cycle symmetric, got ", postSmoothing);
  require(std::isfinite(jacobiWeight) && jacobiWeight > 0 && jacobiWeight <= 1,
          "multigrid: jacobiWeight must be in (0, 1], got ", jacobiWeight);
  require(coarsestNodes >= 3, "multigrid: coarsestNodes must be >= 3, got ", coarsestNodes);
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

int MultigridPreconditioner::levelCount() const {
  if (settings_.singlePrecision) return single_ ? single_->levelCount() : 0;
  return double_ ? double_->levelCount() : 0;
}

}  // namespace lodestone
