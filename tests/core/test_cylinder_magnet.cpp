// The axially magnetized cylinder magnet's field against its on-axis closed
// form, quadrature of its end-cap charges, the dipole far field, the jump
// conditions at its walls and caps and curl H = div H = 0, and its bad inputs.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/pose.h"
#include "lodestone_test/source_references.h"
#include "lodestone/core/sources/cylinder_magnet.h"

using namespace lodestone;
using namespace lodestone::test;

// -------------------------------------------------------- cylinder magnet --

namespace {

double onAxisHz(double z) {
  const double zp = z + kCylL, zm = z - kCylL;
  const double B = 0.5 * kCylM * (zp / std::hypot(zp, kCylR) - zm / std::hypot(zm, kCylR));
  return std::fabs(z) < kCylL ? B - kCylM : B;
}
}  // namespace

TEST(CylinderMagnet, OnAxisClosedFormAndContinuityOffAxis) {
  const CylinderMagnet cyl(Pose{}, kCylR, kCylL, {0, 0, kCylM});
  for (double z : {0.0, 0.3 * kCylL, -0.9 * kCylL, 1.2 * kCylL, -3 * kCylL, 40 * kCylL}) {
    const Vec3d H = cyl.field({0, 0, z}, 0.0);
    EXPECT_EQ(H.x, 0.0);
    EXPECT_EQ(H.y, 0.0);
    EXPECT_NEAR(H.z, onAxisHz(z), 1e-13 * kCylM) << z;
    // Next to the axis the general (elliptic) formula takes over smoothly.
    const Vec3d Hn = cyl.field({1e-9 * kCylR, -2e-9 * kCylR, z}, 0.0);
    EXPECT_NEAR(Hn.z, onAxisHz(z), 1e-12 * kCylM) << z;
    EXPECT_LT(std::hypot(Hn.x, Hn.y), 1e-7 * kCylM) << z;
  }
  // The centre: demagnetizing field M (L / sqrt(L^2 + R^2) - 1).
  EXPECT_NEAR(cyl.field({0, 0, 0}, 0.0).z, kCylM * (kCylL / std::hypot(kCylL, kCylR) - 1),
              1e-13 * kCylM);
}

TEST(CylinderMagnet, MatchesQuadratureOfTheEndCapCharges) {
  const CylinderMagnet cyl(Pose{}, kCylR, kCylL, {0, 0, kCylM});
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> U(-1, 1);
  double worst = 0;
  int inside = 0, outside = 0;
  while (inside < 20 || outside < 40) {
    const Vec3d x{2.5 * kCylR * U(rng), 2.5 * kCylR * U(rng), 2.5 * kCylL * U(rng)};
    const double rho = std::hypot(x.x, x.y);
    // The charges sit on the caps only; keep away from the cap planes.
    if (std::fabs(std::fabs(x.z) - kCylL) < 0.25 * kCylR) continue;
    const bool in = rho < kCylR && std::fabs(x.z) < kCylL;
    int& count = in ? inside : outside;
    if (count >= (in ? 20 : 40)) continue;
    ++count;
    const Vec3d ref = cylinderQuadrature(kCylR, kCylL, kCylM, x);
    worst = std::fmax(worst, relErr(cyl.field(x, 0.0), ref));
  }
  EXPECT_GT(inside, 3);
  EXPECT_GT(outside, 3);
  EXPECT_LT(worst, 1e-12);
  RecordProperty("cylinder_vs_quadrature_max_rel_error", std::to_string(worst));
  std::printf("cylinder vs quadrature: max rel error %.3e over %d inside, %d outside points\n",
              worst, inside, outside);
}

TEST(CylinderMagnet, FarFieldTendsToTheDipole) {
  const CylinderMagnet cyl(Pose::at({0.1, 0.2, 0.3}), kCylR, kCylL, {0, 0, kCylM});
  const Vec3d m{0, 0, kCylM * kPi * kCylR * kCylR * 2 * kCylL};
  EXPECT_LT(relErr(cyl.moment(0.0), m), 1e-15);
  const double s = std::hypot(kCylR, kCylL);
  const Vec3d u = Vec3d{0.6, 0.2, -0.5} / norm(Vec3d{0.6, 0.2, -0.5});
  double previous = 0;
  for (double ratio : {5.0, 10.0, 20.0, 40.0, 80.0}) {
    const Vec3d d = u * (ratio * s);
    const double e = relErr(cyl.field(Vec3d{0.1, 0.2, 0.3} + d, 0.0), dipoleReference(m, d));
    EXPECT_LT(e, 2.0 / (ratio * ratio)) << ratio;
    if (previous > 0) {
      EXPECT_GT(previous / e, 3.5) << ratio;
      EXPECT_LT(previous / e, 4.5) << ratio;
    }
    previous = e;
  }
  // Across the switch to the far-field expansion, and at absurd distances.
  const double r0 = CylinderMagnet::kFarFieldRadii * s;
  EXPECT_LT(relErr(cyl.bodyField(u * (r0 * (1 - 1e-12))), cyl.bodyField(u * (r0 * (1 + 1e-12)))),
            1e-8);
  for (double r : {1e10, 1e100, 1e300}) EXPECT_TRUE(isFinite(cyl.field(u * r, 0.0))) << r;
}

TEST(CylinderMagnet, JumpConditionsAtSideWallAndEndCaps) {
  const CylinderMagnet cyl(Pose{}, kCylR, kCylL, {0, 0, kCylM});
  const double tol = 1e-6 * kCylM;
  const Vec3d M{0, 0, kCylM};
  for (double phi : {0.0, 0.7, 2.0, 4.0}) {
    const Vec3d er{std::cos(phi), std::sin(phi), 0};
    // Side wall, away from the rims: M.n = 0, so H is continuous and B_z jumps by mu0 M.
    for (double z : {0.0, 0.5 * kCylL, -0.8 * kCylL}) {
      const Vec3d Hin = cyl.field(er * (kCylR * (1 - 1e-9)) + Vec3d{0, 0, z}, 0.0);
      const Vec3d Hout = cyl.field(er * (kCylR * (1 + 1e-9)) + Vec3d{0, 0, z}, 0.0);
      EXPECT_LT(norm(Hin - Hout), tol) << phi << " " << z;
      EXPECT_NEAR(kMu0 * (Hin.z + kCylM) - kMu0 * Hout.z, kMu0 * kCylM, kMu0 * tol);
      const Vec3d Hon = cyl.field(er * kCylR + Vec3d{0, 0, z}, 0.0);  // exactly on the wall
      EXPECT_LT(norm(Hon - (Hin + Hout) * 0.5), tol);
    }
    // End caps: B_z continuous, H_z jumps by M.n, tangential H continuous.
    for (double rho : {0.0, 0.3 * kCylR, 0.9 * kCylR})
      for (int s = -1; s <= 1; s += 2) {
        const Vec3d base = er * rho;
        const Vec3d Hin = cyl.field(base + Vec3d{0, 0, s * kCylL * (1 - 1e-9)}, 0.0);
        const Vec3d Hout = cyl.field(base + Vec3d{0, 0, s * kCylL * (1 + 1e-9)}, 0.0);
        EXPECT_NEAR(Hin.z + kCylM, Hout.z, tol) << rho << " " << s;
        EXPECT_NEAR(s * (Hout.z - Hin.z), s * kCylM, tol);
        EXPECT_LT(std::hypot(Hout.x - Hin.x, Hout.y - Hin.y), tol);
        const Vec3d Hon = cyl.field(base + Vec3d{0, 0, s * kCylL}, 0.0);
        EXPECT_LT(norm(Hon - (Hin + Hout) * 0.5), tol);
        EXPECT_EQ(cyl.magnetization(base + Vec3d{0, 0, s * kCylL * (1 - 1e-9)}, 0.0), M);
        EXPECT_EQ(cyl.magnetization(base + Vec3d{0, 0, s * kCylL * (1 + 1e-9)}, 0.0), Vec3d{});
      }
  }
}

TEST(CylinderMagnet, CurlAndDivergenceVanishAwayFromTheSurface) {
  const CylinderMagnet cyl(Pose{}, kCylR, kCylL, {0, 0, kCylM});
  auto H = [&](const Vec3d& x) { return cyl.field(x, 0.0); };
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> U(-3, 3);
  int checked = 0;
  double worst = 0;
  while (checked < 60) {
    const Vec3d x{kCylR * U(rng), kCylR * U(rng), kCylL * U(rng)};
    const double dr = std::fabs(std::hypot(x.x, x.y) - kCylR),
                 dz = std::fabs(std::fabs(x.z) - kCylL);
    const double d = std::fmin(dr, dz);
    if (d < 0.2 * kCylR) continue;
    ++checked;
    const DivCurl dc = divCurl(H, x, 2e-4 * d);
    const double scale = norm(H(x)) / d + kCylM * 1e-3 / d;
    worst = std::fmax(worst, std::fmax(std::fabs(dc.div), norm(dc.curl)) / scale);
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(CylinderMagnet, TiltedAxisEqualsTheRotatedField) {
  // Axis along world x (a quarter turn about y maps body z to world x).
  const Vec3d c{0.01, -0.02, 0.005};
  const CylinderMagnet tilted(Pose::fromAxisAngle(c, {0, 1, 0}, kPi / 2), kCylR, kCylL,
                              {0, 0, kCylM});
  const CylinderMagnet upright(Pose{}, kCylR, kCylL, {0, 0, kCylM});
  std::mt19937 rng(14);
  for (int n = 0; n < 30; ++n) {
    const Vec3d d = randomUnit(rng) * (0.004 + 0.002 * n);
    const Vec3d Hb = upright.field({-d.z, d.y, d.x}, 0.0);  // body coordinates of c + d
    const Vec3d ref{Hb.z, Hb.y, -Hb.x};
    EXPECT_LT(norm(tilted.field(c + d, 0.0) - ref), 1e-12 * kCylM) << n;
  }
}

TEST(CylinderMagnet, FiniteOnAxisRimCentreAndWalls) {
  const CylinderMagnet cyl(Pose{}, kCylR, kCylL, {0, 0, kCylM});
  const double rs[] = {
      0.0, 1e-300, 0.5 * kCylR, kCylR * (1 - 1e-16), kCylR, kCylR * (1 + 1e-16), 2 * kCylR};
  const double zs[] = {0.0,   0.5 * kCylL,         kCylL * (1 - 1e-16),
                       kCylL, kCylL * (1 + 1e-16), 2 * kCylL};
  for (double rho : rs)
    for (double z : zs)
      for (int s = -1; s <= 1; s += 2) {
        const Vec3d H = cyl.field({rho * std::cos(1.0), rho * std::sin(1.0), s * z}, 0.0);
        EXPECT_TRUE(isFinite(H)) << rho << " " << z;
      }
  // Near the rim the field grows only logarithmically.
  const double nearer = norm(cyl.field({kCylR * (1 + 1e-12), 0, kCylL}, 0.0));
  EXPECT_GT(nearer, norm(cyl.field({kCylR * (1 + 1e-6), 0, kCylL}, 0.0)));
  EXPECT_LT(nearer, 10 * kCylM);
}

TEST(CylinderMagnet, BadInputsThrowNamingTheValue) {
  expectContains(thrownMessage([] {
                   CylinderMagnet(Pose{}, -0.5, 0.01, {0, 0, 1});
                 }),
                 {"-0.5", "radius", "in m"});
  expectContains(thrownMessage([] {
                   CylinderMagnet(Pose{}, 0.01, 0.0, {0, 0, 1});
                 }),
                 {"half-length", "got 0"});
  expectContains(thrownMessage([] {
                   CylinderMagnet(Pose{}, 0.01, 0.01, {250.0, 0, 1});
                 }),
                 {"transverse", "250", "A/m"});
  expectContains(thrownMessage([] {
                   CylinderMagnet(Pose{}, 0.01, 0.01, {0, 0, std::nan("")});
                 }),
                 {"nan", "A/m"});
}

// ----------------------------------------------- time scaling, superposition --
