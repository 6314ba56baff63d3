// The damped elastoplastic solid (constitutive.h): the principal stretches
// from the Jacobi eigen-decomposition, the Hencky stress and the von Mises
// return mapping pointwise against closed forms, then in the MPM the permanent
// set of a block compressed beyond yield (perfect plasticity) and the
// Kelvin-Voigt decay rate of a torsion mode.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "lodestone/core/base/symmetric_eigen.h"
#include "lodestone/core/mpm/constitutive.h"
#include "lodestone/core/mpm/solver.h"

using namespace lodestone;

namespace {

Mat3d rotation(const Vec3d& axis, double angle) { return Pose::fromAxisAngle({}, axis, angle).rotation; }

Mat3d diag(double a, double b, double c) { return Mat3d::diagonal(a, b, c); }

double maxAbsDiff(const Mat3d& a, const Mat3d& b) {
  double m = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m = std::max(m, std::abs(a(i, j) - b(i, j)));
  return m;
}

}  // namespace

TEST(MpmElastoplastic, JacobiEigenDecompositionReconstructsSymmetricMatrices) {
  // A = R diag(l) R^T with known l, including a repeated and a tiny eigenvalue.
  const double sets[3][3] = {{3.0, 0.5, 1e-6}, {2.0, 2.0, 0.7}, {1.0, 1.0, 1.0}};
  for (const auto& l : sets) {
    const Mat3d R = rotation({1, 2, 3}, 0.7) * rotation({0, 1, -1}, 1.9);
    const Mat3d A = R * diag(l[0], l[1], l[2]) * R.transposed();
    const SymmetricEigen3<double> e = symmetricEigen(A);
    const Mat3d Q = e.vectors;
    EXPECT_LT(maxAbsDiff(Q * diag(e.values[0], e.values[1], e.values[2]) * Q.transposed(), A), 1e-14);
    EXPECT_LT(maxAbsDiff(Q.transposed() * Q, Mat3d::identity()), 1e-14);
    std::vector<double> got(e.values, e.values + 3), want(l, l + 3);
    std::sort(got.begin(), got.end());
    std::sort(want.begin(), want.end());
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(got[i], want[i], 1e-14 * std::max(1.0, want[i]));
  }
}

TEST(MpmElastoplastic, HenckyStressIsLinearInTheLogStrainsAndDampingIsDeviatoric) {
  // F = R diag(a, b, c): tau = R diag(2 mu ln a_i + lambda ln(abc)) R^T, and
  // for small strain the Neo-Hookean stress to second order.
  const double mu = 3e4, lambda = 5e4;  // Pa
  const Mat3d R = rotation({1, -1, 2}, 0.4);
  const double a = 1.3, b = 0.8, c = 1.1;
  const Mat3d tau = henckyKirchhoff(R * diag(a, b, c), mu, lambda);
  const double tr = std::log(a * b * c);
  const Mat3d want = R * diag(2 * mu * std::log(a) + lambda * tr, 2 * mu * std::log(b) + lambda * tr,
                              2 * mu * std::log(c) + lambda * tr) *
                     R.transposed();
  EXPECT_LT(maxAbsDiff(tau, want), 1e-10 * mu);
  const double e = 1e-4;
  const Mat3d Fs = R * diag(1 + e, 1 - 0.5 * e, 1 + 0.3 * e);
  EXPECT_LT(maxAbsDiff(henckyKirchhoff(Fs, mu, lambda), neoHookeanKirchhoff(Fs, mu, lambda)), 10 * e * e * lambda);
  // The damping adds J 2 eta D_dev: none for a pure dilation rate or a spin.
  const double eta = 7;  // Pa*s
  Mat3d C = diag(3, -1, 0.5);
  C(0, 1) = 2;
  Mat3d want2 = want;
  const double J = a * b * c, third = (3 - 1 + 0.5) / 3;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) want2(i, j) += J * eta * (C(i, j) + C(j, i) - (i == j ? 2 * third : 0));
  EXPECT_LT(maxAbsDiff(elastoplasticKirchhoff(R * diag(a, b, c), C, mu, lambda, eta), want2), 1e-10 * mu);
  Mat3d spinAndDilation = diag(2, 2, 2);
  spinAndDilation(0, 1) = 5;
  spinAndDilation(1, 0) = -5;
  EXPECT_LT(maxAbsDiff(elastoplasticKirchhoff(R * diag(a, b, c), spinAndDilation, mu, lambda, eta), want), 1e-10 * mu);
  EXPECT_NEAR(henckyEnergyDensity(R * diag(a, b, c), mu, lambda),
              mu * (std::log(a) * std::log(a) + std::log(b) * std::log(b) + std::log(c) * std::log(c)) +
                  0.5 * lambda * tr * tr,
              1e-12 * mu);
}

TEST(MpmElastoplastic, ReturnMappingLandsOnTheYieldSurfaceAtConstantVolume) {
  const double mu = 4e4, lambda = 6e4, sy = 1500;  // Pa
  // Uniaxial isochoric stretch s: q = 3 mu ln s, and the return leaves ln s' = sigma_y / (3 mu).
  {
    const double s = 1.2;
    const Mat3d F = diag(s, 1 / std::sqrt(s), 1 / std::sqrt(s));
    const Mat3d Fr = vonMisesReturn(F, mu, sy);
    EXPECT_NEAR(std::log(Fr(0, 0)), sy / (3 * mu), 1e-14);
    EXPECT_NEAR(Fr(1, 1), std::exp(-0.5 * sy / (3 * mu)), 1e-14);
  }
  // General trial states beyond yield: on the surface, same det, same rotation.
  double worstQ = 0, worstDet = 0, worstSym = 0;
  int below = 0;
  for (int n = 0; n < 200; ++n) {
    const double t = 0.37 * n;
    const Mat3d R = rotation({std::sin(t), std::cos(1.3 * t), 0.5}, 0.9 * t);
    const Mat3d V = rotation({1, std::sin(2 * t), -1}, 1.7 * t);
    const double a = std::exp(0.04 * std::sin(1.1 * t)), b = std::exp(0.03 * std::cos(0.7 * t)),
                 c = std::exp(0.02 * std::sin(2.3 * t + 1));
    const Mat3d F = R * diag(a, b, c) * V.transposed();
    const Mat3d Fr = vonMisesReturn(F, mu, sy);
    const double q0 = vonMisesStress(henckyKirchhoff(F, mu, lambda));
    if (q0 <= sy) {
      ++below;
      EXPECT_EQ(maxAbsDiff(Fr, F), 0.0) << "below yield, n = " << n;
      continue;
    }
    worstQ = std::max(worstQ, std::abs(vonMisesStress(henckyKirchhoff(Fr, mu, lambda)) / sy - 1));
    worstDet = std::max(worstDet, std::abs(determinant(Fr) / determinant(F) - 1));
    // Fr = S F with S symmetric (only the left stretch changes): Fr F^-1 symmetric.
    Mat3d S = Fr * (V * diag(1 / a, 1 / b, 1 / c) * R.transposed());
    worstSym = std::max(worstSym, maxAbsDiff(S, S.transposed()));
    // Projecting a projected state changes nothing beyond round-off.
    EXPECT_LT(maxAbsDiff(vonMisesReturn(Fr, mu, sy), Fr), 1e-12);
  }
  std::printf("return mapping: %d of 200 trial states below yield; worst |q/sigma_y - 1| %.2e, |det ratio - 1| %.2e, "
              "asymmetry of F_new F^-1 %.2e\n",
              below, worstQ, worstDet, worstSym);
  EXPECT_GT(below, 5);
  EXPECT_LT(below, 150);
  EXPECT_LT(worstQ, 1e-10);
  EXPECT_LT(worstDet, 1e-12);
  EXPECT_LT(worstSym, 1e-12);
}

namespace {

constexpr double kRho = 1000, kE = 1e5, kNu = 0.3;  // kg/m^3, Pa, -
constexpr double kDx = 0.01;                          // m

/// A grid of dims nodes at kDx without gravity, walls with the given
/// condition, particles kept in emission order (the tests follow them by index or id).
MpmSettings weightless(Index3 dims, BoundaryMode walls) {
  MpmSettings s;
  s.grid.dx = kDx;
  s.grid.dims = dims;
  s.gravity = {0, 0, 0};
  s.walls = BoundaryCondition{walls, 0};
  s.reorderInterval = 0;
  return s;
}

/// Height (m) between the mean z of the particles initially in the lower and
/// upper quarter bands of the block's middle half (clear of the contact layers).
struct Bands {
  std::vector<std::uint64_t> lower, upper;
  double height(const MpmParticles& p) const {
    double zl = 0, zu = 0;
    std::size_t nl = 0, nu = 0;
    for (std::size_t q = 0; q < p.size(); ++q) {
      if (std::binary_search(lower.begin(), lower.end(), p.id[q])) zl += p.x[q].z, ++nl;
      if (std::binary_search(upper.begin(), upper.end(), p.id[q])) zu += p.x[q].z, ++nu;
    }
    return zu / double(nu) - zl / double(nl);
  }
};

struct SetRun {
  double minStrain = 0;  ///< ln(h_min / h0) of the bands
  double endStrain = 0;  ///< ln(h_end / h0)
  double meanStrain = 0;  ///< time average of ln(h / h0) over the last 0.1 s (an undamped block still rings)
  double endSpeed = 0;   ///< largest particle speed at the end, m/s
};

/// A block 6 x 6 x 8 cells on the frictionless floor, pressed by a
/// frictionless plate moving down at 0.12 m/s for 0.12 s (18% of its height)
/// and back up, then left to settle until 0.4 s. No gravity.
SetRun pressBlock(const MpmMaterial& material) {
  MpmSolver solver(weightless({16, 16, 14}, BoundaryMode::Separate));
  const Vec3d lo = solver.domainLower(), hi = solver.domainUpper();
  const double cx = 0.5 * (lo.x + hi.x), cy = 0.5 * (lo.y + hi.y), h0 = 8 * kDx;
  const std::uint32_t m = solver.addMaterial(material);
  solver.emit(EmitterShape::box(Pose::at({cx, cy, lo.z + h0 / 2}), {3 * kDx, 3 * kDx, h0 / 2}), m, {});
  const double t1 = 0.12, v = 0.12, half = 0.05;  // s, m/s, m (plate half-thickness)
  const Vec3d plate0{cx, cy, lo.z + h0 + half};
  solver.addCollider(MpmCollider(ColliderShape::box({0.2, 0.2, half}),
                                 ColliderMotion::keyframed({0, t1, 2 * t1}, {Pose::at(plate0),
                                                                             Pose::at(plate0 - Vec3d{0, 0, v * t1}),
                                                                             Pose::at(plate0)}),
                                 BoundaryCondition{BoundaryMode::Separate, 0}));
  Bands bands;
  const MpmParticles& p = solver.particles();
  for (std::size_t q = 0; q < p.size(); ++q) {
    const double z = (p.x[q].z - lo.z) / h0;
    if (z > 0.25 && z < 0.375) bands.lower.push_back(p.id[q]);
    if (z > 0.625 && z < 0.75) bands.upper.push_back(p.id[q]);
  }
  std::sort(bands.lower.begin(), bands.lower.end());
  std::sort(bands.upper.begin(), bands.upper.end());
  const double band0 = bands.height(p);
  SetRun r;
  while (solver.time() < 0.4 - 1e-12) {
    const double dt = std::min(solver.suggestedDt(), 0.4 - solver.time());
    solver.step(dt);
    const double strain = std::log(bands.height(p) / band0);
    r.minStrain = std::min(r.minStrain, strain);
    if (solver.time() > 0.3) r.meanStrain += strain * dt / 0.1;
  }
  r.endStrain = std::log(bands.height(p) / band0);
  for (const Vec3d& u : p.v) r.endSpeed = std::max(r.endSpeed, norm(u));
  return r;
}

}  // namespace

TEST(MpmElastoplastic, BlockPressedBeyondYieldKeepsThePerfectPlasticityPermanentSet) {
  // Uniaxial stress between frictionless plates: the Hencky strain is
  // tau_zz / E, von Mises yields at |tau_zz| = sigma_y, so after loading to a
  // log strain eps_min < -sigma_y / E and unloading to zero stress the block
  // keeps eps_p = eps_min + sigma_y / E (perfect plasticity: it springs back
  // by exactly the yield strain sigma_y / E). A Neo-Hookean block springs
  // back all the way. The strain is measured between two particle bands in
  // the block's middle half, away from the contact layers; with perfect
  // plasticity the flow concentrates near the plates (nothing hardens to
  // spread it), so the bands see less of the plate's 18% than the elastic
  // block does, and eps_min is their own. Bound: the residual strain within
  // 20% of sigma_y / E of the closed form.
  const double sy = 2000, eta = 20;  // Pa, Pa*s (the damping settles the block)
  const SetRun clay = pressBlock(elastoplasticSolid(kE, kNu, sy, eta, kRho));
  const SetRun rubber = pressBlock(neoHookeanSolid(kE, kNu, kRho));
  const double want = clay.minStrain + sy / kE;
  std::printf("pressed block: clay eps_min %.4f, eps_end %.4f (perfect plasticity %.4f, spring-back %.4f vs "
              "sigma_y/E %.4f), end speed %.2e m/s; Neo-Hookean eps_min %.4f, eps_end %.4f (mean of the last 0.1 s %.4f), "
              "end speed %.2e m/s\n",
              clay.minStrain, clay.endStrain, want, clay.endStrain - clay.minStrain, sy / kE, clay.endSpeed, rubber.minStrain,
              rubber.endStrain, rubber.meanStrain, rubber.endSpeed);
  EXPECT_LT(clay.minStrain, -2.5 * sy / kE);  // well beyond the yield strain
  EXPECT_NEAR(clay.endStrain, want, 0.2 * sy / kE);
  EXPECT_LT(clay.endSpeed, 0.01);
  EXPECT_LT(rubber.minStrain, -0.1);
  // The undamped block still rings (its end speed is 1e-2 m/s): its mean
  // over the last 0.1 s returns to its height.
  EXPECT_NEAR(rubber.meanStrain, 0.0, 0.2 * sy / kE);
}

namespace {

struct ModeRun {
  double decay = 0;  ///< fitted amplitude decay rate alpha, 1/s
  double omega = 0;  ///< angular frequency from the zero crossings, rad/s
  int peaks = 0;
};

/// A rod of radius 3 cells and height H = 10 cells standing on the sticky
/// floor, free elsewhere, no gravity, set twisting in its quarter-wave
/// torsion mode u_theta = r phi sin(k z), k = pi / (2 H) (angular velocity
/// w0 sin(k z) about the axis). Decay rate and frequency of its mean twist.
ModeRun twistingRod(double eta, double seconds) {
  MpmSolver solver(weightless({12, 12, 16}, BoundaryMode::Sticky));
  const Vec3d lo = solver.domainLower(), hi = solver.domainUpper();
  const double H = 10 * kDx, k = kPi / (2 * H), w0 = 0.05;  // m, 1/m, rad/s
  const Vec3d axis{0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), lo.z};
  const std::uint32_t m = solver.addMaterial(elastoplasticSolid(kE, kNu, 1e9, eta, kRho));
  solver.emit(EmitterShape::cylinder(Pose::at(axis + Vec3d{0, 0, H / 2}), 3 * kDx, H / 2), m, {});
  MpmParticles& p = solver.particles();
  std::vector<Vec3d> X(p.x);  // initial positions, by index
  double r2 = 0;
  for (std::size_t q = 0; q < p.size(); ++q) {
    const Vec3d r = p.x[q] - axis;
    const double w = w0 * std::sin(k * r.z), dw = w0 * k * std::cos(k * r.z);
    p.v[q] = {-w * r.y, w * r.x, 0};
    // C = grad v: d(v_x)/dy = -w, d(v_y)/dx = w, d(v_x)/dz = -dw y, d(v_y)/dz = dw x.
    p.C[q](0, 1) = -w;
    p.C[q](1, 0) = w;
    p.C[q](0, 2) = -dw * r.y;
    p.C[q](1, 2) = dw * r.x;
    r2 += r.x * r.x + r.y * r.y;
  }
  std::vector<double> t{0}, d{0};
  while (solver.time() < seconds - 1e-12) {
    solver.step(std::min(solver.suggestedDt(), seconds - solver.time()));
    double twist = 0;  // sum (X x x)_z / sum |X|^2 over the horizontal offsets from the axis, rad
    for (std::size_t q = 0; q < p.size(); ++q) {
      const Vec3d a = X[q] - axis, b = p.x[q] - axis;
      twist += a.x * b.y - a.y * b.x;
    }
    t.push_back(solver.time());
    d.push_back(twist / r2);
  }
  // Extrema of the twist and its zero crossings.
  std::vector<double> tp, lnA, tz;
  for (std::size_t i = 1; i + 1 < d.size(); ++i) {
    if (std::abs(d[i]) > std::abs(d[i - 1]) && std::abs(d[i]) >= std::abs(d[i + 1])) {
      tp.push_back(t[i]);
      lnA.push_back(std::log(std::abs(d[i])));
    }
    if ((d[i] > 0 && d[i + 1] <= 0) || (d[i] < 0 && d[i + 1] >= 0))
      tz.push_back(t[i] + (t[i + 1] - t[i]) * d[i] / (d[i] - d[i + 1]));
  }
  ModeRun r;
  r.peaks = int(tp.size());
  // Least-squares slope of ln|peak| against time.
  double st = 0, sa = 0, stt = 0, sta = 0;
  for (std::size_t i = 0; i < tp.size(); ++i) st += tp[i], sa += lnA[i], stt += tp[i] * tp[i], sta += tp[i] * lnA[i];
  const double n = double(tp.size());
  r.decay = -(n * sta - st * sa) / (n * stt - st * st);
  if (tz.size() >= 2) r.omega = kPi * double(tz.size() - 1) / (tz.back() - tz.front());
  return r;
}

}  // namespace

TEST(MpmElastoplastic, KelvinVoigtDampingSetsTheDecayOfATorsionMode) {
  // Torsion of a round rod is isochoric (pure shear, tr D = 0), so the
  // elastic stress 2 mu eps and the damping stress 2 eta D_dev = 2 eta eps_t
  // share one operator: rho u_tt = -(mu + eta d/dt) L u. A mode of elastic
  // frequency omega0 (rho omega0^2 = mu lambda_L) then obeys
  // s^2 + (eta/mu) omega0^2 s + omega0^2 = 0 and decays at
  // alpha = eta omega0^2 / (2 mu), whatever the rod's discrete shape; the
  // continuum quarter-wave mode has omega0 = sqrt(mu / rho) pi / (2 H). The
  // APIC transfers add a numerical decay of their own (about half the
  // damping set here at this resolution); it is measured on the undamped rod
  // and subtracted. The discrete rod rings about 20% below the continuum
  // frequency (the sticky floor holds at the wall node, half a cell below
  // the rod, and the free top and round face are smeared over the B-spline
  // support), which the closed form takes from the measured omega0.
  // Bound: the damping's decay rate within 10% of the closed form.
  const double eta = 40;  // Pa*s
  const double mu = kE / (2 * (1 + kNu));
  const double cs = std::sqrt(mu / kRho), omegaNominal = cs * kPi / (2 * 10 * kDx);
  const ModeRun free = twistingRod(0.0, 0.25);
  const ModeRun damped = twistingRod(eta, 0.25);
  const double want = eta * free.omega * free.omega / (2 * mu);
  const double got = damped.decay - free.decay;
  std::printf("twisting rod: omega %.2f rad/s (continuum %.2f), numerical decay %.3f 1/s over %d peaks; damped "
              "decay %.3f 1/s (omega %.2f), difference %.3f vs Kelvin-Voigt eta omega^2 / (2 mu) = %.3f 1/s "
              "(%+.1f%%)\n",
              free.omega, omegaNominal, free.decay, free.peaks, damped.decay, damped.omega, got, want,
              100 * (got / want - 1));
  EXPECT_GE(free.peaks, 6);
  EXPECT_NEAR(free.omega, omegaNominal, 0.25 * omegaNominal);
  EXPECT_LT(std::abs(free.decay), 0.6 * want);
  EXPECT_NEAR(got, want, 0.1 * want);
}
