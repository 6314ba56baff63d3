// Sorting the MPM particles by cell (mpm/particle_order.h): when it is due;
// the order P2G bins them in is a permutation grouping them by stencil base
// node, the same for any thread count; applying it keeps every particle's
// attributes together (and the field-reuse record with them), changes
// nothing when the order is stale, and leaves a grid the P2G fills bitwise
// as before.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <tuple>
#include <vector>

#include <tbb/global_control.h>

#include "lodestone/core/base/bspline.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/grid.h"
#include "lodestone/core/mpm/particle_order.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone_test/mpm_samples.h"

using namespace lodestone;
using namespace lodestone::test;

namespace {

GridSpec testGrid() {
  GridSpec g;
  g.dx = 0.05;
  g.origin = {-0.3, 0.1, -0.7};
  g.dims = {12, 13, 14};
  return g;
}

// Random particles inside the stencil box, every attribute distinct (magnetic
// ones, material 1, carry n_p > 0 and a per-particle force).
MpmParticles randomParticles(const GridSpec& g, std::size_t count, unsigned seed) {
  return randomMpmParticles(g, count, seed, true);
}

std::vector<std::uint32_t> binnedOrder(const MpmParticles& p, const GridSpec& g) {
  MpmGrid grid(g);
  grid.particleToGrid(p, twoMaterials(), 1e-3);
  return grid.binnedOrder();
}

// The stencil base node of a particle as (k, j, i): flat order, x fastest.
std::tuple<int, int, int> baseNode(const GridSpec& g, const Vec3d& x) {
  const double inv = 1 / g.dx;
  return {int(quadraticBaseFloor((x.z - g.origin.z) * inv)), int(quadraticBaseFloor((x.y - g.origin.y) * inv)),
          int(quadraticBaseFloor((x.x - g.origin.x) * inv))};
}

bool sameMat(const Mat3d& a, const Mat3d& b) { return std::memcmp(&a, &b, sizeof(Mat3d)) == 0; }

}  // namespace

TEST(MpmParticleOrder, DueEveryIntervalSubstepsAndNeverAtZero) {
  EXPECT_TRUE(particleReorderDue(20, 20));
  EXPECT_TRUE(particleReorderDue(20, 40));
  EXPECT_FALSE(particleReorderDue(20, 1));
  EXPECT_FALSE(particleReorderDue(20, 19));
  EXPECT_FALSE(particleReorderDue(20, 21));
  EXPECT_TRUE(particleReorderDue(1, 7));
  for (long long s : {0LL, 1LL, 20LL, 40LL}) EXPECT_FALSE(particleReorderDue(0, s)) << s;
}

TEST(MpmParticleOrder, BinnedOrderIsAPermutationByCellTheSameForAnyThreadCount) {
  const GridSpec g = testGrid();
  const MpmParticles p = randomParticles(g, 5000, 3);
  const std::vector<std::uint32_t> order = binnedOrder(p, g);
  ASSERT_EQ(order.size(), p.size());
  std::vector<int> seen(p.size(), 0);
  for (std::uint32_t o : order) {
    ASSERT_LT(o, p.size());
    ++seen[o];
  }
  for (std::size_t q = 0; q < seen.size(); ++q) ASSERT_EQ(seen[q], 1) << q;
  // Grouped by base node in flat order, ascending index within a node.
  for (std::size_t q = 1; q < order.size(); ++q) {
    const auto a = baseNode(g, p.x[order[q - 1]]), b = baseNode(g, p.x[order[q]]);
    ASSERT_TRUE(a < b || (a == b && order[q - 1] < order[q])) << q;
  }
  for (int threads : {1, 3}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    EXPECT_EQ(binnedOrder(p, g), order) << threads << " thread(s)";
  }
}

TEST(MpmParticleOrder, ReorderingKeepsEveryParticlesAttributesAndItsReuseRecordTogether) {
  const GridSpec g = testGrid();
  const MpmParticles before = randomParticles(g, 3000, 5);
  MpmParticles p = before;
  const std::vector<std::uint32_t> order = binnedOrder(p, g);
  std::vector<std::uint32_t> magnetic;
  for (std::size_t q = 0; q < p.size(); ++q)
    if (p.count[q] > 0) magnetic.push_back(std::uint32_t(q));
  FieldReuse reuse;
  reuse.record(p.x, magnetic, UniformField(Vec3d{0, 0, 1000}), 0.0);
  std::vector<std::uint64_t> sampledIds;
  for (std::uint32_t q : reuse.samples()) sampledIds.push_back(p.id[q]);

  ASSERT_TRUE(reorderParticles(order, p, reuse));
  ASSERT_EQ(p.size(), before.size());
  EXPECT_EQ(p.nextId, before.nextId);
  bool identity = true;
  for (std::size_t q = 0; q < p.size(); ++q) {
    const std::size_t o = order[q];
    identity = identity && o == q;
    ASSERT_EQ(p.id[q], before.id[o]) << q;
    EXPECT_EQ(p.x[q], before.x[o]) << q;
    EXPECT_EQ(p.v[q], before.v[o]) << q;
    EXPECT_TRUE(sameMat(p.C[q], before.C[o])) << q;
    EXPECT_TRUE(sameMat(p.F[q], before.F[o])) << q;
    EXPECT_EQ(p.J[q], before.J[o]) << q;
    EXPECT_EQ(p.mass[q], before.mass[o]) << q;
    EXPECT_EQ(p.volume0[q], before.volume0[o]) << q;
    EXPECT_EQ(p.count[q], before.count[o]) << q;
    EXPECT_EQ(p.material[q], before.material[o]) << q;
    EXPECT_EQ(p.magneticForce[q], before.magneticForce[o]) << q;
    EXPECT_EQ(reuse.positions()[q], p.x[q]) << q;
  }
  EXPECT_FALSE(identity) << "random particles are not sorted already: the test would be vacuous";
  // Each sample still names the particle it sampled.
  ASSERT_EQ(reuse.samples().size(), sampledIds.size());
  for (std::size_t s = 0; s < sampledIds.size(); ++s) EXPECT_EQ(p.id[reuse.samples()[s]], sampledIds[s]) << s;
  const auto isMagnetic = [&](std::size_t q) { return p.count[q] > 0; };
  EXPECT_TRUE(reuse.pointsWithin(p.x, isMagnetic, 0.0));

  // Sorted particles bin in their own order.
  const std::vector<std::uint32_t> again = binnedOrder(p, g);
  for (std::size_t q = 0; q < again.size(); ++q) ASSERT_EQ(again[q], q) << q;
}

TEST(MpmParticleOrder, P2GFillsTheGridBitwiseAsBeforeTheSort) {
  // Within a base node the sort keeps the particles' relative order, which is
  // the order P2G accumulates them in.
  const GridSpec g = testGrid();
  MpmParticles p = randomParticles(g, 4000, 9);
  const std::vector<MpmMaterial> mats = twoMaterials();
  MpmGrid before(g);
  before.particleToGrid(p, mats, 1e-3, p.magneticForce.data());
  FieldReuse reuse;
  ASSERT_TRUE(reorderParticles(before.binnedOrder(), p, reuse));
  MpmGrid after(g);
  after.particleToGrid(p, mats, 1e-3, p.magneticForce.data());
  ASSERT_EQ(before.nodes().size(), after.nodes().size());
  for (std::size_t n = 0; n < before.nodes().size(); ++n) {
    ASSERT_EQ(before.nodes()[n].mass, after.nodes()[n].mass) << n;
    ASSERT_EQ(before.nodes()[n].momentum, after.nodes()[n].momentum) << n;
  }
}

TEST(MpmParticleOrder, AStaleOrderChangesNothingAndABadOneIsRefused) {
  const GridSpec g = testGrid();
  const MpmParticles before = randomParticles(g, 50, 7);
  MpmParticles p = before;
  std::vector<std::uint32_t> order = binnedOrder(p, g);
  FieldReuse reuse;
  reuse.record(p.x, {1, 3}, UniformField(Vec3d{0, 0, 1000}), 0.0);

  order.pop_back();  // a particle was removed after the P2G that made it
  EXPECT_FALSE(reorderParticles(order, p, reuse));
  EXPECT_EQ(p.id, before.id);
  EXPECT_EQ(reuse.positions(), before.x);

  std::vector<std::uint32_t> notAPermutation(p.size(), 0);
  EXPECT_THROW(reorderParticles(notAPermutation, p, reuse), InvalidArgument);
  EXPECT_EQ(p.id, before.id);
  EXPECT_EQ(p.x, before.x);
  EXPECT_EQ(reuse.positions(), before.x);
}
