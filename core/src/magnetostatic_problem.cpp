#include "lodestone/core/magnetostatic_problem.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lodestone/core/error.h"
#include "lodestone/core/parallel.h"
#include "lodestone/core/q1_element.h"

namespace lodestone {

namespace {
constexpr q1::Tables kQ1 = q1::makeTables();

// Per-cell partial sums of evaluate(), reduced deterministically afterwards.
struct CellSums {
  double energy = 0, energyAbs = 0;
  Multipole multipole;
  bool finite = true;
  CellSums& operator+=(const CellSums& o) {
    energy += o.energy;
    energyAbs += o.energyAbs;
    multipole += o.multipole;
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

const char* toString(BoundaryKind kind) {
  switch (kind) {
    case BoundaryKind::Open: return "open";
    case BoundaryKind::Shield: return "shield";
  }
  return "unknown";
}

MagnetostaticProblem::MagnetostaticProblem(const GridSpec& grid, const MagnetizationLaw<double>& law,
                                           BoundaryKind boundary)
    : grid_(grid), law_(law), boundary_(boundary) {
  grid_.validate("field-solve grid");
  require(boundary != BoundaryKind::Open || (grid.dims.i >= 3 && grid.dims.j >= 3 && grid.dims.k >= 3),
          "field-solve grid: the open boundary needs at least 3 nodes per axis, got ", grid.dims.i, " x ",
          grid.dims.j, " x ", grid.dims.k);
  for (int c = 0; c < 8; ++c)
    cornerOffset_[c] = grid_.index(c & 1, (c >> 1) & 1, (c >> 2) & 1);
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

void MagnetostaticProblem::setMaterial(GridView<const double> n, const AppliedFieldFunction& appliedField) {
  require(n.spec == grid_, "field solve: the density grid does not match the solver grid");
  require(bool(appliedField), "field solve: no applied-field function given");
  const std::size_t count = grid_.nodeCount();
  // First bad density by index (deterministic message).
  const std::size_t bad = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, count, 1 << 14), count,
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t first) {
        for (std::size_t m = r.begin(); m != r.end() && m < first; ++m)
          if (!(std::isfinite(n[m]) && n[m] >= 0)) return m;
        return first;
      },
      [](std::size_t a, std::size_t b) { return std::min(a, b); });
  if (bad < count) {
    const std::size_t nx = std::size_t(grid_.dims.i), ny = std::size_t(grid_.dims.j);
    throw InvalidArgument(concat("field solve: micro-particle density n at node (", bad % nx, ", ",
                                 (bad / nx) % ny, ", ", bad / (nx * ny), ") is ", n[bad],
                                 " 1/m^3; it must be finite and >= 0"));
  }

  // Material cells per z-slab and colour, concatenated in slab order.
  const Index3 cd = grid_.cellDims();
  std::vector<std::vector<std::size_t>> slabs(std::size_t(cd.k) * 8);
  tbb::parallel_for(0, cd.k, [&](int k) {
    for (int j = 0; j < cd.j; ++j)
      for (int i = 0; i < cd.i; ++i) {
        const std::size_t base = grid_.index(i, j, k);
        bool any = false;
        for (int c = 0; c < 8 && !any; ++c) any = n[base + cornerOffset_[c]] > 0;
        if (any) slabs[std::size_t(k) * 8 + std::size_t((i & 1) | ((j & 1) << 1) | ((k & 1) << 2))].push_back(base);
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
  nq_.assign(cells * 8, 0.0);
  hext_.assign(cells * 8, Vec3d{});
  jac_.assign(cells * 8, SymMat3d{});

  const double h = grid_.dx;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<Vec3d> x(r.size() * 8);
    for (std::size_t s = r.begin(); s != r.end(); ++s) {
      double nc[8];
      gatherCorners(cellBase_[s], n.data, nc);
      const Vec3d o = cellOrigin(cellBase_[s]);
      for (int q = 0; q < 8; ++q) {
        nq_[s * 8 + std::size_t(q)] = q1::interpolate(kQ1, q, nc);
        x[(s - r.begin()) * 8 + std::size_t(q)] =
            o + h * Vec3d{q1::gaussAbscissa(q & 1), q1::gaussAbscissa((q >> 1) & 1), q1::gaussAbscissa((q >> 2) & 1)};
      }
    }
    appliedField(x.data(), x.size(), &hext_[r.begin() * 8]);
  });
  for (std::size_t m = 0; m < cells * 8; ++m)
    if (!isFinite(hext_[m]))
      throw InvalidArgument(concat("field solve: the applied field is not finite at (",
                                   cellOrigin(cellBase_[m / 8]).x, ", ", cellOrigin(cellBase_[m / 8]).y, ", ",
                                   cellOrigin(cellBase_[m / 8]).z, ") m"));

  // Clearance to the wall, total count and centroid.
  wallClearance_ = 1 << 30;
  for (std::size_t s = 0; s < cells; ++s) {
    const std::size_t b = cellBase_[s], nx = std::size_t(grid_.dims.i), ny = std::size_t(grid_.dims.j);
    const int i = int(b % nx), j = int((b / nx) % ny), k = int(b / (nx * ny));
    wallClearance_ = std::min({wallClearance_, i, j, k, cd.i - 1 - i, cd.j - 1 - j, cd.k - 1 - k});
  }
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

  // Multipole blocks: cells grouped by (i, j, k) / kMultipoleBlock, sorted by
  // (block, slot) so the per-block sums have a fixed order.
  const int bx = (cd.i + kMultipoleBlock - 1) / kMultipoleBlock, by = (cd.j + kMultipoleBlock - 1) / kMultipoleBlock;
  std::vector<std::uint64_t> key(cells);
  tbb::parallel_for(std::size_t(0), cells, [&](std::size_t s) {
    const std::size_t b = cellBase_[s], nx = std::size_t(grid_.dims.i), ny = std::size_t(grid_.dims.j);
    const std::uint64_t i = b % nx / kMultipoleBlock, j = (b / nx) % ny / kMultipoleBlock,
                        k = b / (nx * ny) / kMultipoleBlock;
    key[s] = i + std::uint64_t(bx) * (j + std::uint64_t(by) * k);
  });
  blockCells_.resize(cells);
  std::iota(blockCells_.begin(), blockCells_.end(), std::size_t(0));
  std::sort(blockCells_.begin(), blockCells_.end(),
            [&](std::size_t a, std::size_t b) { return key[a] != key[b] ? key[a] < key[b] : a < b; });
  blockStart_.clear();
  cellBlock_.assign(cells, 0);
  for (std::size_t m = 0; m < cells; ++m) {
    if (m == 0 || key[blockCells_[m]] != key[blockCells_[m - 1]]) blockStart_.push_back(m);
    cellBlock_[blockCells_[m]] = std::uint32_t(blockStart_.size() - 1);
  }
  blockStart_.push_back(cells);
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
}

template <typename CellFn>
void MagnetostaticProblem::scatterCells(double* out, const CellFn& cellFn) const {
  for (int colour = 0; colour < 8; ++colour) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(colourStart_[colour], colourStart_[colour + 1], 128),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t s = r.begin(); s != r.end(); ++s) {
                          double local[8] = {0, 0, 0, 0, 0, 0, 0, 0};
                          cellFn(s, local);
                          const std::size_t base = cellBase_[s];
                          for (int c = 0; c < 8; ++c) out[base + cornerOffset_[c]] += local[c];
                        }
                      });
  }
}

// ---------------------------------------------------------------------------
// Vacuum Laplacian: the Q1 stiffness K = dx (k x m x m + m x k x m + m x m x k)
// with 1D stiffness k = [-1 2 -1] and mass m = [1/6 4/6 1/6] (halved at walls).
// Interior rows: centre 8/3, face 0, edge -1/6, corner -1/12 (times dx).

namespace {
struct Axis1D {
  double k[3], m[3];
};
inline Axis1D axisWeights(int p, int count) {
  const bool left = p > 0, right = p < count - 1;
  const double cells = double(left) + double(right);
  return {{left ? -1.0 : 0.0, cells, right ? -1.0 : 0.0},
          {left ? 1.0 / 6 : 0.0, cells * (2.0 / 6), right ? 1.0 / 6 : 0.0}};
}
}  // namespace

double MagnetostaticProblem::vacuumDiagonal(int i, int j, int k) const {
  const Axis1D x = axisWeights(i, grid_.dims.i), y = axisWeights(j, grid_.dims.j), z = axisWeights(k, grid_.dims.k);
  return grid_.dx * (x.k[1] * y.m[1] * z.m[1] + x.m[1] * y.k[1] * z.m[1] + x.m[1] * y.m[1] * z.k[1]);
}

double MagnetostaticProblem::vacuumRowGeneral(int i, int j, int k, const double* v) const {
  const Axis1D x = axisWeights(i, grid_.dims.i), y = axisWeights(j, grid_.dims.j), z = axisWeights(k, grid_.dims.k);
  double s = 0;
  for (int c = -1; c <= 1; ++c) {
    if (z.m[c + 1] == 0) continue;
    for (int b = -1; b <= 1; ++b) {
      if (y.m[b + 1] == 0) continue;
      for (int a = -1; a <= 1; ++a) {
        if (x.m[a + 1] == 0) continue;
        const double wgt = x.k[a + 1] * y.m[b + 1] * z.m[c + 1] + x.m[a + 1] * y.k[b + 1] * z.m[c + 1] +
                           x.m[a + 1] * y.m[b + 1] * z.k[c + 1];
        s += wgt * v[grid_.index(i + a, j + b, k + c)];
      }
    }
  }
  return grid_.dx * s;
}

void MagnetostaticProblem::applyVacuum(const double* v, double* out) const {
  const int nx = grid_.dims.i, ny = grid_.dims.j, nz = grid_.dims.k;
  const std::ptrdiff_t sy = nx, sz = std::ptrdiff_t(nx) * ny;
  const double h = grid_.dx, cC = h * 8.0 / 3.0, cE = -h / 6.0, cK = -h / 12.0;
  const bool shield = boundary_ == BoundaryKind::Shield;
  tbb::parallel_for(tbb::blocked_range<int>(0, nz, 1), [&](const tbb::blocked_range<int>& kr) {
    for (int k = kr.begin(); k != kr.end(); ++k)
      for (int j = 0; j < ny; ++j) {
        const std::size_t row = grid_.index(0, j, k);
        const bool wallRow = k == 0 || k == nz - 1 || j == 0 || j == ny - 1;
        if (wallRow) {
          for (int i = 0; i < nx; ++i) out[row + std::size_t(i)] = shield ? vacuumRowGeneral(i, j, k, v) : 0.0;
          continue;
        }
        out[row] = shield ? vacuumRowGeneral(0, j, k, v) : 0.0;
        out[row + std::size_t(nx - 1)] = shield ? vacuumRowGeneral(nx - 1, j, k, v) : 0.0;
        const double* p = v + row;
        for (int i = 1; i < nx - 1; ++i) {
          const double* c = p + i;
          // 12 edge neighbours and 8 corner neighbours; face neighbours weigh 0.
          const double edges = c[1 + sy] + c[1 - sy] + c[-1 + sy] + c[-1 - sy] + c[1 + sz] + c[1 - sz] +
                               c[-1 + sz] + c[-1 - sz] + c[sy + sz] + c[sy - sz] + c[-sy + sz] + c[-sy - sz];
          const double corners = c[1 + sy + sz] + c[1 + sy - sz] + c[1 - sy + sz] + c[1 - sy - sz] +
                                 c[-1 + sy + sz] + c[-1 + sy - sz] + c[-1 - sy + sz] + c[-1 - sy - sz];
          out[row + std::size_t(i)] = cC * c[0] + cE * edges + cK * corners;
        }
      }
  });
}

void MagnetostaticProblem::zeroFixed(double* v) const {
  if (boundary_ == BoundaryKind::Shield) return;
  const int nx = grid_.dims.i, ny = grid_.dims.j, nz = grid_.dims.k;
  tbb::parallel_for(0, nz, [&](int k) {
    for (int j = 0; j < ny; ++j) {
      const std::size_t row = grid_.index(0, j, k);
      if (k == 0 || k == nz - 1 || j == 0 || j == ny - 1) {
        std::fill(v + row, v + row + std::size_t(nx), 0.0);
      } else {
        v[row] = 0.0;
        v[row + std::size_t(nx - 1)] = 0.0;
      }
    }
  });
}

void MagnetostaticProblem::removeMean(double* v) const {
  const std::size_t count = grid_.nodeCount();
  const double mean = deterministicSum<double>(count, [&](std::size_t m) { return v[m]; }) / double(count);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t m = r.begin(); m != r.end(); ++m) v[m] -= mean;
  });
}

// ---------------------------------------------------------------------------
// Material terms.

MagnetostaticProblem::Evaluation MagnetostaticProblem::evaluate(const double* phi, double* F) {
  applyVacuum(phi, F);
  const double h = grid_.dx, w = grid_.cellVolume() / 8.0, fScale = h * h / 8.0, jScale = h / 8.0;
  std::vector<CellSums> sums(cellBase_.size());
  scatterCells(F, [&](std::size_t s, double local[8]) {
    double pc[8];
    gatherCorners(cellBase_[s], phi, pc);
    const Vec3d o = cellOrigin(cellBase_[s]);
    CellSums& cs = sums[s];
    for (int q = 0; q < 8; ++q) {
      const std::size_t g = s * 8 + std::size_t(q);
      const Vec3d H = hext_[g] - q1::referenceGradient(kQ1, q, pc) / h;
      const MagnetizationResponse<double> r = respond(law_, nq_[g], H);
      SymMat3d jq = r.dMdH;
      jq *= jScale;
      jac_[g] = jq;
      cs.finite = cs.finite && isFinite(r.M) && std::isfinite(r.W) && std::isfinite(jq.trace());
      cs.energy += w * r.W;
      cs.energyAbs += w * std::fabs(r.W);
      const Vec3d mw = w * r.M;
      cs.multipole.dipole += mw;
      const Vec3d xq = o + h * Vec3d{q1::gaussAbscissa(q & 1), q1::gaussAbscissa((q >> 1) & 1),
                                     q1::gaussAbscissa((q >> 2) & 1)} - blockCentre_[cellBlock_[s]];
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) cs.multipole.quadrupole[a][b] += mw[a] * xq[b];
      for (int c = 0; c < 8; ++c) local[c] -= fScale * dot(kQ1.dN[q][c], r.M);
    }
  });
  zeroFixed(F);
  const CellSums total = deterministicSum<CellSums>(sums.size(), [&](std::size_t s) { return sums[s]; }, 256);
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
    for (int q = 0; q < 8; ++q) {
      const std::size_t g = s * 8 + std::size_t(q);
      const Vec3d M = magnetization(law_, nq_[g], hext_[g]);
      for (int c = 0; c < 8; ++c) local[c] -= fScale * dot(kQ1.dN[q][c], M);
    }
  });
  zeroFixed(F0);
}

void MagnetostaticProblem::applyJacobian(const double* v, double* out) const {
  applyVacuum(v, out);
  scatterCells(out, [&](std::size_t s, double local[8]) {
    double vc[8];
    gatherCorners(cellBase_[s], v, vc);
    for (int q = 0; q < 8; ++q) {
      const Vec3d y = jac_[s * 8 + std::size_t(q)] * q1::referenceGradient(kQ1, q, vc);
      for (int c = 0; c < 8; ++c) local[c] += dot(kQ1.dN[q][c], y);
    }
  });
  zeroFixed(out);
}

void MagnetostaticProblem::jacobianDiagonal(double* out) const {
  const int nx = grid_.dims.i, ny = grid_.dims.j, nz = grid_.dims.k;
  tbb::parallel_for(0, nz, [&](int k) {
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) out[grid_.index(i, j, k)] = vacuumDiagonal(i, j, k);
  });
  scatterCells(out, [&](std::size_t s, double local[8]) {
    for (int q = 0; q < 8; ++q) {
      const SymMat3d& A = jac_[s * 8 + std::size_t(q)];
      for (int c = 0; c < 8; ++c) local[c] += dot(kQ1.dN[q][c], A * kQ1.dN[q][c]);
    }
  });
  if (boundary_ == BoundaryKind::Open) {
    // Fixed rows: identity.
    tbb::parallel_for(0, nz, [&](int k) {
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i)
          if (grid_.isBoundaryNode(i, j, k)) out[grid_.index(i, j, k)] = 1.0;
    });
  }
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

void MagnetostaticProblem::applyOpenBoundary(const std::vector<Multipole>& multipoles, double* phi) const {
  if (boundary_ != BoundaryKind::Open) return;
  const int nx = grid_.dims.i, ny = grid_.dims.j, nz = grid_.dims.k;
  tbb::parallel_for(0, nz, [&](int k) {
    for (int j = 0; j < ny; ++j) {
      const bool wallRow = k == 0 || k == nz - 1 || j == 0 || j == ny - 1;
      for (int i = 0; i < nx; i += (wallRow || i == nx - 1) ? 1 : nx - 1)
      {
        const Vec3d x = grid_.nodePosition(i, j, k);
        double v = 0;
        for (const Multipole& mp : multipoles) v += mp.potential(x);
        phi[grid_.index(i, j, k)] = v;
      }
    }
  });
}

}  // namespace lodestone
