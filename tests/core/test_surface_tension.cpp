// Surface tension of the MPM fluids: the continuum surface stress
// T = sigma (|g| P + d P H P), P = I - n n^T, on the colour field's gradient g
// and Hessian H (mpm/surface_tension.h, mpm/grid.h).
//
// A resting drop of radius R carries the Laplace pressure 2 sigma / R; the
// fluid's pressure is its equation of state p = K (1 - J) (constitutive.h).
// The stress form conserves linear and angular momentum exactly; a cube of
// liquid pulls itself round; spurious currents at rest stay a small fraction
// of the capillary velocity sigma / mu_N; a stretched drop oscillates at
// Rayleigh's l = 2 frequency. The measured figures are in docs/physics.md.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/constitutive.h"
#include "lodestone/core/mpm/grid.h"
#include "lodestone/core/base/constants.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/mpm/surface_tension.h"

using namespace lodestone;

namespace {

constexpr double kDx = 1e-3;      // m
constexpr double kRho = 1000;     // kg/m^3
constexpr double kSigma = 0.07;   // N/m

MpmSettings dropSettings(int nodes) {
  MpmSettings s;
  s.grid.dx = kDx;
  s.grid.dims = {nodes, nodes, nodes};
  s.gravity = {0, 0, 0};
  s.walls.mode = BoundaryMode::Separate;
  return s;
}

Vec3d centreOf(int nodes) { return Vec3d{0.5, 0.5, 0.5} * (double(nodes - 1) * kDx); }

/// Runs the solver for `duration` s in frames of `frame` s; fails the test on non-finite particles.
int runFor(MpmSolver& solver, double duration, double frame) {
  int substeps = 0;
  while (solver.time() < duration - 1e-12) {
    const MpmFrameReport r = solver.advanceFrame(frame);
    substeps += r.substeps;
    EXPECT_EQ(r.nonFinite, 0u);
    if (r.nonFinite > 0) break;
  }
  return substeps;
}

/// The largest over the smallest distance from the centre of mass of the
/// surface in 26 directions (faces, edges and corners of a cube): about
/// sqrt(3) for a cube, 1 for a sphere. The surface in a direction is the
/// fifth-farthest particle within 10 degrees of it (a few stray particles do
/// not count); `stray` counts the particles beyond 1.5 times the radius of
/// the sphere of the same volume.
double outlineRatio(const MpmParticles& p, std::size_t* stray = nullptr) {
  const Vec3d c = p.centreOfMass();
  std::vector<double> far[26];
  Vec3d dirs[26];
  int n = 0;
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
      for (int k = -1; k <= 1; ++k)
        if (i || j || k) {
          const Vec3d d{double(i), double(j), double(k)};
          dirs[n++] = d / norm(d);
        }
  double volume = 0;
  for (std::size_t q = 0; q < p.size(); ++q) volume += p.volume0[q] * p.J[q];
  const double radius = std::cbrt(3 * volume / (4 * 3.14159265358979));
  if (stray) *stray = 0;
  for (std::size_t q = 0; q < p.size(); ++q) {
    const Vec3d r = p.x[q] - c;
    const double len = norm(r);
    if (len == 0) continue;
    if (stray && len > 1.5 * radius) ++*stray;
    for (int a = 0; a < 26; ++a)
      if (dot(r, dirs[a]) > std::cos(10.0 * 3.14159265358979 / 180) * len) far[a].push_back(len);
  }
  double hi = 0, lo = 1e300;
  for (std::vector<double>& f : far) {
    std::sort(f.begin(), f.end(), std::greater<double>());
    const double d = f.size() > 4 ? f[4] : (f.empty() ? 0.0 : f.back());
    hi = std::max(hi, d);
    lo = std::min(lo, d);
  }
  return hi / lo;
}

/// Radius (m) of the sphere of the particles' current volume sum V_p^0 J_p.
double equivalentRadius(const MpmParticles& p) {
  double volume = 0;
  for (std::size_t q = 0; q < p.size(); ++q) volume += p.volume0[q] * p.J[q];
  return std::cbrt(3 * volume / (4 * kPi));
}

/// Adds water of viscosity mu (Pa*s) and bulk modulus K (Pa) with surface
/// tension kSigma to `solver`; returns its material index.
std::uint32_t addWater(MpmSolver& solver, double mu, double K) {
  MpmMaterial water = viscousFluid(mu, K, kRho);
  water.surfaceTension = kSigma;
  water.validate();
  return solver.addMaterial(water);
}

/// A drop of radius R cells settled for 0.3 s (about 2.5 capillary times
/// sqrt(rho R^3 / sigma) at R = 10 cells), Ohnesorge number mu / sqrt(rho
/// sigma R) = 0.6 (mu = 0.5 Pa*s at R = 10 cells).
struct SettledDrop {
  double R = 0, mu = 0, K = 0;
  double Req = 0;       // radius of the sphere of the settled drop's volume, m
  double pressure = 0;  // mean K (1 - J) of the particles within R/2 of the centre, Pa
  double maxSpeed = 0;  // m/s
  std::size_t inner = 0, particles = 0;
  int substeps = 0;
};

SettledDrop settledDrop(double cells) {
  SettledDrop d;
  d.R = cells * kDx;
  d.mu = 0.6 * std::sqrt(kRho * kSigma * d.R);
  d.K = 25 * 2 * kSigma / d.R;  // the Laplace pressure compresses it by 4%
  const int nodes = int(2 * cells) + 8;
  MpmSolver solver(dropSettings(nodes));
  const std::uint32_t m = addWater(solver, d.mu, d.K);
  solver.emit(EmitterShape::sphere(Pose::at(centreOf(nodes)), d.R), m, {});
  d.substeps = runFor(solver, 0.3, 0.05);
  const MpmParticles& p = solver.particles();
  const Vec3d c = p.centreOfMass();
  double sum = 0;
  for (std::size_t q = 0; q < p.size(); ++q) {
    d.maxSpeed = std::max(d.maxSpeed, norm(p.v[q]));
    if (norm(p.x[q] - c) < 0.5 * d.R) {
      sum += d.K * (1 - p.J[q]);
      ++d.inner;
    }
  }
  d.pressure = sum / double(d.inner);
  d.Req = equivalentRadius(p);
  d.particles = p.size();
  return d;
}

}  // namespace

TEST(SurfaceTension, CapillaryStressIsATangentialTension) {
  const Vec3d g{3.0, -4.0, 12.0};  // |g| = 13 /m
  const double sigma = 0.5;
  const Mat3d T = capillaryStress(g, sigma, 1e-9);
  const Vec3d n = g / 13.0;
  // Symmetric, trace 2 sigma |g|, no normal component: T n = 0.
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) EXPECT_DOUBLE_EQ(T(a, b), T(b, a));
  EXPECT_NEAR(trace(T), 2 * sigma * 13.0, 1e-12);
  const Vec3d Tn = T * n;
  EXPECT_NEAR(norm(Tn), 0.0, 1e-12);
  // A tangent t: T t = sigma |g| t (tension, positive).
  const Vec3d t{4.0 / 5.0, 3.0 / 5.0, 0.0};
  EXPECT_NEAR(dot(T * t, t), sigma * 13.0, 1e-12);
  // No interface, no stress; no sigma, no stress.
  EXPECT_EQ(trace(capillaryStress(Vec3d{}, sigma, 1e-9)), 0.0);
  EXPECT_EQ(trace(capillaryStress(Vec3d{1e-12, 0, 0}, sigma, 1e-9)), 0.0);
  EXPECT_EQ(trace(capillaryStress(g, 0.0, 1e-9)), 0.0);
  // The capillary time step sqrt(rho dx^3 / (2 pi sigma)).
  EXPECT_NEAR(capillaryTimeStep(1000.0, 1e-3, 0.07), std::sqrt(1e-6 / (2 * 3.14159265358979 * 0.07)), 1e-15);
  EXPECT_TRUE(std::isinf(capillaryTimeStep(1000.0, 1e-3, 0.0)));
}

// The tension carried a depth d inside a curved surface is scaled along each
// principal direction by 1 - d kappa_k: on a sphere of radius r by 1 - d / r
// in both, on a cylinder only around it; kept within half the tension.
TEST(SurfaceTension, CurvedStressScalesEachPrincipalTension) {
  const double sigma = 0.07, fp = -400.0, fpp = 3e4;  // N/m; c'(r) (1/m), c''(r) (1/m^2)
  // a A + b B
  const auto sum = [](double a, const Mat3d& A, double b, const Mat3d& B) {
    Mat3d m;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m(i, j) = a * A(i, j) + b * B(i, j);
    return m;
  };
  const auto expectNear = [](const Mat3d& a, const Mat3d& b, double tol) {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(a(i, j), b(i, j), tol) << i << "," << j;
  };
  const Vec3d rhat = Vec3d{2.0, -1.0, 2.0} / 3.0;
  const Mat3d rr = Mat3d::outer(rhat, rhat);
  const Mat3d P = sum(1, Mat3d::identity(), -1, rr);
  // Sphere: c = c(r) at radius r = 8 mm, depth 1 mm.
  const double r = 8e-3, d = 1e-3;
  const Vec3d g = fp * rhat;
  const Mat3d Hs = sum(fpp, rr, fp / r, P);
  expectNear(curvedCapillaryStress(g, Hs, sigma, d, 1e-6), sum(sigma * -fp * (1 - d / r), P, 0, P), 1e-9);
  expectNear(curvedCapillaryStress(g, Hs, sigma, 0.0, 1e-6), capillaryStress(g, sigma, 1e-6), 1e-12);
  // Cylinder along z through the origin, the point in direction (0.6, 0.8, 0).
  const Vec3d rho{0.6, 0.8, 0.0}, theta{-0.8, 0.6, 0.0}, z{0, 0, 1};
  const Mat3d tt = Mat3d::outer(theta, theta), zz = Mat3d::outer(z, z);
  const Mat3d Hc = sum(fpp, Mat3d::outer(rho, rho), fp / r, tt);
  expectNear(curvedCapillaryStress(fp * rho, Hc, sigma, d, 1e-6), sum(sigma * -fp * (1 - d / r), tt, sigma * -fp, zz),
             1e-9);
  // A curvature of the cell's size: the correction stops at half the tension (Frobenius norm).
  const double tight = 1.25e-3;  // d / r = 0.8
  const Mat3d Ht = sum(fpp, rr, fp / tight, P);
  expectNear(curvedCapillaryStress(g, Ht, sigma, d, 1e-6), sum(sigma * -fp * (1 - 0.5 / std::sqrt(2.0)), P, 0, P),
             1e-9);
  // No interface, no sigma: nothing.
  EXPECT_EQ(trace(curvedCapillaryStress(Vec3d{}, Hs, sigma, d, 1e-6)), 0.0);
  EXPECT_EQ(trace(curvedCapillaryStress(g, Hs, 0.0, d, 1e-6)), 0.0);
}

// The colour Hessian from the nodes' central differences: exact for a
// quadratic colour field (central differences and the B-spline's linear
// reproduction both are), at any point of the stencil.
TEST(SurfaceTension, ColourHessianIsExactForAQuadraticField) {
  const int n = 8;
  const double dx = 2e-3, invDx = 1 / dx;
  const Vec3d b{3.0, -2.0, 1.0};
  const double a[3][3] = {{40.0, -7.0, 3.0}, {-7.0, -25.0, 11.0}, {3.0, 11.0, 9.0}};  // 1/m^2, symmetric
  Mat3d A;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) A(i, j) = a[i][j];
  std::vector<double> colour(std::size_t(n) * n * n);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Vec3d x = dx * Vec3d{double(i), double(j), double(k)};
        colour[std::size_t(i) + std::size_t(n) * (std::size_t(j) + std::size_t(n) * std::size_t(k))] =
            0.5 + dot(b, x) + 0.5 * dot(x, A * x);
      }
  for (const Vec3d u : {Vec3d{3.2, 3.9, 4.4}, Vec3d{2.5, 4.0, 3.7}, Vec3d{4.49, 3.51, 3.0}}) {
    const QuadraticWeights<double> wx = quadraticWeightsAt(u.x, int(quadraticBaseFloor(u.x)), invDx);
    const QuadraticWeights<double> wy = quadraticWeightsAt(u.y, int(quadraticBaseFloor(u.y)), invDx);
    const QuadraticWeights<double> wz = quadraticWeightsAt(u.z, int(quadraticBaseFloor(u.z)), invDx);
    const Mat3d H = colourHessian(colour.data(), n, n, n, wx.base, wy.base, wz.base, wx, wy, wz, invDx);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(H(i, j), A(i, j), 1e-9) << i << "," << j;
  }
}

TEST(SurfaceTension, BadValuesAndSolidsAreRefusedNamingTheValue) {
  auto messageOf = [](const MpmMaterial& m) -> std::string {
    try {
      m.validate();
    } catch (const InvalidArgument& e) {
      return e.what();
    }
    return "";
  };
  MpmMaterial fluid = viscousFluid(1, 1e5, 1000);
  EXPECT_EQ(messageOf(fluid), "");
  fluid.surfaceTension = 0.072;
  EXPECT_EQ(messageOf(fluid), "");
  EXPECT_NE(fluid.describe().find("sigma = 0.072 N/m"), std::string::npos) << fluid.describe();
  fluid.surfaceTension = -0.5;
  EXPECT_NE(messageOf(fluid).find("surface tension sigma must be finite and in [0, 10] (N/m), got -0.5"),
            std::string::npos)
      << messageOf(fluid);
  fluid.surfaceTension = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(messageOf(fluid).find("got nan"), std::string::npos) << messageOf(fluid);
  fluid.surfaceTension = 25;
  EXPECT_NE(messageOf(fluid).find("got 25"), std::string::npos) << messageOf(fluid);
  MpmMaterial plastic = viscoplasticFluid(10, 1, 1, 100, 1e5, 1000);
  plastic.surfaceTension = 0.03;
  EXPECT_EQ(messageOf(plastic), "");
  MpmMaterial solid = neoHookeanSolid(1e5, 0.3, 1000);
  EXPECT_EQ(solid.describe().find("sigma"), std::string::npos);
  solid.surfaceTension = 0.07;
  EXPECT_NE(messageOf(solid).find("Neo-Hookean solid: surface tension applies only to the fluid models, got "
                                  "sigma = 0.07 N/m"),
            std::string::npos)
      << messageOf(solid);
  MpmSolver solver(dropSettings(8));
  EXPECT_THROW(solver.addMaterial(solid), InvalidArgument);
}

TEST(SurfaceTension, CapillaryLimitBoundsTheTimeStep) {
  MpmSolver solver(dropSettings(12));
  MpmMaterial water = viscousFluid(0, 1, kRho);  // slow sound, no viscosity: the capillary limit decides
  water.surfaceTension = 1.0;
  solver.addMaterial(water);
  const double limit = capillaryTimeStep(kRho, kDx, 1.0);
  std::printf("capillary limit %.4g s, stability bound %.4g s, suggested %.4g s\n", limit,
              solver.stabilityLimitDt(), solver.suggestedDt());
  EXPECT_DOUBLE_EQ(solver.stabilityLimitDt(), limit);
  EXPECT_LE(solver.suggestedDt(), limit);
}

/// What the liquid particles under a flat surface carry: the tension's mean
/// depth below the surface (cells, |g|-weighted) and sum_p V_p |g_p| per
/// unit area, averaged over ten offsets of the particle lattice from the
/// surface; `perAxis` particles per cell and axis.
struct FlatInterface {
  double depthCells = 0, weight = 0, weightLo = 1e300, weightHi = 0;
};

FlatInterface flatInterface(int perAxis) {
  const GridSpec spec{{0.0, 0.0, 0.0}, kDx, {18, 18, 24}};
  MpmGrid grid(spec);
  MpmMaterial water = viscousFluid(0.1, 1e5, kRho);
  water.surfaceTension = kSigma;
  const std::vector<MpmMaterial> mats = {water};
  const double h = kDx / perAxis;  // lattice spacing, m
  FlatInterface out;
  const int offsets = 10;
  for (int o = 0; o < offsets; ++o) {
    // Liquid fills x, y in [1, 15) cells and z in [2 cells, surface).
    const double surface = (12.0 + double(o) / (offsets * perAxis)) * kDx;
    MpmParticles p;
    for (double z = surface - h / 2; z > 2 * kDx; z -= h)
      for (double y = kDx + h / 2; y < 15 * kDx; y += h)
        for (double x = kDx + h / 2; x < 15 * kDx; x += h) p.add({x, y, z}, {}, kRho * h * h * h, h * h * h, 0, 0);
    grid.particleToGrid(p, mats, 0.0);
    // The colour field on the whole grid (colourAt: zero outside the runs).
    const GridSpec& gs = grid.spec();
    std::vector<double> colour(gs.nodeCount());
    for (int k = 0; k < gs.dims.k; ++k)
      for (int j = 0; j < gs.dims.j; ++j)
        for (int i = 0; i < gs.dims.i; ++i) colour[gs.index(i, j, k)] = grid.colourAt(i, j, k);
    const std::size_t sj = std::size_t(gs.dims.i), sk = sj * std::size_t(gs.dims.j);
    double sumG = 0, sumGd = 0, sumVG = 0;
    for (std::size_t q = 0; q < p.size(); ++q) {
      const Vec3d x = p.x[q] / kDx;  // grid coordinates
      // A 6 x 6-cell patch of the top surface, away from the sides and the bottom.
      if (x.x < 5 || x.x >= 11 || x.y < 5 || x.y >= 11 || x.z < 7) continue;
      const QuadraticWeights<double> wx = quadraticWeightsAt(x.x, int(quadraticBaseFloor(x.x)), 1 / kDx);
      const QuadraticWeights<double> wy = quadraticWeightsAt(x.y, int(quadraticBaseFloor(x.y)), 1 / kDx);
      const QuadraticWeights<double> wz = quadraticWeightsAt(x.z, int(quadraticBaseFloor(x.z)), 1 / kDx);
      const double g = norm(colourGradient(colour.data() + gs.index(wx.base, wy.base, wz.base), sj, sk, wx, wy, wz));
      sumG += g;
      sumGd += g * (surface - p.x[q].z) / kDx;
      sumVG += p.volume0[q] * g;
    }
    const double weight = sumVG / (36 * kDx * kDx);
    out.depthCells += sumGd / sumG / offsets;
    out.weight += weight / offsets;
    out.weightLo = std::min(out.weightLo, weight);
    out.weightHi = std::max(out.weightHi, weight);
  }
  return out;
}

// Under a flat surface the liquid particles hold half of the interface's
// integral of |g| (kLiquidSideWeight = 2) for lattices of 1 to 3 particles
// per cell and axis, at a |g|-weighted mean depth of 0.59 cells: less than
// the depth term's kTensionDepthCells, which also covers a curved surface's
// liquid side holding more than half (surface_tension.h).
TEST(SurfaceTension, FlatInterfaceTensionDepth) {
  for (int perAxis = 1; perAxis <= 3; ++perAxis) {
    const FlatInterface f = flatInterface(perAxis);
    std::printf("flat interface, %d particle(s) per cell and axis: sum V |g| per area %.4f (%.4f .. %.4f over the "
                "offsets), tension depth %.4f cells\n",
                perAxis, f.weight, f.weightLo, f.weightHi, f.depthCells);
    EXPECT_NEAR(f.weight, 1 / kLiquidSideWeight, 0.025);
    EXPECT_LT(f.depthCells, kTensionDepthCells);
  }
}

void printLaplace(const SettledDrop& d) {
  const double laplace = 2 * kSigma / d.Req;
  std::printf(
      "Laplace: R = %.0f cells (settled: %.3f cells), %zu particles (%zu within R/2), %d substeps; mean pressure "
      "K (1 - J) within R/2 %.4g Pa vs 2 sigma / R = %.4g Pa at the settled radius (ratio %.4f; %.4f against the "
      "initial radius)\n",
      d.R / kDx, d.Req / kDx, d.particles, d.inner, d.substeps, d.pressure, laplace, d.pressure / laplace,
      d.pressure / (2 * kSigma / d.R));
}

// Without the depth term of the capillary stress the pressure is high by
// about a cell over the radius (17% at R = 7 cells, 11% at 10, 7.7% at 15);
// with it, measured 0.8% low at 10 cells.
TEST(SurfaceTension, RestingDropCarriesTheLaplacePressure) {
  const SettledDrop d = settledDrop(10);
  printLaplace(d);
  EXPECT_NEAR(d.pressure / (2 * kSigma / d.Req), 1.0, 0.03);
}

// From 7 to 15 cells a radius (measured 1.6% low and 0.1% low).
TEST(SurfaceTension, LaplacePressureHoldsFromSevenToFifteenCells) {
  const SettledDrop small = settledDrop(7), large = settledDrop(15);
  printLaplace(small);
  printLaplace(large);
  EXPECT_NEAR(small.pressure / (2 * kSigma / small.Req), 1.0, 0.05);
  EXPECT_NEAR(large.pressure / (2 * kSigma / large.Req), 1.0, 0.02);
}

TEST(SurfaceTension, SpuriousCurrentsInARestingDropAreSmall) {
  const SettledDrop d = settledDrop(10);
  const double capillaryVelocity = kSigma / d.mu;
  std::printf("spurious currents: largest particle speed %.3g m/s = %.3g sigma / mu_N (sigma / mu_N = %.3g m/s)\n",
              d.maxSpeed, d.maxSpeed / capillaryVelocity, capillaryVelocity);
  EXPECT_LT(d.maxSpeed, 0.03 * capillaryVelocity);
}

TEST(SurfaceTension, CubeOfLiquidRelaxesTowardASphere) {
  const int nodes = 28;
  MpmSolver solver(dropSettings(nodes));
  const std::uint32_t m = addWater(solver, 0.5, 350);
  const double half = 7 * kDx;  // a 14-cell cube
  solver.emit(EmitterShape::box(Pose::at(centreOf(nodes)), {half, half, half}), m, {});
  const double before = outlineRatio(solver.particles());
  // About one capillary time sqrt(rho L^3 / sigma) = 0.14 s of the 14-cell cube.
  runFor(solver, 0.1, 0.05);
  std::size_t stray = 0;
  const double after = outlineRatio(solver.particles(), &stray);
  std::printf("cube to sphere: outline ratio (farthest / nearest surface distance) %.3f -> %.3f at t = 0.1 s; %zu "
              "stray particles\n",
              before, after, stray);
  // Later, at Oh = 0.6, the spurious currents grow (docs/physics.md, "Surface tension"): printed, not asserted.
  for (int i = 3; i <= 6; ++i) {
    runFor(solver, 0.05 * i, 0.05);
    const double ratio = outlineRatio(solver.particles(), &stray);
    std::printf("cube to sphere: t = %.2f s, outline ratio %.3f, %zu stray\n", solver.time(), ratio, stray);
  }
  EXPECT_GT(before, 1.6);
  EXPECT_LT(after, 1.15);
}

TEST(SurfaceTension, IsolatedDropConservesMomentum) {
  const int nodes = 26;
  MpmSolver solver(dropSettings(nodes));
  const std::uint32_t m = addWater(solver, 0.5, 350);
  // A box, off-centre and rotated: strong, asymmetric capillary forces.
  solver.emit(EmitterShape::box(Pose::fromAxisAngle(centreOf(nodes) + Vec3d{0.4, -0.3, 0.2} * kDx, {1, 2, 3}, 0.7),
                                {5 * kDx, 4 * kDx, 3 * kDx}),
              m, {});
  const MpmParticles& p = solver.particles();
  double peakP = 0, peakL = 0, maxSpeed = 0, scaleP = 0;
  const double M = p.totalMass();
  for (int i = 0; i < 200; ++i) {
    const MpmStepReport r = solver.step(solver.suggestedDt());
    peakP = std::max(peakP, norm(p.linearMomentum()));
    peakL = std::max(peakL, norm(p.angularMomentum(kDx)));
    maxSpeed = std::max(maxSpeed, r.maxSpeed);
  }
  scaleP = M * maxSpeed;
  std::printf(
      "momentum: %zu particles, 200 substeps, largest speed %.3g m/s (M v_max = %.3g kg m/s); peak |P| = %.3g kg m/s, "
      "peak |L| = %.3g kg m^2/s\n",
      p.size(), maxSpeed, scaleP, peakP, peakL);
  EXPECT_GT(maxSpeed, 0.01);  // the surface tension did move it
  EXPECT_LT(peakP, 1e-12);
  EXPECT_LT(peakL, 1e-14);
}


// Rayleigh's l = 2 mode of a drop: omega^2 = 8 sigma / (rho R^3) (inviscid;
// the viscous damping rate 5 nu / R^2 = 1/s lowers it by under 0.1%). A drop
// of R = 10 cells stretched by 8% along x at constant volume; the period is
// read from the zero crossings of the second-moment difference
// <x^2> - (<y^2> + <z^2>)/2 over the first two periods.
TEST(SurfaceTension, DropOscillatesAtRayleighsFrequency) {
  const int nodes = 30;
  const double R = 10 * kDx, mu = 0.02, K = 25 * 2 * kSigma / R;
  MpmSolver solver(dropSettings(nodes));
  const std::uint32_t m = addWater(solver, mu, K);
  const Vec3d c0 = centreOf(nodes);
  solver.emit(EmitterShape::sphere(Pose::at(c0), R), m, {});
  const double a = 1.08, b = 1 / std::sqrt(a);
  MpmParticles& p = solver.particles();
  for (std::size_t q = 0; q < p.size(); ++q) {
    const Vec3d d = p.x[q] - c0;
    p.x[q] = c0 + Vec3d{a * d.x, b * d.y, b * d.z};
  }
  auto shape = [&]() {
    const Vec3d c = p.centreOfMass();
    double sx = 0, syz = 0;
    for (std::size_t q = 0; q < p.size(); ++q) {
      const Vec3d d = p.x[q] - c;
      sx += d.x * d.x;
      syz += 0.5 * (d.y * d.y + d.z * d.z);
    }
    return (sx - syz) / double(p.size());
  };
  const double omega = std::sqrt(8 * kSigma / (kRho * R * R * R));
  const double period = 2 * 3.14159265358979 / omega;
  std::vector<double> crossings;
  double prev = shape(), tPrev = 0;
  while (solver.time() < 2.3 * period && crossings.size() < 4) {
    solver.step(solver.suggestedDt());
    const double now = shape();
    if ((prev > 0) != (now > 0)) crossings.push_back(tPrev + (solver.time() - tPrev) * prev / (prev - now));
    prev = now;
    tPrev = solver.time();
  }
  ASSERT_GE(crossings.size(), 3u);
  const double measured = crossings.back() - crossings.front();  // (n - 1) half periods
  const double measuredPeriod = 2 * measured / double(crossings.size() - 1);
  std::printf("l = 2 oscillation: period %.4g s vs Rayleigh's %.4g s (ratio %.4f, omega ratio %.4f), %zu crossings\n",
              measuredPeriod, period, measuredPeriod / period, period / measuredPeriod, crossings.size());
  EXPECT_NEAR(period / measuredPeriod, 1.0, 0.10);
}

// Surface tension acts only on the fluids that have it: a viscous block
// falling beside an unused material with sigma > 0 (which turns the colour
// passes on) moves bit for bit as it does without that material.
TEST(SurfaceTension, FluidsWithoutItAreUntouched) {
  auto run = [](bool withSigmaMaterial) {
    MpmSettings s = dropSettings(16);
    s.gravity = {0, 0, -9.81};
    MpmSolver solver(s);
    const std::uint32_t m = solver.addMaterial(viscousFluid(0.1, 1e3, kRho));
    if (withSigmaMaterial) {
      MpmMaterial other = viscousFluid(0.1, 1e3, kRho);
      other.surfaceTension = 0.5;
      solver.addMaterial(other);
    }
    solver.emit(EmitterShape::box(Pose::at(centreOf(16)), {3 * kDx, 3 * kDx, 3 * kDx}), m, {});
    for (int i = 0; i < 50; ++i) solver.step(2e-4);
    return solver.particles();
  };
  const MpmParticles a = run(false), b = run(true);
  ASSERT_EQ(a.size(), b.size());
  std::size_t differ = 0;
  for (std::size_t q = 0; q < a.size(); ++q)
    if (!(a.x[q] == b.x[q]) || !(a.v[q] == b.v[q]) || a.J[q] != b.J[q]) ++differ;
  EXPECT_EQ(differ, 0u);
  EXPECT_NE(a.centreOfMass().z, centreOf(16).z);  // it did fall
}
