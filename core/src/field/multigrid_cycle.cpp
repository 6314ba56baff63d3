// The multigrid's V-cycle (v_cycle.h) on the levels multigrid_levels.cpp
// builds: level products, damped-Jacobi sweeps, full-weighting restriction,
// trilinear prolongation and the coarsest level's CG.
#include "multigrid_hierarchy.h"

#include "lodestone/core/field/v_cycle.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <string>

#include "lodestone/core/base/error.h"
#include "lodestone/core/base/parallel.h"
#include "lodestone/core/field/pcg.h"
#include "lodestone/core/field/q1_stencil.h"

namespace lodestone {
inline namespace field {

using namespace multigrid_detail;

namespace {

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

}  // namespace

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

template class MultigridPreconditioner::Hierarchy<float>;
template class MultigridPreconditioner::Hierarchy<double>;

}  // namespace field
}  // namespace lodestone
