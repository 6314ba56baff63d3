#include "lodestone/core/field/magnetostatic_problem.h"
#include "lodestone/core/field/wall_clearance.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "lodestone/core/base/coloured_scatter.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/kept_capacity.h"
#include "lodestone/core/base/parallel.h"
#include "lodestone/core/field/element_build.h"
#include "lodestone/core/field/langevin_batch.h"
#include "lodestone/core/field/multipole_blocks.h"
#include "lodestone/core/field/open_wall_lattice.h"
#include "lodestone/core/field/open_wall_sum.h"
#include "lodestone/core/field/q1_element.h"
#include "lodestone/core/field/q1_stencil.h"

namespace lodestone {
inline namespace field {

namespace {
constexpr q1::Tables kQ1 = q1::makeTables();

struct EnergyTotals {
  double energy = 0, energyAbs = 0;
  bool finite = true;
  EnergyTotals& operator+=(const EnergyTotals& o) {
    energy += o.energy;
    energyAbs += o.energyAbs;
    finite = finite && o.finite;
    return *this;
  }
};

struct EnergySums {
  double s = 0, a = 0;
  EnergySums& operator+=(const EnergySums& o) {
    s += o.s;
    a += o.a;
    return *this;
  }
};
}  // namespace

MagnetostaticProblem::MagnetostaticProblem(const GridSpec& grid, const MagnetizationLaw<double>& law,
                                           BoundaryKind boundary)
    : grid_(grid), law_(law), boundary_(boundary) {
  grid_.validate("field-solve grid");
  require(boundary != BoundaryKind::Open || (grid.dims.i >= 3 && grid.dims.j >= 3 && grid.dims.k >= 3),
          "field-solve grid: the open boundary needs at least 3 nodes per axis, got ", grid.dims.i, " x ",
          grid.dims.j, " x ", grid.dims.k);
  cornerOffsets(grid_, cornerOffset_);
}

std::size_t MagnetostaticProblem::freeNodeCount() const {
  if (boundary_ == BoundaryKind::Shield) return grid_.nodeCount();
  return std::size_t(grid_.dims.i - 2) * std::size_t(grid_.dims.j - 2) * std::size_t(grid_.dims.k - 2);
}

Vec3d MagnetostaticProblem::cellOrigin(std::size_t base) const {
  const std::size_t nx = std::size_t(grid_.dims.i), ny = std::size_t(grid_.dims.j);
  const int i = int(base % nx), j = int((base / nx) % ny), k = int(base / (nx * ny));
  return grid_.nodePosition(i, j, k);
}

void MagnetostaticProblem::gatherCorners(std::size_t base, const double* v, double c[8]) const {
  for (int n = 0; n < 8; ++n) c[n] = v[base + cornerOffset_[n]];
}

void MagnetostaticProblem::setMaterial(GridView<const double> n, const AppliedFieldFunction& appliedField,
                                       bool sameAppliedField) {
  // Gauss points' values are kept only from a call that completed.
  const bool keep = sameAppliedField && haveAppliedField_;
  haveAppliedField_ = false;
  require(n.spec == grid_, "field solve: the density grid does not match the solver grid");
  require(bool(appliedField), "field solve: no applied-field function given");
  const std::size_t count = grid_.nodeCount();
  // First bad density by index (deterministic message).
  const std::size_t bad = firstIndexWhere(count, [&](std::size_t m) { return !(std::isfinite(n[m]) && n[m] >= 0); },
                                           std::size_t(1) << 14);
  if (bad < count) {
    const std::size_t nx = std::size_t(grid_.dims.i), ny = std::size_t(grid_.dims.j);
    throw InvalidArgument(concat("field solve: micro-particle density n at node (", bad % nx, ", ",
                                 (bad / nx) % ny, ", ", bad / (nx * ny), ") is ", n[bad],
                                 " 1/m^3; it must be finite and >= 0"));
  }

  // The previous cells: their Gauss points' applied field stays in hext_
  // (keep), and their multipole blocks stay while the cells do.
  std::vector<std::size_t>& oldBase = previousCellBase_;
  oldBase.swap(cellBase_);
  const bool hadBlocks = haveBlocks_;
  haveBlocks_ = false;
  std::size_t oldStart[9] = {};
  std::copy(colourStart_, colourStart_ + 9, oldStart);

  // Material cells per z-slab and colour, concatenated in slab order.
  const Index3 cd = grid_.cellDims();
  std::vector<std::vector<std::size_t>> slabs(std::size_t(cd.k) * 8);
  tbb::parallel_for(0, cd.k, [&](int k) {
    for (int j = 0; j < cd.j; ++j)
      for (int i = 0; i < cd.i; ++i) {
        const std::size_t base = grid_.index(i, j, k);
        bool any = false;
        for (int c = 0; c < 8 && !any; ++c) any = n[base + cornerOffset_[c]] > 0;
        if (any) slabs[std::size_t(k) * 8 + std::size_t(cellColour(i, j, k))].push_back(base);
      }
  });
  cellBase_.clear();
  for (int colour = 0; colour < 8; ++colour) {
    colourStart_[colour] = cellBase_.size();
    for (int k = 0; k < cd.k; ++k) {
      const auto& s = slabs[std::size_t(k) * 8 + std::size_t(colour)];
      cellBase_.insert(cellBase_.end(), s.begin(), s.end());
    }
  }
  colourStart_[8] = cellBase_.size();
  const std::size_t cells = cellBase_.size();
  const bool cellsUnchanged = hadBlocks && oldBase == cellBase_;
  // The per-cell arrays keep their storage from one call to the next.
  // (nq_ and hextOut are written whole below.)
  resizeKeepingCapacity(nq_, cells * 8);
  // The same cells as before (the material stayed in its cells): the kept
  // values stay where they are; otherwise each kept cell's values move to
  // its new slot in the spare buffer, which then becomes hext_.
  const bool sameCells = keep && cellsUnchanged;
  std::vector<Vec3d>& hextOut = keep ? hextSpare_ : hext_;
  if (!sameCells) resizeKeepingCapacity(hextOut, cells * 8);
  if (!stencil_.sameCells(grid_, cellBase_.data(), cells)) stencil_.build(grid_, cellBase_.data(), cells);
  stencil_.clear();

  // Each kept cell's slot in the previous lists: within a colour both list
  // their cells by ascending base index.
  constexpr std::size_t kFresh = std::numeric_limits<std::size_t>::max();
  std::vector<std::size_t> oldSlot;
  if (keep && !sameCells) {
    oldSlot.assign(cells, kFresh);
    tbb::parallel_for(0, 8, [&](int c) {
      std::size_t a = oldStart[c], s = colourStart_[c];
      while (a < oldStart[c + 1] && s < colourStart_[c + 1]) {
        if (oldBase[a] < cellBase_[s]) {
          ++a;
        } else if (cellBase_[s] < oldBase[a]) {
          ++s;
        } else {
          oldSlot[s++] = a++;
        }
      }
    });
  }

  const double h = grid_.dx;
  std::atomic<std::size_t> evaluated{0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<Vec3d> x;
    x.reserve(r.size() * 8);
    std::vector<std::size_t> fresh;  // cells of r evaluated now (keep only)
    for (std::size_t s = r.begin(); s != r.end(); ++s) {
      double nc[8];
      gatherCorners(cellBase_[s], n.data, nc);
      for (int q = 0; q < 8; ++q) nq_[s * 8 + std::size_t(q)] = q1::interpolate(kQ1, q, nc);
      if (sameCells) continue;
      if (keep) {
        if (oldSlot[s] != kFresh) {
          std::copy_n(&hext_[oldSlot[s] * 8], 8, &hextOut[s * 8]);
          continue;
        }
        fresh.push_back(s);
      }
      const Vec3d o = cellOrigin(cellBase_[s]);
      for (int q = 0; q < 8; ++q)
        x.push_back(o + h * Vec3d{q1::gaussAbscissa(q & 1), q1::gaussAbscissa((q >> 1) & 1),
                                  q1::gaussAbscissa((q >> 2) & 1)});
    }
    evaluated += x.size() / 8;
    if (!keep) {
      appliedField(x.data(), x.size(), &hextOut[r.begin() * 8]);
    } else if (!x.empty()) {
      std::vector<Vec3d> H(x.size());
      appliedField(x.data(), x.size(), H.data());
      for (std::size_t f = 0; f < fresh.size(); ++f) std::copy_n(&H[f * 8], 8, &hextOut[fresh[f] * 8]);
    }
  });
  cellsEvaluated_ = evaluated;
  if (keep && !sameCells) hext_.swap(hextSpare_);
  // Written whole by every evaluate(..., true).
  resizeKeepingCapacity(elem_, cells * kPacked);
  resizeKeepingCapacity(cellTensor_, cells);
  if (const std::size_t m = firstIndexWhere(cells * 8, [&](std::size_t g) { return !isFinite(hext_[g]); });
      m < cells * 8)
    throw InvalidArgument(concat("field solve: the applied field is not finite at (", cellOrigin(cellBase_[m / 8]).x,
                                 ", ", cellOrigin(cellBase_[m / 8]).y, ", ", cellOrigin(cellBase_[m / 8]).z, ") m"));
  haveAppliedField_ = true;

  // Clearance to the wall, total count and centroid.
  wallClearance_ = lodestone::materialWallClearance(grid_, cellBase_.data(), cells);
  const double w = grid_.cellVolume() / 8.0;
  struct Moments {
    double count = 0;
    Vec3d first;
    Moments& operator+=(const Moments& o) {
      count += o.count;
      first += o.first;
      return *this;
    }
  };
  const Moments mom = deterministicSum<Moments>(cells, [&](std::size_t s) {
    Moments m;
    const Vec3d o = cellOrigin(cellBase_[s]);
    for (int q = 0; q < 8; ++q) {
      const double nw = w * nq_[s * 8 + std::size_t(q)];
      m.count += nw;
      m.first += nw * (o + h * Vec3d{q1::gaussAbscissa(q & 1), q1::gaussAbscissa((q >> 1) & 1),
                                     q1::gaussAbscissa((q >> 2) & 1)});
    }
    return m;
  }, 256);
  totalCount_ = mom.count;
  centroid_ = mom.count > 0 ? mom.first / mom.count : 0.5 * (grid_.origin + grid_.maxCorner());

  // Multipole blocks (multipole_blocks.h), sorted by (block, slot) so the
  // per-block sums have a fixed order.
  // The same cells (hence the same clearance and block edge) keep their
  // blocks; only the centres, which follow the density, are recomputed.
  const int edge = multipoleBlockEdgeFor(wallClearance_);
  if (!cellsUnchanged || edge != blockEdge_) {
    blockEdge_ = edge;
    sortCellsIntoBlocks();
  }
  const std::size_t blocks = blockStart_.size() - 1;
  blockCentre_.assign(blocks, Vec3d{});
  tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
    double c = 0;
    Vec3d first{}, geo{};
    for (std::size_t m = blockStart_[b]; m < blockStart_[b + 1]; ++m) {
      const std::size_t sl = blockCells_[m];
      const Vec3d o = cellOrigin(cellBase_[sl]) + Vec3d{0.5 * h, 0.5 * h, 0.5 * h};
      double nc = 0;
      for (int q = 0; q < 8; ++q) nc += nq_[sl * 8 + std::size_t(q)];
      c += nc;
      first += nc * o;
      geo += o;
    }
    blockCentre_[b] = c > 0 ? first / c : geo / double(blockStart_[b + 1] - blockStart_[b]);
  });
  // Each cell's offset from its block's centre, for the second moments
  // (evaluate, linearizedMultipoles).
  cellFromCentre_.resize(cells);
  tbb::parallel_for(std::size_t(0), cells, [&](std::size_t s) {
    cellFromCentre_[s] = cellOrigin(cellBase_[s]) - blockCentre_[cellBlock_[s]];
  });
  haveBlocks_ = true;
}

void MagnetostaticProblem::sortCellsIntoBlocks() {
  // Cells by (block key, slot): one 64-bit word each (key above, slot
  // below), sorted as plain integers, which is the same order.
  const std::size_t cells = cellBase_.size();
  const MultipoleBlockTiling tiling(grid_.cellDims(), blockEdge_);
  require(tiling.keyCount() < (std::uint64_t(1) << 32) && cells < (std::size_t(1) << 32),
          "field solve: ", cells, " material cells in ", tiling.keyCount(), " multipole blocks is too many to sort");
  std::vector<std::uint64_t> order(cells);
  const std::size_t nx = std::size_t(grid_.dims.i), ny = std::size_t(grid_.dims.j);
  parallelForEach(cells, [&](std::size_t s) {
    const std::size_t b = cellBase_[s];
    order[s] = (tiling.key(int(b % nx), int((b / nx) % ny), int(b / (nx * ny))) << 32) | std::uint64_t(s);
  });
  tbb::parallel_sort(order.begin(), order.end());
  blockCells_.resize(cells);
  blockStart_.clear();
  cellBlock_.assign(cells, 0);
  for (std::size_t m = 0; m < cells; ++m) {
    const std::size_t s = std::size_t(order[m] & 0xffffffffu);
    if (m == 0 || (order[m] >> 32) != (order[m - 1] >> 32)) blockStart_.push_back(m);
    blockCells_[m] = s;
    cellBlock_[s] = std::uint32_t(blockStart_.size() - 1);
  }
  blockStart_.push_back(cells);
}

template <typename CellFn>
void MagnetostaticProblem::scatterCells(double* out, const CellFn& cellFn) const {
  scatterByColour(cellBase_.data(), colourStart_, cornerOffset_, out, cellFn);
}

void MagnetostaticProblem::applyVacuum(const double* v, double* out) const {
  applyQ1Laplacian(grid_, boundary_, v, out);
}

void MagnetostaticProblem::zeroFixed(double* v) const { zeroFixedNodes(grid_, boundary_, v); }

void MagnetostaticProblem::removeMean(double* v) const {
  const std::size_t count = grid_.nodeCount();
  const double mean = deterministicSum<double>(count, [&](std::size_t m) { return v[m]; }) / double(count);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t m = r.begin(); m != r.end(); ++m) v[m] -= mean;
  });
}

// ---------------------------------------------------------------------------
// Material terms.

MagnetostaticProblem::Evaluation MagnetostaticProblem::evaluate(const double* phi, double* F, bool jacobian,
                                                                const double* vacuumPart) {
  if (vacuumPart == F) {
    // F holds the vacuum part already.
  } else if (vacuumPart) {
    const std::size_t count = grid_.nodeCount();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1 << 14),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        std::copy(vacuumPart + r.begin(), vacuumPart + r.end(), F + r.begin());
                      });
  } else {
    applyVacuum(phi, F);
  }
  const double h = grid_.dx, w = grid_.cellVolume() / 8.0, fScale = h * h / 8.0;
  std::vector<CellSums>& sums = sums_;
  resizeKeepingCapacity(sums, cellBase_.size());  // every cell's sums are written before they are read
  scatterCells(F, [&](std::size_t s, double local[8]) {
    double pc[8];
    gatherCorners(cellBase_[s], phi, pc);
    // grad phi at the 8 Gauss points by sum factorization: the x-derivative
    // is the edge difference along x interpolated in y and z (it does not
    // depend on the x abscissa), likewise for y and z.
    double gradient[8][3];
    q1::gaussGradients(pc, gradient);
    CellSums& cs = sums[s];
    cs = CellSums{};
    double* E = &elem_[s * kPacked];
    SymMat3d tensorSum;
    Vec3d upper[3];  // sum of w M over the Gauss points with bit a set (the upper abscissa on axis a)
    double Mq[8][3];
    Vec3d Hq[8];
    for (int q = 0; q < 8; ++q) {
      const std::size_t g = s * 8 + std::size_t(q);
      Hq[q] = {hext_[g].x - gradient[q][0] / h, hext_[g].y - gradient[q][1] / h, hext_[g].z - gradient[q][2] / h};
    }
    ResponseBatch rb;
    respondBatch(law_, &nq_[s * 8], Hq, rb);
    for (int q = 0; q < 8; ++q) {
      struct {
        Vec3d M, h;
        double iso, rank1, W;
      } r{{rb.Mx[q], rb.My[q], rb.Mz[q]}, {rb.hx[q], rb.hy[q], rb.hz[q]}, rb.iso[q], rb.rank1[q], rb.W[q]};
      if (jacobian) tensorSum += SymMat3d::identityPlusOuter(r.iso, r.rank1, r.h);
      cs.finite = cs.finite && isFinite(r.M) && std::isfinite(r.W) && std::isfinite(r.iso) && std::isfinite(r.rank1);
      cs.energy += w * r.W;
      cs.energyAbs += w * std::fabs(r.W);
      const Vec3d mw = w * r.M;
      cs.multipole.dipole += mw;
      for (int axis = 0; axis < 3; ++axis)
        if ((q >> axis) & 1) upper[axis] += mw;
      Mq[q][0] = r.M.x;
      Mq[q][1] = r.M.y;
      Mq[q][2] = r.M.z;
    }
    if (jacobian) {
      // Element matrix (dx/8) sum_q dN_q^T (iso I + rank1 h h^T) dN_q, packed.
      buildElementMatrix(h, rb, E);
      tensorSum *= 0.125;
      cellTensor_[s] = tensorSum;
    }
    // Second moment about the block centre.
    cs.multipole = cellMultipole(cs.multipole.dipole, upper, cellFromCentre_[s], h);
    // Residual -fScale sum_q dN_qc . M_q, the transpose of the gradient.
    double res[8];
    q1::gaussDivergenceTranspose(Mq, res);
    for (int c = 0; c < 8; ++c) local[c] -= fScale * res[c];
  });
  zeroFixed(F);
  if (jacobian) stencil_.assemble(elem_.data());
  const EnergyTotals total = deterministicSum<EnergyTotals>(
      sums.size(), [&](std::size_t s) { return EnergyTotals{sums[s].energy, sums[s].energyAbs, sums[s].finite}; },
      256);
  Evaluation e;
  e.materialEnergy = total.energy;
  e.materialEnergyAbs = total.energyAbs;
  e.finite = total.finite;
  e.multipoles.resize(blockCentre_.size());
  tbb::parallel_for(std::size_t(0), blockCentre_.size(), [&](std::size_t b) {
    Multipole mp;
    mp.centre = blockCentre_[b];
    for (std::size_t m = blockStart_[b]; m < blockStart_[b + 1]; ++m) mp += sums[blockCells_[m]].multipole;
    e.multipoles[b] = mp;
  });
  return e;
}

void MagnetostaticProblem::residualAtZero(double* F0) const {
  std::fill(F0, F0 + grid_.nodeCount(), 0.0);
  const double fScale = grid_.dx * grid_.dx / 8.0;
  scatterCells(F0, [&](std::size_t s, double local[8]) {
    // The batched response of the cell's 8 Gauss points (vectorized where
    // the CPU allows), of which only M is used.
    ResponseBatch rb;
    respondBatch(law_, &nq_[s * 8], &hext_[s * 8], rb);
    double Mq[8][3];
    for (int q = 0; q < 8; ++q) {
      Mq[q][0] = rb.Mx[q];
      Mq[q][1] = rb.My[q];
      Mq[q][2] = rb.Mz[q];
    }
    double res[8];
    q1::gaussDivergenceTranspose(Mq, res);
    for (int c = 0; c < 8; ++c) local[c] -= fScale * res[c];
  });
  zeroFixed(F0);
}

void MagnetostaticProblem::applyJacobian(const double* v, double* out) const {
  applyVacuum(v, out);
  stencil_.addProduct(v, out);
  zeroFixed(out);
}

double MagnetostaticProblem::applyJacobianDot(const double* v, double* out) const {
  const int nx = grid_.dims.i, ny = grid_.dims.j, nz = grid_.dims.k;
  const bool open = boundary_ == BoundaryKind::Open;
  rowSums_.resize(std::size_t(ny) * std::size_t(nz));
  tbb::parallel_for(tbb::blocked_range<int>(0, nz, 1), [&](const tbb::blocked_range<int>& kr) {
    for (int k = kr.begin(); k != kr.end(); ++k)
      for (int j = 0; j < ny; ++j) {
        const std::size_t row = grid_.index(0, j, k);
        double* o = out + row;
        const double* x = v + row;
        double& sum = rowSums_[std::size_t(j) + std::size_t(ny) * std::size_t(k)];
        sum = 0;
        if (open && (j == 0 || k == 0 || j == ny - 1 || k == nz - 1)) {
          std::fill(o, o + nx, 0.0);  // a wall row: fixed nodes only
          continue;
        }
        applyQ1LaplacianRow(grid_, boundary_, j, k, v, out);
        // The material rows on this row's hull; for Open its end nodes are fixed.
        const int lo = stencil_.lo(j, k), hi = stencil_.hi(j, k);
        const int from = open ? std::max(lo, 1) : lo, to = open ? std::min(hi, nx - 1) : hi;
        stencil_.addRow(j, k, from, to, x, o);
        if (open) o[0] = o[nx - 1] = 0.0;
        for (int i = 0; i < nx; ++i) sum += x[i] * o[i];
      }
  });
  double total = 0;
  for (const double r : rowSums_) total += r;
  return total;
}

void MagnetostaticProblem::jacobianDiagonal(double* out) const {
  q1LaplacianDiagonalAll(grid_, out);
  stencil_.addDiagonal(out);
  setFixedNodes(grid_, boundary_, 1.0, out);  // fixed rows: identity
}

double MagnetostaticProblem::materialEnergyAlong(const double* phi, const double* delta, double lambda,
                                                 double* absSum) const {
  const double h = grid_.dx, w = grid_.cellVolume() / 8.0;
  const EnergySums e = deterministicSum<EnergySums>(cellBase_.size(), [&](std::size_t s) {
    double pc[8], dc[8];
    gatherCorners(cellBase_[s], phi, pc);
    gatherCorners(cellBase_[s], delta, dc);
    EnergySums r;
    for (int q = 0; q < 8; ++q) {
      const std::size_t g = s * 8 + std::size_t(q);
      const Vec3d H = hext_[g] - (q1::referenceGradient(kQ1, q, pc) + lambda * q1::referenceGradient(kQ1, q, dc)) / h;
      const double W = w * coEnergy(law_, nq_[g], H);
      r.s += W;
      r.a += std::fabs(W);
    }
    return r;
  }, 256);
  if (absSum) *absSum = e.a;
  return e.s;
}

std::vector<Multipole> MagnetostaticProblem::linearizedMultipoles(const double* dphi) const {
  const double h = grid_.dx, w = grid_.cellVolume() / 8.0;
  std::vector<Multipole> out(blockCentre_.size());
  tbb::parallel_for(std::size_t(0), blockCentre_.size(), [&](std::size_t b) {
    Multipole& mp = out[b];
    mp.centre = blockCentre_[b];
    for (std::size_t m = blockStart_[b]; m < blockStart_[b + 1]; ++m) {
      const std::size_t s = blockCells_[m];
      double pc[8];
      gatherCorners(cellBase_[s], dphi, pc);
      double gradient[8][3];
      q1::gaussGradients(pc, gradient);
      // sum_q w dH_q and the same over the Gauss points with bit a set; dM
      // is linear in dH with the cell's constant tensor.
      Vec3d all, upper[3];
      for (int q = 0; q < 8; ++q) {
        const Vec3d dH{-gradient[q][0] / h, -gradient[q][1] / h, -gradient[q][2] / h};
        all += dH;
        for (int axis = 0; axis < 3; ++axis)
          if ((q >> axis) & 1) upper[axis] += dH;
      }
      const SymMat3d& T = cellTensor_[s];
      const Vec3d dip = w * (T * all);
      Vec3d up[3];
      for (int a = 0; a < 3; ++a) up[a] = w * (T * upper[a]);
      mp += cellMultipole(dip, up, cellFromCentre_[s], h);
    }
  });
  return out;
}

void MagnetostaticProblem::applyOpenBoundary(const std::vector<Multipole>& multipoles, double* phi) const {
  if (boundary_ != BoundaryKind::Open) return;
  // The far-field potential is smooth on the wall on the scale of the
  // material's clearance, so it is summed on a lattice of wall nodes and
  // interpolated in between (open_wall_lattice.h).
  const OpenWallLattice lattice(grid_, wallClearance_);
  const auto forWallNodes = [&](const auto& fn) {
    tbb::parallel_for(0, grid_.dims.k, [&](int k) { grid_.forEachBoundaryNodeOfLayer(k, fn); });
  };
  const OpenWallSum farField(multipoles, grid_, blockEdge_, wallClearance_, lattice);
  farField.forEachSum([&](std::size_t node, double value) { phi[node] = value / (4.0 * kPi); });
  // Off-lattice wall nodes: interpolated between the lattice nodes around them.
  forWallNodes([&](int i, int j, int k) {
    if (lattice.onLattice(i, j, k)) return;
    phi[grid_.index(i, j, k)] =
        lattice.interpolate(i, j, k, [&](int p, int q, int r) { return phi[grid_.index(p, q, r)]; });
  });
}

std::vector<std::size_t> MagnetostaticProblem::fixedNodes() const {
  std::vector<std::size_t> out;
  if (boundary_ != BoundaryKind::Open) return out;
  out.reserve(grid_.nodeCount() - freeNodeCount());
  grid_.forEachBoundaryNode([&](int i, int j, int k) { out.push_back(grid_.index(i, j, k)); });
  return out;
}

void MagnetostaticProblem::addWallCoupling(const double* v, double* out) const {
  if (boundary_ != BoundaryKind::Open) return;
  const int nx = grid_.dims.i, ny = grid_.dims.j, nz = grid_.dims.k;
  // Row (i, j, k) of K restricted to the wall columns. Free rows are
  // interior rows: face neighbours weigh 0, edge neighbours -dx/6, corner
  // neighbours -dx/12 (q1_stencil.h), and the centre is never on the wall.
  // A neighbour is on the wall when one of its coordinates is; the three
  // per-axis tests are made once per row, not per neighbour.
  const double weight[4] = {0.0, 0.0, -grid_.dx / 6.0, -grid_.dx / 12.0};
  const std::ptrdiff_t sy = nx, sz = std::ptrdiff_t(nx) * ny;
  const auto row = [&](int i, int j, int k) {
    bool wi[3], wj[3], wk[3];
    for (int o = 0; o < 3; ++o) {
      wi[o] = i + o - 1 == 0 || i + o - 1 == nx - 1;
      wj[o] = j + o - 1 == 0 || j + o - 1 == ny - 1;
      wk[o] = k + o - 1 == 0 || k + o - 1 == nz - 1;
    }
    const double* centre = v + grid_.index(i, j, k);
    double sum = 0;
    for (int c = -1; c <= 1; ++c)
      for (int b = -1; b <= 1; ++b)
        for (int a = -1; a <= 1; ++a) {
          const int order = (a != 0) + (b != 0) + (c != 0);
          if (order >= 2 && (wi[a + 1] || wj[b + 1] || wk[c + 1])) sum += weight[order] * centre[a + sy * b + sz * c];
        }
    return sum;
  };
  tbb::parallel_for(1, nz - 1, [&](int k) {
    for (int j = 1; j < ny - 1; ++j) {
      const bool shellRow = k == 1 || k == nz - 2 || j == 1 || j == ny - 2;
      for (int i = 1; i < nx - 1; i += (shellRow || i == nx - 2) ? 1 : nx - 3) out[grid_.index(i, j, k)] += row(i, j, k);
    }
  });
}

}  // namespace field
}  // namespace lodestone
