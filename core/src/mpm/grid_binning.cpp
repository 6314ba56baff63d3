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
#include <stdexcept>

#include "lodestone/core/base/bspline.h"
#include "lodestone/core/base/cpu_features.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/grid.h"
#include "grid_kernels.h"

#if defined(LODESTONE_X86_AVX2)
#include <immintrin.h>
#endif

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

/// run(first, end) on each run [first, end) of consecutive particles with
/// one key, in parallel chunks: once the particles are ordered by cell,
/// most runs are a bin's particles, and each takes one atomic operation.
/// The chunks (hence the runs) depend only on np, not on the threads or the
/// schedule (simple_partitioner: halved down to the grain), so two calls
/// over the same keys see the same runs.
template <typename Run>
void forEachKeyRun(const std::uint64_t* key, std::size_t np, const Run& run) {
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, np, 4096),
      [&](const tbb::blocked_range<std::size_t>& r) {
        std::size_t start = r.begin();
        for (std::size_t p = r.begin() + 1; p < r.end(); ++p)
          if (key[p] != key[start]) {
            run(start, p);
            start = p;
          }
        if (start < r.end()) run(start, r.end());
      },
      tbb::simple_partitioner());
}

/// The packed stencil base of particle (x, mat): bi | bj << 21 | bk << 42
/// with each base quadraticBaseFloor((x - o) invDx) in [0, bd - 1], or
/// kBadBase for a base out of range, a non-finite position or a material
/// index >= materialCount. BinKernel computes them kKeyBlock particles at a
/// time, then finds their runs.
constexpr std::size_t kKeyBlock = 64;

/// key[q] for q in [from, n) of particles X, mat.
void keysScalar(const Vec3d* X, const std::uint32_t* mat, std::size_t from, std::size_t n, const Vec3d& o, double invDx,
                const Index3& bd, std::size_t materialCount, std::uint64_t* key) {
  for (std::size_t q = from; q < n; ++q) {
    const double f[3] = {quadraticBaseFloor((X[q].x - o.x) * invDx), quadraticBaseFloor((X[q].y - o.y) * invDx),
                         quadraticBaseFloor((X[q].z - o.z) * invDx)};
    // The comparisons are false for NaN, so non-finite positions are not ok.
    bool ok = mat[q] < materialCount;
    for (int a = 0; a < 3; ++a) ok = ok && f[a] >= 0 && f[a] <= bd[a] - 1;
    key[q] = ok ? std::uint64_t(f[0]) | (std::uint64_t(f[1]) << 21) | (std::uint64_t(f[2]) << 42) : kBadBase;
  }
}

#if defined(LODESTONE_X86_AVX2)
/// keysScalar four particles at a time: the same operations (subtract,
/// multiply, floor, the half-cell test), so the same keys. Needs
/// materialCount <= 2^32 - 1.
__attribute__((target("avx2"))) void keysAvx2(const Vec3d* X, const std::uint32_t* mat, std::size_t n, const Vec3d& o,
                                              double invDx, const Index3& bd, std::size_t materialCount,
                                              std::uint64_t* key) {
  const std::size_t n4 = n / 4 * 4;
  const __m256d inv = _mm256_set1_pd(invDx), half = _mm256_set1_pd(0.5), one = _mm256_set1_pd(1.0);
  const __m256d zero = _mm256_setzero_pd();
  // mat < materialCount as a signed comparison of both offset by 2^31.
  const __m128i bias = _mm_set1_epi32(std::int32_t(0x80000000u));
  const __m128i limit = _mm_xor_si128(_mm_set1_epi32(std::int32_t(std::uint32_t(materialCount))), bias);
  const double origin[3] = {o.x, o.y, o.z};
  const double* x = &X[0].x;
  for (std::size_t q = 0; q < n4; q += 4) {
    const double* p = x + 3 * q;
    const __m128i m = _mm_loadu_si128(reinterpret_cast<const __m128i*>(mat + q));
    __m256i ok = _mm256_cvtepi32_epi64(_mm_cmplt_epi32(_mm_xor_si128(m, bias), limit));
    // The four positions (x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3) as one
    // vector per axis: three loads, three lane swaps, three shuffles.
    const __m256d a0 = _mm256_loadu_pd(p), a1 = _mm256_loadu_pd(p + 4), a2 = _mm256_loadu_pd(p + 8);
    const __m256d t0 = _mm256_permute2f128_pd(a0, a1, 0x30);  // x0 y0 | x2 y2
    const __m256d t1 = _mm256_permute2f128_pd(a0, a2, 0x21);  // z0 x1 | z2 x3
    const __m256d t2 = _mm256_permute2f128_pd(a1, a2, 0x30);  // y1 z1 | y3 z3
    const __m256d axis[3] = {_mm256_shuffle_pd(t0, t1, 0xA), _mm256_shuffle_pd(t0, t2, 0x5),
                             _mm256_shuffle_pd(t1, t2, 0xA)};
    __m256i packed = _mm256_setzero_si256();
    for (int a = 0; a < 3; ++a) {
      const __m256d u = _mm256_mul_pd(_mm256_sub_pd(axis[a], _mm256_set1_pd(origin[a])), inv);
      const __m256d b = _mm256_round_pd(u, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
      // quadraticBaseFloor: b - 1 where u - b < 1/2 (b - 0 is b, bit for bit).
      const __m256d f = _mm256_sub_pd(b, _mm256_and_pd(_mm256_cmp_pd(_mm256_sub_pd(u, b), half, _CMP_LT_OQ), one));
      const __m256d in = _mm256_and_pd(_mm256_cmp_pd(f, zero, _CMP_GE_OQ),
                                       _mm256_cmp_pd(f, _mm256_set1_pd(double(bd[a] - 1)), _CMP_LE_OQ));
      ok = _mm256_and_si256(ok, _mm256_castpd_si256(in));
      // Lanes out of range become 0 before the conversion.
      const __m256i base = _mm256_cvtepi32_epi64(_mm256_cvttpd_epi32(_mm256_and_pd(in, f)));
      packed = _mm256_or_si256(packed, _mm256_sll_epi64(base, _mm_cvtsi32_si128(21 * a)));
    }
    // Lanes not ok become kBadBase (all bits set).
    packed = _mm256_or_si256(packed, _mm256_andnot_si256(ok, _mm256_set1_epi64x(-1)));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(key + q), packed);
  }
  keysScalar(X, mat, n4, n, o, invDx, bd, materialCount, key);
}
#endif

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
  std::uint64_t* key = nullptr;
  std::atomic<std::uint32_t>*rowLow = nullptr, *rowHigh = nullptr;  // per row of bins: bd.i - first, end
  std::atomic<std::size_t>* firstBad = nullptr;
  bool avx2 = false;  // the keys four at a time (keysAvx2)

  // Keys, each row's extent of bins and the box of bases of particles
  // [begin, end). Inlined into each instruction-set variant (runKernel).
  __attribute__((always_inline)) inline void operator()(std::size_t begin, std::size_t end, BaseBox& acc) const {
    // The run of equal keys in progress (kBadBase: none) and its base.
    std::uint64_t runKey = kBadBase;
    int runBi = 0, runBj = 0, runBk = 0;
    std::size_t extentRow = kNone;
    std::uint32_t extentLo = 0, extentHi = 0;  // bins [extentLo, extentHi) of row extentRow
    auto endExtent = [&] {
      if (extentRow == kNone) return;
      atomicMax(rowLow[extentRow], std::uint32_t(bd.i) - extentLo);
      atomicMax(rowHigh[extentRow], extentHi);
      extentRow = kNone;
    };
    auto endRun = [&] {
      if (runKey == kBadBase) return;
      const std::size_t row = std::size_t(runBj) + std::size_t(bd.j) * std::size_t(runBk);
      const std::uint32_t bi = std::uint32_t(runBi);
      if (row != extentRow) {
        endExtent();
        extentRow = row;
        extentLo = bi;
        extentHi = bi + 1;
      } else {
        extentLo = std::min(extentLo, bi);
        extentHi = std::max(extentHi, bi + 1);
      }
      runKey = kBadBase;
    };
    for (std::size_t first = begin; first < end; first += kKeyBlock) {
      const std::size_t n = std::min(kKeyBlock, end - first);
#if defined(LODESTONE_X86_AVX2)
      if (avx2)
        keysAvx2(X + first, mat + first, n, o, invDx, bd, materialCount, key + first);
      else
#endif
        keysScalar(X + first, mat + first, 0, n, o, invDx, bd, materialCount, key + first);
      for (std::size_t p = first; p < first + n; ++p) {
        const std::uint64_t k = key[p];
        if (k == kBadBase) {
          endRun();
          atomicMin(*firstBad, p);
          continue;
        }
        if (k == runKey) continue;  // a run's particles share one base: the box grows once a run
        endRun();
        runKey = k;
        runBi = int(k & 0x1FFFFF);
        runBj = int((k >> 21) & 0x1FFFFF);
        runBk = int(k >> 42);
        acc.add(runBi, runBj, runBk);
      }
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

void MpmGrid::bin(const MpmParticles& particles, std::size_t materialCount) {
  const std::size_t np = particles.size();
  require(np < std::size_t(kBadKey), "MPM grid: at most 2^32 - 2 particles are supported, got ", np);
  const Vec3d* X = particles.x.data();
  const std::uint32_t* mat = particles.material.data();
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

  // Pass 1: base node of every particle (packed 21 bits per axis), the
  // extent of bins of each row of bins (in the whole grid's rows: atomic
  // min and max, order-free) and the box of bases in use (min/max are
  // exact, so the reduction is deterministic).
  std::atomic<std::size_t> firstBad{kNone};
  BinKernel kernel;
  kernel.X = X;
  kernel.mat = mat;
  kernel.materialCount = materialCount;
  kernel.o = spec_.origin;
  kernel.invDx = 1.0 / spec_.dx;
  kernel.bd = bd;
  kernel.key = key_.data();
  kernel.rowLow = rowLow;
  kernel.rowHigh = rowHigh;
  kernel.firstBad = &firstBad;
  kernel.avx2 = cpuHasAvx2Fma() && materialCount <= std::numeric_limits<std::uint32_t>::max();
  const BaseBox box = reduceKernel<BaseBox>(kernel, np, 2048);

  if (const std::size_t bad = firstBad.load(); bad != kNone) {
    // Restore the invariants before throwing: row extents zero, and every
    // node zero (no runs).
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

  if (np == 0) {
    activeLo_ = activeHi_ = binLo_ = binDims_ = {0, 0, 0};
    offsets_.assign(1, 0);
    sorted_.clear();
    return;
  }
  binLo_ = {box.lo[0], box.lo[1], box.lo[2]};
  binDims_ = {box.hi[0] - box.lo[0] + 1, box.hi[1] - box.lo[1] + 1, box.hi[2] - box.lo[2] + 1};
  activeLo_ = binLo_;
  activeHi_ = {box.hi[0] + 3, box.hi[1] + 3, box.hi[2] + 3};

  // Each row's extent of bins (pass 1's atomics, reset here: zero between
  // calls) and the first slot of its bins: the rows' bins, from the first
  // to the last holding particles, back to back.
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

  // Pass 2: the particles of each bin, counted in offsets_ (zeroed here),
  // each run of particles given its place among its bin's (at its first
  // particle; scheduling-dependent, pass 5 sorts each bin).
  static_assert(sizeof(std::atomic<std::uint32_t>) == sizeof(std::uint32_t) &&
                    alignof(std::atomic<std::uint32_t>) == alignof(std::uint32_t) &&
                    std::atomic<std::uint32_t>::is_always_lock_free,
                "the bins' counts are uint32 storage used as lock-free atomics");
  offsets_.assign(slots + 1, 0);
  std::atomic<std::uint32_t>* count = reinterpret_cast<std::atomic<std::uint32_t>*>(offsets_.data());
  forEachKeyRun(key_.data(), np, [&](std::size_t first, std::size_t end) {
    rank_[first] = count[binIndex(key_[first])].fetch_add(std::uint32_t(end - first), std::memory_order_relaxed);
  });

  // Pass 3: the counts become the bins' offsets, in place (integer prefix
  // sums: order-free).
  tbb::parallel_scan(
      tbb::blocked_range<std::size_t>(0, slots, 4096), std::uint32_t(0),
      [&](const tbb::blocked_range<std::size_t>& r, std::uint32_t sum, bool isFinal) {
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
          const std::uint32_t n = offsets_[b];
          if (isFinal) offsets_[b] = sum;
          sum += n;
        }
        return sum;
      },
      std::plus<std::uint32_t>());
  offsets_[slots] = std::uint32_t(np);

  // The node runs of the active box's rows.
  runFirst_.assign(std::size_t(binDims_.j + 2) * std::size_t(binDims_.k + 2), 0);
  runEnd_.assign(runFirst_.size(), 0);
  mpmNodeRuns(rowFirst_.data(), rowEnd_.data(), binDims_.j, binDims_.k, runFirst_.data(), runEnd_.data());

  // Pass 4: scatter indices into their bins, a run at a time (pass 2's runs).
  sorted_.resize(np);
  forEachKeyRun(key_.data(), np, [&](std::size_t first, std::size_t end) {
    const std::size_t b = binIndex(key_[first]);
    const std::size_t at = std::size_t(offsets_[b]) + rank_[first];
    // Pass 2 saw the same runs; a run reaching past its bin would mean it did not.
    if (at + (end - first) > offsets_[b + 1])
      throw std::logic_error("MPM binning: the scatter's runs are not the count's");
    std::uint32_t* out = sorted_.data() + at;
    for (std::size_t q = first; q < end; ++q) *out++ = std::uint32_t(q);
  });

  // Pass 5: ascending particle index within each bin (bins are small:
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
