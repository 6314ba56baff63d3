// Particle emission: counts, volumes, masses and micro-particle counts of
// box, sphere, cylinder and level-set emitters, reproducible jitter, spin.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/emitter.h"

using namespace lodestone;

TEST(MpmEmitter, BoxIsFilledExactly) {
  MpmParticles p;
  const MpmMaterial mat = neoHookeanSolid(1e5, 0.3, 2500, paperMaterial());
  EmitterSettings e;
  e.cellSize = 0.01;
  e.particlesPerCell = 8;
  e.velocity = {0.1, 0, 0};
  const EmitterShape box = EmitterShape::box(Pose::at({0.5, 0.5, 0.5}), {0.04, 0.03, 0.02});
  const EmitReport r = emitParticles(p, box, mat, 2, e);
  // 16 x 12 x 8 lattice cells of h = dx/2.
  EXPECT_EQ(r.particles, 16u * 12u * 8u);
  EXPECT_EQ(p.size(), r.particles);
  EXPECT_NEAR(r.volume, box.volume(), 1e-15);
  EXPECT_NEAR(r.mass, 2500 * box.volume(), 1e-12);
  EXPECT_NEAR(r.count, mat.magnetic.numberDensity * box.volume(), 1e-6 * r.count);
  // n_p = n0 V_p: 3.6e17 micro-particles per filled cell of the paper's dx,
  // shared among its particles.
  EXPECT_NEAR(p.count[0], mat.magnetic.numberDensity * p.volume0[0], 1e-9 * p.count[0]);
  for (std::size_t q = 0; q < p.size(); ++q) {
    ASSERT_EQ(p.material[q], 2u);
    ASSERT_EQ(p.id[q], q);
    ASSERT_LE(std::fabs(p.x[q].x - 0.5), 0.04);
    ASSERT_EQ(p.v[q], (Vec3d{0.1, 0, 0}));
  }
  // Non-magnetic material: no micro-particles.
  MpmParticles p2;
  emitParticles(p2, box, neoHookeanSolid(1e5, 0.3, 1000), 0, e);
  for (double c : p2.count) ASSERT_EQ(c, 0.0);
}

TEST(MpmEmitter, SphereAndCylinderVolumesConverge) {
  const MpmMaterial mat = viscousFluid(1, 1e5, 1000);
  for (int ppc : {8, 27}) {
    MpmParticles s, c;
    EmitterSettings e;
    e.cellSize = 0.01;
    e.particlesPerCell = ppc;
    const EmitterShape sphere = EmitterShape::sphere(Pose::at({0, 0, 0}), 0.05);
    const EmitterShape cyl = EmitterShape::cylinder(Pose::fromAxisAngle({0, 0, 0}, {1, 0, 0}, 0.3), 0.04, 0.03);
    const EmitReport rs = emitParticles(s, sphere, mat, 0, e);
    const EmitReport rc = emitParticles(c, cyl, mat, 0, e);
    // Staircase error O(h / R): 5% at h = dx/2 = R/10.
    EXPECT_NEAR(rs.volume, sphere.volume(), 0.05 * sphere.volume()) << ppc;
    EXPECT_NEAR(rc.volume, cyl.volume(), 0.05 * cyl.volume()) << ppc;
    EXPECT_NEAR(rs.spacing, 0.01 / std::cbrt(double(ppc)), 1e-15);
    for (const Vec3d& x : s.x) ASSERT_LE(norm(x), 0.05);
    for (const Vec3d& x : c.x) {
      const Vec3d b = cyl.pose.toLocal(x);
      ASSERT_LE(std::hypot(b.x, b.y), 0.04 + 1e-15);
      ASSERT_LE(std::fabs(b.z), 0.03 + 1e-15);
    }
  }
}

TEST(MpmEmitter, JitterIsReproducibleAndSpinIsRigid) {
  const MpmMaterial mat = neoHookeanSolid(1e5, 0.3, 1000);
  EmitterSettings e;
  e.cellSize = 0.02;
  e.jitter = 1.0;
  e.seed = 42;
  e.angularVelocity = {0, 0, 2};
  const EmitterShape box = EmitterShape::box(Pose::at({1, 1, 1}), {0.05, 0.05, 0.05});
  MpmParticles a, b, c;
  emitParticles(a, box, mat, 0, e);
  emitParticles(b, box, mat, 0, e);
  e.seed = 43;
  emitParticles(c, box, mat, 0, e);
  ASSERT_EQ(a.size(), b.size());
  bool differ = false;
  for (std::size_t q = 0; q < a.size(); ++q) {
    ASSERT_EQ(a.x[q], b.x[q]);
    differ = differ || a.x[q] != c.x[q];
    // Jittered within its lattice cell, inside the box.
    ASSERT_LE(std::fabs(a.x[q].x - 1), 0.05);
    // v = w x (x - centre) and C = [w]x.
    const Vec3d v = cross(e.angularVelocity, a.x[q] - Vec3d{1, 1, 1});
    ASSERT_LT(norm(a.v[q] - v), 1e-15);
    ASSERT_LT(norm(a.C[q] * Vec3d{0.3, 0.2, 0.1} - cross(e.angularVelocity, Vec3d{0.3, 0.2, 0.1})), 1e-15);
  }
  EXPECT_TRUE(differ);
}

TEST(MpmEmitter, RejectsBadInputNamingIt) {
  MpmParticles p;
  const MpmMaterial mat = neoHookeanSolid(1e5, 0.3, 1000);
  EmitterSettings e;  // cellSize 0
  try {
    emitParticles(p, EmitterShape::sphere(Pose::at({0, 0, 0}), 0.1), mat, 0, e);
    FAIL();
  } catch (const InvalidArgument& ex) {
    EXPECT_NE(std::string(ex.what()).find("cell size"), std::string::npos) << ex.what();
  }
  e.cellSize = 0.01;
  e.jitter = 2;
  EXPECT_THROW(emitParticles(p, EmitterShape::sphere(Pose::at({0, 0, 0}), 0.1), mat, 0, e), InvalidArgument);
  EXPECT_THROW(EmitterShape::sphere(Pose::at({0, 0, 0}), 0), InvalidArgument);
  EXPECT_THROW(EmitterShape::box(Pose::at({0, 0, 0}), {1, -1, 1}), InvalidArgument);
  EXPECT_EQ(p.size(), 0u);
}

TEST(MpmEmitter, LevelSetFillsTheSdfVolume) {
  // The exact sphere distance sampled every 2.5 mm: the SDF's own volume
  // estimate is second-order (0.5% here) and the emitted points' volumes
  // match the sphere to the staircase error, as for the analytic sphere.
  const double R = 0.05, hs = 0.0025;
  const int n = 57;  // +-0.07 m
  GridSpec g;
  g.dx = hs;
  g.origin = -0.5 * (n - 1) * hs * Vec3d{1, 1, 1};
  g.dims = {n, n, n};
  std::vector<float> v(g.nodeCount());
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) v[g.index(i, j, k)] = float(norm(g.nodePosition(i, j, k)) - R);
  const auto sdf = std::make_shared<const SampledSdf>(g, std::move(v));
  const double exact = 4.0 / 3.0 * kPi * R * R * R;
  EXPECT_NEAR(sdf->volume(), exact, 0.005 * exact);
  const MpmMaterial mat = viscousFluid(1, 1e5, 1000);
  const Pose pose = Pose::fromAxisAngle({0.3, 0.2, 0.1}, {1, 1, 0}, 0.7);
  const EmitterShape shape = EmitterShape::levelSetShape(pose, sdf);
  EXPECT_NEAR(shape.volume(), sdf->volume(), 0);
  for (int ppc : {8, 27}) {
    MpmParticles p;
    EmitterSettings e;
    e.cellSize = 0.01;
    e.particlesPerCell = ppc;
    const EmitReport r = emitParticles(p, shape, mat, 0, e);
    EXPECT_NEAR(r.volume, exact, 0.05 * exact) << ppc;
    EXPECT_NEAR(double(r.particles) * std::pow(r.spacing, 3), r.volume, 1e-12 * r.volume);
    // Every point inside the sphere about the pose's origin, up to the
    // interpolation error (< 1e-4 m here).
    for (const Vec3d& x : p.x) ASSERT_LE(norm(x - pose.position), R + 1e-4);
  }
  EXPECT_THROW(EmitterShape::levelSetShape(pose, nullptr), InvalidArgument);
}
