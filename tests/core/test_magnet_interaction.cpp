// Forces and torques between magnets: two spheres against the dipole closed
// form, Newton's third law and the angular-momentum balance, the
// surface-charge integral (exact for spheres, converging with quadrature
// order for cubes and cylinders, approaching the dipole form with distance),
// and the bad inputs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/pose.h"
#include "lodestone/core/sources/cuboid_magnet.h"
#include "lodestone/core/sources/cylinder_magnet.h"
#include "lodestone/core/sources/magnet_interaction.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone_test/source_references.h"

using namespace lodestone;
using namespace lodestone::test;

namespace {

constexpr double kRadius = 0.005;  // m
constexpr double kMs = 1.0e6;      // A/m
const double kSphereMoment = kMs * 4.0 / 3.0 * kPi * kRadius * kRadius * kRadius;  // A*m^2

// Relative residual of the angular-momentum balance about a common point:
// torque_A + torque_B + (x_B - x_A) x F_B (all about the bodies' centres).
double angularMomentumResidual(const MagnetWrench& onA, const MagnetWrench& onB, const Vec3d& r) {
  const Vec3d sum = onA.torque + onB.torque + cross(r, onB.force);
  const double scale = std::max({norm(onA.torque), norm(onB.torque), norm(r) * norm(onB.force)});
  return norm(sum) / scale;
}

}  // namespace

TEST(MagnetInteraction, CoaxialSpheresAttractAsDipoles) {
  // Both moments along +z, centres on the z axis: F_z = -3 mu0 m^2 / (2 pi d^4)
  // (attraction), no torque.
  for (double d : {0.0101, 0.02, 0.1}) {
    const SphereMagnet a(Pose::at({0.001, -0.002, 0.003}), kRadius, {0, 0, kMs});
    const SphereMagnet b(Pose::at({0.001, -0.002, 0.003 + d}), kRadius, {0, 0, kMs});
    const MagnetWrench w = magnetInteraction(a, b, 0.0);
    const double Fz = -3.0 * kMu0 * kSphereMoment * kSphereMoment / (2.0 * kPi * std::pow(d, 4));
    EXPECT_LT(relErr(w.force, {0, 0, Fz}), 1e-12) << "d = " << d;
    EXPECT_LT(norm(w.torque), 1e-14 * std::fabs(Fz) * d);
  }
}

TEST(MagnetInteraction, SideBySideSpheresRepelAndTwistAsDipoles) {
  // Centres along x. Parallel moments along z repel: F_x = 3 mu0 m^2/(4 pi d^4).
  // mA along z, mB along x: B sits in H_A = -mA/(4 pi d^3), torque on B
  // mu0 mB x H_A = mu0 m^2 / (4 pi d^3) e_y, and F = 3 mu0 m^2/(4 pi d^4) e_z.
  for (double d : {0.0102, 0.03}) {
    const SphereMagnet a(Pose::at({0, 0, 0}), kRadius, {0, 0, kMs});
    const SphereMagnet b(Pose::at({d, 0, 0}), kRadius, {0, 0, kMs});
    const double f = 3.0 * kMu0 * kSphereMoment * kSphereMoment / (4.0 * kPi * std::pow(d, 4));
    EXPECT_LT(relErr(magnetInteraction(a, b, 0.0).force, {f, 0, 0}), 1e-12);
    const SphereMagnet c(Pose::at({d, 0, 0}), kRadius, {kMs, 0, 0});
    const MagnetWrench w = magnetInteraction(a, c, 0.0);
    EXPECT_LT(relErr(w.force, {0, 0, f}), 1e-12);
    const double tau = kMu0 * kSphereMoment * kSphereMoment / (4.0 * kPi * std::pow(d, 3));
    EXPECT_LT(relErr(w.torque, {0, tau, 0}), 1e-12);
  }
}

TEST(MagnetInteraction, DipoleForceIsMinusTheEnergyGradient) {
  // Oblique moments: F_B = -grad_rB U with U = mu0/(4 pi r^3) [mA.mB - 3 (mA.u)(mB.u)],
  // by central differences (h = 1e-6 r, truncation ~1e-12, rounding ~1e-10).
  const Vec3d mA{0.3, -0.7, 0.5}, mB{-0.2, 0.4, 0.9};  // A*m^2
  const Vec3d r{0.013, 0.007, -0.011};                 // m
  const auto U = [&](const Vec3d& x) {
    const double d = norm(x);
    const Vec3d u = x / d;
    return kMu0 / (4 * kPi * d * d * d) * (dot(mA, mB) - 3 * dot(mA, u) * dot(mB, u));
  };
  const double h = 1e-6 * norm(r);
  Vec3d grad;
  for (int k = 0; k < 3; ++k) {
    Vec3d e;
    e[k] = h;
    grad[k] = (U(r + e) - U(r - e)) / (2 * h);
  }
  EXPECT_LT(relErr(dipoleDipoleForce(mA, mB, r), -1.0 * grad), 1e-8);
}

TEST(MagnetInteraction, NewtonsThirdLawAndAngularMomentumBalance) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1, 1);
  double worstF = 0, worstL = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const Vec3d xa{U(rng) * 0.01, U(rng) * 0.01, U(rng) * 0.01};
    const Vec3d r = randomUnit(rng) * (0.011 + 0.02 * (U(rng) + 1));
    const SphereMagnet a(Pose::fromAxisAngle(xa, randomUnit(rng), 3 * U(rng)), kRadius,
                         randomUnit(rng) * kMs);
    const SphereMagnet b(Pose::fromAxisAngle(xa + r, randomUnit(rng), 3 * U(rng)), 0.8 * kRadius,
                         randomUnit(rng) * (0.5 * kMs));
    const MagnetWrench onB = magnetInteraction(a, b, 0.0), onA = magnetInteraction(b, a, 0.0);
    worstF = std::max(worstF, norm(onA.force + onB.force) / norm(onB.force));
    worstL = std::max(worstL, angularMomentumResidual(onA, onB, r));
  }
  std::printf("spheres: worst |F_AB + F_BA|/|F| = %.2e, angular momentum residual %.2e\n", worstF,
              worstL);
  EXPECT_LT(worstF, 1e-12);
  EXPECT_LT(worstL, 1e-12);
}

TEST(MagnetInteraction, SphereSurfaceChargeIntegralIsTheDipoleForm) {
  // The surface-charge integral over B in A's exact field must reproduce the
  // exact (dipole) result for spheres; rotated bodies, oblique moments.
  const SphereMagnet a(Pose::fromAxisAngle({0, 0, 0}, {1, 2, 3}, 0.7), kRadius, {2e5, -5e5, 7e5});
  const SphereMagnet b(Pose::fromAxisAngle({0.008, 0.006, 0.004}, {-1, 0, 2}, 1.1), kRadius,
                       {-3e5, 6e5, 1e5});
  const MagnetWrench exact = magnetInteraction(a, b, 0.0);
  const MagnetWrench q = magnetInteraction(a, b, 0.0, MagnetInteractionMethod::SurfaceCharge, 32);
  std::printf("spheres, gap 0.08 radius: surface integral (order 32) vs dipole: force %.2e, torque %.2e\n",
              relErr(q.force, exact.force), relErr(q.torque, exact.torque));
  EXPECT_LT(relErr(q.force, exact.force), 1e-10);
  EXPECT_LT(relErr(q.torque, exact.torque), 1e-10);
}

TEST(MagnetInteraction, CubeSurfaceIntegralConvergesAndApproachesTheDipoleForm) {
  // Two cubes of edge 2 h, both magnetized along z. Coaxial (separation along
  // z) and side by side (along x); rotated B for the oblique case.
  const double h = 0.005;  // m, half edge
  const Vec3d half{h, h, h}, M{0, 0, 1e6};
  const auto pair = [&](const Vec3d& offset, double angle) {
    return std::make_pair(CuboidMagnet(Pose{}, half, M),
                          CuboidMagnet(Pose::fromAxisAngle(offset, {1, 1, 0}, angle), half, M));
  };
  const auto surface = [](const CuboidMagnet& a, const CuboidMagnet& b, int order) {
    return magnetInteraction(a, b, 0.0, MagnetInteractionMethod::SurfaceCharge, order);
  };
  // Convergence with order at the closest distance, 1.5 edge lengths.
  for (const Vec3d dir : {Vec3d{0, 0, 1}, Vec3d{1, 0, 0}}) {
    const auto [a, b] = pair(dir * (3.0 * h), 0.3);
    const MagnetWrench ref = surface(a, b, 64);
    double previous = 1;
    for (int order : {2, 4, 8, 16, 24}) {
      const MagnetWrench w = surface(a, b, order);
      const double eF = relErr(w.force, ref.force), eT = relErr(w.torque, ref.torque);
      std::printf("cubes at 1.5 edges, dir (%g,%g,%g): order %2d force error %.2e torque %.2e\n",
                  dir.x, dir.y, dir.z, order, eF, eT);
      if (previous > 1e-13) {
        EXPECT_LT(eF, previous);  // until rounding level
      }
      previous = eF;
      if (order == kMagnetInteractionDefaultOrder) {
        EXPECT_LT(eF, 1e-9);
        EXPECT_LT(eT, 1e-9);
      }
    }
  }
  // Dipole error against the converged integral at 1.5, 2, 4 edge lengths.
  for (const Vec3d dir : {Vec3d{0, 0, 1}, Vec3d{1, 0, 0}}) {
    double previous = 1;
    for (double edges : {1.5, 2.0, 4.0}) {
      const auto [a, b] = pair(dir * (2 * h * edges), 0.0);
      const MagnetWrench ref = surface(a, b, 48);
      const MagnetWrench dip = magnetInteraction(a, b, 0.0);
      const double e = relErr(dip.force, ref.force);
      std::printf("cubes, dir (%g,%g,%g), %.1f edges: dipole force error %.3e\n", dir.x, dir.y,
                  dir.z, edges, e);
      EXPECT_LT(e, previous);
      previous = e;
    }
    EXPECT_LT(previous, 1e-2);   // at 4 edge lengths
    EXPECT_GT(previous, 1e-7);   // but a cube is not a dipole
  }
}

TEST(MagnetInteraction, SurfaceIntegralObeysTheBalanceLawsForRotatedBodies) {
  const CuboidMagnet a(Pose::fromAxisAngle({0, 0, 0}, {0.3, -1, 0.4}, 0.9), {0.004, 0.006, 0.003},
                       {3e5, -1e5, 8e5});
  const CylinderMagnet b(Pose::fromAxisAngle({0.012, 0.009, -0.007}, {1, 0.5, 0.2}, 1.3), 0.004,
                         0.005, {0, 0, 9e5});
  const int order = kMagnetInteractionDefaultOrder;
  const MagnetWrench onB = magnetInteraction(a, b, 0.0, MagnetInteractionMethod::SurfaceCharge, order);
  const MagnetWrench onA = magnetInteraction(b, a, 0.0, MagnetInteractionMethod::SurfaceCharge, order);
  const Vec3d r = b.pose().position - a.pose().position;
  const double eF = norm(onA.force + onB.force) / norm(onB.force);
  const double eL = angularMomentumResidual(onA, onB, r);
  std::printf("cuboid-cylinder, order %d: |F_AB + F_BA|/|F| = %.2e, angular momentum %.2e\n", order,
              eF, eL);
  EXPECT_LT(eF, 1e-9);
  EXPECT_LT(eL, 1e-9);
}

TEST(MagnetInteraction, CylinderSurfaceIntegralApproachesTheDipoleForm) {
  const double R = 0.004, L = 0.005;  // m
  const CylinderMagnet a(Pose{}, R, L, {0, 0, 9e5});
  double previous = 1;
  for (double d : {0.02, 0.04, 0.08}) {
    const CylinderMagnet b(Pose::fromAxisAngle({d * 0.6, 0, d * 0.8}, {0, 1, 0}, 0.4), R, L,
                           {0, 0, 9e5});
    const MagnetWrench ref = magnetInteraction(a, b, 0.0, MagnetInteractionMethod::SurfaceCharge, 32);
    const MagnetWrench dip = magnetInteraction(a, b, 0.0);
    const double e = relErr(dip.force, ref.force);
    std::printf("cylinders at %.2f m: dipole force error %.3e, torque %.3e\n", d, e,
                relErr(dip.torque, ref.torque));
    EXPECT_LT(e, previous);
    previous = e;
  }
  EXPECT_LT(previous, 1e-2);
}

TEST(MagnetInteraction, RejectsCoincidentAndOverlappingBodies) {
  const SphereMagnet a(Pose::at({0.01, 0, 0}), kRadius, {0, 0, kMs});
  const SphereMagnet same(Pose::at({0.01, 0, 0}), kRadius, {kMs, 0, 0});
  expectContains(thrownMessage([&] { magnetInteraction(a, same, 0.0); }),
                 {"coincident", "0.01"});
  const SphereMagnet near(Pose::at({0.019, 0, 0}), kRadius, {0, 0, kMs});
  expectContains(thrownMessage([&] { magnetInteraction(a, near, 0.0); }),
                 {"overlap", "0.009", "0.005"});
  const CuboidMagnet c1(Pose{}, {0.005, 0.005, 0.005}, {0, 0, kMs});
  const CuboidMagnet c2(Pose::fromAxisAngle({0.0095, 0, 0}, {0, 0, 1}, 0.3), {0.005, 0.005, 0.005},
                        {0, 0, kMs});
  expectContains(thrownMessage([&] { magnetInteraction(c1, c2, 0.0); }), {"overlap", "inside"});
  expectContains(
      thrownMessage([&] {
        magnetInteraction(c1, c2, 0.0, MagnetInteractionMethod::SurfaceCharge, 0);
      }),
      {"order", "0"});
}
