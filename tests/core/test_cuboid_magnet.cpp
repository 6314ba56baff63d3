// The cuboid magnet's field against brute-force quadrature of its six charged
// faces, the dipole far field, the jump conditions across every face and
// curl H = div H = 0, and its bad inputs.
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
#include "lodestone/core/sources/cuboid_magnet.h"

using namespace lodestone;
using namespace lodestone::test;

// ---------------------------------------------------------- cuboid magnet --

TEST(CuboidMagnet, MatchesQuadratureOfTheSurfaceChargeIntegral) {
  const CuboidMagnet cub(Pose{}, kCuboidHalf, kCuboidM);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> U(-1, 1);
  double worst = 0;
  int outside = 0, inside = 0;
  while (outside < 40 || inside < 20) {
    const Vec3d x{2.5 * kCuboidHalf.x * U(rng), 2.5 * kCuboidHalf.y * U(rng),
                  2.5 * kCuboidHalf.z * U(rng)};
    // Keep away from the faces so that the quadrature converges.
    const double d = boxSurfaceDistance(x, kCuboidHalf);
    if (std::fabs(d) < 0.25 * kCuboidHalf.z) continue;
    int& count = d > 0 ? outside : inside;
    if (count >= (d > 0 ? 40 : 20)) continue;
    ++count;
    const Vec3d ref = cuboidQuadrature(kCuboidHalf, kCuboidM, Mat3d::identity(), {}, x);
    worst = std::fmax(worst, relErr(cub.field(x, 0.0), ref));
  }
  EXPECT_GT(inside, 3);
  EXPECT_GT(outside, 3);
  EXPECT_LT(worst, 1e-11);
  RecordProperty("cuboid_vs_quadrature_max_rel_error", std::to_string(worst));
  std::printf("cuboid vs quadrature: max rel error %.3e over %d inside, %d outside points\n", worst,
              inside, outside);
}

TEST(CuboidMagnet, RotatedAndTranslatedPoseMatchesQuadrature) {
  const Mat3d R = rotation({1, -2, 0.5}, 0.7);
  const Vec3d p{0.05, -0.02, 0.1};
  const CuboidMagnet cub(Pose{p, R}, kCuboidHalf, kCuboidM);
  std::mt19937 rng(2);
  double worst = 0;
  for (int n = 0; n < 20; ++n) {
    const Vec3d x = p + randomUnit(rng) * (norm(kCuboidHalf) * (1.3 + n * 0.2));
    const Vec3d ref = cuboidQuadrature(kCuboidHalf, kCuboidM, R, p, x);
    worst = std::fmax(worst, relErr(cub.field(x, 0.0), ref));
  }
  EXPECT_LT(worst, 1e-11);
  // Magnetization and moment are rotated into the world frame.
  EXPECT_LT(relErr(cub.magnetization(p, 0.0), R * kCuboidM), 1e-15);
  EXPECT_LT(relErr(cub.moment(0.0), R * kCuboidM * cub.volume()), 1e-15);
  EXPECT_EQ(cub.magnetization(p + R * (kCuboidHalf * 1.01), 0.0), Vec3d{});
}

TEST(CuboidMagnet, QuarterTurnEqualsTheSwappedBox) {
  // Rotating by 90 degrees about z maps body x to world y: the same magnet as an
  // axis-aligned box with half-sizes (hy, hx, hz) and M = (-My, Mx, Mz).
  const Vec3d h = kCuboidHalf, M = kCuboidM;
  const CuboidMagnet turned(Pose::fromAxisAngle({0.01, 0.02, 0.03}, {0, 0, 1}, kPi / 2), h, M);
  const CuboidMagnet swapped(Pose::at({0.01, 0.02, 0.03}), {h.y, h.x, h.z}, {-M.y, M.x, M.z});
  std::mt19937 rng(4);
  for (int n = 0; n < 50; ++n) {
    const Vec3d x = Vec3d{0.01, 0.02, 0.03} + randomUnit(rng) * (0.005 + 0.001 * n);
    EXPECT_LT(relErr(turned.field(x, 0.0), swapped.field(x, 0.0)), 1e-12) << n;
  }
}

TEST(CuboidMagnet, CentreFieldIsTheTwoFaceClosedForm) {
  // A cube: -M/3 exactly by symmetry, for any direction of M.
  const CuboidMagnet cube(Pose{}, {0.01, 0.01, 0.01}, kCuboidM);
  EXPECT_LT(relErr(cube.field({0, 0, 0}, 0.0), kCuboidM * (-1.0 / 3.0)), 1e-14);
  // A cuboid: H_k(0) = -(2 M_k / pi) atan(h_i h_j / (h_k |h|)).
  const CuboidMagnet cub(Pose{}, kCuboidHalf, kCuboidM);
  const Vec3d h = kCuboidHalf;
  Vec3d ref;
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    ref[k] = -2 * kCuboidM[k] / kPi * std::atan(h[i] * h[j] / (h[k] * norm(h)));
  }
  EXPECT_LT(relErr(cub.field({0, 0, 0}, 0.0), ref), 1e-14);
}

TEST(CuboidMagnet, FarFieldTendsToTheDipoleAsSizeOverDistanceSquared) {
  const CuboidMagnet cub(Pose{}, kCuboidHalf, kCuboidM);
  const Vec3d m = kCuboidM * cub.volume();
  const double s = norm(kCuboidHalf);
  const Vec3d u = Vec3d{0.3, -0.5, 0.8} / norm(Vec3d{0.3, -0.5, 0.8});
  double previous = 0;
  for (double ratio : {5.0, 10.0, 20.0, 40.0, 80.0}) {
    const double e = relErr(cub.field(u * (ratio * s), 0.0), dipoleReference(m, u * (ratio * s)));
    EXPECT_LT(e, 2.0 / (ratio * ratio)) << ratio;
    if (previous > 0) {
      EXPECT_GT(previous / e, 3.5) << ratio;  // second order: ~4 per doubling
      EXPECT_LT(previous / e, 4.5) << ratio;
    }
    previous = e;
  }
}

TEST(CuboidMagnet, FarFieldExpansionJoinsTheClosedFormAndStaysFinite) {
  const CuboidMagnet cub(Pose{}, kCuboidHalf, kCuboidM);
  const double r0 = CuboidMagnet::kFarFieldRadii * norm(kCuboidHalf);
  std::mt19937 rng(9);
  for (int n = 0; n < 50; ++n) {
    const Vec3d u = randomUnit(rng);
    const Vec3d below = cub.field(u * (r0 * (1 - 1e-12)), 0.0),
                above = cub.field(u * (r0 * (1 + 1e-12)), 0.0);
    EXPECT_LT(relErr(below, above), 1e-8) << n;
  }
  for (double r : {1e3, 1e10, 1e100, 1e200, 1e300}) {
    const Vec3d H = cub.field(Vec3d{1, 2, -3} * r, 0.0);
    EXPECT_TRUE(isFinite(H)) << r;
  }
  const Vec3d far{0, 0, 1e3};
  EXPECT_LT(relErr(cub.field(far, 0.0), dipoleReference(kCuboidM * cub.volume(), far)), 1e-9);
}

TEST(CuboidMagnet, JumpConditionsAcrossEveryFace) {
  const CuboidMagnet cub(Pose{}, kCuboidHalf, kCuboidM);
  const Vec3d& h = kCuboidHalf;
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> U(-0.9, 0.9);
  const double tol = 1e-6 * norm(kCuboidM);
  for (int k = 0; k < 3; ++k)
    for (int s = -1; s <= 1; s += 2)
      for (int n = 0; n < 10; ++n) {
        Vec3d nrm;
        nrm[k] = s;
        Vec3d x{h.x * U(rng), h.y * U(rng), h.z * U(rng)};
        x[k] = s * h[k];
        Vec3d xin = x, xout = x;
        xin[k] -= s * 1e-9 * h[k];
        xout[k] += s * 1e-9 * h[k];
        const Vec3d Hin = cub.field(xin, 0.0), Hout = cub.field(xout, 0.0);
        EXPECT_NEAR(dot(Hin + kCuboidM, nrm), dot(Hout, nrm), tol);  // normal B
        EXPECT_NEAR(dot(Hout - Hin, nrm), dot(kCuboidM, nrm), tol);  // normal H jumps by M.n
        const Vec3d dt = (Hout - Hin) - dot(Hout - Hin, nrm) * nrm;  // tangential H
        EXPECT_LT(norm(dt), tol);
        // Exactly on the face: the mean of the two sides.
        EXPECT_LT(norm(cub.field(x, 0.0) - (Hin + Hout) * 0.5), tol);
        EXPECT_EQ(cub.magnetization(xin, 0.0), kCuboidM);
        EXPECT_EQ(cub.magnetization(xout, 0.0), Vec3d{});
      }
}

TEST(CuboidMagnet, CurlAndDivergenceVanishAwayFromTheFaces) {
  const CuboidMagnet cub(Pose::fromAxisAngle({0.002, 0, -0.001}, {1, 1, 0}, 0.3), kCuboidHalf,
                         kCuboidM);
  auto H = [&](const Vec3d& x) { return cub.field(x, 0.0); };
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> U(-3, 3);
  int checked = 0;
  double worst = 0;
  while (checked < 60) {
    const Vec3d xb{kCuboidHalf.x * U(rng), kCuboidHalf.y * U(rng), kCuboidHalf.z * U(rng)};
    const double d = std::fabs(boxSurfaceDistance(xb, kCuboidHalf));
    if (d < 0.3 * kCuboidHalf.z) continue;
    ++checked;
    const Vec3d x = cub.pose().toWorld(xb);
    const DivCurl dc = divCurl(H, x, 2e-4 * d);
    const double scale = norm(H(x)) / d + norm(kCuboidM) * 1e-3 / d;
    worst = std::fmax(worst, std::fmax(std::fabs(dc.div), norm(dc.curl)) / scale);
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(CuboidMagnet, FiniteOnEdgesCornersAndFaces) {
  const CuboidMagnet cub(Pose{}, kCuboidHalf, kCuboidM);
  const Vec3d& h = kCuboidHalf;
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j)
      for (int k = -2; k <= 2; ++k) {
        // Every combination of centre, half-way, face, and beyond: covers the
        // centre, face centres, edges, corners and their extensions.
        const Vec3d x{0.5 * i * h.x, 0.5 * j * h.y, 0.5 * k * h.z};
        for (const Vec3d& y : {x, x * (1 + 1e-15), x * (1 - 1e-15)}) {
          const Vec3d H = cub.field(y, 0.0);
          EXPECT_TRUE(isFinite(H)) << i << j << k;
        }
      }
  // Approaching an edge the field grows only logarithmically.
  const Vec3d edge{h.x, h.y, 0};
  const double near = norm(cub.field(edge * (1 + 1e-6), 0.0));
  const double nearer = norm(cub.field(edge * (1 + 1e-12), 0.0));
  EXPECT_GT(nearer, near);
  EXPECT_LT(nearer, 10 * norm(kCuboidM));
}

TEST(CuboidMagnet, BadInputsThrowNamingTheValue) {
  expectContains(thrownMessage([] {
                   CuboidMagnet(Pose{}, {0.01, -0.02, 0.01}, {0, 0, 1});
                 }),
                 {"-0.02", "in m", "along y"});
  expectContains(thrownMessage([] {
                   CuboidMagnet(Pose{}, {0.01, 0.02, 0.0}, {0, 0, 1});
                 }),
                 {"got 0", "along z"});
  expectContains(
      thrownMessage([] {
        CuboidMagnet(Pose{}, {0.01, 0.01, 0.01}, {0, -std::numeric_limits<double>::infinity(), 1});
      }),
      {"inf", "A/m"});
  Pose skew;
  skew.rotation(0, 1) = 0.5;
  expectContains(thrownMessage([&] {
                   CuboidMagnet(skew, {0.01, 0.01, 0.01}, {0, 0, 1});
                 }),
                 {"orthonormal", "0.5"});
  Pose mirror;
  mirror.rotation(2, 2) = -1;
  expectContains(thrownMessage([&] {
                   CuboidMagnet(mirror, {0.01, 0.01, 0.01}, {0, 0, 1});
                 }),
                 {"det", "-1"});
  CuboidMagnet ok(Pose{}, {0.01, 0.01, 0.01}, {0, 0, 1});
  expectContains(thrownMessage([&] {
                   ok.setPose(Pose::at({0, std::nan(""), 0}));
                 }),
                 {"nan", "(m)"});
  expectContains(ok.describe(), {"cuboid", "0.01", " m", "A/m"});
}

