// Grid memory follows what is written: PageArray takes memory only for the
// pages written and hands them back when zeroed, and the MPM grid's memory
// follows the rows of nodes its particles reach, not the domain's box. Measured on the
// process's resident set (/proc/self/statm), which pages only read do not
// enter. The MPM solver's whole substep is checked the same way.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <vector>

#include "lodestone/core/base/page_array.h"
#include "lodestone/core/mpm/grid.h"
#include "lodestone/core/mpm/material.h"
#include "lodestone/core/mpm/particles.h"
#include "lodestone/core/mpm/solver.h"

using namespace lodestone;

namespace {

double residentMiB() {
  std::ifstream in("/proc/self/statm");
  double size = 0, resident = 0;
  in >> size >> resident;
  return resident * double(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

constexpr double kMiB = 1024.0 * 1024.0;

// Under strict overcommit (vm.overcommit_memory = 2) address space counts
// against the commit limit: the multi-GiB reservations below may be refused.
bool strictOvercommit() {
  std::ifstream in("/proc/sys/vm/overcommit_memory");
  int mode = 0;
  in >> mode;
  return mode == 2;
}

#define LODESTONE_SKIP_UNDER_STRICT_OVERCOMMIT()                                                   \
  if (strictOvercommit()) GTEST_SKIP() << "vm.overcommit_memory = 2: large reservations count " \
                                          "against the commit limit here"

// Under AddressSanitizer the resident set also holds the shadow of what was
// written, which handing pages back does not return: the figures are checked
// in the plain builds only (the values everywhere).
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kResidentSetMeasures = false;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kResidentSetMeasures = false;
#else
constexpr bool kResidentSetMeasures = true;
#endif
#else
constexpr bool kResidentSetMeasures = true;
#endif

}  // namespace

TEST(PageArray, MemoryFollowsThePagesWrittenAndGoesBackWhenZeroed) {
  LODESTONE_SKIP_UNDER_STRICT_OVERCOMMIT();
  const std::size_t n = std::size_t(1) << 30;  // 8 GiB of doubles reserved
  PageArray<double> a(n);
  const double r0 = residentMiB();
  double sum = 0;
  for (std::size_t i = 0; i < n; i += n / 64) sum += a[i];  // reading costs nothing
  EXPECT_EQ(sum, 0.0);
  if (kResidentSetMeasures) {
    EXPECT_LT(residentMiB() - r0, 8.0);
  }
  const std::size_t first = n / 3, count = std::size_t(96 * kMiB) / sizeof(double);  // 96 MiB in the middle
  std::fill(a.begin() + first, a.begin() + first + count, 1.5);
  const double written = residentMiB() - r0;
  a.zero(first + 1, count - 2);  // all but the first and last elements
  if (kResidentSetMeasures) {
    EXPECT_GT(written, 90.0);
    EXPECT_LT(written, 110.0);
    EXPECT_LT(residentMiB() - r0, 8.0);
  }
  EXPECT_EQ(a[first], 1.5);
  EXPECT_EQ(a[first + 1], 0.0);
  EXPECT_EQ(a[first + count / 2], 0.0);
  EXPECT_EQ(a[first + count - 2], 0.0);
  EXPECT_EQ(a[first + count - 1], 1.5);
  EXPECT_EQ(a[first + count], 0.0);
}

TEST(PageArray, ZeroingOutsideTheArrayIsRefused) {
  PageArray<double> a(1000);
  EXPECT_THROW(a.zero(990, 20), InvalidArgument);
}

TEST(MpmGridMemory, ABallCrossingAHugeBoxCostsItsOwnBoxAndNoMore) {
  LODESTONE_SKIP_UNDER_STRICT_OVERCOMMIT();
  // A 641^3-node grid (263M nodes: 15 GiB as dense node, velocity and bin
  // arrays) and a ball of 4,224 particles (radius 5 cells) carried across it
  // over 1,000 P2G calls, 0.4 cell per call along a diagonal: the grid holds
  // the pages of the box the ball reaches and hands back those it leaves.
  const GridSpec g{{0.0, 0.0, 0.0}, 0.01, {641, 641, 641}};
  const double r0 = residentMiB();
  MpmGrid grid(g);
  if (kResidentSetMeasures) {
    EXPECT_LT(residentMiB() - r0, 8.0) << "constructing the grid takes no memory";
  }
  MpmParticles p;
  const double h = g.dx / 2;
  const Vec3d c0{0.2, 0.2, 0.2};
  for (double z = -0.05; z < 0.05; z += h)
    for (double y = -0.05; y < 0.05; y += h)
      for (double x = -0.05; x < 0.05; x += h)
        if (x * x + y * y + z * z < 0.05 * 0.05) p.add(c0 + Vec3d{x, y, z}, {}, 1e-3, h * h * h, 0.0, 0);
  const std::vector<MpmMaterial> mats = {viscousFluid(0.1, 1e5, 1000.0)};
  const Vec3d step{0.004, 0.003, 0.0035};  // m per call
  double atTen = 0, highest = 0;
  for (int s = 0; s < 1000; ++s) {
    grid.particleToGrid(p, mats, 1e-4);
    for (std::size_t q = 0; q < p.size(); ++q) p.x[q] += step;
    const double r = residentMiB() - r0;
    if (s == 10) atTen = r;
    highest = std::max(highest, r);
  }
  const double boxMiB = 14.0 * 14.0 * 14.0 * (sizeof(MpmNode) + sizeof(Vec3d) + 4) / kMiB;
  std::printf("ball crossing a 641^3 grid: %.1f MiB after 10 calls, at most %.1f MiB over 1,000 (its box %.2f MiB)\n",
              atTen, highest, boxMiB);
  EXPECT_GT(grid.activeLo().i, 400) << "the ball crossed the grid";
  // The box's nodes lie on at most 14^2 rows of pages per array; the
  // particles' own arrays and the binning's are the rest.
  if (!kResidentSetMeasures) return;
  EXPECT_LT(highest, atTen + 4.0) << "memory grew as the ball moved";
  EXPECT_LT(highest, 40.0);
}

TEST(MpmGridMemory, AJellyBallFlyingThroughALargeDomainKeepsItsMemory) {
  LODESTONE_SKIP_UNDER_STRICT_OVERCOMMIT();
  // The whole substep (P2G, grid update with the domain walls, G2P): an
  // elastic ball (radius 4 cells) thrown at 20 m/s along a diagonal of a
  // 385^3-node domain (3.3 GiB of grid arrays if held whole), no gravity,
  // 1,000 substeps of 1e-4 s: 2 m (120 cells along x). The resident set after the
  // first 10 substeps bounds the rest.
  MpmSettings s;
  s.grid = GridSpec{{0.0, 0.0, 0.0}, 0.01, {385, 385, 385}};
  s.gravity = {0, 0, 0};
  s.fixedDt = 1e-4;
  const double r0 = residentMiB();
  MpmSolver solver(s);
  const std::uint32_t m = solver.addMaterial(neoHookeanSolid(1e5, 0.3, 1000));
  EmitterSettings e;
  e.velocity = Vec3d{12.0, 10.0, 12.6};  // 20 m/s
  solver.emit(EmitterShape::sphere(Pose::at({0.3, 0.3, 0.3}), 0.04), m, e);
  double atTen = 0, highest = 0;
  for (int step = 0; step < 1000; ++step) {
    solver.step(1e-4);
    const double r = residentMiB() - r0;
    if (step == 10) atTen = r;
    highest = std::max(highest, r);
  }
  const Index3 lo = solver.grid().activeLo();
  std::printf("a ball flying through a 385^3 domain: %.1f MiB after 10 substeps, at most %.1f MiB over 1,000; "
              "its box now from node (%d, %d, %d)\n",
              atTen, highest, lo.i, lo.j, lo.k);
  EXPECT_GT(lo.i, 130) << "the ball travelled 120 cells along x";
  if (!kResidentSetMeasures) return;
  EXPECT_LT(highest, atTen + 4.0) << "memory grew as the ball moved";
  EXPECT_LT(highest, 60.0);
}

TEST(MpmGridMemory, TwoBallsFarApartCostTheirOwnRowsAndDepositAsAlone) {
  LODESTONE_SKIP_UNDER_STRICT_OVERCOMMIT();
  // Two balls of 4,224 particles at opposite corners of a 641^3 grid: their
  // box is the whole grid (15 GiB of node, velocity and bin arrays), but
  // each x-row holds memory only for its run of nodes (mpm/grid.h). The
  // node data match those of each ball deposited alone on its own grid,
  // value for value, and nothing between the balls is written.
  const GridSpec g{{0.0, 0.0, 0.0}, 0.01, {641, 641, 641}};
  const std::vector<MpmMaterial> mats = {viscousFluid(0.1, 1e5, 1000.0)};
  const auto ball = [](const Vec3d& c, MpmParticles& p) {
    const double h = 0.005;
    for (double z = -0.05; z < 0.05; z += h)
      for (double y = -0.05; y < 0.05; y += h)
        for (double x = -0.05; x < 0.05; x += h)
          if (x * x + y * y + z * z < 0.05 * 0.05) p.add(c + Vec3d{x, y, z}, {0.1, -0.2, 0.3}, 1e-3, h * h * h, 0.0, 0);
  };
  const Vec3d a{0.2, 0.2, 0.2}, b{6.2, 6.2, 6.2};
  const double r0 = residentMiB();
  MpmGrid both(g);
  MpmParticles p;
  ball(a, p);
  ball(b, p);
  both.particleToGrid(p, mats, 1e-4);
  const double used = residentMiB() - r0;
  std::printf("two balls at opposite corners of a 641^3 grid: %.1f MiB\n", used);
  EXPECT_LT(both.activeLo().i, 20);
  EXPECT_GT(both.activeHi().i, 620);
  int first = 0, end = 0;
  both.activeRun(320, 320, first, end);  // a row between the balls
  EXPECT_GE(first, end);
  for (const Vec3d& c : {a, b}) {
    MpmGrid alone(g);
    MpmParticles q;
    ball(c, q);
    alone.particleToGrid(q, mats, 1e-4);
    const Index3 lo = alone.activeLo(), hi = alone.activeHi();
    std::size_t differ = 0;
    for (int k = lo.k; k < hi.k; ++k)
      for (int j = lo.j; j < hi.j; ++j) {
        both.activeRun(j, k, first, end);
        int f = 0, e = 0;
        alone.activeRun(j, k, f, e);
        EXPECT_EQ(first, f);
        EXPECT_EQ(end, e);
        for (int i = lo.i; i < hi.i; ++i) {
          const MpmNode x = both.nodeAt(i, j, k), y = alone.nodeAt(i, j, k);
          differ += !(x.mass == y.mass && x.momentum == y.momentum);
        }
      }
    EXPECT_EQ(differ, 0u);
  }
  if (!kResidentSetMeasures) return;
  // Each ball's 14^3 nodes lie on 14^2 rows of a page or two per array;
  // the rest is the particles (3.4 MB) and the runs' bookkeeping, about 24
  // bytes per row of the box (625^2 rows: 9 MB), against 15 GiB for the box.
  EXPECT_LT(used, 30.0) << "the grid held the box between the balls";
}

TEST(MpmGridMemory, PlatesAndASlantedSheetHoldTheirRunsAsHeldBytesCounts) {
  LODESTONE_SKIP_UNDER_STRICT_OVERCOMMIT();
  // A plate of one point a cell, 2 cells thick and 200 x 200 cells across,
  // in a 257^3 grid, thin along x, thin along z, and slanted at 45 degrees
  // between x and z: one P2G takes what heldBytes() (mpmHeldBytes) counts,
  // and the runs are packed, so each takes about 56 B a node of its runs
  // plus the bins' offsets and the rows' bookkeeping. The slanted sheet's runs of about 5
  // nodes in rows about 150 nodes apart took a page of each node array per
  // x-row when the runs lay in rows of the material's box (over 300 MiB).
  const GridSpec g{{0.0, 0.0, 0.0}, 0.01, {257, 257, 257}};
  const std::vector<MpmMaterial> mats = {viscousFluid(0.1, 1e5, 1000.0)};
  const char* names[3] = {"thin along x", "thin along z", "slanted across x"};
  for (int shape = 0; shape < 3; ++shape) {
    MpmParticles p;
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 200; ++b)
        for (int c = 0; c < 200; ++c) {
          const double thin = 1.28 + (a - 0.5) * g.dx, u = 0.28 + (b + 0.5) * g.dx, v = 0.28 + (c + 0.5) * g.dx;
          const Vec3d x = shape == 0   ? Vec3d{thin, u, v}
                          : shape == 1 ? Vec3d{u, v, thin}
                                       : Vec3d{0.56 + 0.75 * (v - 0.28) + (a - 0.5) * g.dx, u, v};
          p.add(x, {}, 1e-3, g.dx * g.dx * g.dx, 0.0, 0);
        }
    MpmGrid grid(g);
    grid.setWholeLayout(false);
    const double r0 = residentMiB();
    grid.particleToGrid(p, mats, 1e-4);
    const double measured = residentMiB() - r0;
    const double held = grid.heldBytes() / kMiB;
    double nodes = 0;
    for (int k = grid.activeLo().k; k < grid.activeHi().k; ++k)
      for (int j = grid.activeLo().j; j < grid.activeHi().j; ++j) {
        int first = 0, end = 0;
        grid.activeRun(j, k, first, end);
        if (end > first) nodes += end - first;
      }
    const double rows = double(grid.activeHi().j - grid.activeLo().j) * double(grid.activeHi().k - grid.activeLo().k);
    std::printf("plate %s: %.1f MiB held after one P2G, heldBytes %.1f MiB for %.0f nodes of runs in %.0f rows\n",
                names[shape], measured, held, nodes, rows);
    EXPECT_TRUE(grid.packed());
    // The runs' 56 B a node, the bins' offsets (4 B, fewer bins than nodes)
    // and the rows' bookkeeping (40 B), within a page of each array.
    EXPECT_LT(held, (60.0 * nodes + 40.0 * rows) / kMiB + 0.02) << names[shape];
    EXPECT_GT(held, 56.0 * nodes / kMiB) << names[shape];
    if (!kResidentSetMeasures) continue;
    // The rest is the binning's per-point arrays (80,000 points, about 1.5 MiB).
    EXPECT_NEAR(measured, held, 0.1 * held + 3.0) << names[shape];
  }
}

TEST(MpmGridPacked, MovingLiquidDepositsAndGathersAsTheWholeGrid) {
  // A ball of liquid with surface tension (the colour field and its Hessian
  // read one node beyond the stencils) carried 0.6 cell per call along a
  // diagonal of a 97^3 grid for 120 calls, then back: on packed runs every
  // node of P2G (mass, momentum, colour) and every particle of G2P is
  // bitwise the whole grid's, the memory held stays that of the ball, and
  // going whole after a P2G (the data moves) and packed again is seamless.
  const GridSpec g{{0.0, 0.0, 0.0}, 0.01, {97, 97, 97}};
  MpmMaterial liquid = viscousFluid(0.1, 1e5, 1000.0);
  liquid.surfaceTension = 0.07;
  const std::vector<MpmMaterial> mats = {liquid, neoHookeanSolid(1e5, 0.3, 1000)};
  MpmParticles p;
  const double h = g.dx / 2;
  for (double z = -0.05; z < 0.05; z += h)
    for (double y = -0.05; y < 0.05; y += h)
      for (double x = -0.05; x < 0.05; x += h)
        if (x * x + y * y + z * z < 0.05 * 0.05)
          p.add(Vec3d{0.1, 0.1, 0.1} + Vec3d{x, y, z}, {0.3, -0.2, 0.1}, 1e-3, h * h * h, 0.0, x > 0 ? 0 : 1);
  MpmGrid follow(g), whole(g);
  follow.setWholeLayout(false);
  double heldFirst = 0, heldMost = 0;
  for (int s = 0; s < 240; ++s) {
    const Vec3d step = (s < 120 ? 1.0 : -1.0) * Vec3d{0.006, 0.005, 0.0055};
    if (s == 101) follow.setWholeLayout(false);
    follow.particleToGrid(p, mats, 1e-4);
    whole.particleToGrid(p, mats, 1e-4);
    ASSERT_EQ(follow.packed(), true) << "call " << s;
    if (s == 0) heldFirst = follow.heldBytes();
    heldMost = std::max(heldMost, follow.heldBytes());
    if (s == 100) {
      follow.setWholeLayout(true);  // the runs move to their whole-grid places
      ASSERT_FALSE(follow.packed());
    }
    const Index3 lo = whole.activeLo(), hi = whole.activeHi();
    ASSERT_EQ(follow.activeLo(), lo);
    std::size_t differ = 0;
    for (int k = lo.k; k < hi.k; ++k)
      for (int j = lo.j; j < hi.j; ++j)
        for (int i = lo.i; i < hi.i; ++i) {
          const MpmNode a = follow.nodeAt(i, j, k), b = whole.nodeAt(i, j, k);
          differ += std::memcmp(&a, &b, sizeof a) != 0;
          differ += follow.colourAt(i, j, k) != whole.colourAt(i, j, k);
          // A grid update without forces, the same on both, on the runs (the
          // nodes the arrays hold).
          ASSERT_EQ(follow.inRun(i, j, k), whole.inRun(i, j, k));
          if (!follow.inRun(i, j, k)) continue;
          const Vec3d v = a.mass > 0 ? a.momentum / a.mass : Vec3d{};
          follow.velocity()[follow.nodeIndex(i, j, k)] = v;
          whole.velocity()[whole.nodeIndex(i, j, k)] = v;
        }
    ASSERT_EQ(differ, 0u) << "call " << s;
    MpmParticles q = p;
    follow.gridToParticle(p, mats, 1e-4);
    whole.gridToParticle(q, mats, 1e-4);
    ASSERT_EQ(0, std::memcmp(p.x.data(), q.x.data(), p.size() * sizeof(Vec3d))) << "call " << s;
    ASSERT_EQ(0, std::memcmp(p.C.data(), q.C.data(), p.size() * sizeof(Mat3d))) << "call " << s;
    for (std::size_t n = 0; n < p.size(); ++n) {
      p.x[n] += step;
      p.v[n] = {0.3, -0.2, 0.1};
      p.C[n] = Mat3d{};
      p.F[n] = Mat3d::identity();
      p.J[n] = 1.0;
    }
  }
  std::printf("the moving ball's grid held %.3f MiB after the first call, at most %.3f MiB\n", heldFirst / kMiB,
              heldMost / kMiB);
  EXPECT_LT(heldMost, 1.2 * heldFirst) << "the grid's memory grew as the ball moved";
}
