#pragma once
// The MLS-MPM background grid and its particle <-> grid transfers (Hu et al.
// 2018; Section 4.3 of the paper, steps 1, 5, 6 and 7) with quadratic
// B-splines (bspline.h) on the node-centred grid of grid.h.
//
// P2G (step 1): for every particle p and node i of its 3x3x3 stencil, with
// weight w_ip and offset d_ip = x_i - x_p,
//   m_i  += w_ip m_p
//   mv_i += w_ip (m_p v_p + A_p d_ip + dt f_p)
//   A_p   = m_p C_p - dt (4/dx^2) V_p^0 tau_p,
// APIC momentum (Jiang et al. 2015) plus the MLS stress force: tau_p = J sigma
// is the Kirchhoff stress (mpm_constitutive.h), V_p^0 J = V_p the current
// volume, 4/dx^2 = D_p^-1 for quadratic B-splines; f_p an optional external
// force per particle (N).
// Surface tension (only when some material has sigma > 0; otherwise nothing
// of it runs): a first scatter gives the colour field c_i = sum_p w_ip V_p /
// dx^3 of the liquids with sigma > 0, a pass over those particles its
// gradient g_p = sum_i c_i grad w_ip and the capillary stress T_p = sigma
// |g_p| (I - n n^T) (surface_tension.h), and tau_p += J_p T_p.
// G2P (steps 5-7): v_p = sum_i w_ip v_i, C_p = (4/dx^2) sum_i w_ip v_i d_ip^T,
// then F_p <- (I + dt C_p) F_p (solids, MLS update) or J_p <- (1 + dt tr C_p) J_p
// (fluids), and x_p <- x_p + dt v_p.
//
// Conservation: P2G preserves mass, linear momentum and APIC angular momentum
// (MpmParticles::angularMomentum) exactly in exact arithmetic, the stress term
// contributing zero net force and, tau being symmetric, zero net torque; G2P
// (before advection) returns exactly the grid's momentum and angular momentum.
//
// Determinism of the parallel P2G. Particles are binned by the base node of
// their stencil (counting sort; atomics only count, and the order they give
// inside a bin is replaced by ascending particle index). Bins form x-rows
// (bj, bk); a row writes only nodes with j in [bj, bj+2], k in [bk, bk+2], so
// rows of equal colour (bj mod 3, bk mod 3) write disjoint nodes. The nine
// colours run one after another, the rows of a colour in parallel, each row
// by one task walking its bins in increasing bi and each bin in increasing
// particle index. A node receives contributions from 9 rows of 9 distinct
// colours, so it accumulates them in one fixed order whatever the thread
// count or schedule: the grid is bitwise identical for any number of
// threads. G2P writes only its own particle. On CPUs with AVX2 and FMA the
// transfers fuse multiplies and adds (one rounding where the portable code
// rounds twice), so such a machine and one without AVX2 agree to the last
// few digits, not bit for bit.
//
// Storage. Each x-row of nodes the material reaches holds one run, from the
// first to the last stencil that reaches it (activeRun). The node arrays
// hold either the whole grid, node (i, j, k) at spec().index(i, j, k) and
// every node outside the runs zero, or (setWholeLayout(false), as
// MpmSolver's grid) only the runs, packed back to back in row order from the
// arrays' start: the run of row (j, k) starts after the runs of the rows
// before it. The packing is redone at every P2G (a prefix sum of the run
// lengths), so memory follows any shape of material (a sheet slanted across
// the grid, bodies apart) at the nodes its stencils reach, and pages are
// taken only as far as the runs reach (base/page_array.h). The bins are
// packed the same way: each row of bins holds its bins from the first to
// the last holding particles, back to back. Storage changes where nodes lie
// in memory, never what is added to them or in what order: either gives
// the same bits.
//
// Particles must lie where their stencil fits the grid: grid coordinate
// u = (x - origin)/dx in [1/2, dims - 3/2) per axis (transfer.h). The solver
// keeps them there; the transfers throw InvalidArgument otherwise.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/base/page_array.h"
#include "lodestone/core/mpm/material.h"
#include "lodestone/core/mpm/particles.h"

namespace lodestone {
inline namespace mpm {

/// One node during P2G: mass (kg) and momentum (kg*m/s).
struct MpmNode {
  Vec3d momentum;
  double mass = 0;
};

/// Where G2P keeps the advected particles (optional): positions outside
/// [lo, hi] (m, per axis) are clamped back, stopping their outward velocity,
/// or only counted (clamp = false), for the caller to remove.
struct ParticleBounds {
  Vec3d lo, hi;
  bool clamp = true;
  /// Whether x lies outside [lo, hi] on some axis.
  bool excludes(const Vec3d& x) const {
    return x.x < lo.x || x.y < lo.y || x.z < lo.z || x.x > hi.x || x.y > hi.y || x.z > hi.z;
  }
};

/// What G2P measured.
struct GridToParticleReport {
  double maxSpeed = 0;        ///< largest |v_p| after the transfer, m/s
  std::size_t clamped = 0;    ///< particles moved back inside the bounds
  std::size_t outside = 0;    ///< particles outside the bounds, left there (clamp = false)
  std::size_t nonFinite = 0;  ///< particles whose position, velocity or J became non-finite (left as they are)
};

/// The stencil base node (quadraticBaseFloor) along `axis` (0, 1, 2 for x,
/// y, z) of a point whose coordinate on that axis is x (m), clamped to the
/// grid's bins [0, dims - 3]: the bin a particle there lands in.
int mpmStencilBase(const GridSpec& spec, double x, int axis);

/// An MpmGrid holds fewer stencil bins (base nodes: dims - 2 per axis) than
/// this, and fewer particles: its binning counts them in 32 bits.
constexpr std::uint64_t kMpmGridCountLimit = 0xFFFFFFFFu;  // 2^32 - 1

/// The node runs of rows of stencil bins (MpmGrid::activeRun): the bins
/// [rowFirst, rowEnd) of bin row (bj, bk) (entry bj + nbj bk; none when
/// end <= first; bi in grid indices) reach nodes [first, end + 2) of node
/// rows bj .. bj + 2 and bk .. bk + 2, and node row (j, k) (entry
/// j + (nbj + 2) k of (nbj + 2) x (nbk + 2), counted from the first bin row)
/// gets the union's extent [runFirst, runEnd) (0, 0 when none).
void mpmNodeRuns(const std::uint32_t* rowFirst, const std::uint32_t* rowEnd, int nbj, int nbk, std::int32_t* runFirst,
                 std::int32_t* runEnd);

/// The memory (bytes) an MpmGrid on `spec` takes for the runs of one P2G:
/// bins [rowFirst, rowEnd) of the nbj x nbk rows of bins from base node row
/// (binLo.j, binLo.k) (bi in grid indices, as mpmNodeRuns takes them) and
/// the node runs runFirst/runEnd mpmNodeRuns gives for them. Whole pages
/// (PageMapping::pageSize) of the node data (32 B a node), the velocities
/// (24 B) and the colour field (8 B, when `colour`), each page counted once
/// however many runs share it: packed = true (setWholeLayout(false)), the
/// runs back to back from the arrays' start; false, each run in its row of
/// the whole grid, where a run shorter than a page in a longer row still
/// takes a page. Plus the bins' offsets (4 B a bin) and the rows'
/// bookkeeping (40 B a row).
double mpmHeldBytes(const GridSpec& spec, Index3 binLo, int nbj, int nbk, const std::uint32_t* rowFirst,
                    const std::uint32_t* rowEnd, const std::int32_t* runFirst, const std::int32_t* runEnd,
                    bool colour, bool packed);

class MpmGrid {
 public:
  MpmGrid() = default;
  /// Throws InvalidArgument on a bad grid (fewer than 3 nodes per axis).
  explicit MpmGrid(const GridSpec& spec);
  MpmGrid(MpmGrid&&) noexcept;
  MpmGrid& operator=(MpmGrid&&) noexcept;
  ~MpmGrid();

  const GridSpec& spec() const { return spec_; }

  /// Step 1: bins the particles and deposits mass and momentum (including the
  /// stress impulse over dt (s) and, when particleForces is given, dt times
  /// those forces (N, one per particle)). Throws InvalidArgument naming the
  /// lowest offending particle for a non-finite position, a stencil outside
  /// the grid or a material index out of range. Nodes outside the runs
  /// (activeRun) are zero afterwards, and their pages are handed back.
  void particleToGrid(const MpmParticles& particles, const std::vector<MpmMaterial>& materials, double dt,
                      const Vec3d* particleForces = nullptr);

  /// Steps 5-7: G2P (APIC), the MLS update of F (solids) or J (fluids) and
  /// advection, from the node velocities velocity() (m/s), which the grid
  /// update must have set on the runs (activeRun). Particles must be the ones of
  /// the last particleToGrid, unmoved.
  GridToParticleReport gridToParticle(MpmParticles& particles, const std::vector<MpmMaterial>& materials, double dt,
                                      const ParticleBounds* bounds = nullptr) const;

  /// The largest |v| of velocities v[0 .. count) (m/s), computed with the
  /// arithmetic of gridToParticle's maxSpeed: the same bits for the
  /// velocities G2P wrote.
  static double maxSpeed(const Vec3d* v, std::size_t count);

  /// Node data of the last P2G, node (i, j, k) of the runs (activeRun) at
  /// nodeIndex(i, j, k); every other node is zero (and, packed, not
  /// stored). Memory is taken only for the pages written
  /// (base/page_array.h), handed back when the runs no longer reach them.
  PageArray<MpmNode>& nodes() { return nodes_; }
  const PageArray<MpmNode>& nodes() const { return nodes_; }
  /// Node velocities (m/s) used by G2P, at nodeIndex; written by the grid
  /// update.
  PageArray<Vec3d>& velocity() { return velocity_; }
  const PageArray<Vec3d>& velocity() const { return velocity_; }

  /// Whether the node arrays hold only the runs, back to back (after a P2G
  /// with setWholeLayout(false)); false: the whole grid.
  bool packed() const { return packed_; }
  /// Index of node (i, j, k) in nodes(), velocity() and colour(); the node
  /// must lie in a run (activeRun): packed, no other node is stored.
  std::size_t nodeIndex(int i, int j, int k) const {
    if (!packed_) return spec_.index(i, j, k);
    return std::size_t(rowOrigin_[activeRow(j, k)] + i);
  }
  /// Whether node (i, j, k) lies in a run (activeRun).
  bool inRun(int i, int j, int k) const {
    int first = 0, end = 0;
    activeRun(j, k, first, end);
    return i >= first && i < end;
  }
  /// Node (i, j, k) of the last P2G, zero outside the runs.
  MpmNode nodeAt(int i, int j, int k) const {
    return inRun(i, j, k) ? nodes_[nodeIndex(i, j, k)] : MpmNode{};
  }
  /// Velocity (m/s) of node (i, j, k), zero outside the runs.
  Vec3d velocityAt(int i, int j, int k) const {
    return inRun(i, j, k) ? velocity_[nodeIndex(i, j, k)] : Vec3d{};
  }
  /// The colour field (colour()) at node (i, j, k), zero outside the runs
  /// (with a sum over processes, setColourSum, whatever the sum left there).
  double colourAt(int i, int j, int k) const {
    if (colour_.empty() || i < 0 || j < 0 || k < 0 || i >= spec_.dims.i || j >= spec_.dims.j || k >= spec_.dims.k)
      return 0.0;
    if (!packed_) return colour_[spec_.index(i, j, k)];
    return inRun(i, j, k) ? colour_[nodeIndex(i, j, k)] : 0.0;
  }
  /// whole = true (the default): the node arrays hold the whole grid, node
  /// (i, j, k) at spec().index(i, j, k); data already written moves with
  /// it. whole = false: from the next P2G on, the node arrays hold only the
  /// runs, packed, so that memory follows the material rather than the
  /// grid's rows (MpmSolver's grid does this unless MpmSettings::denseGrid).
  /// A partition's sums and setColourSum, which add whole arrays, need the
  /// whole layout.
  void setWholeLayout(bool whole);

  /// The box of nodes the last P2G could touch: [activeLo, activeHi) per
  /// axis (empty when there were no particles).
  Index3 activeLo() const { return activeLo_; }
  Index3 activeHi() const { return activeHi_; }
  /// The nodes of x-row (j, k) the last P2G could touch: [first, end) (first
  /// >= end: none). Within the active box each row holds one run, from the
  /// first to the last stencil that reaches it; every node outside the runs
  /// is zero, and only the runs' pages hold memory. After
  /// activateWholeGrid(), whole rows.
  void activeRun(int j, int k, int& first, int& end) const {
    first = end = 0;
    if (wholeGrid_) {
      end = spec_.dims.i;
      return;
    }
    if (j < activeLo_.j || j >= activeHi_.j || k < activeLo_.k || k >= activeHi_.k) return;
    const std::size_t row = std::size_t(j - activeLo_.j) + std::size_t(activeHi_.j - activeLo_.j) * std::size_t(k - activeLo_.k);
    first = runFirst_[row];
    end = runEnd_[row];
  }

  /// A sum of the colour field over processes (mpm/partition.h): called
  /// after the colour scatter with the field on the whole grid (zero outside
  /// what this grid's particles reach), it must leave every node holding the
  /// total over the processes. Empty (the default): none. A sum sets the
  /// whole layout (setWholeLayout).
  void setColourSum(std::function<void(double* colour, std::size_t count)> sum) {
    if (sum) setWholeLayout(true);
    colourSum_ = std::move(sum);
  }

  /// Widens the active box to the whole grid: for a caller that wrote node
  /// data outside it (a partition's sums, mpm/partition.h), so that the grid
  /// update covers those nodes and the next particleToGrid zeroes them.
  /// Sets the whole layout (setWholeLayout) if the grid has another.
  void activateWholeGrid() {
    setWholeLayout(true);
    activeLo_ = {0, 0, 0};
    activeHi_ = spec_.dims;
    wholeGrid_ = true;
    placeRuns();
  }

  /// The particle indices of the last P2G grouped by stencil bin (bins in
  /// flat order, ascending index within a bin): a cache-friendly order.
  const std::vector<std::uint32_t>& binnedOrder() const { return sorted_; }

  /// The colour field c_i = sum_p w_ip V_p / dx^3 (dimensionless) of the
  /// liquids with surface tension, node (i, j, k) of the runs at nodeIndex
  /// (colourAt for any node), after a P2G of a scene that has one (empty
  /// when none ever had).
  const PageArray<double>& colour() const { return colour_; }

  /// The memory the grid's arrays hold for the runs of the last P2G, bytes
  /// (mpmHeldBytes of its bins and runs; with the colour field once a scene
  /// with surface tension used it). After activateWholeGrid, what the caller
  /// wrote is its own and not counted.
  double heldBytes() const;

  /// Seconds spent binning in the last particleToGrid.
  double lastBinningSeconds() const { return binningSeconds_; }

 private:
  void bin(const MpmParticles& particles, std::size_t materialCount);
  // Moves the node data of the runs from their packed places to the whole
  // grid's, zeroing what they leave (a whole-grid index is never below the
  // packed one).
  void unpack();
  // Row (j, k) of the active box, as runFirst_ and rowOrigin_ count them.
  std::size_t activeRow(int j, int k) const {
    return std::size_t(j - activeLo_.j) + std::size_t(activeHi_.j - activeLo_.j) * std::size_t(k - activeLo_.k);
  }
  // Sets rowOrigin_ (and, packed, packedCount_) for the runs of the active box.
  void placeRuns();
  void zeroBox(Index3 lo, Index3 hi);
  // Zeroes the node data of the runs (activeRun) of the active box.
  void zeroRuns();
  // Whole grid: zeroes the node data of the previous runs (of box [lo, hi))
  // outside the current ones and hands back the pages that hold nothing of
  // those.
  void releaseOutsideRuns(Index3 lo, Index3 hi, const std::vector<std::int32_t>& first,
                          const std::vector<std::int32_t>& end);
  // Packed: hands back the node data past the runs, up to `was` nodes (the
  // previous runs').
  void releasePackedTail(std::size_t was);
  // Runs rowFn(bj, bk) on every row of bins of the active box, in the nine
  // colours of disjoint nodes (grid.cpp).
  template <typename RowFn>
  void forEachRow(const RowFn& rowFn) const;
  // Surface tension: the colour field and the capillary stress per particle
  // (sigma: N/m per material, 0 for none).
  void computeCapillaryStress(const MpmParticles& particles, const std::vector<double>& sigma);

  GridSpec spec_;
  Index3 baseDims_{0, 0, 0};
  PageArray<MpmNode> nodes_;
  PageArray<Vec3d> velocity_;
  PageArray<double> colour_;      // surface tension: colour field per node (reserved when first needed)
  std::vector<Mat3d> capillary_;  // surface tension: capillary Cauchy stress per particle, Pa
  std::function<void(double*, std::size_t)> colourSum_;  // setColourSum
  Index3 activeLo_{0, 0, 0}, activeHi_{0, 0, 0};
  bool wholeLayout_ = true;  // setWholeLayout
  bool wholeGrid_ = false;  // activateWholeGrid since the last P2G: the caller writes the whole grid
  // The node runs of the active box's rows (activeRun), and those of the
  // previous P2G (handed back where the new ones do not reach).
  std::vector<std::int32_t> runFirst_, runEnd_, prevRunFirst_, prevRunEnd_;
  // Per row of the active box: node (i, j, k) of its run lies at
  // rowOrigin_[row] + i of the node arrays (packed or whole).
  std::vector<std::ptrdiff_t> rowOrigin_;
  bool packed_ = false;          // the node arrays hold the runs packed (setWholeLayout(false))
  std::size_t packedCount_ = 0;  // packed: the nodes of the runs, from the arrays' start
  // Binning scratch. Bins are stencil base nodes; each row of bins of the
  // box in use, [binLo_, binLo_ + binDims_), gets slots for its bins from
  // the first to the last holding particles: bins [rowFirst_, rowEnd_) of
  // row r (bi, grid indices) are offsets_[rowStart_[r] ...].
  std::size_t binIndex(std::uint64_t packed) const {
    const std::size_t bi = std::size_t(packed & 0x1FFFFF);
    const std::size_t bj = std::size_t((packed >> 21) & 0x1FFFFF) - std::size_t(binLo_.j);
    const std::size_t bk = std::size_t(packed >> 42) - std::size_t(binLo_.k);
    const std::size_t row = bj + std::size_t(binDims_.j) * bk;
    return rowStart_[row] + (bi - rowFirst_[row]);
  }
  Index3 binLo_{0, 0, 0}, binDims_{0, 0, 0};
  std::vector<std::uint32_t> rowFirst_, rowEnd_;  // per row of bins of the box
  std::vector<std::size_t> rowStart_;             // per row + 1: first offset slot
  // Per row of bins of the whole grid (baseDims_ j x k), filled by pass 1:
  // baseDims_.i - first and end of the bins holding particles (0: none);
  // zero between calls (read back and reset within the box), used as atomics.
  PageArray<std::uint32_t> rowLow_, rowHigh_;
  std::vector<std::uint64_t> key_;   // per particle: base node, 21 bits per axis
  std::vector<std::uint32_t> rank_;  // at each run's first particle: its place in its bin (scheduling-dependent)
  std::vector<std::uint32_t> offsets_;  // per slot + 1: the bins' first places in sorted_
  std::vector<std::uint32_t> sorted_;   // particle indices grouped by bin, ascending within a bin
  double binningSeconds_ = 0;
};

}  // namespace mpm
}  // namespace lodestone
