// Particle <-> grid transfers: deterministic parallel deposit of the
// micro-particle number density and B-spline sampling to particles.
// The determinism argument is in transfer.h.
#include "lodestone/core/base/stopwatch.h"
#include "lodestone/core/stage/transfer.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_scan.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <string>

#include "lodestone/core/base/bspline.h"
#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace stage {
namespace {

using Clock = std::chrono::steady_clock;

constexpr std::uint64_t kNonFinite = std::numeric_limits<std::uint64_t>::max();
constexpr std::uint64_t kOutside = std::numeric_limits<std::uint64_t>::max() - 1;
constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();


void atomicMin(std::atomic<std::size_t>& a, std::size_t v) {
  std::size_t cur = a.load(std::memory_order_relaxed);
  while (v < cur && !a.compare_exchange_weak(cur, v, std::memory_order_relaxed)) {
  }
}

/// Grid coordinate (x - origin)/dx per axis, in node spacings.
inline Vec3d gridCoord(const Vec3d& x, const GridSpec& g) {
  return {(x.x - g.origin.x) / g.dx, (x.y - g.origin.y) / g.dx, (x.z - g.origin.z) / g.dx};
}

/// Base node of the stencil of a particle at finite grid coordinate u, or
/// false if the 3x3x3 stencil leaves the grid (base < 0 or base + 2 > dims - 1
/// on some axis). Range-checked in floating point before the int conversion.
inline bool stencilBase(const Vec3d& u, const Index3& dims, Index3& base) {
  int b[3];
  for (int a = 0; a < 3; ++a) {
    const double f = quadraticBaseFloor(u[a]);
    if (!(f >= 0.0 && f <= double(dims[a]) - 3.0)) return false;
    b[a] = static_cast<int>(f);
  }
  base = {b[0], b[1], b[2]};
  return true;
}

std::string describeExtent(const GridSpec& g) {
  const Vec3d hi = g.maxCorner();
  const double lo = 0.5 * g.dx;
  return concat("the grid has origin (", g.origin.x, ", ", g.origin.y, ", ", g.origin.z, ") m, dx = ", g.dx, " m and ",
                g.dims.i, " x ", g.dims.j, " x ", g.dims.k, " nodes, spanning up to (", hi.x, ", ", hi.y, ", ", hi.z,
                ") m; a quadratic B-spline stencil fits only for positions in [origin + dx/2, origin + "
                "(dims - 3/2) dx) per axis: x in [",
                g.origin.x + lo, ", ", g.origin.x + (g.dims.i - 1.5) * g.dx, "), y in [", g.origin.y + lo, ", ",
                g.origin.y + (g.dims.j - 1.5) * g.dx, "), z in [", g.origin.z + lo, ", ",
                g.origin.z + (g.dims.k - 1.5) * g.dx, ") m");
}

[[noreturn]] void throwNonFinitePosition(std::size_t p, const Vec3d& x) {
  throw InvalidArgument(concat("particle ", p, ": position must be finite, got (", x.x, ", ", x.y, ", ", x.z, ") m"));
}

[[noreturn]] void throwOutside(std::size_t p, const Vec3d& x, const GridSpec& g) {
  throw InvalidArgument(concat("particle ", p, " at (", x.x, ", ", x.y, ", ", x.z,
                               ") m is outside the grid (its 3x3x3 stencil leaves it): ", describeExtent(g)));
}

/// A total order on doubles (all bit patterns, NaN included) as unsigned keys.
inline std::uint64_t totalOrderKey(double v) {
  std::uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  constexpr std::uint64_t sign = std::uint64_t(1) << 63;
  return (bits & sign) ? ~bits : (bits | sign);
}

}  // namespace

// ---------------------------------------------------------------------------
// ParticleBinning

ParticleBinning::ParticleBinning() = default;
ParticleBinning::~ParticleBinning() = default;
ParticleBinning::ParticleBinning(ParticleBinning&&) noexcept = default;
ParticleBinning& ParticleBinning::operator=(ParticleBinning&&) noexcept = default;

void ParticleBinning::clear() {
  baseDims_ = {0, 0, 0};
  binCount_ = 0;
  binned_ = 0;
  skipped_ = 0;
  offsets_.assign(1, 0);
  entries_.clear();
}

std::size_t ParticleBinning::build(const ParticleView& particles, const GridSpec& grid, OutOfGridPolicy policy) {
  clear();
  grid.validate("particle binning grid");
  const std::size_t np = particles.size;
  require(np == 0 || particles.positions != nullptr, "particle binning: positions is null for ", np, " particles");
  require(np <= std::size_t(std::numeric_limits<std::uint32_t>::max()) - 1,
          "particle binning: at most 2^32 - 2 particles are supported, got ", np);

  grid_ = grid;
  const Index3 bd{std::max(grid.dims.i - 2, 0), std::max(grid.dims.j - 2, 0), std::max(grid.dims.k - 2, 0)};
  const std::size_t nb = std::size_t(bd.i) * std::size_t(bd.j) * std::size_t(bd.k);
  baseDims_ = bd;
  binCount_ = nb;

  if (binSizeCapacity_ < nb) {
    binSize_.reset(new std::atomic<std::uint32_t>[nb]);
    binSizeCapacity_ = nb;
  }
  std::atomic<std::uint32_t>* binSize = binSize_.get();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b != r.end(); ++b) binSize[b].store(0, std::memory_order_relaxed);
  });

  keys_.resize(np);
  rank_.resize(np);
  const Vec3d* pos = particles.positions;
  const bool throwOutsiders = policy == OutOfGridPolicy::Throw;
  std::atomic<std::size_t> firstError{kNone};
  std::atomic<std::size_t> outside{0};

  // Pass 1: bin of every particle, and a (scheduling-dependent) slot in it.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, np, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    std::size_t localOutside = 0;
    for (std::size_t p = r.begin(); p != r.end(); ++p) {
      const Vec3d& x = pos[p];
      if (!isFinite(x)) {
        keys_[p] = kNonFinite;
        atomicMin(firstError, p);
        continue;
      }
      Index3 b;
      if (!stencilBase(gridCoord(x, grid), grid.dims, b)) {
        keys_[p] = kOutside;
        ++localOutside;
        if (throwOutsiders) atomicMin(firstError, p);
        continue;
      }
      const std::size_t key = binIndex(b.i, b.j, b.k);
      keys_[p] = key;
      rank_[p] = binSize[key].fetch_add(1, std::memory_order_relaxed);
    }
    if (localOutside) outside.fetch_add(localOutside, std::memory_order_relaxed);
  });

  const std::size_t bad = firstError.load();
  if (bad != kNone) {
    const Vec3d x = pos[bad];
    const bool nonFinite = keys_[bad] == kNonFinite;
    clear();
    if (nonFinite) throwNonFinitePosition(bad, x);
    throwOutside(bad, x, grid);
  }
  skipped_ = outside.load();
  binned_ = np - skipped_;

  // Pass 2: bin offsets (exclusive prefix sums; integers, so order-free).
  offsets_.resize(nb + 1);
  tbb::parallel_scan(
      tbb::blocked_range<std::size_t>(0, nb, 16384), std::uint32_t(0),
      [&](const tbb::blocked_range<std::size_t>& r, std::uint32_t sum, bool isFinal) {
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
          if (isFinal) offsets_[b] = sum;
          sum += binSize[b].load(std::memory_order_relaxed);
        }
        return sum;
      },
      std::plus<std::uint32_t>());
  offsets_[nb] = std::uint32_t(binned_);

  // Pass 3: scatter the particles into their bins. gridCoord is the same
  // computation as in pass 1 (the stencil base used later is the bin's anyway).
  entries_.resize(binned_);
  const double* counts = particles.counts;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, np, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p) {
      const std::uint64_t key = keys_[p];
      if (key < nb) {
        entries_[offsets_[key] + rank_[p]] = {gridCoord(pos[p], grid), counts ? counts[p] : 0.0, std::uint32_t(p)};
      }
    }
  });

  // Pass 4: canonical in-bin order, (u.x, u.y, u.z, count) then index. u is
  // finite here so < is a strict weak order; counts use a total order on the
  // bits so even unvalidated counts (NaN) cannot break the sort.
  auto less = [](const Entry& a, const Entry& b) {
    if (a.u.x != b.u.x) return a.u.x < b.u.x;
    if (a.u.y != b.u.y) return a.u.y < b.u.y;
    if (a.u.z != b.u.z) return a.u.z < b.u.z;
    const std::uint64_t ca = totalOrderKey(a.count), cb = totalOrderKey(b.count);
    if (ca != cb) return ca < cb;
    return a.index < b.index;
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b != r.end(); ++b) {
      Entry* first = entries_.data() + offsets_[b];
      Entry* last = entries_.data() + offsets_[b + 1];
      if (last - first < 2) continue;
      if (last - first > 24) {
        std::sort(first, last, less);
        continue;
      }
      // Bins usually hold a handful of particles: insertion sort.
      for (Entry* i = first + 1; i != last; ++i) {
        if (!less(*i, *(i - 1))) continue;
        const Entry v = *i;
        Entry* j = i;
        do {
          *j = *(j - 1);
          --j;
        } while (j != first && less(v, *(j - 1)));
        *j = v;
      }
    }
  });
  return skipped_;
}

// ---------------------------------------------------------------------------
// Deposit

TransferReport depositNumberDensity(const ParticleView& particles, GridView<double> n, OutOfGridPolicy policy) {
  ParticleBinning binning;
  return depositNumberDensity(particles, n, policy, binning);
}

TransferReport depositNumberDensity(const ParticleView& particles, GridView<double> n, OutOfGridPolicy policy,
                                    ParticleBinning& binning) {
  const auto t0 = Clock::now();
  const GridSpec& g = n.spec;
  g.validate("number density grid");
  require(n.data != nullptr, "depositNumberDensity: the number density grid has no data");
  const std::size_t np = particles.size;
  require(np == 0 || particles.counts != nullptr, "depositNumberDensity: counts is null for ", np, " particles");

  // Counts: finite and >= 0; report the lowest bad index (deterministic).
  const double* counts = particles.counts;
  std::atomic<std::size_t> firstBadCount{kNone};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, np, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p) {
      if (!(std::isfinite(counts[p]) && counts[p] >= 0.0)) {
        atomicMin(firstBadCount, p);
        break;  // later ones in this range have higher indices
      }
    }
  });
  if (const std::size_t bad = firstBadCount.load(); bad != kNone) {
    throw InvalidArgument(concat("particle ", bad,
                                 ": count n_p (micro-particles per material point) must be finite and >= 0, got ",
                                 counts[bad]));
  }

  binning.build(particles, g, policy);

  double* nd = n.data;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.nodeCount(), 8192),
                    [&](const tbb::blocked_range<std::size_t>& r) { std::fill(nd + r.begin(), nd + r.end(), 0.0); });

  const Index3 bd = binning.baseDims();
  const double invVolume = 1.0 / g.cellVolume();
  const std::size_t sj = std::size_t(g.dims.i);
  const std::size_t sk = std::size_t(g.dims.i) * std::size_t(g.dims.j);
  // Per-row sums of n_p, added in row order at the end (deterministic).
  std::vector<double> rowTotal(std::size_t(bd.j) * std::size_t(bd.k), 0.0);

  auto depositRow = [&](int bj, int bk) {
    double total = 0.0;
    const std::size_t firstBin = binning.binIndex(0, bj, bk);
    for (int bi = 0; bi < bd.i; ++bi) {
      const ParticleBinning::Entry* it = binning.binBegin(firstBin + std::size_t(bi));
      const ParticleBinning::Entry* end = binning.binEnd(firstBin + std::size_t(bi));
      if (it == end) continue;
      double* corner = nd + g.index(bi, bj, bk);
      for (; it != end; ++it) {
        // The bin's base, not a recomputed one: the stencil is exactly the bin's.
        const QuadraticWeights<double> wx = quadraticWeightsAt(it->u.x, bi);
        const QuadraticWeights<double> wy = quadraticWeightsAt(it->u.y, bj);
        const QuadraticWeights<double> wz = quadraticWeightsAt(it->u.z, bk);
        const double c = it->count * invVolume;
        total += it->count;
        for (int cz = 0; cz < 3; ++cz) {
          const double wzc = wz.w[cz] * c;
          for (int cy = 0; cy < 3; ++cy) {
            const double wyz = wy.w[cy] * wzc;
            double* line = corner + std::size_t(cy) * sj + std::size_t(cz) * sk;
            line[0] += wx.w[0] * wyz;
            line[1] += wx.w[1] * wyz;
            line[2] += wx.w[2] * wyz;
          }
        }
      }
    }
    rowTotal[std::size_t(bj) + std::size_t(bd.j) * std::size_t(bk)] = total;
  };

  // Nine colours (bj mod 3, bk mod 3), one after another; rows of one colour
  // write disjoint nodes, so they run in parallel without races.
  for (int ck = 0; ck < 3; ++ck) {
    for (int cj = 0; cj < 3; ++cj) {
      const int nrj = bd.j > cj ? (bd.j - cj + 2) / 3 : 0;
      const int nrk = bd.k > ck ? (bd.k - ck + 2) / 3 : 0;
      const std::size_t rows = std::size_t(nrj) * std::size_t(nrk);
      if (rows == 0) continue;
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t row = r.begin(); row != r.end(); ++row) {
          const int bj = cj + 3 * int(row % std::size_t(nrj));
          const int bk = ck + 3 * int(row / std::size_t(nrj));
          depositRow(bj, bk);
        }
      });
    }
  }

  TransferReport report;
  report.particles = np;
  report.skipped = binning.skippedCount();
  double total = 0.0;
  for (double t : rowTotal) total += t;
  report.totalCount = total;
  report.seconds = secondsSince(t0);
  return report;
}

// ---------------------------------------------------------------------------
// Sampling

namespace {

template <typename V>
TransferReport sampleImpl(GridView<const V> field, const Vec3d* positions, std::size_t count, V* out,
                          OutOfGridPolicy policy, const char* what) {
  const auto t0 = Clock::now();
  const GridSpec& g = field.spec;
  g.validate("sampled field grid");
  require(field.data != nullptr, what, ": the field grid has no data");
  require(count == 0 || positions != nullptr, what, ": positions is null for ", count, " particles");
  require(count == 0 || out != nullptr, what, ": output is null for ", count, " particles");

  const bool throwOutsiders = policy == OutOfGridPolicy::Throw;
  std::atomic<std::size_t> firstError{kNone};
  std::atomic<std::size_t> outside{0};
  const V* fd = field.data;
  const std::size_t sj = std::size_t(g.dims.i);
  const std::size_t sk = std::size_t(g.dims.i) * std::size_t(g.dims.j);

  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    std::size_t localOutside = 0;
    for (std::size_t p = r.begin(); p != r.end(); ++p) {
      const Vec3d x = positions[p];  // copy: out may alias positions
      // Under an error out[p] is not written, so an aliased position survives
      // for the message.
      if (!isFinite(x)) {
        atomicMin(firstError, p);
        continue;
      }
      const Vec3d u = gridCoord(x, g);
      Index3 b;
      if (!stencilBase(u, g.dims, b)) {
        ++localOutside;
        if (throwOutsiders) {
          atomicMin(firstError, p);
        } else {
          out[p] = V{};
        }
        continue;
      }
      const QuadraticWeights<double> wx = quadraticWeightsAt(u.x, b.i);
      const QuadraticWeights<double> wy = quadraticWeightsAt(u.y, b.j);
      const QuadraticWeights<double> wz = quadraticWeightsAt(u.z, b.k);
      const V* corner = fd + g.index(b.i, b.j, b.k);
      V acc{};
      for (int cz = 0; cz < 3; ++cz) {
        for (int cy = 0; cy < 3; ++cy) {
          const V* line = corner + std::size_t(cy) * sj + std::size_t(cz) * sk;
          const V lineSum = wx.w[0] * line[0] + wx.w[1] * line[1] + wx.w[2] * line[2];
          acc += (wy.w[cy] * wz.w[cz]) * lineSum;
        }
      }
      out[p] = acc;
    }
    if (localOutside) outside.fetch_add(localOutside, std::memory_order_relaxed);
  });

  if (const std::size_t bad = firstError.load(); bad != kNone) {
    const Vec3d x = positions[bad];
    if (!isFinite(x)) throwNonFinitePosition(bad, x);
    throwOutside(bad, x, g);
  }
  TransferReport report;
  report.particles = count;
  report.skipped = outside.load();
  report.seconds = secondsSince(t0);
  return report;
}

}  // namespace

TransferReport sampleToParticles(GridView<const Vec3d> field, const Vec3d* positions, std::size_t count, Vec3d* out,
                                 OutOfGridPolicy policy) {
  return sampleImpl<Vec3d>(field, positions, count, out, policy, "sampleToParticles");
}

TransferReport sampleToParticles(GridView<const double> field, const Vec3d* positions, std::size_t count, double* out,
                                 OutOfGridPolicy policy) {
  return sampleImpl<double>(field, positions, count, out, policy, "sampleToParticles");
}

}  // namespace stage
}  // namespace lodestone
