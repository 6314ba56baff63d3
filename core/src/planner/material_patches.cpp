#include "lodestone/core/planner/material_patches.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace planner {

namespace {
struct Box {
  std::array<int, 3> lo, hi;  // node indices, inclusive
  std::size_t first;          // the group's first point
  bool meets(const Box& o) const {
    for (int a = 0; a < 3; ++a)
      if (hi[a] < o.lo[a] || o.hi[a] < lo[a]) return false;
    return true;
  }
  void add(const Box& o) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], o.lo[a]);
      hi[a] = std::max(hi[a], o.hi[a]);
    }
    first = std::min(first, o.first);
  }
};

std::size_t findRoot(std::vector<std::size_t>& parent, std::size_t a) {
  while (parent[a] != a) a = parent[a] = parent[parent[a]];
  return a;
}
}  // namespace

MaterialPatches findMaterialPatches(const GridSpec& grid, const Vec3d* x, std::size_t count, int pad) {
  require(pad >= 1, "material patches: pad must be at least 1 cell, got ", pad);
  require(count > 0 && x, "material patches: no points");
  // Cells of edge `pad` cells holding points, with their points' node boxes.
  const auto cellKey = [](long i, long j, long k) {
    return (std::uint64_t(i + (1 << 20)) << 42) | (std::uint64_t(j + (1 << 20)) << 21) | std::uint64_t(k + (1 << 20));
  };
  std::unordered_map<std::uint64_t, std::size_t> cellOf;
  std::vector<std::array<long, 3>> cellIndex;
  std::vector<Box> cellBox;
  std::vector<std::size_t> pointCell(count);
  // Points come in runs of one cell (the particles are kept sorted by cell):
  // the last cell found is tried before the hash.
  std::uint64_t lastKey = 0;
  std::size_t lastCell = 0;
  for (std::size_t p = 0; p < count; ++p) {
    std::array<double, 3> u;
    std::array<long, 3> c;
    for (int a = 0; a < 3; ++a) {
      u[a] = (x[p][a] - grid.origin[a]) / grid.dx;
      require(std::isfinite(u[a]), "material patches: point ", p, " is not finite");
      c[a] = long(std::floor(std::clamp(u[a], -1e6, 1e6) / pad));
    }
    Box b;
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = std::max(0, int(std::floor(u[a])) - pad);
      b.hi[a] = std::min(grid.dims[a] - 1, int(std::ceil(u[a])) + pad);
    }
    b.first = p;
    const std::uint64_t key = cellKey(c[0], c[1], c[2]);
    if (p == 0 || key != lastKey) {
      const auto [it, fresh] = cellOf.emplace(key, cellBox.size());
      if (fresh) {
        cellIndex.push_back(c);
        cellBox.push_back(b);
      } else {
        cellBox[it->second].add(b);
      }
      lastKey = key;
      lastCell = it->second;
    } else {
      cellBox[lastCell].add(b);
    }
    pointCell[p] = lastCell;
  }
  // Touching cells are one group.
  std::vector<std::size_t> parent(cellBox.size());
  std::iota(parent.begin(), parent.end(), std::size_t(0));
  for (std::size_t c = 0; c < cellIndex.size(); ++c)
    for (long dk = -1; dk <= 1; ++dk)
      for (long dj = -1; dj <= 1; ++dj)
        for (long di = -1; di <= 1; ++di) {
          const auto it = cellOf.find(cellKey(cellIndex[c][0] + di, cellIndex[c][1] + dj, cellIndex[c][2] + dk));
          if (it == cellOf.end()) continue;
          const std::size_t a = findRoot(parent, c), b = findRoot(parent, it->second);
          if (a != b) parent[std::max(a, b)] = std::min(a, b);
        }
  std::vector<std::size_t> groupOfCell(cellBox.size());
  std::vector<Box> groups;
  std::unordered_map<std::size_t, std::size_t> groupOfRoot;
  for (std::size_t c = 0; c < cellBox.size(); ++c) {
    const auto [it, fresh] = groupOfRoot.emplace(findRoot(parent, c), groups.size());
    if (fresh)
      groups.push_back(cellBox[c]);
    else
      groups[it->second].add(cellBox[c]);
    groupOfCell[c] = it->second;
  }
  // Groups whose widened boxes share a node become one, until none do.
  std::vector<std::size_t> merged(groups.size());
  std::iota(merged.begin(), merged.end(), std::size_t(0));
  for (bool again = true; again;) {
    again = false;
    for (std::size_t a = 0; a < groups.size(); ++a)
      for (std::size_t b = a + 1; b < groups.size(); ++b)
        if (merged[a] == a && merged[b] == b && groups[a].meets(groups[b])) {
          groups[a].add(groups[b]);
          merged[b] = a;
          again = true;
        }
  }
  const auto finalGroup = [&](std::size_t g) {
    while (merged[g] != g) g = merged[g];
    return g;
  };
  std::vector<std::size_t> kept;
  for (std::size_t g = 0; g < groups.size(); ++g)
    if (merged[g] == g) kept.push_back(g);
  std::sort(kept.begin(), kept.end(), [&](std::size_t a, std::size_t b) { return groups[a].first < groups[b].first; });
  std::vector<std::uint32_t> patchOfGroup(groups.size());
  MaterialPatches out;
  for (std::size_t n = 0; n < kept.size(); ++n) {
    const Box& b = groups[kept[n]];
    GridSpec g;
    g.dx = grid.dx;
    g.origin = grid.nodePosition(b.lo[0], b.lo[1], b.lo[2]);
    g.dims = {b.hi[0] - b.lo[0] + 1, b.hi[1] - b.lo[1] + 1, b.hi[2] - b.lo[2] + 1};
    out.grids.push_back(g);
    patchOfGroup[kept[n]] = std::uint32_t(n);
  }
  out.patchOf.resize(count);
  for (std::size_t p = 0; p < count; ++p) out.patchOf[p] = patchOfGroup[finalGroup(groupOfCell[pointCell[p]])];
  return out;
}

}  // namespace planner
}  // namespace lodestone
