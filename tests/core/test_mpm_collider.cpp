// Analytic colliders: signed distances and normals of each shape against
// closed forms, rigid motions (static, keyframed with slerp, constant
// velocity) and the sticky / slip / separate boundary conditions with
// Coulomb friction; level-set (sampled) shapes against the analytic ones,
// including a block coming to rest on a level-set slab.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/collider.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/mpm/sampled_sdf.h"

using namespace lodestone;

namespace {
void expectVec(const Vec3d& a, const Vec3d& b, double tol) {
  EXPECT_LE(norm(a - b), tol) << "(" << a.x << ", " << a.y << ", " << a.z << ") vs (" << b.x << ", " << b.y << ", "
                              << b.z << ")";
}
}  // namespace

TEST(MpmCollider, SignedDistancesAndNormalsOfTheShapes) {
  const ColliderShape plane = ColliderShape::plane();
  EXPECT_DOUBLE_EQ(plane.signedDistance({3, -2, 0.25}), 0.25);
  expectVec(plane.normal({3, -2, -0.25}), {0, 0, 1}, 0);

  const ColliderShape sphere = ColliderShape::sphere(0.5);
  EXPECT_NEAR(sphere.signedDistance({0.3, 0.4, 1.2}), 1.3 - 0.5, 1e-15);
  EXPECT_NEAR(sphere.signedDistance({0.1, 0, 0}), -0.4, 1e-15);
  expectVec(sphere.normal({0.3, 0.4, 1.2}), Vec3d{0.3, 0.4, 1.2} / 1.3, 1e-15);

  const ColliderShape box = ColliderShape::box({1, 2, 3});
  EXPECT_NEAR(box.signedDistance({1.5, 0, 0}), 0.5, 1e-15);           // face
  EXPECT_NEAR(box.signedDistance({2, 3, 0}), std::sqrt(2.0), 1e-15);  // edge
  EXPECT_NEAR(box.signedDistance({2, 3, 4}), std::sqrt(3.0), 1e-15);  // corner
  EXPECT_NEAR(box.signedDistance({0.5, 0, 0}), -0.5, 1e-15);          // inside, nearest face x
  EXPECT_NEAR(box.signedDistance({0, 1.8, 0}), -0.2, 1e-15);          // nearest face y
  expectVec(box.normal({0, 1.8, 0}), {0, 1, 0}, 0);
  expectVec(box.normal({0, 0, -2.9}), {0, 0, -1}, 0);
  expectVec(box.normal({2, 3, 0}), Vec3d{1, 1, 0} / std::sqrt(2.0), 1e-15);

  const ColliderShape cyl = ColliderShape::cylinder(1.0, 2.0);
  EXPECT_NEAR(cyl.signedDistance({3, 4, 0}), 4.0, 1e-15);             // side
  EXPECT_NEAR(cyl.signedDistance({0.5, 0, 3}), 1.0, 1e-15);           // cap
  EXPECT_NEAR(cyl.signedDistance({0, 2, 3}), std::sqrt(2.0), 1e-15);  // rim
  EXPECT_NEAR(cyl.signedDistance({0.5, 0, 0}), -0.5, 1e-15);
  EXPECT_NEAR(cyl.signedDistance({0, 0, 1.9}), -0.1, 1e-15);
  expectVec(cyl.normal({0, 0.5, 0}), {0, 1, 0}, 1e-15);
  expectVec(cyl.normal({0, 0, -1.9}), {0, 0, -1}, 0);
  expectVec(cyl.normal({0, 2, 3}), Vec3d{0, 1, 1} / std::sqrt(2.0), 1e-15);

  // The normal is the gradient of the distance (central differences) off the ridges.
  for (const ColliderShape* s : {&sphere, &box, &cyl}) {
    for (const Vec3d& x : {Vec3d{0.7, 0.2, 0.1}, Vec3d{1.3, 2.4, -0.3}, Vec3d{0.2, -0.1, 2.6}}) {
      Vec3d grad;
      const double e = 1e-7;
      for (int a = 0; a < 3; ++a) {
        Vec3d xp = x, xm = x;
        xp[a] += e;
        xm[a] -= e;
        grad[a] = (s->signedDistance(xp) - s->signedDistance(xm)) / (2 * e);
      }
      expectVec(s->normal(x), grad, 1e-6);
    }
  }
  // A container: the inverted sphere is solid outside.
  const ColliderShape bowl = sphere.invertedShape();
  EXPECT_NEAR(bowl.signedDistance({0.1, 0, 0}), 0.4, 1e-15);
  expectVec(bowl.normal({0, 0, -0.45}), {0, 0, 1}, 1e-15);

  EXPECT_THROW(ColliderShape::sphere(-1), InvalidArgument);
  EXPECT_THROW(ColliderShape::box({1, 0, 1}), InvalidArgument);
  EXPECT_THROW(ColliderShape::cylinder(1, NAN), InvalidArgument);
}

TEST(MpmCollider, BoundaryConditions) {
  const Vec3d n{0, 0, 1}, wall{0.1, 0, 0};
  const Vec3d in{1.0, 0.5, -2.0}, out{1.0, 0.5, 2.0};
  BoundaryCondition bc;
  bc.mode = BoundaryMode::Sticky;
  expectVec(applyBoundaryCondition(in, wall, n, bc), wall, 0);
  bc.mode = BoundaryMode::Slip;
  expectVec(applyBoundaryCondition(in, wall, n, bc), {1.0, 0.5, 0}, 1e-15);
  expectVec(applyBoundaryCondition(out, wall, n, bc), {1.0, 0.5, 0}, 1e-15);
  bc.mode = BoundaryMode::Separate;
  expectVec(applyBoundaryCondition(in, wall, n, bc), {1.0, 0.5, 0}, 1e-15);
  expectVec(applyBoundaryCondition(out, wall, n, bc), out, 0);
  // Coulomb friction: the relative tangential speed |(0.9, 0.5)| = 1.0296
  // shrinks by mu |v_n| = 0.25 * 2.
  bc.friction = 0.25;
  const Vec3d vt{0.9, 0.5, 0};
  const double speed = norm(vt);
  expectVec(applyBoundaryCondition(in, wall, n, bc), wall + vt * ((speed - 0.5) / speed), 1e-15);
  bc.friction = 1.0;  // 2 > 1.0296: stops
  expectVec(applyBoundaryCondition(in, wall, n, bc), wall, 1e-15);
  BoundaryCondition bad;
  bad.friction = -1;
  EXPECT_THROW(bad.validate("test"), InvalidArgument);
}

TEST(MpmCollider, MotionsGivePosesAndVelocities) {
  // Constant velocity with spin about z: after t, rotated by w t.
  const Pose p0 = Pose::at({1, 0, 0});
  const ColliderMotion spin = ColliderMotion::constantVelocity(p0, {0, 1, 0}, {0, 0, kPi}, 0.0);
  const Pose p = spin.poseAt(0.5);
  expectVec(p.position, {1, 0.5, 0}, 1e-15);
  expectVec(p.vectorToWorld({1, 0, 0}), {0, 1, 0}, 1e-15);  // quarter turn
  const MpmCollider c(ColliderShape::sphere(0.2), spin, BoundaryCondition{});
  // Rigid velocity at a point: v + w x (x - centre).
  expectVec(c.velocity({1.1, 0.5, 0}, 0.5), Vec3d{0, 1, 0} + cross(Vec3d{0, 0, kPi}, Vec3d{0.1, 0, 0}), 1e-15);
  EXPECT_NEAR(c.signedDistance({1.0, 0.5, 0.5}, 0.5), 0.3, 1e-15);

  // Keyframes: linear position, slerped orientation, constant segment velocities.
  const Pose k0 = Pose::at({0, 0, 0});
  const Pose k1 = Pose::fromAxisAngle({2, 0, 0}, {0, 0, 1}, kPi / 2);
  const Pose k2 = Pose::fromAxisAngle({2, 2, 0}, {0, 0, 1}, kPi / 2);
  const ColliderMotion key = ColliderMotion::keyframed({1.0, 2.0, 4.0}, {k0, k1, k2});
  expectVec(key.poseAt(0.0).position, {0, 0, 0}, 0);  // held before
  const Pose mid = key.poseAt(1.5);
  expectVec(mid.position, {1, 0, 0}, 1e-15);
  expectVec(mid.vectorToWorld({1, 0, 0}), {std::cos(kPi / 4), std::sin(kPi / 4), 0}, 1e-15);  // half of 90 deg
  Vec3d v, w;
  key.velocityAt(1.5, v, w);
  expectVec(v, {2, 0, 0}, 1e-15);
  expectVec(w, {0, 0, kPi / 2}, 1e-12);
  key.velocityAt(3.0, v, w);
  expectVec(v, {0, 1, 0}, 1e-15);
  expectVec(w, {0, 0, 0}, 1e-12);
  expectVec(key.poseAt(9.0).position, {2, 2, 0}, 0);  // held after
  key.velocityAt(9.0, v, w);
  expectVec(v, {}, 0);
  // The keyframed velocity is the derivative of the pose (finite difference).
  const double t = 1.3, e = 1e-6;
  const Pose a = key.poseAt(t - e), b = key.poseAt(t + e);
  key.velocityAt(t, v, w);
  expectVec((b.position - a.position) / (2 * e), v, 1e-8);
  const Vec3d xb{0.3, -0.2, 0.1};
  expectVec((b.toWorld(xb) - a.toWorld(xb)) / (2 * e), v + cross(w, key.poseAt(t).toWorld(xb) - key.poseAt(t).position),
            1e-8);

  EXPECT_THROW(ColliderMotion::keyframed({1.0, 1.0}, {k0, k1}), InvalidArgument);
  EXPECT_THROW(ColliderMotion::keyframed({1.0}, {k0, k1}), InvalidArgument);
  EXPECT_THROW(ColliderMotion::constantVelocity(k0, {NAN, 0, 0}, {}), InvalidArgument);
}

TEST(MpmCollider, ApplyActsOnlyInsideTheSolid) {
  const MpmCollider floor(ColliderShape::plane(), ColliderMotion::fixed(Pose::at({0, 0, 0.1})),
                          BoundaryCondition{BoundaryMode::Sticky, 0});
  expectVec(floor.apply({0, 0, 0.2}, {1, 2, -3}, 0), {1, 2, -3}, 0);  // above: untouched
  expectVec(floor.apply({0, 0, 0.05}, {1, 2, -3}, 0), {0, 0, 0}, 0);  // inside: stuck
  // A moving box pushes: separate boundary, node inside moving with the box.
  const MpmCollider pusher(ColliderShape::box({0.1, 0.1, 0.1}),
                           ColliderMotion::constantVelocity(Pose::at({0, 0, 0}), {1, 0, 0}, {}));
  expectVec(pusher.apply({0.09, 0, 0}, {0, 0, 0}, 0), {1, 0, 0}, 1e-15);  // approaching relative to the wall
  expectVec(pusher.apply({0.09, 0, 0}, {2, 0, 0}, 0), {2, 0, 0}, 0);      // leaving faster: free
}

// ---------------------------------------------------------------------------
// Level sets (SampledSdf)

namespace {

/// The exact signed distance of `shape` sampled on a cube of n^3 nodes of
/// spacing h centred on `centre` (body frame).
std::shared_ptr<const SampledSdf> sampledShape(const ColliderShape& shape, const Vec3d& centre, int n, double h) {
  GridSpec g;
  g.dx = h;
  g.origin = centre - 0.5 * (n - 1) * h * Vec3d{1, 1, 1};
  g.dims = {n, n, n};
  std::vector<float> v(g.nodeCount());
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) v[g.index(i, j, k)] = float(shape.signedDistance(g.nodePosition(i, j, k)));
  return std::make_shared<const SampledSdf>(g, std::move(v), "sampled test shape");
}

}  // namespace

TEST(MpmCollider, LevelSetMatchesTheAnalyticSphere) {
  // Trilinear interpolation of the exact distance r - R errs by at most
  // (h^2 / 8) * max|d2 phi| * 3 axes = 3 h^2 / (8 r) near the surface; with
  // h = 5 mm and r >= R/2 = 0.1 m that is 1e-4 m (plus float rounding).
  const double R = 0.2, h = 0.005;
  const ColliderShape sphere = ColliderShape::sphere(R);
  const ColliderShape ls = ColliderShape::levelSetShape(sampledShape(sphere, {0, 0, 0}, 121, h));  // box +-0.3 m
  EXPECT_STREQ(toString(ls.kind), "level set");
  double worstD = 0, worstN = 0;
  for (int s = 0; s < 2000; ++s) {
    // Deterministic points on shells r in [0.1, 0.29] m.
    const double u = (s * 0.618034) - std::floor(s * 0.618034), w = (s * 0.414214) - std::floor(s * 0.414214);
    const double r = 0.1 + 0.19 * ((s * 0.7548777) - std::floor(s * 0.7548777));
    const double ct = 2 * u - 1, st = std::sqrt(1 - ct * ct), ph = 2 * kPi * w;
    const Vec3d x = r * Vec3d{st * std::cos(ph), st * std::sin(ph), ct};
    worstD = std::max(worstD, std::fabs(ls.signedDistance(x) - sphere.signedDistance(x)));
    worstN = std::max(worstN, norm(ls.normal(x) - sphere.normal(x)));
  }
  EXPECT_LE(worstD, 3 * h * h / (8 * 0.1) + 1e-6) << worstD;
  // The normal of the trilinear interpolant is first-order: on a node it is
  // a one-sided difference, off by about h / r (<= 0.05 here).
  EXPECT_LE(worstN, h / 0.1) << worstN;
  // Outside the sampled box: distance to the box plus the rim value, exact for
  // points straight out along an axis (rim value 0.3 - R, then + distance).
  EXPECT_NEAR(ls.signedDistance({0.5, 0, 0}), 0.5 - R, 1e-6);
  expectVec(ls.normal({0.5, 0, 0}), {1, 0, 0}, h / 0.3);
  // Inverted: a spherical container.
  const ColliderShape bowl = ls.invertedShape();
  EXPECT_NEAR(bowl.signedDistance({0.15, 0, 0}), 0.05, 1e-4);
  expectVec(bowl.normal({0.15, 0, 0}), {-1, 0, 0}, h / 0.15);
  EXPECT_THROW(ColliderShape::levelSetShape(nullptr), InvalidArgument);
  ColliderShape empty;
  empty.kind = ColliderShapeKind::LevelSet;
  EXPECT_THROW(MpmCollider{empty}, InvalidArgument);
}

TEST(MpmCollider, LevelSetRejectsBadGrids) {
  GridSpec g;
  g.dx = 0.1;
  g.dims = {3, 3, 3};
  EXPECT_THROW(SampledSdf(g, std::vector<float>(26, -1.0f)), InvalidArgument);  // size
  EXPECT_THROW(SampledSdf(g, std::vector<float>(27, 1.0f)), InvalidArgument);   // nothing inside
  std::vector<float> v(27, -1.0f);
  v[4] = NAN;
  try {
    SampledSdf(g, v, "grid 'x'");
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("grid 'x'"), std::string::npos) << e.what();
  }
}

namespace {

/// A 6 x 6 x 4 cm elastic block dropped from 4 cm above a floor slab whose
/// top is at z = 0.06 m, for 0.6 s; returns the final centre-of-mass height.
double blockOnSlab(const MpmCollider& slab) {
  MpmSettings s;
  s.grid.dx = 0.01;
  s.grid.origin = {0, 0, 0};
  s.grid.dims = {21, 21, 21};
  MpmSolver solver(s);
  solver.addCollider(slab);
  const std::uint32_t m = solver.addMaterial(neoHookeanSolid(1e5, 0.3, 1000));
  solver.emit(EmitterShape::box(Pose::at({0.1, 0.1, 0.12}), {0.03, 0.03, 0.02}), m, {});
  while (solver.time() < 0.6 - 1e-12) solver.advanceFrame(1.0 / 50);
  return solver.particles().centreOfMass().z;
}

}  // namespace

TEST(MpmCollider, LevelSetStopsAFallingBlockLikeTheAnalyticBox) {
  // The same slab (top at z = 0.06 m) as an analytic box and as its signed
  // distance sampled every 5 mm: the block comes to rest on it at the same
  // height (within a tenth of a cell). Its centre stays above top + h/2 =
  // 0.08 m and below that plus the B-spline reach 1.5 dx (the MPM stops
  // material where its kernels touch solid nodes); without the slab it would
  // sink to the domain floor, centre near z = 0.05 m.
  const BoundaryCondition bc{BoundaryMode::Separate, 0.0};
  const ColliderShape box = ColliderShape::box({0.15, 0.15, 0.03});
  const MpmCollider analytic(box, ColliderMotion::fixed(Pose::at({0.1, 0.1, 0.03})), bc);
  const MpmCollider sampled(ColliderShape::levelSetShape(sampledShape(box, {0, 0, 0}, 81, 0.005)),
                            ColliderMotion::fixed(Pose::at({0.1, 0.1, 0.03})), bc);
  const double za = blockOnSlab(analytic), zs = blockOnSlab(sampled);
  std::printf("block on slab: rest height analytic %.5f m, level set %.5f m\n", za, zs);
  EXPECT_NEAR(zs, za, 0.001);
  EXPECT_GT(zs, 0.08);
  EXPECT_LT(zs, 0.08 + 1.5 * 0.01);
}
