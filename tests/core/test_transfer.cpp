// Quadratic B-spline weights and the particle <-> grid transfers: moment
// conservation (count and first moment), agreement with a serial reference
// written here from the kernel N(r), bitwise determinism across thread
// counts, input orders and reused scratch, linear reproduction of sampling,
// out-of-grid policies, invalid input, and particles exactly on node and
// base-switch (cell-centre) boundaries.
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "lodestone/core/base/bspline.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/grid.h"
#include "lodestone/core/stage/transfer.h"

using namespace lodestone;

namespace {

GridSpec makeGrid(Vec3d origin, double dx, Index3 dims) {
  GridSpec g;
  g.origin = origin;
  g.dx = dx;
  g.dims = dims;
  return g;
}

// The 1-D quadratic B-spline kernel N(r), r = |u - i| in node spacings.
double kernelN(double r) {
  r = std::fabs(r);
  if (r < 0.5) return 0.75 - r * r;
  if (r < 1.5) return 0.5 * (1.5 - r) * (1.5 - r);
  return 0.0;
}

// Uniform positions strictly inside the region where the stencil fits,
// [origin + dx/2, origin + (dims - 3/2) dx) per axis.
std::vector<Vec3d> randomInside(const GridSpec& g, std::size_t n, std::mt19937_64& rng) {
  std::vector<Vec3d> x(n);
  for (int a = 0; a < 3; ++a) {
    std::uniform_real_distribution<double> d(g.origin[a] + 0.5 * g.dx, g.origin[a] + (g.dims[a] - 1.5) * g.dx);
    for (auto& p : x) p[a] = d(rng);
  }
  return x;
}

std::vector<double> randomCounts(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> d(0.0, 1e6);
  std::vector<double> c(n);
  for (auto& v : c) v = d(rng);
  return c;
}

// Straightforward serial deposit: every particle, every node of the 4^3 box
// around it, weights from kernelN. Accumulates in long double.
std::vector<double> referenceDeposit(const GridSpec& g, const std::vector<Vec3d>& x, const std::vector<double>& c) {
  std::vector<long double> acc(g.nodeCount(), 0.0L);
  const long double invV = 1.0L / ((long double)g.dx * g.dx * g.dx);
  for (std::size_t p = 0; p < x.size(); ++p) {
    const double ux = (x[p].x - g.origin.x) / g.dx, uy = (x[p].y - g.origin.y) / g.dx,
                 uz = (x[p].z - g.origin.z) / g.dx;
    const int fx = int(std::floor(ux)), fy = int(std::floor(uy)), fz = int(std::floor(uz));
    for (int k = fz - 1; k <= fz + 2; ++k)
      for (int j = fy - 1; j <= fy + 2; ++j)
        for (int i = fx - 1; i <= fx + 2; ++i) {
          const double w = kernelN(ux - i) * kernelN(uy - j) * kernelN(uz - k);
          if (w == 0.0) continue;
          EXPECT_TRUE(i >= 0 && j >= 0 && k >= 0 && i < g.dims.i && j < g.dims.j && k < g.dims.k);
          acc[g.index(i, j, k)] += (long double)w * c[p] * invV;
        }
  }
  return std::vector<double>(acc.begin(), acc.end());
}

template <typename V>
V referenceSample(const GridSpec& g, const std::vector<V>& f, const Vec3d& x) {
  const double ux = (x.x - g.origin.x) / g.dx, uy = (x.y - g.origin.y) / g.dx, uz = (x.z - g.origin.z) / g.dx;
  const int fx = int(std::floor(ux)), fy = int(std::floor(uy)), fz = int(std::floor(uz));
  V acc{};
  for (int k = fz - 1; k <= fz + 2; ++k)
    for (int j = fy - 1; j <= fy + 2; ++j)
      for (int i = fx - 1; i <= fx + 2; ++i) {
        const double w = kernelN(ux - i) * kernelN(uy - j) * kernelN(uz - k);
        if (w != 0.0) acc += w * f[g.index(i, j, k)];
      }
  return acc;
}

long double sumOf(const std::vector<double>& v) {
  long double s = 0;
  for (double x : v) s += x;
  return s;
}

bool bitwiseEqual(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

std::vector<double> deposit(const GridSpec& g, const std::vector<Vec3d>& x, const std::vector<double>& c,
                            OutOfGridPolicy policy = OutOfGridPolicy::Throw, TransferReport* report = nullptr) {
  DenseGrid<double> n(g);
  const TransferReport r = depositNumberDensity({x.data(), c.data(), x.size()}, n.view(), policy);
  if (report) *report = r;
  return n.values();
}

std::string thrownMessage(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected InvalidArgument";
  return {};
}

}  // namespace

// ---------------------------------------------------------------------------
// bspline.h

TEST(QuadraticBSpline, MatchesKernelPartitionOfUnityAndLinearReproduction) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> d(-50.0, 50.0);
  const double dx = 0.37;
  for (int t = 0; t < 10000; ++t) {
    const double u = d(rng);
    const QuadraticWeights<double> q = quadraticWeights(u, 1.0 / dx);
    ASSERT_EQ(q.base, int(std::floor(u - 0.5)));
    double s = 0, m = 0, ds = 0, dm = 0;
    for (int i = 0; i < 3; ++i) {
      const int node = q.base + i;
      EXPECT_NEAR(q.w[i], kernelN(u - node), 1e-15);
      EXPECT_GE(q.w[i], 0.0);
      s += q.w[i];
      m += q.w[i] * node;
      ds += q.dw[i];
      dm += q.dw[i] * node * dx;  // sum_i dw_i x_i with x_i = node * dx
      // d/dx by central differences of the kernel
      const double h = 1e-6;
      const double fd = (kernelN(u + h - node) - kernelN(u - h - node)) / (2 * h) / dx;
      EXPECT_NEAR(q.dw[i], fd, 1e-7);
    }
    EXPECT_NEAR(s, 1.0, 4e-16);
    EXPECT_NEAR(m, u, 1e-13);
    EXPECT_NEAR(ds, 0.0, 1e-14);
    EXPECT_NEAR(dm, 1.0, 1e-13);
  }
  // float instantiation
  const QuadraticWeights<float> qf = quadraticWeights(3.3f, 2.0f);
  EXPECT_EQ(qf.base, 2);
  EXPECT_NEAR(qf.w[0] + qf.w[1] + qf.w[2], 1.0f, 1e-6f);
  EXPECT_NEAR(qf.w[0] * 2 + qf.w[1] * 3 + qf.w[2] * 4, 3.3f, 1e-5f);
}

TEST(QuadraticBSpline, NodeAndBaseSwitchValues) {
  // On a node (f = 1): 1/8, 3/4, 1/8.
  QuadraticWeights<double> q = quadraticWeights(7.0);
  EXPECT_EQ(q.base, 6);
  EXPECT_EQ(q.w[0], 0.125);
  EXPECT_EQ(q.w[1], 0.75);
  EXPECT_EQ(q.w[2], 0.125);
  // Exactly at the switch u = b + 1/2: base b, weights (1/2, 1/2, 0).
  q = quadraticWeights(7.5);
  EXPECT_EQ(q.base, 7);
  EXPECT_EQ(q.w[0], 0.5);
  EXPECT_EQ(q.w[1], 0.5);
  EXPECT_EQ(q.w[2], 0.0);
  // Just below it: base b - 1, weights -> (0, 1/2, 1/2): same node weights.
  q = quadraticWeights(std::nextafter(7.5, 0.0));
  EXPECT_EQ(q.base, 6);
  EXPECT_NEAR(q.w[0], 0.0, 1e-15);
  EXPECT_NEAR(q.w[1], 0.5, 1e-15);
  EXPECT_NEAR(q.w[2], 0.5, 1e-15);
}

// ---------------------------------------------------------------------------
// depositNumberDensity

TEST(DepositNumberDensity, ConservesTotalCount) {
  const GridSpec g = makeGrid({-0.31, 0.02, 1.7}, 0.013, {40, 33, 27});
  std::mt19937_64 rng(2);
  const auto x = randomInside(g, 100000, rng);
  const auto c = randomCounts(x.size(), rng);
  TransferReport r;
  const auto n = deposit(g, x, c, OutOfGridPolicy::Throw, &r);
  const long double expected = sumOf(c);
  const long double got = sumOf(n) * g.cellVolume();
  EXPECT_LE(std::fabs(double(got - expected)), 1e-12 * double(expected));
  EXPECT_LE(std::fabs(r.totalCount - double(expected)), 1e-12 * double(expected));
  EXPECT_EQ(r.particles, x.size());
  EXPECT_EQ(r.skipped, 0u);
  EXPECT_GE(r.seconds, 0.0);
  for (double v : n) ASSERT_GE(v, 0.0);
}

TEST(DepositNumberDensity, MatchesSerialReference) {
  const GridSpec g = makeGrid({0.5, -0.25, 0.125}, 0.02, {21, 17, 19});
  std::mt19937_64 rng(3);
  const auto x = randomInside(g, 50000, rng);
  const auto c = randomCounts(x.size(), rng);
  const auto n = deposit(g, x, c);
  const auto ref = referenceDeposit(g, x, c);
  double maxRef = 0;
  for (double v : ref) maxRef = std::max(maxRef, std::fabs(v));
  ASSERT_GT(maxRef, 0.0);
  for (std::size_t i = 0; i < n.size(); ++i) {
    ASSERT_LE(std::fabs(n[i] - ref[i]), 1e-12 * std::max(std::fabs(ref[i]), 1e-3 * maxRef)) << "node " << i;
  }
}

TEST(DepositNumberDensity, ConservesFirstMoment) {
  const GridSpec g = makeGrid({-1.1, 2.3, 0.4}, 0.05, {24, 30, 20});
  std::mt19937_64 rng(4);
  const auto x = randomInside(g, 100000, rng);
  const auto c = randomCounts(x.size(), rng);
  const auto n = deposit(g, x, c);
  for (int a = 0; a < 3; ++a) {
    long double particles = 0, scale = 0, grid = 0;
    for (std::size_t p = 0; p < x.size(); ++p) {
      particles += (long double)c[p] * x[p][a];
      scale += (long double)c[p] * std::fabs(x[p][a]);
    }
    for (int k = 0; k < g.dims.k; ++k)
      for (int j = 0; j < g.dims.j; ++j)
        for (int i = 0; i < g.dims.i; ++i)
          grid += (long double)n[g.index(i, j, k)] * g.nodePosition(i, j, k)[a] * g.cellVolume();
    EXPECT_LE(std::fabs(double(grid - particles)), 1e-12 * double(scale)) << "axis " << a;
  }
}

TEST(DepositNumberDensity, BitwiseDeterministicAcrossThreadsOrderAndReuse) {
  // Dense (about 30 particles per cell) so that any change of summation order
  // within a node shows up in the last bits.
  const GridSpec g = makeGrid({0.0, 0.0, 0.0}, 1.0 / 64, {18, 16, 17});
  std::mt19937_64 rng(5);
  auto x = randomInside(g, 100000, rng);
  auto c = randomCounts(x.size(), rng);
  // Exact duplicates (same position, different and equal counts) too.
  for (std::size_t p = 0; p < 2000; ++p) {
    x[x.size() - 1 - p] = x[p];
    if (p % 2) c[c.size() - 1 - p] = c[p];
  }

  std::vector<double> reference;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    reference = deposit(g, x, c);
  }
  for (int threads : {1, 2, 8}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    tbb::task_arena arena(threads);
    for (int run = 0; run < 3; ++run) {
      std::vector<double> n;
      arena.execute([&] { n = deposit(g, x, c); });
      EXPECT_TRUE(bitwiseEqual(n, reference)) << threads << " threads, run " << run;
    }
  }

  // Shuffled input order: the in-bin order is derived from the data.
  std::vector<std::size_t> perm(x.size());
  for (std::size_t i = 0; i < perm.size(); ++i) perm[i] = i;
  std::shuffle(perm.begin(), perm.end(), rng);
  std::vector<Vec3d> xs(x.size());
  std::vector<double> cs(c.size());
  for (std::size_t i = 0; i < perm.size(); ++i) {
    xs[i] = x[perm[i]];
    cs[i] = c[perm[i]];
  }
  TransferReport r1, r2;
  const auto shuffled = deposit(g, xs, cs, OutOfGridPolicy::Throw, &r2);
  deposit(g, x, c, OutOfGridPolicy::Throw, &r1);
  EXPECT_TRUE(bitwiseEqual(shuffled, reference));
  EXPECT_EQ(r1.totalCount, r2.totalCount);

  // A reused ParticleBinning, after binning other particles on another grid.
  ParticleBinning binning;
  {
    const GridSpec other = makeGrid({1, 1, 1}, 0.1, {30, 30, 30});
    const auto xo = randomInside(other, 5000, rng);
    const auto co = randomCounts(xo.size(), rng);
    DenseGrid<double> no(other);
    depositNumberDensity({xo.data(), co.data(), xo.size()}, no.view(), OutOfGridPolicy::Throw, binning);
  }
  DenseGrid<double> n(g, 123.0);  // stale values must be overwritten
  depositNumberDensity({x.data(), c.data(), x.size()}, n.view(), OutOfGridPolicy::Throw, binning);
  EXPECT_TRUE(bitwiseEqual(n.values(), reference));
  EXPECT_EQ(binning.binnedCount(), x.size());
  EXPECT_EQ(binning.skippedCount(), 0u);
}

TEST(DepositNumberDensity, NoRacesBetweenConcurrentRows) {
  // Few, heavily loaded rows (7 rows along y, one layer in z, about 7000
  // particles per bin): the rows that run concurrently walk their bins in
  // lockstep, so any two concurrent rows writing a shared node would lose
  // updates and change the result.
  const GridSpec g = makeGrid({0, 0, 0}, 1.0 / 8, {6, 9, 3});
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> ux(0.5, 4.5), uy(0.5, 7.5), uz(0.5, 1.4999);
  std::vector<Vec3d> x(200000);
  std::vector<double> c(x.size());
  for (std::size_t p = 0; p < x.size(); ++p) {
    x[p] = {ux(rng) * g.dx, uy(rng) * g.dx, uz(rng) * g.dx};
    c[p] = 1.0 + double(p % 7);
  }
  std::vector<double> reference;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    reference = deposit(g, x, c);
  }
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 4);
  tbb::task_arena arena(4);
  int differing = 0;
  for (int run = 0; run < 12; ++run) {
    std::vector<double> n;
    arena.execute([&] { n = deposit(g, x, c); });
    differing += !bitwiseEqual(n, reference);
  }
  EXPECT_EQ(differing, 0);
  EXPECT_LE(std::fabs(double(sumOf(reference) * g.cellVolume() - sumOf(c))), 1e-12 * double(sumOf(c)));
}

TEST(DepositNumberDensity, BinningIsSortedByBaseNode) {
  const GridSpec g = makeGrid({0.1, 0.2, 0.3}, 0.1, {9, 8, 7});
  std::mt19937_64 rng(6);
  const auto x = randomInside(g, 3000, rng);
  const auto c = randomCounts(x.size(), rng);
  ParticleBinning b;
  EXPECT_EQ(b.build({x.data(), c.data(), x.size()}, g, OutOfGridPolicy::Throw), 0u);
  EXPECT_EQ(b.baseDims(), (Index3{7, 6, 5}));
  ASSERT_EQ(b.binCount(), 7u * 6u * 5u);
  std::vector<int> seen(x.size(), 0);
  for (int bk = 0; bk < 5; ++bk)
    for (int bj = 0; bj < 6; ++bj)
      for (int bi = 0; bi < 7; ++bi) {
        const std::size_t bin = b.binIndex(bi, bj, bk);
        for (const ParticleBinning::Entry* e = b.binBegin(bin); e != b.binEnd(bin); ++e) {
          ASSERT_LT(e->index, x.size());
          ++seen[e->index];
          const Vec3d& xp = x[e->index];
          EXPECT_EQ(e->count, c[e->index]);
          EXPECT_EQ(e->u.x, (xp.x - g.origin.x) / g.dx);
          EXPECT_EQ(quadraticWeights(e->u.x).base, bi);
          EXPECT_EQ(quadraticWeights(e->u.y).base, bj);
          EXPECT_EQ(quadraticWeights(e->u.z).base, bk);
          if (e + 1 != b.binEnd(bin)) {
            EXPECT_LE(e->u.x, e[1].u.x);
          }
        }
      }
  for (int s : seen) ASSERT_EQ(s, 1);
}

// ---------------------------------------------------------------------------
// Out-of-grid and invalid input

TEST(DepositNumberDensity, OutOfGridThrowNamesTheParticle) {
  const GridSpec g = makeGrid({0, 0, 0}, 0.25, {10, 10, 10});
  std::mt19937_64 rng(7);
  auto x = randomInside(g, 100, rng);
  const auto c = randomCounts(x.size(), rng);
  x[37] = {1.0, 2.3, 1.0};   // u_y = 9.2 > dims - 3/2
  x[80] = {-1.0, 1.0, 1.0};  // also outside; the lowest index is reported
  DenseGrid<double> n(g, 42.0);
  const std::string msg = thrownMessage([&] {
    depositNumberDensity({x.data(), c.data(), x.size()}, n.view(), OutOfGridPolicy::Throw);
  });
  EXPECT_NE(msg.find("particle 37 "), std::string::npos) << msg;
  EXPECT_NE(msg.find("2.3,"), std::string::npos) << msg;                 // its position
  EXPECT_NE(msg.find("10 x 10 x 10"), std::string::npos) << msg;         // the grid
  EXPECT_NE(msg.find("y in [0.125, 2.125)"), std::string::npos) << msg;  // the admissible range
  for (double v : n.values()) ASSERT_EQ(v, 42.0);                        // untouched on throw

  // Sampling, same rule.
  DenseGrid<Vec3d> f(g, Vec3d{1, 2, 3});
  std::vector<Vec3d> out(x.size());
  const std::string msg2 = thrownMessage([&] { sampleToParticles(f.view(), x.data(), x.size(), out.data()); });
  EXPECT_NE(msg2.find("particle 37 "), std::string::npos) << msg2;
}

TEST(DepositNumberDensity, OutOfGridSkipIgnoresAndCounts) {
  const GridSpec g = makeGrid({-0.5, -0.5, -0.5}, 0.125, {12, 9, 10});
  std::mt19937_64 rng(8);
  auto x = randomInside(g, 20000, rng);
  auto c = randomCounts(x.size(), rng);
  std::vector<Vec3d> xin;
  std::vector<double> cin;
  std::size_t outside = 0;
  std::uniform_real_distribution<double> far(-3.0, 3.0);
  for (std::size_t p = 0; p < x.size(); ++p) {
    if (p % 7 == 3) {
      // Move it just outside one face (or far away).
      const int axis = int(p % 3);
      x[p][axis] = (p % 2) ? g.origin[axis] + 0.5 * g.dx - 1e-9 : g.origin[axis] + (g.dims[axis] - 1.5) * g.dx;
      if (p % 5 == 0) x[p] = {far(rng) + 10.0, far(rng), far(rng)};
      ++outside;
    } else {
      xin.push_back(x[p]);
      cin.push_back(c[p]);
    }
  }
  TransferReport r;
  const auto n = deposit(g, x, c, OutOfGridPolicy::Skip, &r);
  EXPECT_EQ(r.skipped, outside);
  EXPECT_EQ(r.particles, x.size());
  const long double inside = sumOf(cin);
  EXPECT_LE(std::fabs(double(sumOf(n) * g.cellVolume() - inside)), 1e-12 * double(inside));
  EXPECT_LE(std::fabs(r.totalCount - double(inside)), 1e-12 * double(inside));
  // Exactly what the in-grid particles alone deposit.
  EXPECT_TRUE(bitwiseEqual(n, deposit(g, xin, cin)));
  // And Throw refuses the same input.
  EXPECT_THROW(deposit(g, x, c, OutOfGridPolicy::Throw), InvalidArgument);

  // Sampling under Skip writes zeros for those particles and counts them.
  DenseGrid<double> f(g, 5.0);
  std::vector<double> out(x.size(), -1.0);
  const TransferReport rs = sampleToParticles(f.view(), x.data(), x.size(), out.data(), OutOfGridPolicy::Skip);
  EXPECT_EQ(rs.skipped, outside);
  std::size_t zeros = 0;
  for (double v : out) {
    if (v == 0.0) {
      ++zeros;
    } else {
      EXPECT_NEAR(v, 5.0, 1e-14);
    }
  }
  EXPECT_EQ(zeros, outside);
}

TEST(DepositNumberDensity, InvalidInputAlwaysThrows) {
  const GridSpec g = makeGrid({0, 0, 0}, 0.25, {10, 10, 10});
  std::mt19937_64 rng(9);
  const auto x0 = randomInside(g, 64, rng);
  const auto c0 = randomCounts(x0.size(), rng);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (OutOfGridPolicy policy : {OutOfGridPolicy::Throw, OutOfGridPolicy::Skip}) {
    auto x = x0;
    x[21].y = nan;
    x[50].x = nan;  // the lowest bad index is the one reported
    std::string msg = thrownMessage([&] { deposit(g, x, c0, policy); });
    EXPECT_NE(msg.find("particle 21"), std::string::npos) << msg;
    EXPECT_NE(msg.find("nan"), std::string::npos) << msg;
    x = x0;
    x[5].z = -inf;
    msg = thrownMessage([&] { deposit(g, x, c0, policy); });
    EXPECT_NE(msg.find("particle 5"), std::string::npos) << msg;
    EXPECT_NE(msg.find("-inf"), std::string::npos) << msg;

    auto c = c0;
    c[12] = -2.5;
    msg = thrownMessage([&] { deposit(g, x0, c, policy); });
    EXPECT_NE(msg.find("particle 12"), std::string::npos) << msg;
    EXPECT_NE(msg.find("-2.5"), std::string::npos) << msg;
    c = c0;
    c[40] = nan;
    msg = thrownMessage([&] { deposit(g, x0, c, policy); });
    EXPECT_NE(msg.find("particle 40"), std::string::npos) << msg;
    c = c0;
    c[41] = inf;
    EXPECT_THROW(deposit(g, x0, c, policy), InvalidArgument);

    x = x0;
    x[9].x = nan;
    std::vector<Vec3d> out(x.size());
    DenseGrid<Vec3d> f(g);
    msg = thrownMessage([&] { sampleToParticles(f.view(), x.data(), x.size(), out.data(), policy); });
    EXPECT_NE(msg.find("particle 9"), std::string::npos) << msg;
  }
  // Zero counts are fine; null arrays with particles are not.
  auto c = c0;
  c[3] = 0.0;
  EXPECT_NO_THROW(deposit(g, x0, c));
  DenseGrid<double> n(g);
  EXPECT_THROW(depositNumberDensity({x0.data(), nullptr, x0.size()}, n.view()), InvalidArgument);
  EXPECT_THROW(depositNumberDensity({nullptr, c0.data(), c0.size()}, n.view()), InvalidArgument);
  // No particles: zeros everywhere.
  n.fill(7.0);
  const TransferReport r = depositNumberDensity({nullptr, nullptr, 0}, n.view());
  EXPECT_EQ(r.totalCount, 0.0);
  for (double v : n.values()) ASSERT_EQ(v, 0.0);
}

// ---------------------------------------------------------------------------
// Boundaries

TEST(DepositNumberDensity, ParticlesOnNodesAndStencilBoundaries) {
  // dx a power of two and origin 0, so these positions are exact in grid units.
  const GridSpec g = makeGrid({0, 0, 0}, 0.5, {8, 8, 8});
  const double dx = g.dx;
  const double invV = 1.0 / g.cellVolume();

  // On node (3, 4, 5): weights 1/8, 3/4, 1/8 per axis on nodes 2..4 etc.
  {
    const std::vector<Vec3d> x = {{3 * dx, 4 * dx, 5 * dx}};
    const auto n = deposit(g, x, {1.0});
    const double w1[3] = {0.125, 0.75, 0.125};
    double total = 0;
    for (int k = 0; k < 8; ++k)
      for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 8; ++i) {
          double expect = 0;
          if (i >= 2 && i <= 4 && j >= 3 && j <= 5 && k >= 4 && k <= 6)
            expect = w1[i - 2] * w1[j - 3] * w1[k - 4] * invV;
          EXPECT_EQ(n[g.index(i, j, k)], expect) << i << " " << j << " " << k;
          total += n[g.index(i, j, k)];
        }
    EXPECT_EQ(total * g.cellVolume(), 1.0);
  }

  // Exactly on a base switch (cell centre u = 2.5): weight 1/2 on nodes 2 and
  // 3, none on 4; the same as the limit from below (stencil 1..3).
  {
    const std::vector<Vec3d> at = {{2.5 * dx, 3 * dx, 3 * dx}};
    const std::vector<Vec3d> below = {{std::nextafter(2.5 * dx, 0.0), 3 * dx, 3 * dx}};
    const auto na = deposit(g, at, {1.0});
    const auto nb = deposit(g, below, {1.0});
    for (std::size_t i = 0; i < na.size(); ++i) EXPECT_NEAR(na[i], nb[i], 1e-12 * invV) << i;
    EXPECT_EQ(na[g.index(2, 3, 3)], 0.5 * 0.75 * 0.75 * invV);
    EXPECT_EQ(na[g.index(3, 3, 3)], 0.5 * 0.75 * 0.75 * invV);
    EXPECT_EQ(na[g.index(4, 3, 3)], 0.0);
    EXPECT_EQ(na[g.index(1, 3, 3)], 0.0);
    EXPECT_NEAR(nb[g.index(1, 3, 3)], 0.0, 1e-12 * invV);
  }

  // The admissible range is the half-open [dx/2, (dims - 3/2) dx) per axis.
  const double lo = 0.5 * dx, hi = (g.dims.i - 1.5) * dx;
  const double mid = 3 * dx;
  TransferReport r;
  deposit(g, {{lo, mid, mid}, {mid, lo, mid}, {mid, mid, lo}, {lo, lo, lo}}, {1, 1, 1, 1}, OutOfGridPolicy::Skip, &r);
  EXPECT_EQ(r.skipped, 0u);
  const double below = std::nextafter(hi, 0.0);
  deposit(g, {{below, mid, mid}, {mid, below, mid}, {mid, mid, below}}, {1, 1, 1}, OutOfGridPolicy::Skip, &r);
  EXPECT_EQ(r.skipped, 0u);
  deposit(g,
          {{hi, mid, mid},
           {mid, hi, mid},
           {mid, mid, hi},
           {std::nextafter(lo, 0.0), mid, mid},
           {mid, std::nextafter(lo, 0.0), mid},
           {mid, mid, std::nextafter(lo, 0.0)}},
          {1, 1, 1, 1, 1, 1}, OutOfGridPolicy::Skip, &r);
  EXPECT_EQ(r.skipped, 6u);
  EXPECT_EQ(r.totalCount, 0.0);

  // Sampling agrees on the same boundary points.
  DenseGrid<double> f(g, 2.0);
  std::vector<Vec3d> pts = {{lo, mid, mid}, {below, below, below}, {hi, mid, mid}};
  std::vector<double> out(pts.size(), -1.0);
  const TransferReport rs = sampleToParticles(f.view(), pts.data(), pts.size(), out.data(), OutOfGridPolicy::Skip);
  EXPECT_EQ(rs.skipped, 1u);
  EXPECT_NEAR(out[0], 2.0, 1e-15);
  EXPECT_NEAR(out[1], 2.0, 1e-15);
  EXPECT_EQ(out[2], 0.0);

  // A grid with 2 nodes on an axis has no admissible positions at all.
  const GridSpec thin = makeGrid({0, 0, 0}, 0.5, {8, 2, 8});
  deposit(thin, {{mid, 0.25, mid}}, {1.0}, OutOfGridPolicy::Skip, &r);
  EXPECT_EQ(r.skipped, 1u);
  EXPECT_THROW(deposit(thin, {{mid, 0.25, mid}}, {1.0}), InvalidArgument);
}

// ---------------------------------------------------------------------------
// sampleToParticles

TEST(SampleToParticles, ReproducesLinearAndConstantFields) {
  const GridSpec g = makeGrid({-0.7, 0.3, 1.1}, 0.03, {20, 25, 18});
  const Vec3d a{1.5, -2.0, 0.25};
  const Vec3d Bx{3.0, -1.0, 0.5}, By{-0.5, 2.0, 4.0}, Bz{0.7, 0.1, -3.0};  // rows of B
  DenseGrid<Vec3d> lin(g);
  DenseGrid<double> slin(g), cst(g, 6.02214076e23);
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) {
        const Vec3d x = g.nodePosition(i, j, k);
        lin(i, j, k) = {a.x + dot(Bx, x), a.y + dot(By, x), a.z + dot(Bz, x)};
        slin(i, j, k) = 4.0 - dot(By, x);
      }
  std::mt19937_64 rng(10);
  const auto x = randomInside(g, 20000, rng);
  std::vector<Vec3d> out(x.size());
  std::vector<double> sout(x.size()), cout(x.size());
  const TransferReport r = sampleToParticles(lin.view(), x.data(), x.size(), out.data());
  EXPECT_EQ(r.particles, x.size());
  EXPECT_EQ(r.skipped, 0u);
  sampleToParticles(slin.view(), x.data(), x.size(), sout.data());
  sampleToParticles(cst.view(), x.data(), x.size(), cout.data());
  for (std::size_t p = 0; p < x.size(); ++p) {
    const Vec3d e{a.x + dot(Bx, x[p]), a.y + dot(By, x[p]), a.z + dot(Bz, x[p])};
    ASSERT_NEAR(out[p].x, e.x, 1e-13) << p;
    ASSERT_NEAR(out[p].y, e.y, 1e-13) << p;
    ASSERT_NEAR(out[p].z, e.z, 1e-13) << p;
    ASSERT_NEAR(sout[p], 4.0 - dot(By, x[p]), 1e-13) << p;
    ASSERT_NEAR(cout[p], 6.02214076e23, 4 * 6.02214076e23 * std::numeric_limits<double>::epsilon()) << p;
  }
  // In place: output aliasing the positions.
  std::vector<Vec3d> inplace = x;
  sampleToParticles(lin.view(), inplace.data(), inplace.size(), inplace.data());
  for (std::size_t p = 0; p < x.size(); ++p) ASSERT_EQ(inplace[p], out[p]);
}

TEST(SampleToParticles, MatchesSerialReferenceAndIsDeterministic) {
  const GridSpec g = makeGrid({0.2, 0.1, -0.4}, 0.04, {15, 12, 14});
  std::mt19937_64 rng(11);
  std::normal_distribution<double> nd;
  DenseGrid<Vec3d> f(g);
  for (auto& v : f.values()) v = {nd(rng), nd(rng), nd(rng)};
  const auto x = randomInside(g, 20000, rng);
  std::vector<Vec3d> out(x.size()), out1(x.size());
  sampleToParticles(f.view(), x.data(), x.size(), out.data());
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    sampleToParticles(f.view(), x.data(), x.size(), out1.data());
  }
  for (std::size_t p = 0; p < x.size(); ++p) {
    const Vec3d e = referenceSample(g, f.values(), x[p]);
    ASSERT_NEAR(out[p].x, e.x, 1e-13) << p;
    ASSERT_NEAR(out[p].y, e.y, 1e-13) << p;
    ASSERT_NEAR(out[p].z, e.z, 1e-13) << p;
    ASSERT_EQ(out[p], out1[p]) << p;
  }
}
