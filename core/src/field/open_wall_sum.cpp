#include "lodestone/core/field/open_wall_sum.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>

#include <tbb/parallel_for.h>

#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace field {

Multipole mergedMultipole(const Multipole* const* members, std::size_t count) {
  Multipole c;
  if (count == 0) return c;
  for (std::size_t i = 0; i < count; ++i) c.centre += members[i]->centre;
  c.centre = c.centre / double(count);
  for (std::size_t i = 0; i < count; ++i) {
    const Multipole& m = *members[i];
    const Vec3d shift = m.centre - c.centre;
    c.dipole += m.dipole;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) c.quadrupole[a][b] += m.quadrupole[a][b] + m.dipole[a] * shift[b];
  }
  return c;
}

namespace {

constexpr long kMiddle = 1L << 40, kFromTop = 1L << 41;

// A cluster: its expansion, its extent (m) and its members (indices into
// the level below; none for a block).
struct Cluster {
  Multipole m;
  double extent = 0;
  std::vector<std::uint32_t> members;
};

// The cell of edge `edge` (m) holding coordinate c on an axis spanning
// [lo, hi] (m), counted from the nearer end; within a quarter cell of the
// mid-plane, a middle cell of its own (the blocks' middle run of one cell
// has its centroid there).
long axisCell(double c, double lo, double hi, double edge, double dx) {
  const double mid = 0.5 * (lo + hi);
  if (std::fabs(c - mid) < 0.25 * dx) return kMiddle;
  if (c < mid) return long(std::floor((c - lo) / edge));
  return kFromTop - long(std::floor((hi - c) / edge));
}

// The patch of node coordinate c on an axis of n nodes, `width` nodes a
// patch counted from the nearer end; the middle node of an odd count is a
// patch of its own.
long axisPatch(int c, int n, int width) {
  if (2 * c < n - 1) return c / width;
  if (2 * c > n - 1) return kFromTop - (n - 1 - c) / width;
  return kMiddle;
}

// Squared distance from x to the box [lo, hi], m^2.
double boxDistance2(const Vec3d& x, const Vec3d& lo, const Vec3d& hi) {
  double d2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double d = std::max({lo[a] - x[a], x[a] - hi[a], 0.0});
    d2 += d * d;
  }
  return d2;
}

}  // namespace

OpenWallSum::Key OpenWallSum::patchKey(int i, int j, int k) const {
  return {axisPatch(i, grid_.dims.i, patchNodes_), axisPatch(j, grid_.dims.j, patchNodes_),
          axisPatch(k, grid_.dims.k, patchNodes_)};
}

OpenWallSum::OpenWallSum(const std::vector<Multipole>& blocks, const GridSpec& grid, int blockEdge, int clearance,
                         const OpenWallLattice& lattice, const std::vector<Index3>* only)
    : grid_(grid), patchNodes_(kPatchLattice * lattice.spacing()) {
  require(blockEdge >= 1, "open wall sum: block edge ", blockEdge, " cells is not >= 1");
  const double dx = grid.dx;
  const double halfDiagonal = 0.5 * std::sqrt(3.0) * double(blockEdge) * dx;  // m
  theta_ = std::min(0.25, halfDiagonal / (double(std::max(clearance, 1)) * dx));
  const Vec3d lo = grid.origin, hi = grid.maxCorner();

  // The tree, level by level: the blocks, then 2x2x2 merges down to 8 roots
  // (a level that would merge nothing is skipped) or until a cluster's edge
  // spans the grid twice.
  std::vector<std::vector<Cluster>> level(1);
  for (const Multipole& b : blocks)
    if (!b.empty()) level[0].push_back({b, halfDiagonal, {}});
  const double span = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z, dx});
  for (int L = 1; level.back().size() > 8; ++L) {
    const std::vector<Cluster>& below = level.back();
    const double edge = std::ldexp(double(blockEdge) * dx, L);
    if (edge > 2 * span) break;
    std::map<Key, std::vector<std::uint32_t>> cells;  // ordered: a fixed order
    for (std::uint32_t i = 0; i < below.size(); ++i) {
      const Vec3d& c = below[i].m.centre;
      cells[{axisCell(c.x, lo.x, hi.x, edge, dx), axisCell(c.y, lo.y, hi.y, edge, dx),
             axisCell(c.z, lo.z, hi.z, edge, dx)}]
          .push_back(i);
    }
    if (cells.size() == below.size()) continue;
    std::vector<Cluster> above;
    above.reserve(cells.size());
    std::vector<const Multipole*> members;
    for (auto& entry : cells) {
      members.clear();
      for (std::uint32_t i : entry.second) members.push_back(&below[i].m);
      Cluster c{mergedMultipole(members.data(), members.size()), 0.0, std::move(entry.second)};
      for (std::uint32_t i : c.members)
        c.extent = std::max(c.extent, norm(below[i].m.centre - c.m.centre) + below[i].extent);
      above.push_back(std::move(c));
    }
    level.push_back(std::move(above));
  }

  // The patches: the wall's lattice nodes grouped per kPatchLattice
  // spacings on each axis, each patch's box (m, over all its lattice nodes,
  // so that a patch takes the same clusters whichever of its nodes are
  // summed) and the nodes to sum at.
  struct Patch {
    Vec3d lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    std::vector<Index3> nodes;
  };
  std::vector<Patch> patches;
  std::map<Key, std::size_t> patchOf;
  grid.forEachBoundaryNode([&](int i, int j, int k) {
    if (!lattice.onLattice(i, j, k)) return;
    const auto found = patchOf.emplace(patchKey(i, j, k), patches.size());
    if (found.second) patches.emplace_back();
    Patch& p = patches[found.first->second];
    const Vec3d x = grid.nodePosition(i, j, k);
    for (int a = 0; a < 3; ++a) {
      p.lo[a] = std::min(p.lo[a], x[a]);
      p.hi[a] = std::max(p.hi[a], x[a]);
    }
    if (!only) p.nodes.push_back({i, j, k});
  });
  if (only) {
    for (const Index3& n : *only) {
      const bool onWall = grid.hasNode(n.i, n.j, n.k) && grid.isBoundaryNode(n.i, n.j, n.k);
      require(onWall && lattice.onLattice(n.i, n.j, n.k), "open wall sum: node (", n.i, ", ", n.j, ", ", n.k,
              ") is not on the wall's lattice");
      patches[patchOf.at(patchKey(n.i, n.j, n.k))].nodes.push_back(n);
    }
  }
  patchCount_ = patches.size();

  // Each patch's expansions, depth first from each root, children in order,
  // a cluster taken whole where the patch is at least extent / theta from
  // its centre; packed and summed at the patch's nodes, then dropped.
  std::vector<std::size_t> offset(patches.size() + 1, 0);
  for (std::size_t p = 0; p < patches.size(); ++p) offset[p + 1] = offset[p] + patches[p].nodes.size();
  std::vector<std::pair<std::size_t, double>>& values = sums_;
  values.resize(offset.back());
  std::vector<double> terms(patches.size(), 0.0);
  const int top = int(level.size()) - 1;
  tbb::parallel_for(std::size_t(0), patches.size(), [&](std::size_t p) {
    if (patches[p].nodes.empty()) return;
    std::vector<Multipole> taken;
    std::vector<std::pair<int, std::uint32_t>> stack;
    for (std::uint32_t r = std::uint32_t(level[std::size_t(top)].size()); r-- > 0;) stack.emplace_back(top, r);
    while (!stack.empty()) {
      const auto [L, i] = stack.back();
      stack.pop_back();
      const Cluster& c = level[std::size_t(L)][i];
      const double reach = c.extent / theta_;
      if (L == 0 || boxDistance2(c.m.centre, patches[p].lo, patches[p].hi) >= reach * reach) {
        taken.push_back(c.m);
        continue;
      }
      for (std::size_t m = c.members.size(); m-- > 0;) stack.emplace_back(L - 1, c.members[m]);
    }
    const PackedMultipoles packed(taken);
    // PackedMultipoles pads to 4: the padded terms are summed too.
    terms[p] = double(packed.arrays().count) * double(patches[p].nodes.size());
    for (std::size_t n = 0; n < patches[p].nodes.size(); ++n) {
      const Index3 x = patches[p].nodes[n];
      values[offset[p] + n] = {grid.index(x.i, x.j, x.k),
                               multipoleSum(packed.arrays(), grid.nodePosition(x.i, x.j, x.k))};
    }
  });
  std::sort(values.begin(), values.end());
  double total = 0;
  for (const double t : terms) total += t;
  meanTerms_ = values.empty() ? 0.0 : total / double(values.size());
}

double OpenWallSum::sum(int i, int j, int k) const {
  const bool inside = grid_.hasNode(i, j, k);
  const std::size_t node = inside ? grid_.index(i, j, k) : 0;
  const auto it = std::lower_bound(sums_.begin(), sums_.end(), node,
                                   [](const std::pair<std::size_t, double>& s, std::size_t n) { return s.first < n; });
  require(inside && it != sums_.end() && it->first == node, "open wall sum: node (", i, ", ", j, ", ", k,
          ") is not on the wall's lattice or not among the nodes summed");
  return it->second;
}

}  // namespace field
}  // namespace lodestone
