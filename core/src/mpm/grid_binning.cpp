// The MPM grid's binning: particles sorted by the base node of their
// stencil, each row of bins' extent, the offsets of the rows' bins and the
// node runs they reach (mpm/grid.h).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_scan.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <functional>
#include <limits>

#include "lodestone/core/base/bspline.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/grid.h"
#include "grid_kernels.h"

namespace lodestone {
inline namespace mpm {

namespace {

constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
constexpr std::uint64_t kBadBase = std::numeric_limits<std::uint64_t>::max();

void atomicMin(std::atomic<std::size_t>& a, std::size_t v) {
  std::size_t cur = a.load(std::memory_order_relaxed);
  while (v < cur && !a.compare_exchange_weak(cur, v, std::memory_order_relaxed)) {
  }
}

void atomicMax(std::atomic<std::uint32_t>& a, std::uint32_t v) {
  std::uint32_t cur = a.load(std::memory_order_relaxed);
  while (v > cur && !a.compare_exchange_weak(cur, v, std::memory_order_relaxed)) {
  }
}

/// Box of base nodes touched: [lo, hi] inclusive, as a reduction value.
struct BaseBox {
  int lo[3] = {std::numeric_limits<int>::max(), std::numeric_limits<int>::max(), std::numeric_limits<int>::max()};
  int hi[3] = {-1, -1, -1};
  void add(int i, int j, int k) {
    lo[0] = std::min(lo[0], i);
    lo[1] = std::min(lo[1], j);
    lo[2] = std::min(lo[2], k);
    hi[0] = std::max(hi[0], i);
    hi[1] = std::max(hi[1], j);
    hi[2] = std::max(hi[2], k);
  }
  void join(const BaseBox& o) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], o.lo[a]);
      hi[a] = std::max(hi[a], o.hi[a]);
    }
  }
};

/// What pass 1 of the binning reads and writes (MpmGrid::bin sets it up).
struct BinKernel {
  const Vec3d* X = nullptr;
  const std::uint32_t* mat = nullptr;
  std::size_t materialCount = 0;
  Vec3d o;              // grid origin, m
  double invDx = 0;     // 1/m
  Index3 bd;            // stencil bases per axis
  MpmGridLayout bins;   // the layout's bins (MpmGridLayout::binLayout)
  std::uint64_t* key = nullptr;
  std::uint32_t* rank = nullptr;
  std::atomic<std::uint32_t>* binSize = nullptr;
  std::atomic<std::uint32_t>*rowLow = nullptr, *rowHigh = nullptr;  // per row of bins: bd.i - first, end
  std::atomic<std::size_t>* firstBad = nullptr;
  std::atomic<bool>* outside = nullptr;  // set when a bin lies outside the layout's

  // Bases, bin slots, each row's extent of bins and the box of bases of
  // particles [begin, end). Inlined into each instruction-set variant
  // (runKernel).
  __attribute__((always_inline)) inline void operator()(std::size_t begin, std::size_t end, BaseBox& acc) const {
    std::size_t runFlat = 0, runStart = 0, runLength = 0;
    int runBase[3] = {0, 0, 0};
    std::size_t extentRow = kNone;
    std::uint32_t extentLo = 0, extentHi = 0;  // bins [extentLo, extentHi) of row extentRow
    auto endExtent = [&] {
      if (extentRow == kNone) return;
      atomicMax(rowLow[extentRow], std::uint32_t(bd.i) - extentLo);
      atomicMax(rowHigh[extentRow], extentHi);
      extentRow = kNone;
    };
    auto endRun = [&] {
      if (runLength == 0) return;
      // A bin outside the layout's takes no slots: the binning lays the grid
      // out anew and runs this pass again. The rows' extents are the
      // particles' own, kept.
      const int b0 = runBase[0], b1 = runBase[1], b2 = runBase[2];
      if (b0 >= bins.lo.i && b1 >= bins.lo.j && b2 >= bins.lo.k && b0 < bins.lo.i + bins.dims.i &&
          b1 < bins.lo.j + bins.dims.j && b2 < bins.lo.k + bins.dims.k) {
        const std::uint32_t first =
            binSize[bins.index(b0, b1, b2)].fetch_add(std::uint32_t(runLength), std::memory_order_relaxed);
        for (std::size_t q = 0; q < runLength; ++q) rank[runStart + q] = first + std::uint32_t(q);
      } else {
        outside->store(true, std::memory_order_relaxed);
      }
      const std::size_t row = runFlat / std::size_t(bd.i);
      const std::uint32_t bi = std::uint32_t(b0);
      if (row != extentRow) {
        endExtent();
        extentRow = row;
        extentLo = bi;
        extentHi = bi + 1;
      } else {
        extentLo = std::min(extentLo, bi);
        extentHi = std::max(extentHi, bi + 1);
      }
      runLength = 0;
    };
    for (std::size_t p = begin; p != end; ++p) {
      const Vec3d u{(X[p].x - o.x) * invDx, (X[p].y - o.y) * invDx, (X[p].z - o.z) * invDx};
      const double fx = quadraticBaseFloor(u.x), fy = quadraticBaseFloor(u.y), fz = quadraticBaseFloor(u.z);
      // The comparisons are false for NaN, so non-finite positions land here too.
      if (!(fx >= 0 && fx <= bd.i - 1 && fy >= 0 && fy <= bd.j - 1 && fz >= 0 && fz <= bd.k - 1) ||
          mat[p] >= materialCount) {
        endRun();
        key[p] = kBadBase;
        atomicMin(*firstBad, p);
        continue;
      }
      const int bi = int(fx), bj = int(fy), bk = int(fz);
      key[p] = std::uint64_t(bi) | (std::uint64_t(bj) << 21) | (std::uint64_t(bk) << 42);
      const std::size_t flat =
          std::size_t(bi) + std::size_t(bd.i) * (std::size_t(bj) + std::size_t(bd.j) * std::size_t(bk));
      if (runLength != 0 && flat != runFlat) endRun();
      if (runLength == 0) {
        runFlat = flat;
        runStart = p;
        runBase[0] = bi;
        runBase[1] = bj;
        runBase[2] = bk;
      }
      ++runLength;
      acc.add(bi, bj, bk);
    }
    endRun();
    endExtent();
  }
};

}  // namespace

void mpmNodeRuns(const std::uint32_t* rowFirst, const std::uint32_t* rowEnd, int nbj, int nbk, std::int32_t* runFirst,
                 std::int32_t* runEnd) {
  const int nj = nbj + 2, nk = nbk + 2;
  const std::size_t nodeRows = std::size_t(nj) * std::size_t(nk);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nodeRows, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t q = r.begin(); q != r.end(); ++q) {
      const int jj = int(q % std::size_t(nj)), kk = int(q / std::size_t(nj));
      int lo = std::numeric_limits<int>::max(), hi = std::numeric_limits<int>::min();
      for (int dk = 0; dk < 3; ++dk)
        for (int dj = 0; dj < 3; ++dj) {
          const int bj = jj - dj, bk = kk - dk;
          if (bj < 0 || bj >= nbj || bk < 0 || bk >= nbk) continue;
          const std::size_t row = std::size_t(bj) + std::size_t(nbj) * std::size_t(bk);
          if (rowEnd[row] <= rowFirst[row]) continue;
          lo = std::min(lo, int(rowFirst[row]));
          hi = std::max(hi, int(rowEnd[row]) + 2);
        }
      runFirst[q] = lo < hi ? lo : 0;
      runEnd[q] = lo < hi ? hi : 0;
    }
  });
}

bool MpmGrid::binPass1(const MpmParticles& particles, std::size_t materialCount, Index3& boxLo, Index3& boxHi) {
  const std::size_t np = particles.size();
  const Vec3d* X = particles.x.data();
  const std::uint32_t* mat = particles.material.data();
  std::atomic<std::size_t> firstBad{kNone};
  std::atomic<bool> outside{false};

  // Pass 1: base node of every particle (packed 21 bits per axis), a
  // scheduling-dependent slot in its bin, and the box of bases in use
  // (min/max are exact, so the reduction is deterministic). A run of
  // consecutive particles in one bin (the usual case once the particles are
  // ordered by cell) takes its slots with one atomic addition.
  BinKernel kernel;
  kernel.X = X;
  kernel.mat = mat;
  kernel.materialCount = materialCount;
  kernel.o = spec_.origin;
  kernel.invDx = 1.0 / spec_.dx;
  kernel.bd = baseDims_;
  kernel.bins = layout_.binLayout();
  kernel.key = key_.data();
  kernel.rank = rank_.data();
  kernel.binSize = binSizes();
  kernel.rowLow = reinterpret_cast<std::atomic<std::uint32_t>*>(rowLow_.data());
  kernel.rowHigh = reinterpret_cast<std::atomic<std::uint32_t>*>(rowHigh_.data());
  kernel.firstBad = &firstBad;
  kernel.outside = &outside;
  const BaseBox box = reduceKernel<BaseBox>(kernel, np, 2048);

  if (const std::size_t bad = firstBad.load(); bad != kNone) {
    // Restore the invariants before throwing: bin sizes and row extents
    // zero, and every node zero (no runs), in no layout.
    binSize_.clear();
    rowLow_.clear();
    rowHigh_.clear();
    nodes_.clear();
    velocity_.clear();
    colour_.clear();
    key_.clear();
    prevRunFirst_.clear();
    prevRunEnd_.clear();
    runFirst_.clear();
    runEnd_.clear();
    rowOrigin_.clear();
    packedCount_ = 0;
    activeLo_ = activeHi_ = binLo_ = binDims_ = {0, 0, 0};
    if (!wholeLayout_) layout_ = MpmGridLayout{};
    const Vec3d x = X[bad];
    const Vec3d o = spec_.origin;
    if (mat[bad] >= materialCount)
      throw InvalidArgument(concat("MPM particle ", bad, ": material index ", mat[bad], " is out of range (",
                                   materialCount, " materials)"));
    if (!isFinite(x))
      throw InvalidArgument(
          concat("MPM particle ", bad, ": position must be finite, got (", x.x, ", ", x.y, ", ", x.z, ") m"));
    const Vec3d hi = spec_.maxCorner();
    throw InvalidArgument(concat("MPM particle ", bad, " at (", x.x, ", ", x.y, ", ", x.z,
                                 ") m is outside the MPM grid: its quadratic stencil needs (x - origin)/dx in "
                                 "[1/2, dims - 3/2) per axis; the grid spans (",
                                 o.x, ", ", o.y, ", ", o.z, ") to (", hi.x, ", ", hi.y, ", ", hi.z,
                                 ") m with dx = ", spec_.dx, " m"));
  }
  boxLo = {box.lo[0], box.lo[1], box.lo[2]};
  boxHi = {box.hi[0], box.hi[1], box.hi[2]};
  return !outside.load();
}

void MpmGrid::bin(const MpmParticles& particles, std::size_t materialCount) {
  const std::size_t np = particles.size();
  require(np < std::size_t(kBadKey), "MPM grid: at most 2^32 - 2 particles are supported, got ", np);
  // Invariant: every bin size is zero between calls (pass 2 resets the
  // ones it used), so only the bins of the active box are ever touched.
  std::atomic<std::uint32_t>* binSize = binSizes();
  std::atomic<std::uint32_t>* rowLow = reinterpret_cast<std::atomic<std::uint32_t>*>(rowLow_.data());
  std::atomic<std::uint32_t>* rowHigh = reinterpret_cast<std::atomic<std::uint32_t>*>(rowHigh_.data());
  key_.resize(np);
  rank_.resize(np);
  // The runs of the previous P2G, which particleToGrid hands back where the new ones do not reach.
  prevRunFirst_.swap(runFirst_);
  prevRunEnd_.swap(runEnd_);
  runFirst_.clear();
  runEnd_.clear();
  const Index3 bd = baseDims_;

  // Pass 1 in the current layout. Where some bin lies outside it, or the
  // layout has grown eight times the one the material needs, the grid takes
  // the material's layout (mpmGridLayout), the slots taken are given back
  // and pass 1 runs again.
  Index3 boxLo, boxHi;
  const bool fits = binPass1(particles, materialCount, boxLo, boxHi);
  if (np > 0 && !wholeLayout_) {
    const MpmGridLayout wanted = mpmGridLayout(spec_, boxLo, boxHi);
    const MpmGridLayout reach = mpmGridReach(spec_, boxLo, boxHi);
    const Index3 reachHi{reach.lo.i + reach.dims.i, reach.lo.j + reach.dims.j, reach.lo.k + reach.dims.k};
    if (!fits || !layout_.holds(reach.lo, reachHi) || layout_.count() > 8 * wanted.count()) {
      if (!layout_.empty()) {
        // Give back the slots pass 1 took (bins of the layout within the box).
        const MpmGridLayout had = layout_.binLayout();
        const Index3 lo{std::max(boxLo.i, had.lo.i), std::max(boxLo.j, had.lo.j), std::max(boxLo.k, had.lo.k)};
        const Index3 hi{std::min(boxHi.i + 1, had.lo.i + had.dims.i), std::min(boxHi.j + 1, had.lo.j + had.dims.j),
                        std::min(boxHi.k + 1, had.lo.k + had.dims.k)};
        if (lo.i < hi.i && lo.j < hi.j && lo.k < hi.k) {
          const int nj = hi.j - lo.j;
          tbb::parallel_for(tbb::blocked_range<int>(0, nj * (hi.k - lo.k), 16), [&](const tbb::blocked_range<int>& r) {
            for (int row = r.begin(); row != r.end(); ++row) {
              std::atomic<std::uint32_t>* sizes = binSize + had.index(lo.i, lo.j + row % nj, lo.k + row / nj);
              for (int i = 0; i < hi.i - lo.i; ++i)
                if (sizes[i].load(std::memory_order_relaxed) != 0) sizes[i].store(0, std::memory_order_relaxed);
            }
          });
        }
      }
      layout_ = wanted;
      const bool again = binPass1(particles, materialCount, boxLo, boxHi);
      require(again, "MPM grid: a particle's bin lies outside the layout taken for it");  // never: the same bases
    }
  }

  if (np == 0) {
    activeLo_ = activeHi_ = binLo_ = binDims_ = {0, 0, 0};
    offsets_.assign(1, 0);
    sorted_.clear();
    return;
  }
  binLo_ = boxLo;
  binDims_ = {boxHi.i - boxLo.i + 1, boxHi.j - boxLo.j + 1, boxHi.k - boxLo.k + 1};
  activeLo_ = binLo_;
  activeHi_ = {boxHi.i + 3, boxHi.j + 3, boxHi.k + 3};
  const MpmGridLayout bins = layout_.binLayout();

  // Each row's extent of bins (pass 1's atomics, reset here: zero between
  // calls) and the first offset slot of its bins.
  const std::size_t rows = std::size_t(binDims_.j) * std::size_t(binDims_.k);
  rowFirst_.resize(rows);
  rowEnd_.resize(rows);
  rowStart_.resize(rows + 1);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t row = r.begin(); row != r.end(); ++row) {
      const std::size_t bj = std::size_t(binLo_.j) + row % std::size_t(binDims_.j);
      const std::size_t bk = std::size_t(binLo_.k) + row / std::size_t(binDims_.j);
      const std::size_t at = bj + std::size_t(bd.j) * bk;
      const std::uint32_t low = rowLow[at].load(std::memory_order_relaxed), high = rowHigh[at].load(std::memory_order_relaxed);
      rowFirst_[row] = high > 0 ? std::uint32_t(bd.i) - low : 0;
      rowEnd_[row] = high;
      if (high > 0) {
        rowLow[at].store(0, std::memory_order_relaxed);
        rowHigh[at].store(0, std::memory_order_relaxed);
      }
    }
  });
  std::size_t slots = 0;
  for (std::size_t row = 0; row < rows; ++row) {
    rowStart_[row] = slots;
    slots += rowEnd_[row] - rowFirst_[row];
  }
  rowStart_[rows] = slots;

  // Pass 2: offsets of the rows' bins, x-rows in order (integer prefix
  // sums: order-free); the final pass also resets the sizes it read.
  offsets_.resize(slots + 1);
  tbb::parallel_scan(
      tbb::blocked_range<std::size_t>(0, rows, 64), std::uint32_t(0),
      [&](const tbb::blocked_range<std::size_t>& r, std::uint32_t sum, bool isFinal) {
        for (std::size_t row = r.begin(); row != r.end(); ++row) {
          if (rowEnd_[row] <= rowFirst_[row]) continue;  // an empty row: no bins (its first bin may lie before the layout)
          const std::size_t bj = std::size_t(binLo_.j) + row % std::size_t(binDims_.j);
          const std::size_t bk = std::size_t(binLo_.k) + row / std::size_t(binDims_.j);
          std::atomic<std::uint32_t>* sizes = binSize + bins.index(int(rowFirst_[row]), int(bj), int(bk));
          std::uint32_t* off = offsets_.data() + rowStart_[row];
          for (std::size_t i = 0; i < rowEnd_[row] - rowFirst_[row]; ++i) {
            const std::uint32_t n = sizes[i].load(std::memory_order_relaxed);
            if (isFinal) {
              off[i] = sum;
              if (n != 0) sizes[i].store(0, std::memory_order_relaxed);  // empty bins' pages stay unwritten
            }
            sum += n;
          }
        }
        return sum;
      },
      std::plus<std::uint32_t>());
  offsets_[slots] = std::uint32_t(np);

  // The node runs of the active box's rows.
  runFirst_.assign(std::size_t(binDims_.j + 2) * std::size_t(binDims_.k + 2), 0);
  runEnd_.assign(runFirst_.size(), 0);
  mpmNodeRuns(rowFirst_.data(), rowEnd_.data(), binDims_.j, binDims_.k, runFirst_.data(), runEnd_.data());

  // Pass 3: scatter indices into their bins.
  sorted_.resize(np);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, np, 8192), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p) sorted_[offsets_[binIndex(key_[p])] + rank_[p]] = std::uint32_t(p);
  });

  // Pass 4: ascending particle index within each bin (bins are small:
  // insertion sort; std::sort for crowded ones).
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, slots, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b != r.end(); ++b) {
      std::uint32_t* first = sorted_.data() + offsets_[b];
      std::uint32_t* last = sorted_.data() + offsets_[b + 1];
      if (last - first < 2) continue;
      if (last - first > 32) {
        std::sort(first, last);
        continue;
      }
      for (std::uint32_t* i = first + 1; i != last; ++i) {
        const std::uint32_t v = *i;
        std::uint32_t* j = i;
        while (j != first && *(j - 1) > v) {
          *j = *(j - 1);
          --j;
        }
        *j = v;
      }
    }
  });
}

}  // namespace mpm
}  // namespace lodestone
