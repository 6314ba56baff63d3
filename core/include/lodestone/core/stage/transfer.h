#pragma once
// Particle <-> grid transfers with quadratic B-splines (bspline.h):
//
//  * depositNumberDensity: material points carrying n_p micro-particles each
//    (dimensionless counts) deposit the micro-particle number density
//        n_i = sum_p w_ip n_p / dx^3     (1/m^3)
//    on the nodes of a GridView<double>. The deposit is parallel (TBB) and
//    bitwise deterministic: on a given build the result depends only on the
//    multiset of (position, count) pairs, not on the thread count, the
//    scheduling, or the order of the particles in the input arrays (see
//    "Determinism" below).
//  * sampleToParticles: interpolates a node field to particle positions,
//        out_p = sum_i w_ip field_i,
//    for handing force densities or H to hosts that use another grid.
//
// Stencils and the grid boundary. A particle at x has grid coordinate
// u = (x - origin)/dx per axis and touches nodes base..base+2 with
// base = floor(u - 1/2). It is inside the grid iff on every axis
// 0 <= base and base + 2 <= dims - 1, i.e. u in [1/2, dims - 3/2): positions in
// the half-open box [origin + dx/2, origin + (dims - 3/2) dx) per axis. The
// last half cell at each face is outside (a particle exactly at
// u = dims - 3/2 would have base = dims - 2), so a one-node margin of the grid
// is only ever reached by stencil tails. Particles outside are handled by the
// OutOfGridPolicy.
//
// Determinism. Particles are binned by their base node with a counting sort;
// within a bin they are ordered by grid coordinate u = (x - origin)/dx and
// count, (u.x, u.y, u.z, n_p) lexicographically, ties by particle index (tied
// particles have identical contributions, so their order cannot change a
// sum). Base nodes are grouped into x-rows (bj, bk). A row writes only nodes
// with j in [bj, bj+2] and k in [bk, bk+2]; two different rows with equal
// colour (bj mod 3, bk mod 3) therefore write disjoint nodes.
// The deposit runs the 9 colours one after another; within a colour the rows
// run in parallel, each row by one task that walks its bins in increasing bi
// and each bin's particles in sorted order. A node (i,j,k) receives
// contributions from the 9 rows bj in [j-2, j], bk in [k-2, k], which have 9
// distinct colours, so at most one task ever touches it per colour and its
// value is accumulated in one fixed order: by colour, then by bi, then by the
// in-bin order. Hence every node's floating-point sum is evaluated in the
// same sequence of operations whatever the number of threads or the task
// schedule, and (because the in-bin order is derived from the particle data,
// not its index) whatever the input order. Binning itself uses atomic
// counters, but only to count; the order they produce is discarded by the
// in-bin sort.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace stage {

/// Material points as seen by the transfers (non-owning; arrays of `size`).
struct ParticleView {
  const Vec3d* positions = nullptr;  ///< world positions, m
  const double* counts = nullptr;    ///< n_p: micro-particles carried by each point (dimensionless, >= 0)
  std::size_t size = 0;              ///< number of material points
};

/// What to do with a particle whose 3x3x3 stencil leaves the grid.
enum class OutOfGridPolicy {
  Throw,  ///< throw InvalidArgument naming the (lowest-index) offending particle
  Skip    ///< ignore it (deposit nothing / sample zeros) and count it in TransferReport::skipped
};

/// Summary of one transfer.
struct TransferReport {
  std::size_t particles = 0;  ///< particles given
  std::size_t skipped = 0;    ///< particles outside the grid ignored under OutOfGridPolicy::Skip
  double totalCount = 0;      ///< deposit: sum of n_p over the deposited particles (dimensionless); sampling: 0
  double seconds = 0;         ///< wall-clock time of the call, s
};

/// Particles sorted by the base node of their quadratic stencil: reusable
/// scratch for depositNumberDensity (keep one alive across time steps so its
/// buffers are not reallocated) and for other deterministic scatters.
///
/// Bins are base nodes (bi, bj, bk) with 0 <= bi < dims.i - 2 (same for j, k),
/// flat index bi + nbi*(bj + nbj*bk) where (nbi, nbj, nbk) = baseDims(). The
/// binned particles are stored contiguously, bin after bin, so all bins of one
/// x-row (bj, bk) form one contiguous range. Within a bin they are ordered by
/// (u.x, u.y, u.z, count) lexicographically, then by particle index; this
/// order depends only on the particle data, not on the input order (two
/// particles that tie have identical (u, count), hence identical deposits).
class ParticleBinning {
 public:
  /// One binned particle.
  struct Entry {
    Vec3d u;              ///< grid coordinate (x - origin)/dx (dimensionless, node spacings)
    double count;         ///< n_p (0 when the binning was built without counts)
    std::uint32_t index;  ///< index in the input arrays
  };

  ParticleBinning();
  ~ParticleBinning();
  ParticleBinning(ParticleBinning&&) noexcept;
  ParticleBinning& operator=(ParticleBinning&&) noexcept;
  ParticleBinning(const ParticleBinning&) = delete;
  ParticleBinning& operator=(const ParticleBinning&) = delete;

  /// Bins `particles` on `grid`. Positions must be finite (else
  /// InvalidArgument naming the lowest such index). Particles whose stencil
  /// leaves the grid throw (naming the lowest such index, its position and the
  /// grid's extent) under Throw, or are left out under Skip. Counts may be
  /// null and are not validated here (they are only copied and used to order
  /// ties). At most 2^32 - 2 particles. Returns the number of particles left
  /// out. On throw the binning is empty.
  std::size_t build(const ParticleView& particles, const GridSpec& grid, OutOfGridPolicy policy);

  const GridSpec& grid() const { return grid_; }
  /// Number of base nodes per axis (dims - 2, clamped at 0).
  Index3 baseDims() const { return baseDims_; }
  std::size_t binCount() const { return binCount_; }
  std::size_t binIndex(int bi, int bj, int bk) const {
    return std::size_t(bi) + std::size_t(baseDims_.i) * (std::size_t(bj) + std::size_t(baseDims_.j) * std::size_t(bk));
  }
  /// Particles binned (inside the grid).
  std::size_t binnedCount() const { return binned_; }
  /// Particles left out under Skip.
  std::size_t skippedCount() const { return skipped_; }
  /// The particles of bin b (b < binCount()), in the canonical in-bin order.
  const Entry* binBegin(std::size_t b) const { return entries_.data() + offsets_[b]; }
  const Entry* binEnd(std::size_t b) const { return entries_.data() + offsets_[b + 1]; }

 private:
  void clear();

  GridSpec grid_;
  Index3 baseDims_{0, 0, 0};
  std::size_t binCount_ = 0;
  std::size_t binned_ = 0;
  std::size_t skipped_ = 0;
  std::vector<std::uint64_t> keys_;  // per particle: bin, or a sentinel
  std::vector<std::uint32_t> rank_;  // per particle: slot within its bin (scheduling-dependent, re-sorted)
  std::unique_ptr<std::atomic<std::uint32_t>[]> binSize_;
  std::size_t binSizeCapacity_ = 0;
  std::vector<std::uint32_t> offsets_;  // binCount_ + 1 prefix sums
  std::vector<Entry> entries_;          // binned particles grouped by bin
};

/// Deposits the micro-particle number density n_i = sum_p w_ip n_p / dx^3
/// (1/m^3) on the grid of `n` (first zeroing every node of `n`).
/// Positions must be finite and counts finite and >= 0 (else InvalidArgument
/// naming the particle index and value, under either policy). Particles whose
/// stencil leaves the grid follow `policy`. Parallel and bitwise deterministic
/// (see the header comment). On throw `n` is left untouched.
TransferReport depositNumberDensity(const ParticleView& particles, GridView<double> n,
                                    OutOfGridPolicy policy = OutOfGridPolicy::Throw);

/// As above, reusing the buffers of `binning` (which afterwards holds the
/// binning of `particles` on n's grid).
TransferReport depositNumberDensity(const ParticleView& particles, GridView<double> n, OutOfGridPolicy policy,
                                    ParticleBinning& binning);

/// Interpolates a vector node field to particles: out[p] = sum_i w_ip field_i
/// (same units as the field, e.g. N/m^3 for a force density, A/m for H).
/// Positions in m must be finite (else InvalidArgument naming the lowest bad
/// index). Out-of-grid particles throw (lowest index, with position and grid
/// extent) under Throw or get zeros under Skip. Parallel; each out[p] depends
/// only on positions[p] and the field, so results are deterministic.
/// `out` may alias `positions` (each entry is read before it is written).
/// On throw the contents of `out` are unspecified.
TransferReport sampleToParticles(GridView<const Vec3d> field, const Vec3d* positions, std::size_t count, Vec3d* out,
                                 OutOfGridPolicy policy = OutOfGridPolicy::Throw);

/// Scalar version of sampleToParticles (same rules).
TransferReport sampleToParticles(GridView<const double> field, const Vec3d* positions, std::size_t count, double* out,
                                 OutOfGridPolicy policy = OutOfGridPolicy::Throw);

}  // namespace stage
}  // namespace lodestone
