// MLS-MPM transfers (mpm_grid.h): P2G and G2P conserve mass, linear momentum
// and APIC angular momentum to round-off, reproduce affine velocity fields
// exactly, and the parallel P2G gives bitwise the same grid for any thread
// count. The vectorised transfers give the scalar formulas of mpm/grid.h
// (P2G summed in its documented order, G2P with the scalar gather): bitwise
// on a CPU without AVX2, and within a few roundings of each term where the
// AVX2 variant fuses multiplies and adds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <tuple>
#include <vector>

#include <tbb/global_control.h>

#include "lodestone/core/base/bspline.h"
#include "lodestone/core/base/cpu_features.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/apic_gather.h"
#include "lodestone/core/mpm/constitutive.h"
#include "lodestone/core/mpm/grid.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone_test/mpm_samples.h"

using namespace lodestone;
using namespace lodestone::test;

namespace {

GridSpec testGrid(int n, double dx) {
  GridSpec g;
  g.dx = dx;
  g.origin = {-0.3, 0.1, -0.7};
  g.dims = {n, n + 1, n + 2};
  return g;
}

MpmParticles randomParticles(const GridSpec& g, std::size_t count, unsigned seed) {
  return randomMpmParticles(g, count, seed, false);
}

struct GridSums {
  double mass = 0;
  Vec3d momentum, angular;
};

GridSums gridSums(const MpmGrid& grid) {
  GridSums s;
  const GridSpec& g = grid.spec();
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) {
        const MpmNode n = grid.nodeAt(i, j, k);
        s.mass += n.mass;
        s.momentum += n.momentum;
        s.angular += cross(g.nodePosition(i, j, k), n.momentum);
      }
  return s;
}

// Velocities from momenta on the massive nodes (a grid update without forces).
void momentumToVelocity(MpmGrid& grid) {
  for (std::size_t n = 0; n < grid.nodes().size(); ++n) {
    const MpmNode& nd = grid.nodes()[n];
    grid.velocity()[n] = nd.mass > 0 ? nd.momentum / nd.mass : Vec3d{};
  }
}

double scaleOf(const Vec3d& v) { return std::fmax(norm(v), 1e-300); }

}  // namespace

TEST(MpmTransfer, ParticleToGridConservesMassMomentumAndAngularMomentum) {
  const GridSpec g = testGrid(14, 0.05);
  const MpmParticles p = randomParticles(g, 3000, 11);
  const std::vector<MpmMaterial> mats = twoMaterials();
  MpmGrid grid(g);
  // dt > 0 includes the stress impulse: zero net force and (tau symmetric) zero net torque.
  grid.particleToGrid(p, mats, 1e-3);
  const GridSums s = gridSums(grid);
  const double M = p.totalMass();
  const Vec3d P = p.linearMomentum();
  const Vec3d L = p.angularMomentum(g.dx);
  // Round-off bounds: ~1e-13 relative to the sums of magnitudes.
  double pScale = 0, lScale = 0;
  for (std::size_t q = 0; q < p.size(); ++q) {
    pScale += p.mass[q] * (norm(p.v[q]) + g.dx * 5 * 3);
    lScale += p.mass[q] * (norm(p.x[q]) + g.dx) * (norm(p.v[q]) + g.dx * 5 * 3);
  }
  EXPECT_NEAR(s.mass, M, 1e-13 * M);
  EXPECT_LT(norm(s.momentum - P), 1e-13 * pScale) << "P = " << P.x << ", " << P.y << ", " << P.z;
  EXPECT_LT(norm(s.angular - L), 1e-13 * lScale) << "L = " << L.x << ", " << L.y << ", " << L.z << " grid "
                                                 << s.angular.x << ", " << s.angular.y << ", " << s.angular.z;
  // The stress impulse is not negligible here: without it the grid momentum
  // per node differs (the check above is not vacuous).
  MpmGrid noStress(g);
  noStress.particleToGrid(p, mats, 0.0);
  double diff = 0;
  for (std::size_t n = 0; n < grid.nodes().size(); ++n)
    diff += norm(grid.nodes()[n].momentum - noStress.nodes()[n].momentum);
  EXPECT_GT(diff, 1e-6 * pScale);
}

TEST(MpmTransfer, GridToParticleConservesMomentumAndAngularMomentum) {
  const GridSpec g = testGrid(14, 0.05);
  MpmParticles p = randomParticles(g, 3000, 12);
  const std::vector<MpmMaterial> mats = twoMaterials();
  MpmGrid grid(g);
  grid.particleToGrid(p, mats, 0.0);
  momentumToVelocity(grid);
  const GridSums s = gridSums(grid);
  // G2P with advection: (x + dt v) x m v = x x m v, so L is kept exactly.
  grid.gridToParticle(p, mats, 1e-3);
  const Vec3d P = p.linearMomentum();
  const Vec3d L = p.angularMomentum(g.dx);
  EXPECT_LT(norm(P - s.momentum), 1e-13 * scaleOf(s.momentum) + 1e-15);
  EXPECT_LT(norm(L - s.angular), 1e-12 * scaleOf(s.angular) + 1e-15)
      << "particles " << L.x << ", " << L.y << ", " << L.z << " grid " << s.angular.x << ", " << s.angular.y << ", "
      << s.angular.z;
  // And a second round trip keeps them (APIC is conservative both ways).
  grid.particleToGrid(p, mats, 0.0);
  const GridSums s2 = gridSums(grid);
  EXPECT_LT(norm(s2.momentum - P), 1e-13 * scaleOf(P));
  EXPECT_LT(norm(s2.angular - L), 1e-12 * scaleOf(L));
}

TEST(MpmTransfer, AffineVelocityFieldIsReproducedExactly) {
  // v(x) = a + B x: P2G gives v_i = a + B x_i on every massive node, and G2P
  // returns v_p = a + B x_p and C_p = B (linear reproduction of the
  // B-splines). A viscosity-free fluid at J = 1 has zero stress.
  const GridSpec g = testGrid(12, 0.1);
  MpmParticles p = randomParticles(g, 1500, 13);
  const Vec3d a{0.3, -0.2, 0.1};
  Mat3d B;
  B(0, 0) = 0.5;
  B(0, 1) = -1.0;
  B(0, 2) = 0.25;
  B(1, 0) = 2.0;
  B(1, 1) = 0.1;
  B(1, 2) = -0.3;
  B(2, 0) = 0.7;
  B(2, 1) = 0.4;
  B(2, 2) = -0.6;
  for (std::size_t q = 0; q < p.size(); ++q) {
    p.v[q] = a + B * p.x[q];
    p.C[q] = B;
    p.J[q] = 1.0;
    p.material[q] = 0;
  }
  const std::vector<MpmMaterial> mats{viscousFluid(0.0, 1e5, 1000)};
  MpmGrid grid(g);
  grid.particleToGrid(p, mats, 1e-3);
  momentumToVelocity(grid);
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) {
        if (grid.nodeAt(i, j, k).mass <= 0) continue;
        const Vec3d expect = a + B * g.nodePosition(i, j, k);
        ASSERT_LT(norm(grid.velocityAt(i, j, k) - expect), 1e-12) << i << " " << j << " " << k;
      }
  const std::vector<Vec3d> x0 = p.x;
  grid.gridToParticle(p, mats, 0.0);
  double worstV = 0, worstC = 0;
  for (std::size_t q = 0; q < p.size(); ++q) {
    worstV = std::fmax(worstV, norm(p.v[q] - (a + B * x0[q])));
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) worstC = std::fmax(worstC, std::fabs(p.C[q](r, c) - B(r, c)));
  }
  EXPECT_LT(worstV, 1e-12);
  EXPECT_LT(worstC, 1e-10);
}

// P2G against the formula of mpm/grid.h evaluated one component at a time,
// each node summing its contributions in the documented order: colour
// (bk mod 3, then bj mod 3) of the sending row, then the bin's bi, then the
// particle index. Bitwise on a CPU without AVX2 and FMA; with them, each
// node within 16 roundings of the sum of its terms' magnitudes (the fused
// multiply-adds round once where the formula rounds twice, and nothing
// else differs). Every thread count and layout gives the same bits.
TEST(MpmTransfer, ParticleToGridIsTheScalarFormulaInTheDocumentedOrder) {
  const GridSpec g = testGrid(12, 0.05);
  const MpmParticles p = randomParticles(g, 2000, 21);
  const std::vector<MpmMaterial> mats = twoMaterials();
  const double dt = 1e-3, dx = g.dx, invDx = 1.0 / dx;
  struct Contribution {
    int colour, bi;
    std::size_t particle;
    Vec3d momentum;
    double mass, magnitude;
  };
  std::vector<std::vector<Contribution>> perNode(g.nodeCount());
  for (std::size_t q = 0; q < p.size(); ++q) {
    const Vec3d u = (p.x[q] - g.origin) * invDx;
    const int b[3] = {int(quadraticBaseFloor(u.x)), int(quadraticBaseFloor(u.y)), int(quadraticBaseFloor(u.z))};
    const QuadraticWeights<double> w[3] = {quadraticWeightsAt(u.x, b[0]), quadraticWeightsAt(u.y, b[1]),
                                           quadraticWeightsAt(u.z, b[2])};
    const MpmMaterial& mat = mats[p.material[q]];
    const Mat3d tau = mat.isFluid() ? viscousFluidKirchhoff(p.C[q], p.J[q], mat.viscosity, mat.bulkModulus)
                                    : neoHookeanKirchhoff(p.F[q], mat.mu, mat.lambda);
    const double m = p.mass[q], s = dt * 4.0 * invDx * invDx * p.volume0[q];
    Mat3d A;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) A(r, c) = m * p.C[q](r, c) - s * tau(r, c);
    const Vec3d f{u.x - b[0], u.y - b[1], u.z - b[2]};
    const Vec3d q0 = m * p.v[q] - A * Vec3d{f.x * dx, f.y * dx, f.z * dx};
    Vec3d col[3];
    for (int c = 0; c < 3; ++c) col[c] = Vec3d{A(0, c) * dx, A(1, c) * dx, A(2, c) * dx};
    // A bound on every product the contribution sums (kg m/s): m v, A d and
    // up to two columns of A dx.
    double maxA = 0;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) maxA = std::max(maxA, std::abs(A(r, c)));
    const Vec3d mv = m * p.v[q];
    const double magnitude = std::max({std::abs(mv.x), std::abs(mv.y), std::abs(mv.z)}) + 10.0 * maxA * dx;
    for (int c = 0; c < 3; ++c)
      for (int bb = 0; bb < 3; ++bb) {
        const Vec3d line = q0 + double(bb) * col[1] + double(c) * col[2];
        const Vec3d atA[3] = {line, line + col[0], line + 2.0 * col[0]};
        for (int a = 0; a < 3; ++a) {
          const double wabc = w[0].w[a] * (w[1].w[bb] * w[2].w[c]);
          perNode[g.index(b[0] + a, b[1] + bb, b[2] + c)].push_back(
              {3 * (b[2] % 3) + b[1] % 3, b[0], q, wabc * atA[a], wabc * m, wabc * magnitude});
        }
      }
  }
  std::vector<MpmNode> expected(g.nodeCount());
  std::vector<double> scale(g.nodeCount(), 0.0);  // the node's sum of term magnitudes, kg m/s and kg
  for (std::size_t n = 0; n < perNode.size(); ++n) {
    std::vector<Contribution>& list = perNode[n];
    std::sort(list.begin(), list.end(), [](const Contribution& l, const Contribution& r) {
      return std::tie(l.colour, l.bi, l.particle) < std::tie(r.colour, r.bi, r.particle);
    });
    for (const Contribution& c : list) {
      expected[n].momentum += c.momentum;
      expected[n].mass += c.mass;
      scale[n] += c.magnitude + c.mass;
    }
  }
  const bool exact = !cpuHasAvx2Fma();
  const double eps = std::numeric_limits<double>::epsilon();
  // With 1 and 2 threads, on the whole grid and (3 threads) on packed runs.
  std::vector<MpmNode> first;
  for (int threads : {1, 2, 3}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(std::min(threads, 2)));
    MpmGrid grid(g);
    grid.setWholeLayout(threads < 3);
    grid.particleToGrid(p, mats, dt);
    EXPECT_EQ(grid.packed(), threads == 3);
    std::vector<MpmNode> got(g.nodeCount());
    for (int k = 0; k < g.dims.k; ++k)
      for (int j = 0; j < g.dims.j; ++j)
        for (int i = 0; i < g.dims.i; ++i) got[g.index(i, j, k)] = grid.nodeAt(i, j, k);
    std::size_t differing = 0, worstNode = 0;
    double worst = 0;  // largest difference over the node's scale, in roundings
    for (std::size_t n = 0; n < got.size(); ++n) {
      if (std::memcmp(&expected[n], &got[n], sizeof(MpmNode)) != 0) ++differing;
      const double diff = std::max(
          {std::abs(got[n].momentum.x - expected[n].momentum.x), std::abs(got[n].momentum.y - expected[n].momentum.y),
           std::abs(got[n].momentum.z - expected[n].momentum.z), std::abs(got[n].mass - expected[n].mass)});
      const double r = diff == 0 ? 0 : diff / (eps * scale[n]);
      if (r > worst) {
        worst = r;
        worstNode = n;
      }
    }
    if (exact) {
      EXPECT_EQ(differing, 0u) << threads << " threads";
    }
    EXPECT_LT(worst, 16.0) << threads << " threads; node " << worstNode << ": mass " << got[worstNode].mass
                           << " kg, expected " << expected[worstNode].mass << "; momentum x "
                           << got[worstNode].momentum.x << ", expected " << expected[worstNode].momentum.x;
    std::printf(
        "%d threads: %zu of %zu nodes differ from the formula's bits, by at most %.2f roundings of their terms\n",
        threads, differing, got.size(), worst);
    if (first.empty()) {
      first = got;
    } else {
      EXPECT_EQ(0, std::memcmp(first.data(), got.data(), got.size() * sizeof(MpmNode)))
          << threads << " threads differ from 1 thread";
    }
  }
}

// G2P against the scalar gather (gatherApic in Vec3d, as on the device, on
// the velocities copied into a whole grid) and the scalar F, J and position
// updates of mpm/grid.h, on the whole grid and on packed runs: bitwise on a
// CPU without AVX2 and FMA; with them, within 16 roundings of each
// quantity's scale (the fastest node velocity, 4/dx times it for C, 1 for F
// and J, the domain's extent for x).
TEST(MpmTransfer, GridToParticleIsTheScalarGather) {
  for (const bool packed : {false, true}) {
  SCOPED_TRACE(packed ? "packed" : "whole");
  const GridSpec g = testGrid(12, 0.05);
  MpmParticles p = randomParticles(g, 2000, 22);
  const std::vector<MpmMaterial> mats = twoMaterials();
  const double dt = 1e-3, invDx = 1.0 / g.dx;
  MpmGrid grid(g);
  grid.setWholeLayout(!packed);
  grid.particleToGrid(p, mats, dt);
  ASSERT_EQ(grid.packed(), packed);
  momentumToVelocity(grid);
  std::vector<Vec3d> whole(g.nodeCount());
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) whole[g.index(i, j, k)] = grid.velocityAt(i, j, k);
  MpmParticles expected = p;
  for (std::size_t q = 0; q < p.size(); ++q) {
    const Vec3d x = p.x[q];
    const double u[3] = {(x.x - g.origin.x) * invDx, (x.y - g.origin.y) * invDx, (x.z - g.origin.z) * invDx};
    const int b[3] = {int(quadraticBaseFloor(u[0])), int(quadraticBaseFloor(u[1])), int(quadraticBaseFloor(u[2]))};
    Vec3d vp;
    Mat3d C;
    gatherApic<Vec3d>(whole.data(), std::size_t(g.dims.i), std::size_t(g.dims.j), u, b, 4.0 * invDx, vp, C);
    if (mats[p.material[q]].isFluid()) {
      expected.J[q] *= 1.0 + dt * trace(C);
    } else {
      Mat3d G = Mat3d::identity();
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) G(r, c) += dt * C(r, c);
      expected.F[q] = G * p.F[q];
      expected.J[q] = determinant(expected.F[q]);
    }
    expected.C[q] = C;
    expected.v[q] = vp;
    expected.x[q] = x + dt * vp;
  }
  grid.gridToParticle(p, mats, dt);
  const std::size_t n = p.size();
  if (!cpuHasAvx2Fma()) {
    EXPECT_EQ(0, std::memcmp(p.x.data(), expected.x.data(), n * sizeof(Vec3d)));
    EXPECT_EQ(0, std::memcmp(p.v.data(), expected.v.data(), n * sizeof(Vec3d)));
    EXPECT_EQ(0, std::memcmp(p.C.data(), expected.C.data(), n * sizeof(Mat3d)));
    EXPECT_EQ(0, std::memcmp(p.F.data(), expected.F.data(), n * sizeof(Mat3d)));
    EXPECT_EQ(0, std::memcmp(p.J.data(), expected.J.data(), n * sizeof(double)));
  }
  double vmax = 0;
  for (const Vec3d& v : whole) vmax = std::max({vmax, std::abs(v.x), std::abs(v.y), std::abs(v.z)});
  const double extent = std::max({std::abs(g.origin.x), std::abs(g.origin.y), std::abs(g.origin.z)}) +
                        g.dx * double(std::max({g.dims.i, g.dims.j, g.dims.k}));
  const double eps = std::numeric_limits<double>::epsilon();
  double worst[5] = {0, 0, 0, 0, 0};  // x, v, C, F, J: largest difference over its scale, in roundings
  for (std::size_t q = 0; q < n; ++q) {
    for (int a = 0; a < 3; ++a) {
      worst[0] = std::max(worst[0], std::abs(p.x[q][a] - expected.x[q][a]) / (eps * extent));
      worst[1] = std::max(worst[1], std::abs(p.v[q][a] - expected.v[q][a]) / (eps * vmax));
      for (int b = 0; b < 3; ++b) {
        worst[2] = std::max(worst[2], std::abs(p.C[q](a, b) - expected.C[q](a, b)) / (eps * 4.0 * invDx * vmax));
        worst[3] = std::max(worst[3], std::abs(p.F[q](a, b) - expected.F[q](a, b)) / eps);
      }
    }
    worst[4] = std::max(worst[4], std::abs(p.J[q] - expected.J[q]) / eps);
  }
  const char* names[5] = {"x", "v", "C", "F", "J"};
  for (int i = 0; i < 5; ++i) {
    EXPECT_LT(worst[i], 16.0) << names[i];
    std::printf("%s: at most %.2f roundings of its scale from the scalar formula\n", names[i], worst[i]);
  }
  }
}

// The fastest speed G2P reports is MpmGrid::maxSpeed of the velocities it
// wrote, bit for bit: the solver's time step takes either. One particle a
// transfer, so that each of 300 velocities is compared, not only the
// fastest of many.
TEST(MpmTransfer, GridToParticlesFastestSpeedIsMaxSpeedOfItsVelocities) {
  const GridSpec g = testGrid(8, 0.05);
  const std::vector<MpmMaterial> mats = twoMaterials();
  MpmGrid grid(g);
  for (unsigned seed = 0; seed < 300; ++seed) {
    MpmParticles p = randomParticles(g, 1, 1000 + seed);
    grid.particleToGrid(p, mats, 1e-3);
    momentumToVelocity(grid);
    const GridToParticleReport rep = grid.gridToParticle(p, mats, 1e-3);
    ASSERT_GT(rep.maxSpeed, 0.0) << "seed " << seed;
    EXPECT_EQ(rep.maxSpeed, MpmGrid::maxSpeed(p.v.data(), 1))
        << "seed " << seed << ": v = (" << p.v[0].x << ", " << p.v[0].y << ", " << p.v[0].z << ") m/s";
  }
}

TEST(MpmTransfer, ParallelParticleToGridIsBitwiseDeterministic) {
  const GridSpec g = testGrid(20, 0.05);
  const MpmParticles p = randomParticles(g, 20000, 14);
  const std::vector<MpmMaterial> mats = twoMaterials();
  std::vector<MpmNode> ref;
  for (int threads : {1, 2, 3, 4}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    MpmGrid grid(g);
    grid.particleToGrid(p, mats, 1e-3);
    if (ref.empty()) {
      ref.assign(grid.nodes().begin(), grid.nodes().end());
      continue;
    }
    ASSERT_EQ(grid.nodes().size(), ref.size());
    EXPECT_EQ(0, std::memcmp(grid.nodes().data(), ref.data(), ref.size() * sizeof(MpmNode)))
        << threads << " threads differ from 1 thread";
  }
}

TEST(MpmTransfer, SolverStepsAreBitwiseDeterministicAcrossThreadCounts) {
  auto run = [](int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    MpmSettings s;
    s.grid = testGrid(16, 0.02);
    s.fixedDt = 2e-4;
    MpmSolver solver(s);
    const std::uint32_t solid = solver.addMaterial(neoHookeanSolid(2e4, 0.3, 1000));
    const std::uint32_t fluid = solver.addMaterial(viscousFluid(0.1, 2e4, 1000));
    EmitterSettings e;
    e.jitter = 0.8;
    e.seed = 5;
    const Vec3d c = s.grid.origin + 0.5 * s.grid.dx * Vec3d{15, 16, 17};
    solver.emit(EmitterShape::box(Pose::at(c + Vec3d{-0.05, 0, 0}), {0.04, 0.05, 0.05}), solid, e);
    solver.emit(EmitterShape::sphere(Pose::at(c + Vec3d{0.06, 0, 0.02}), 0.04), fluid, e);
    for (int n = 0; n < 30; ++n) solver.step(2e-4);
    return solver.particles();
  };
  const MpmParticles a = run(1);
  for (int threads : {2, 4}) {
    const MpmParticles b = run(threads);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(0, std::memcmp(a.x.data(), b.x.data(), a.size() * sizeof(Vec3d))) << threads << " threads";
    EXPECT_EQ(0, std::memcmp(a.v.data(), b.v.data(), a.size() * sizeof(Vec3d))) << threads << " threads";
    EXPECT_EQ(0, std::memcmp(a.F.data(), b.F.data(), a.size() * sizeof(Mat3d))) << threads << " threads";
  }
}

// The binning computes stencil bases four particles at a time where the CPU
// has AVX2: on positions at half-cell edges (where the base steps), one ulp
// either side of them and at the first and last base of the grid, every
// particle's mass lands on the nodes of its scalar base
// (quadraticBaseFloor), and one ulp past the grid's range is refused naming
// the particle. dx is a power of two and the origin 0, so x / dx is exact,
// one ulp included.
TEST(MpmTransfer, BasesAtHalfCellEdgesAreTheScalarBases) {
  GridSpec g;
  g.dx = 0.0625;  // m
  g.origin = {0, 0, 0};
  g.dims = {9, 10, 11};
  const std::vector<double> edges = {0.5, 1.5, 2.5, 3.5, 4.0, 5.5, double(g.dims.i) - 1.5};
  std::vector<double> us;
  for (double u : edges)
    for (double d : {-1.0, 0.0, 1.0}) {
      const double v = d == 0 ? u : std::nextafter(u, d * HUGE_VAL);
      if (v >= 0.5 && v < double(g.dims.i) - 1.5) us.push_back(v);
    }
  MpmParticles p;
  for (std::size_t a = 0; a < us.size(); ++a)
    for (std::size_t b = 0; b < us.size(); b += 2)  // 2 * 3 axes' worth of combinations, a count not a multiple of 4
      p.add(g.origin + g.dx * Vec3d{us[a], us[b], us[(a + b) % us.size()]}, {}, 1.0 + double(p.size()), 1e-6, 0, 0);
  ASSERT_NE(p.size() % 4, 0u) << "the last particles would not take the scalar tail";
  std::vector<double> expected(g.nodeCount(), 0.0);
  for (std::size_t q = 0; q < p.size(); ++q) {
    const Vec3d u = (p.x[q] - g.origin) * (1.0 / g.dx);
    const int b[3] = {int(quadraticBaseFloor(u.x)), int(quadraticBaseFloor(u.y)), int(quadraticBaseFloor(u.z))};
    const QuadraticWeights<double> w[3] = {quadraticWeightsAt(u.x, b[0]), quadraticWeightsAt(u.y, b[1]),
                                           quadraticWeightsAt(u.z, b[2])};
    for (int c = 0; c < 3; ++c)
      for (int bb = 0; bb < 3; ++bb)
        for (int a = 0; a < 3; ++a)
          expected[g.index(b[0] + a, b[1] + bb, b[2] + c)] += p.mass[q] * w[0].w[a] * w[1].w[bb] * w[2].w[c];
  }
  const std::vector<MpmMaterial> mats{neoHookeanSolid(1e5, 0.3, 1000)};
  MpmGrid grid(g);
  grid.particleToGrid(p, mats, 0.0);
  double worst = 0, total = 0;
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) {
        worst = std::max(worst, std::fabs(grid.nodeAt(i, j, k).mass - expected[g.index(i, j, k)]));
        total += expected[g.index(i, j, k)];
      }
  // A base one node off would move a whole particle's mass (at least 1 kg)
  // by a node; summation order alone differs by rounding.
  EXPECT_LT(worst, 1e-12 * total) << p.size() << " particles";

  // One ulp below the first base's range along each axis in turn.
  for (int axis = 0; axis < 3; ++axis) {
    MpmParticles bad = p;
    Vec3d u = (bad.x[5] - g.origin) * (1.0 / g.dx);
    u[axis] = std::nextafter(0.5, 0.0);
    bad.x[5] = g.origin + g.dx * u;
    try {
      grid.particleToGrid(bad, mats, 0.0);
      ADD_FAILURE() << "axis " << axis << ": accepted";
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find("particle 5 "), std::string::npos) << e.what();
    }
  }
}

TEST(MpmTransfer, RejectsParticlesOutsideTheGridNamingThem) {
  const GridSpec g = testGrid(8, 0.1);
  MpmParticles p;
  p.add(g.origin + Vec3d{0.35, 0.35, 0.35}, {}, 1, 1e-3, 0, 0);
  p.add(g.origin + Vec3d{0.02, 0.35, 0.35}, {}, 1, 1e-3, 0, 0);  // u.x = 0.2 < 1/2
  MpmGrid grid(g);
  const std::vector<MpmMaterial> mats{neoHookeanSolid(1e5, 0.3, 1000)};
  try {
    grid.particleToGrid(p, mats, 1e-3);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("particle 1"), std::string::npos) << e.what();
  }
  p.x[1] = g.origin + Vec3d{0.35, 0.35, 0.35};
  p.material[0] = 3;
  EXPECT_THROW(grid.particleToGrid(p, mats, 1e-3), InvalidArgument);
}

TEST(MpmTransfer, NamesTheFirstBadParticleWhereverItLiesInABlockOfFour) {
  // The binning computes four particles' bases at a time: a bad material,
  // a position outside and a NaN in each lane of a block, and one left to
  // the scalar remainder, are each found and the lowest index named.
  const GridSpec g = testGrid(8, 0.1);
  const std::vector<MpmMaterial> mats{neoHookeanSolid(1e5, 0.3, 1000), neoHookeanSolid(2e5, 0.3, 1000)};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t bad = 0; bad < 11; ++bad)
    for (int kind = 0; kind < 3; ++kind) {
      MpmParticles p;
      for (std::size_t q = 0; q < 11; ++q)
        p.add(g.origin + Vec3d{0.3 + 0.01 * double(q), 0.35, 0.35}, {}, 1, 1e-3, std::uint32_t(q % 2), 0);
      if (kind == 0) p.material[bad] = 2;  // one past the last material
      if (kind == 1) p.x[bad].y = g.origin.y + 0.02;
      if (kind == 2) p.x[bad].z = nan;
      if (bad + 3 < 11) p.material[bad + 3] = 7;  // a later bad particle is not the one named
      MpmGrid grid(g);
      try {
        grid.particleToGrid(p, mats, 1e-3);
        ADD_FAILURE() << "particle " << bad << " (kind " << kind << ") was not refused";
      } catch (const InvalidArgument& e) {
        const char* what[] = {": material index 2 ", " at (", ": position must be finite"};
        const std::string want = "MPM particle " + std::to_string(bad) + what[kind];
        EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
      }
    }
  // The largest valid index passes.
  MpmParticles p;
  for (std::size_t q = 0; q < 8; ++q) p.add(g.origin + Vec3d{0.35, 0.35, 0.35}, {}, 1, 1e-3, 1, 0);
  MpmGrid grid(g);
  EXPECT_NO_THROW(grid.particleToGrid(p, mats, 1e-3));
}
