// The MPM grid's storage: construction, and the nodes and bins zeroed or
// handed back to the system as the rows of nodes the material reaches move
// (mpm/grid.h). The transfers are in grid.cpp, the binning in
// grid_binning.cpp.
#include "lodestone/core/mpm/grid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "grid_kernels.h"
#include "lodestone/core/base/bspline.h"

#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace mpm {

MpmGrid::MpmGrid(const GridSpec& spec) : spec_(spec) {
  spec_.validate("MPM grid");
  require(spec_.dims.i >= 3 && spec_.dims.j >= 3 && spec_.dims.k >= 3,
          "MPM grid: a quadratic B-spline stencil needs at least 3 nodes per axis, got ", spec_.dims.i, " x ",
          spec_.dims.j, " x ", spec_.dims.k);
  baseDims_ = {spec_.dims.i - 2, spec_.dims.j - 2, spec_.dims.k - 2};
  const std::size_t nb = std::size_t(baseDims_.i) * std::size_t(baseDims_.j) * std::size_t(baseDims_.k);
  require(nb < std::size_t(kBadKey), "MPM grid: ", nb, " stencil bins is too many (at most 2^32 - 2)");
  require(spec_.dims.i < (1 << 21) && spec_.dims.j < (1 << 21) && spec_.dims.k < (1 << 21),
          "MPM grid: at most 2^21 - 1 nodes per axis");
  // Reserved, not yet backed by memory: pages are taken as P2G first writes them.
  nodes_ = PageArray<MpmNode>(spec_.nodeCount());
  velocity_ = PageArray<Vec3d>(spec_.nodeCount());
  rowLow_ = PageArray<std::uint32_t>(std::size_t(baseDims_.j) * std::size_t(baseDims_.k));
  rowHigh_ = PageArray<std::uint32_t>(std::size_t(baseDims_.j) * std::size_t(baseDims_.k));
}

MpmGrid::MpmGrid(MpmGrid&&) noexcept = default;
MpmGrid& MpmGrid::operator=(MpmGrid&&) noexcept = default;
MpmGrid::~MpmGrid() = default;

void MpmGrid::zeroBox(Index3 lo, Index3 hi) {
  if (lo.i >= hi.i || lo.j >= hi.j || lo.k >= hi.k) return;
  const std::size_t rows = std::size_t(hi.j - lo.j) * std::size_t(hi.k - lo.k);
  const int nj = hi.j - lo.j;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows, 16), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t row = r.begin(); row != r.end(); ++row) {
      const int j = lo.j + int(row % std::size_t(nj));
      const int k = lo.k + int(row / std::size_t(nj));
      const std::size_t first = spec_.index(lo.i, j, k);
      std::fill(nodes_.begin() + std::ptrdiff_t(first), nodes_.begin() + std::ptrdiff_t(first + (hi.i - lo.i)),
                MpmNode{});
      std::fill(velocity_.begin() + std::ptrdiff_t(first), velocity_.begin() + std::ptrdiff_t(first + (hi.i - lo.i)),
                Vec3d{});
      // The colour's Hessian reads neighbours outside the runs, which must read 0.
      if (!colour_.empty())
        std::fill(colour_.begin() + std::ptrdiff_t(first), colour_.begin() + std::ptrdiff_t(first + (hi.i - lo.i)),
                  0.0);
    }
  });
}

int mpmStencilBase(const GridSpec& spec, double x, int axis) {
  const double u = (x - spec.origin[axis]) / spec.dx;
  return int(std::clamp(quadraticBaseFloor(u), 0.0, double(spec.dims[axis] - 3)));
}

namespace {

bool emptyBox(Index3 lo, Index3 hi) { return lo.i >= hi.i || lo.j >= hi.j || lo.k >= hi.k; }

// Zeroes the pieces [i0, i1) of each row (j, k) of box [lo, hi) that
// `zeroRow(j, k, zero)` passes to zero(i0, i1), in an array over the whole
// grid `spec` (x fastest); `keep(j, k, f, e)` gives the run [f, e) of row
// (j, k) whose pages must stay. Contiguous runs are merged, and since every
// element outside what is kept is zero or about to be, a page holding
// nothing kept goes back to the system whole.
template <typename T, typename ZeroRow, typename Keep>
void zeroRowPieces(PageArray<T>& a, const GridSpec& spec, Index3 lo, Index3 hi, const ZeroRow& zeroRow,
                   const Keep& keep) {
  if (a.empty() || emptyBox(lo, hi)) return;
  const std::size_t rowLength = std::size_t(spec.dims.i), plane = rowLength * std::size_t(spec.dims.j);
  const std::size_t keptCount = spec.nodeCount();
  // Whether elements [e0, e1) all lie outside what is kept.
  const auto outsideKeep = [&](std::size_t e0, std::size_t e1) {
    e1 = std::min(e1, keptCount);
    for (std::size_t e = e0; e < e1;) {
      const std::size_t i = e % rowLength, j = (e / rowLength) % std::size_t(spec.dims.j), k = e / plane;
      const std::size_t rowEnd = std::min(e1, e - i + rowLength);
      const int iLo = int(i), iHi = iLo + int(rowEnd - e);
      int f = 0, l = 0;
      keep(int(j), int(k), f, l);
      if (f < l && iLo < l && iHi > f) return false;
      e = rowEnd;
    }
    return true;
  };
  std::size_t runStart = 0, runEnd = 0;  // pending run [runStart, runEnd)
  const auto flush = [&] { a.zeroPages(runStart, runEnd - runStart, outsideKeep); };
  const auto zero = [&](std::size_t first, std::size_t count) {
    if (count == 0) return;
    if (first == runEnd) {
      runEnd += count;
      return;
    }
    flush();
    runStart = first;
    runEnd = first + count;
  };
  for (int k = lo.k; k < hi.k; ++k)
    for (int j = lo.j; j < hi.j; ++j) {
      const std::size_t row = spec.index(0, j, k);
      zeroRow(j, k, [&](int i0, int i1) {
        if (i1 > i0) zero(row + std::size_t(i0), std::size_t(i1 - i0));
      });
    }
  flush();
}

// Distinct pages that runs of elements of `elementBytes` bytes take, the
// runs given in increasing memory order.
class PageCount {
 public:
  PageCount(std::size_t elementBytes, std::size_t pageBytes) : element_(elementBytes), page_(pageBytes) {}
  // Elements [first, end) of the array.
  void add(std::size_t first, std::size_t end) {
    if (end <= first) return;
    std::size_t p0 = first * element_ / page_;
    const std::size_t p1 = (end * element_ - 1) / page_;
    if (any_ && p0 <= last_) p0 = last_ + 1;
    if (p1 >= p0) pages_ += double(p1 - p0 + 1);
    if (!any_ || p1 > last_) last_ = p1;
    any_ = true;
  }
  double bytes() const { return pages_ * double(page_); }

 private:
  std::size_t element_, page_, last_ = 0;
  bool any_ = false;
  double pages_ = 0;
};

}  // namespace

double mpmHeldBytes(const GridSpec& spec, Index3 binLo, int nbj, int nbk, const std::uint32_t* rowFirst,
                    const std::uint32_t* rowEnd, const std::int32_t* runFirst, const std::int32_t* runEnd,
                    bool colour, bool packed) {
  const std::size_t page = PageMapping::pageSize();
  PageCount nodes(sizeof(MpmNode), page), velocity(sizeof(Vec3d), page), colourField(sizeof(double), page);
  double binCount = 0;
  for (std::size_t row = 0; row < std::size_t(nbj) * std::size_t(nbk); ++row)
    if (rowEnd[row] > rowFirst[row]) binCount += double(rowEnd[row] - rowFirst[row]);
  const int nj = nbj + 2, nk = nbk + 2;
  std::size_t packedAt = 0;  // packed: where the next run starts
  for (int kk = 0; kk < nk; ++kk)
    for (int jj = 0; jj < nj; ++jj) {
      const std::size_t q = std::size_t(jj) + std::size_t(nj) * std::size_t(kk);
      if (runEnd[q] <= runFirst[q]) continue;
      const std::size_t first = packed ? packedAt : spec.index(runFirst[q], binLo.j + jj, binLo.k + kk);
      const std::size_t end = first + std::size_t(runEnd[q] - runFirst[q]);
      packedAt = end;
      nodes.add(first, end);
      velocity.add(first, end);
      if (colour) colourField.add(first, end);
    }
  return nodes.bytes() + velocity.bytes() + colourField.bytes() + 4 * binCount + 40.0 * double(nj) * double(nk);
}

double MpmGrid::heldBytes() const {
  if (binDims_.j <= 0 || binDims_.k <= 0 || runFirst_.empty()) return 0;
  return mpmHeldBytes(spec_, binLo_, binDims_.j, binDims_.k, rowFirst_.data(), rowEnd_.data(), runFirst_.data(),
                      runEnd_.data(), !colour_.empty(), packed_);
}

void MpmGrid::placeRuns() {
  packedCount_ = 0;
  if (!packed_) {
    const int nj = activeHi_.j - activeLo_.j;
    const std::size_t rows = emptyBox(activeLo_, activeHi_) ? 0 : std::size_t(nj) * std::size_t(activeHi_.k - activeLo_.k);
    rowOrigin_.resize(rows);
    for (std::size_t row = 0; row < rows; ++row)
      rowOrigin_[row] = std::ptrdiff_t(
          spec_.index(0, activeLo_.j + int(row % std::size_t(nj)), activeLo_.k + int(row / std::size_t(nj))));
    return;
  }
  const std::size_t rows = runFirst_.size();
  rowOrigin_.resize(rows);
  std::size_t at = 0;
  for (std::size_t row = 0; row < rows; ++row) {
    rowOrigin_[row] = std::ptrdiff_t(at) - std::ptrdiff_t(runFirst_[row]);
    if (runEnd_[row] > runFirst_[row]) at += std::size_t(runEnd_[row] - runFirst_[row]);
  }
  packedCount_ = at;
}

void MpmGrid::zeroRuns() {
  if (packed_) {
    const std::size_t n = packedCount_;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
      std::fill(nodes_.begin() + std::ptrdiff_t(r.begin()), nodes_.begin() + std::ptrdiff_t(r.end()), MpmNode{});
      std::fill(velocity_.begin() + std::ptrdiff_t(r.begin()), velocity_.begin() + std::ptrdiff_t(r.end()), Vec3d{});
    });
    return;
  }
  const std::size_t rows = runFirst_.size();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows, 16), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t row = r.begin(); row != r.end(); ++row) {
      const int first = runFirst_[row], end = runEnd_[row];
      if (first >= end) continue;
      const std::size_t at = std::size_t(rowOrigin_[row] + first);
      std::fill(nodes_.begin() + std::ptrdiff_t(at), nodes_.begin() + std::ptrdiff_t(at + std::size_t(end - first)),
                MpmNode{});
      std::fill(velocity_.begin() + std::ptrdiff_t(at),
                velocity_.begin() + std::ptrdiff_t(at + std::size_t(end - first)), Vec3d{});
    }
  });
}

void MpmGrid::releasePackedTail(std::size_t was) {
  if (was <= packedCount_) return;
  nodes_.zero(packedCount_, was - packedCount_);
  velocity_.zero(packedCount_, was - packedCount_);
  if (!colour_.empty()) colour_.zero(packedCount_, was - packedCount_);
}

void MpmGrid::releaseOutsideRuns(Index3 lo, Index3 hi, const std::vector<std::int32_t>& first,
                                 const std::vector<std::int32_t>& end) {
  if (emptyBox(lo, hi)) return;
  const int nj = hi.j - lo.j;
  const auto keep = [&](int j, int k, int& f, int& e) { activeRun(j, k, f, e); };
  // The previous run of each row less the current one (up to two pieces).
  const auto zeroRow = [&](int j, int k, const auto& zero) {
    const std::size_t row = std::size_t(j - lo.j) + std::size_t(nj) * std::size_t(k - lo.k);
    const int a = first[row], b = end[row];
    if (a >= b) return;
    int c = 0, d = 0;
    activeRun(j, k, c, d);
    if (c >= d) {
      zero(a, b);
      return;
    }
    zero(a, std::min(b, c));
    zero(std::max(a, d), b);
  };
  zeroRowPieces(nodes_, spec_, lo, hi, zeroRow, keep);
  zeroRowPieces(velocity_, spec_, lo, hi, zeroRow, keep);
  zeroRowPieces(colour_, spec_, lo, hi, zeroRow, keep);
}

void MpmGrid::setWholeLayout(bool whole) {
  wholeLayout_ = whole;
  if (whole && packed_) unpack();
}

void MpmGrid::unpack() {
  // Node (i, j, k) moves from its packed index to spec_.index(i, j, k),
  // never lower (the packed runs of the rows before it are at most the
  // whole rows before it): walking the runs from the last node down, each
  // node is read before anything lands on it. The packed places left keep
  // their pages (zero) until the arrays are cleared.
  const Index3 lo = activeLo_, hi = activeHi_;
  packed_ = false;
  packedCount_ = 0;
  if (emptyBox(lo, hi)) return;
  const int nj = hi.j - lo.j;
  const bool colour = !colour_.empty();
  for (int k = hi.k - 1; k >= lo.k; --k)
    for (int j = hi.j - 1; j >= lo.j; --j) {
      const std::size_t row = std::size_t(j - lo.j) + std::size_t(nj) * std::size_t(k - lo.k);
      const std::ptrdiff_t origin = rowOrigin_[row];
      rowOrigin_[row] = std::ptrdiff_t(spec_.index(0, j, k));
      for (int i = runEnd_[row] - 1; i >= runFirst_[row]; --i) {
        const std::size_t s = std::size_t(origin + i), d = spec_.index(i, j, k);
        if (s == d) continue;
        nodes_[d] = nodes_[s];
        nodes_[s] = MpmNode{};
        velocity_[d] = velocity_[s];
        velocity_[s] = Vec3d{};
        if (colour) {
          colour_[d] = colour_[s];
          colour_[s] = 0.0;
        }
      }
    }
}

}  // namespace mpm
}  // namespace lodestone
