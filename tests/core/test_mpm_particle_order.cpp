// Sorting the MPM particles by cell (mpm/particle_order.h): when it is due;
// the order P2G bins them in is a permutation grouping them by stencil base
// node, the same for any thread count; applying it keeps every particle's
// attributes together (and the field-reuse record with them), changes
// nothing when the order is stale, and leaves a grid the P2G fills bitwise
// as before.
#include <gtest/gtest.h>

#include <algorithm>
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
#include "lodestone/core/mpm/emitter.h"
#include "lodestone/core/mpm/material.h"
#include "lodestone/core/mpm/particle_order.h"
#include "lodestone/core/mpm/solver.h"
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

  // Sorted particles bin in their own order, and sorting them again moves nothing.
  const std::vector<std::uint32_t> again = binnedOrder(p, g);
  for (std::size_t q = 0; q < again.size(); ++q) ASSERT_EQ(again[q], q) << q;
  const MpmParticles sorted = p;
  const std::vector<Vec3d> recorded = reuse.positions();
  ASSERT_TRUE(reorderParticles(again, p, reuse));
  EXPECT_EQ(p.id, sorted.id);
  EXPECT_EQ(p.x, sorted.x);
  EXPECT_EQ(reuse.positions(), recorded);
}

TEST(MpmParticleOrder, AttributesEqualButForOneParticleFollowThatParticle) {
  // Arrays whose elements are all equal are left in place; one differing
  // element anywhere (here deep inside each array, past the first chunk of
  // a parallel check) makes the array move with its particles.
  const GridSpec g = testGrid();
  MpmParticles before = randomParticles(g, 20000, 11);
  const std::size_t odd = 17000;
  for (std::size_t q = 0; q < before.size(); ++q) {
    before.mass[q] = 1e-3;
    before.volume0[q] = 1e-6;
    before.count[q] = 0.0;
    before.material[q] = 0;
    before.magneticForce[q] = Vec3d{};
  }
  before.mass[odd] = 2e-3;
  before.volume0[odd] = 3e-6;
  before.count[odd] = 5.0;
  before.material[odd] = 1;
  before.magneticForce[odd] = Vec3d{0, 0, 1e-9};
  MpmParticles p = before;
  const std::vector<std::uint32_t> order = binnedOrder(p, g);
  const std::size_t to = std::size_t(std::find(order.begin(), order.end(), std::uint32_t(odd)) - order.begin());
  ASSERT_NE(to, odd) << "the odd particle must move for the test to mean anything";
  FieldReuse reuse;
  ASSERT_TRUE(reorderParticles(order, p, reuse));
  for (std::size_t q = 0; q < p.size(); ++q) {
    const std::size_t o = order[q];
    ASSERT_EQ(p.mass[q], before.mass[o]) << q;
    ASSERT_EQ(p.volume0[q], before.volume0[o]) << q;
    ASSERT_EQ(p.count[q], before.count[o]) << q;
    ASSERT_EQ(p.material[q], before.material[o]) << q;
    ASSERT_EQ(p.magneticForce[q], before.magneticForce[o]) << q;
  }
  EXPECT_EQ(p.mass[to], 2e-3);
  EXPECT_EQ(p.material[to], 1u);

  // All equal: the arrays come out as they went in.
  MpmParticles uniform = before;
  uniform.mass[odd] = 1e-3;
  uniform.material[odd] = 0;
  const MpmParticles sortedUniform = uniform;
  ASSERT_TRUE(reorderParticles(order, uniform, reuse));
  EXPECT_EQ(uniform.mass, sortedUniform.mass);
  EXPECT_EQ(uniform.material, sortedUniform.material);
  for (std::size_t q = 0; q < uniform.size(); ++q) ASSERT_EQ(uniform.id[q], sortedUniform.id[order[q]]) << q;
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

TEST(MpmParticleOrder, DueAfterAnEmissionUnlessNever) {
  EXPECT_TRUE(particleReorderDue(20, 1, true));
  EXPECT_TRUE(particleReorderDue(20, 7, true));
  EXPECT_FALSE(particleReorderDue(20, 7, false));
  for (long long s : {1LL, 20LL}) EXPECT_FALSE(particleReorderDue(0, s, true)) << s;
}

namespace {

// A moving, spinning solid block emitted into a small grid, its particles in
// the emitter's lattice order.
MpmSolver& emitBlock(MpmSolver& solver) {
  const std::uint32_t m = solver.addMaterial(neoHookeanSolid(1e5, 0.3, 1000));
  EmitterSettings e;
  e.velocity = {0.3, 0, -0.2};  // m/s
  e.angularVelocity = {0, 2, 1};  // rad/s
  solver.emit(EmitterShape::box(Pose::at({0.5, 0.45, 0.55}), {0.12, 0.1, 0.08}), m, e);
  return solver;
}

MpmSettings blockSettings(int reorderInterval) {
  MpmSettings s;
  s.grid.dx = 1.0 / 32;
  s.grid.dims = {33, 33, 33};
  s.fixedDt = 2e-4;  // s
  s.reorderInterval = reorderInterval;
  return s;
}

bool sortedByCell(const MpmSolver& solver, const std::vector<Vec3d>& x) {
  const GridSpec g = solver.settings().grid;
  for (std::size_t q = 1; q < x.size(); ++q)
    if (baseNode(g, x[q]) < baseNode(g, x[q - 1])) return false;
  return true;
}

}  // namespace

TEST(MpmParticleOrder, TheFirstSubstepAfterAnEmissionSortsAndTheParticlesAreThoseOfNoSort) {
  MpmSolver sorted(blockSettings(20)), never(blockSettings(0));
  emitBlock(sorted);
  emitBlock(never);
  const std::vector<Vec3d> emitted = sorted.particles().x;
  ASSERT_GT(emitted.size(), 1000u);
  ASSERT_FALSE(sortedByCell(sorted, emitted)) << "the lattice order is the cell order: the test would be vacuous";

  // Substep 1 sorts by the cells P2G binned the particles in (their positions
  // before it advected them); substep 2 keeps that order.
  std::vector<Vec3d> before = sorted.particles().x;
  sorted.step(2e-4);
  never.step(2e-4);
  std::vector<std::uint64_t> ids = sorted.particles().id;
  std::vector<Vec3d> x0(ids.size());
  for (std::size_t q = 0; q < ids.size(); ++q) x0[q] = before[ids[q]];  // ids are emission indices
  EXPECT_TRUE(sortedByCell(sorted, x0));
  for (std::size_t q = 0; q < ids.size(); ++q) ASSERT_EQ(never.particles().id[q], q) << q;
  sorted.step(2e-4);
  never.step(2e-4);
  EXPECT_EQ(sorted.particles().id, ids) << "no emission since the sort, and substep 2 is not on the interval";

  // A second emission: the next substep sorts again.
  emitBlock(sorted);
  emitBlock(never);
  sorted.step(2e-4);
  never.step(2e-4);
  EXPECT_NE(std::vector<std::uint64_t>(sorted.particles().id.begin(), sorted.particles().id.begin() + ids.size()), ids);

  // P2G sums each node's particles in index order, which the sort keeps
  // within a node: every particle ends where it does unsorted, bit for bit.
  const MpmParticles& a = sorted.particles();
  const MpmParticles& b = never.particles();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t q = 0; q < a.size(); ++q) {
    const std::size_t o = a.id[q];  // b holds particle id o at index o
    ASSERT_EQ(b.id[o], o);
    ASSERT_EQ(a.x[q], b.x[o]) << q;
    ASSERT_EQ(a.v[q], b.v[o]) << q;
    ASSERT_TRUE(sameMat(a.F[q], b.F[o])) << q;
    ASSERT_TRUE(sameMat(a.C[q], b.C[o])) << q;
  }
}
