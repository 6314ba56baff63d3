// The open wall's far field through the tree of block clusters (OpenWallSum)
// against the source itself: a voxelized ball of point dipoles (one per
// cell), grouped into the solve's multipole blocks. The tree's error at any
// wall node, over the sum of the dipoles' term magnitudes there, stays within
// the blocks' own worst (which the nearest wall node already accepts), while
// it sums fewer expansions; a mirror-symmetric body gets a mirror-symmetric
// wall.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/field/multipole_blocks.h"
#include "lodestone/core/field/open_wall_sum.h"

using namespace lodestone;

namespace {

struct Source {
  GridSpec grid;
  std::vector<Vec3d> x, m;        // cell centres (m) and their dipoles (A m^2)
  std::vector<Multipole> blocks;  // the cells grouped as the solve groups them
  int clearance = 0, edge = 0;    // cells
};

// A ball of radius a (cells) centred at c (cells from the origin) on an
// n-node grid, magnetization M(x) (A/m) per cell.
template <typename Magnetization>
Source ball(int n, double a, Vec3d c, const Magnetization& M) {
  Source s;
  s.grid.dx = 0.01;
  s.grid.dims = {n, n, n};
  const double dx = s.grid.dx, V = dx * dx * dx;
  int lo = n, hi = 0;
  std::map<std::uint64_t, std::vector<std::size_t>> byBlock;
  std::vector<Index3> cells;
  for (int k = 0; k < n - 1; ++k)
    for (int j = 0; j < n - 1; ++j)
      for (int i = 0; i < n - 1; ++i) {
        const Vec3d u{i + 0.5, j + 0.5, k + 0.5};
        if (norm2(u - c) >= a * a) continue;
        lo = std::min({lo, i, j, k});
        hi = std::max({hi, i + 1, j + 1, k + 1});
        const Vec3d x = dx * u;
        s.x.push_back(x);
        s.m.push_back(V * M(x));
        cells.push_back({i, j, k});
      }
  s.clearance = std::min(lo, n - 1 - hi);
  s.edge = multipoleBlockEdgeFor(s.clearance);
  const MultipoleBlockTiling tiling(s.grid.cellDims(), s.edge);
  for (std::size_t q = 0; q < cells.size(); ++q) byBlock[tiling.key(cells[q].i, cells[q].j, cells[q].k)].push_back(q);
  for (const auto& entry : byBlock) {
    Multipole b;
    for (std::size_t q : entry.second) b.centre += s.x[q];
    b.centre = b.centre / double(entry.second.size());
    for (std::size_t q : entry.second) {
      b.dipole += s.m[q];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) b.quadrupole[i][j] += s.m[q][i] * (s.x[q] - b.centre)[j];
    }
    s.blocks.push_back(b);
  }
  return s;
}

// 4 pi phi of the point dipoles at x, and the sum of their terms'
// magnitudes |m| / r^2 (the scale an error is measured against: phi itself
// vanishes where the dipoles' terms cancel).
struct Exact {
  double phi = 0, scale = 0;
};
Exact exact(const Source& s, const Vec3d& x) {
  Exact e;
  for (std::size_t q = 0; q < s.x.size(); ++q) {
    const Vec3d r = x - s.x[q];
    const double r2 = norm2(r);
    e.phi += dot(s.m[q], r) / (r2 * std::sqrt(r2));
    e.scale += norm(s.m[q]) / r2;
  }
  return e;
}

// Every `stride`-th lattice node of the wall.
std::vector<Index3> wallNodes(const GridSpec& g, const OpenWallLattice& lattice, int stride) {
  std::vector<Index3> out;
  int count = 0;
  const int n = g.dims.i;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const bool wall = i == 0 || j == 0 || k == 0 || i == n - 1 || j == n - 1 || k == n - 1;
        if (wall && lattice.onLattice(i, j, k) && count++ % stride == 0) out.push_back({i, j, k});
      }
  return out;
}

}  // namespace

TEST(OpenWallSum, StaysWithinTheBlocksWorstErrorWithFewerTerms) {
  // Radius 26 cells in a 96-cell box: clearance 22 cells, blocks of 8, a
  // lattice spacing of 8 (patches of 32 nodes).
  const Source s = ball(97, 26.0, {48, 48, 48}, [](const Vec3d& x) {
    return Vec3d{2e4 * (x.y - 0.48) / 0.2, 0.0, 1e5 * (1.0 + 0.3 * (x.x - 0.48) / 0.2)};
  });
  const OpenWallLattice lattice(s.grid, s.clearance);
  const OpenWallSum tree(s.blocks, s.grid, s.edge, s.clearance, lattice);
  const PackedMultipoles packed(s.blocks);
  double worstBlocks = 0, worstTree = 0;
  for (const Index3& p : wallNodes(s.grid, lattice, 7)) {
    const Vec3d x = s.grid.nodePosition(p.i, p.j, p.k);
    const Exact ref = exact(s, x);
    worstBlocks = std::max(worstBlocks, std::fabs(multipoleSum(packed.arrays(), x) - ref.phi) / ref.scale);
    worstTree = std::max(worstTree, std::fabs(tree.sum(p.i, p.j, p.k) - ref.phi) / ref.scale);
  }
  std::printf("blocks %zu, terms per node %.1f, theta %.3f; worst relative error: blocks %.3g, tree %.3g\n",
              s.blocks.size(), tree.meanTerms(), tree.theta(), worstBlocks, worstTree);
  // A cluster taken at extent / distance <= theta drops an octupole of at
  // most about theta^2 of its terms' magnitude; its moments shifted wrongly
  // would leave first-order terms (with the shift's sign flipped: 1.2e-2).
  // Measured: blocks 2.8e-4, tree 4.8e-4 of the magnitudes, theta = 0.25.
  EXPECT_LT(worstBlocks, 1e-3);
  EXPECT_LT(worstTree, tree.theta() * tree.theta() / 16);
  // The tree took clusters somewhere: fewer terms than the blocks (padded to
  // 4). Measured: 244 against 280.
  EXPECT_LT(tree.meanTerms(), 0.9 * double(packed.arrays().count));
  // Summed at a few nodes only (as a rank of the distributed solve sums
  // those its wall interpolates from), each node gets the same value.
  const std::vector<Index3> few = wallNodes(s.grid, lattice, 97);
  const OpenWallSum some(s.blocks, s.grid, s.edge, s.clearance, lattice, &few);
  for (const Index3& p : few) EXPECT_EQ(some.sum(p.i, p.j, p.k), tree.sum(p.i, p.j, p.k));
  const Index3 other = wallNodes(s.grid, lattice, 1)[1];  // not among the few
  EXPECT_THROW((void)some.sum(other.i, other.j, other.k), InvalidArgument);
}

TEST(OpenWallSum, AMirrorSymmetricBodyGetsAMirrorSymmetricWall) {
  // A ball at the centre magnetized along z: phi is even in x and y. An odd
  // cell count puts the blocks' middle run of one cell on the mid-planes.
  for (int n : {96, 97}) {
    const double c = 0.5 * (n - 1);
    const Source s = ball(n, 22.0, {c, c, c}, [](const Vec3d&) { return Vec3d{0, 0, 1e5}; });
    const OpenWallLattice lattice(s.grid, s.clearance);
    const OpenWallSum tree(s.blocks, s.grid, s.edge, s.clearance, lattice);
    double worst = 0, scale = 0;
    for (const Index3& p : wallNodes(s.grid, lattice, 1)) {
      const double v = tree.sum(p.i, p.j, p.k);
      scale = std::max(scale, std::fabs(v));
      worst = std::max(worst, std::fabs(v - tree.sum(n - 1 - p.i, p.j, p.k)));
      worst = std::max(worst, std::fabs(v - tree.sum(p.i, n - 1 - p.j, p.k)));
    }
    EXPECT_LT(worst, 1e-12 * scale) << n << " nodes per axis";
    EXPECT_LT(tree.meanTerms(), double(s.blocks.size())) << n << " nodes per axis";
  }
}

TEST(OpenWallSum, MergedMultipoleShiftsTheQuadrupoleToTheMeanCentre) {
  // Two dipoles: merged about their midpoint, the expansion equals the sum of
  // the two far away to (s/d)^2 (the dropped octupole), and its quadrupole is
  // m_i (c_b - c)_j summed.
  Multipole a, b;
  a.centre = {0.1, 0, 0};
  a.dipole = {0, 0, 1};
  b.centre = {-0.1, 0, 0};
  b.dipole = {0, 0, -1};
  const Multipole* both[2] = {&a, &b};
  const Multipole m = mergedMultipole(both, 2);
  EXPECT_EQ(m.centre.x, 0.0);
  EXPECT_EQ(m.dipole.z, 0.0);
  EXPECT_NEAR(m.quadrupole[2][0], 0.2, 1e-15);  // 1 * 0.1 + (-1) * (-0.1)
  for (double d : {1.0, 10.0}) {
    const Vec3d x{d, 0.3 * d, 0.5 * d};
    const double sum = a.potential(x) + b.potential(x);
    EXPECT_NEAR(m.potential(x), sum, 3.0 * (0.1 / d) * (0.1 / d) * std::fabs(sum)) << "d = " << d;
  }
}

TEST(OpenWallSum, NamesABadBlockEdgeOrANodeOffTheLattice) {
  GridSpec g;
  g.dx = 0.01;
  g.dims = {33, 33, 33};
  const OpenWallLattice lattice(g, 8);
  EXPECT_THROW(OpenWallSum({}, g, 0, 8, lattice), InvalidArgument);
  const OpenWallSum empty({}, g, 8, 8, lattice);
  EXPECT_EQ(empty.sum(0, 0, 0), 0.0);
  try {
    (void)empty.sum(16, 16, 16);
    FAIL() << "an interior node was summed";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("(16, 16, 16)"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)empty.sum(-1, 0, 0), InvalidArgument);
  const std::vector<Index3> interior{{0, 0, 0}, {16, 16, 16}};
  try {
    const OpenWallSum some({}, g, 8, 8, lattice, &interior);
    FAIL() << "an interior node was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("(16, 16, 16)"), std::string::npos) << e.what();
  }
}

// The lattice's interpolation against the exact potential of the worst
// source, a point dipole at depth d (cells) below a face, normal or
// tangential to it: within 0.6 (s/d)^3 of the face's peak value up to the
// lattice's largest spacing s = 0.4 d, and third order (the error drops by
// more than 6x when s halves; linear interpolation drops by 4x at best).
// Measured: 2.0e-2 and 3.6e-2 at s = 0.4 d, 7.7 to 14x less per halving.
TEST(OpenWallLattice, InterpolatesADipolesWallToThirdOrder) {
  GridSpec g;
  g.dx = 0.01;
  g.dims = {129, 129, 129};
  const double d = 20.0;
  for (const Vec3d m : {Vec3d{0, 0, 1}, Vec3d{1, 0, 0}}) {
    const Vec3d source{64.3, 64.0, -d};  // cells
    const auto phi = [&](int i, int j, int k) {
      const Vec3d r = Vec3d{double(i), double(j), double(k)} - source;
      return dot(m, r) / std::pow(norm2(r), 1.5);
    };
    double previous = 0;
    for (int clearance : {20, 10, 5}) {  // spacings 8, 4, 2
      const OpenWallLattice lattice(g, clearance);
      const int s = lattice.spacing();
      ASSERT_EQ(s, 2 * clearance / 5);
      double worst = 0, peak = 0;
      for (int j = 0; j < g.dims.j; ++j)
        for (int i = 0; i < g.dims.i; ++i) {
          worst = std::max(worst, std::fabs(lattice.interpolate(i, j, 0, phi) - phi(i, j, 0)));
          peak = std::max(peak, std::fabs(phi(i, j, 0)));
        }
      worst /= peak;
      std::printf("dipole (%g, %g, %g), spacing %d: worst error %.3g of the peak\n", m.x, m.y, m.z, s, worst);
      EXPECT_LT(worst, 0.6 * std::pow(s / d, 3)) << "spacing " << s;
      if (previous > 0) {
        EXPECT_GT(previous / worst, 6.0) << "spacing " << s;
      }
      previous = worst;
    }
  }
  // An axis with fewer than 4 lattice nodes interpolates through those it has
  // (a linear function exactly).
  g.dims = {5, 5, 5};
  const OpenWallLattice coarse(g, 10);
  const auto linear = [](int i, int j, int k) { return 1.0 + 2.0 * i - 3.0 * j + 0.5 * k; };
  EXPECT_NEAR(coarse.interpolate(1, 3, 0, linear), linear(1, 3, 0), 1e-12);
}
