// Colliders that hold: the collider projection (particles deeper in a
// collider than its allowance are pushed back) and the crossing limit of the
// substep (MpmSettings::colliderProjection). The shapes' half-thicknesses
// against closed forms, the projection of single points, and three scenes
// that lose material through a wall without them: fluid pressed onto a plate
// thinner than a cell, a fast thin paddle sweeping a layer, and magnetic
// fluid pulled against a thin level-set bowl wall by a magnet beneath it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <vector>

#include "lodestone/core/field/material.h"
#include "lodestone/core/mpm/collider.h"
#include "lodestone/core/mpm/sampled_sdf.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/sources/sphere_magnet.h"

using namespace lodestone;

namespace {

/// `phi` sampled on the nodes of `g` (body frame).
template <typename Phi>
std::shared_ptr<const SampledSdf> sampled(const GridSpec& g, const Phi& phi) {
  std::vector<float> v(g.nodeCount());
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) v[g.index(i, j, k)] = float(phi(g.nodePosition(i, j, k)));
  return std::make_shared<const SampledSdf>(g, std::move(v), "sampled test shape");
}

GridSpec cube(const Vec3d& centre, double half, double h) {
  GridSpec g;
  g.dx = h;
  const int n = int(std::lround(2 * half / h)) + 1;
  g.dims = {n, n, n};
  g.origin = centre - half * Vec3d{1, 1, 1};
  return g;
}

/// The signed distance of a hemispherical bowl (opening upwards, z <= 0) of
/// inner radius a and outer radius b centred at the origin: the shell
/// a <= |x| <= b below the equator, closed by the flat rim in the plane z = 0.
double bowlDistance(const Vec3d& x, double a, double b) {
  const double r = norm(x), mid = 0.5 * (a + b), half = 0.5 * (b - a);
  if (x.z <= 0) return std::fabs(r - mid) - half;
  // Above the rim: the distance to the rim annulus in the plane z = 0.
  const double rho = std::sqrt(x.x * x.x + x.y * x.y);
  const double dr = rho < a ? a - rho : (rho > b ? rho - b : 0.0);
  return std::sqrt(dr * dr + x.z * x.z);
}

/// Lowest particle depth inside the collider (m, > 0 inside), and the number of
/// particles below `zBelow`.
struct Leak {
  double deepest = 0;
  std::size_t below = 0;
};
Leak leakOf(const MpmSolver& solver, const MpmCollider& c, double zBelow) {
  Leak l;
  const MpmParticles& p = solver.particles();
  for (std::size_t i = 0; i < p.size(); ++i) {
    l.deepest = std::max(l.deepest, -c.signedDistance(p.x[i], solver.time()));
    if (p.x[i].z < zBelow) ++l.below;
  }
  return l;
}

}  // namespace

TEST(ThinWalls, HalfThicknessOfEachShape) {
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(ColliderShape::plane().halfThickness(), inf);
  EXPECT_DOUBLE_EQ(ColliderShape::sphere(0.3).halfThickness(), 0.3);
  EXPECT_DOUBLE_EQ(ColliderShape::box({0.2, 0.004, 0.5}).halfThickness(), 0.004);
  EXPECT_DOUBLE_EQ(ColliderShape::cylinder(0.1, 0.02).halfThickness(), 0.02);
  EXPECT_EQ(ColliderShape::box({0.2, 0.1, 0.5}).invertedShape().halfThickness(), inf);

  // A level-set bowl with a 15 mm wall sampled every 2 mm: the shallowest
  // ridge is the wall's mid-surface, 7.5 mm deep, found to within h/2 (the
  // ridge node is the nearer of two nodes straddling the mid-surface along an
  // axis). The medial surfaces that run into the rim's edges are not ridges.
  const double a = 0.08, b = 0.095, h = 0.002;
  const auto bowl = sampled(cube({0, 0, 0}, 0.11, h), [&](const Vec3d& x) { return bowlDistance(x, a, b); });
  const double ridge = ColliderShape::levelSetShape(bowl).halfThickness();
  std::printf("bowl wall half-thickness 7.5 mm, ridge found %.3f mm\n", 1e3 * ridge);
  EXPECT_LE(ridge, 0.0075 + 1e-6);
  EXPECT_GE(ridge, 0.0075 - h / 2);
  // The inverted bowl's solid is everything else, the cavity included: its
  // thinnest part is the cavity's, whose ridge is the inner sphere's centre,
  // a deep.
  EXPECT_NEAR(ColliderShape::levelSetShape(bowl).invertedShape().halfThickness(), a, h);
  // A spherical container (the inside of a sampled sphere, inverted): its
  // solid outside never thins to a ridge, but the sampled sphere's own inside
  // ridge is its centre, at depth R.
  const auto ball = sampled(cube({0, 0, 0}, 0.1, 0.005), [](const Vec3d& x) { return norm(x) - 0.06; });
  EXPECT_NEAR(ColliderShape::levelSetShape(ball).halfThickness(), 0.06, 1e-6);
  EXPECT_EQ(ColliderShape::levelSetShape(ball).invertedShape().halfThickness(), inf);
  // A box 6 cm x 6 cm x 1 cm: its convex edges are not thin walls; the
  // ridge is the mid-plane, 5 mm deep (on a node here).
  const auto slab = sampled(cube({0, 0, 0}, 0.05, 0.0025),
                            [](const Vec3d& x) { return ColliderShape::box({0.03, 0.03, 0.005}).signedDistance(x); });
  EXPECT_NEAR(ColliderShape::levelSetShape(slab).halfThickness(), 0.005, 1e-6);
  // A narrow band (values clamped at -+3 h) of a thick block: no ridge, the
  // band's half width.
  const auto band = sampled(cube({0, 0, 0}, 0.1, 0.005), [](const Vec3d& x) {
    return std::max(-0.015, std::min(0.015, ColliderShape::box({0.06, 0.06, 0.06}).signedDistance(x)));
  });
  EXPECT_NEAR(ColliderShape::levelSetShape(band).halfThickness(), 0.015, 1e-6);
}

TEST(ThinWalls, ProjectionMovesAPointOntoTheSurfaceAndAppliesTheCondition) {
  // A plate 8 mm thick (|z| <= 4 mm) moving up at 0.5 m/s; a point 1 mm into
  // its top face moving down at 2 m/s and sideways at 1 m/s.
  const ColliderShape plate = ColliderShape::box({0.1, 0.1, 0.004});
  const ColliderMotion up = ColliderMotion::constantVelocity(Pose::at({0, 0, 0}), {0, 0, 0.5}, {});
  const MpmCollider slip(plate, up, {BoundaryMode::Slip, 0});
  const ColliderState s = slip.stateAt(0);
  Vec3d x{0.01, 0.02, 0.003}, v{1, 0, -2};
  ASSERT_TRUE(slip.projectOut(s, x, v));
  EXPECT_NEAR(x.z, 0.004, 1e-15);
  EXPECT_EQ(x.x, 0.01);
  EXPECT_NEAR(v.z, 0.5, 1e-15);  // the normal velocity is the plate's
  EXPECT_NEAR(v.x, 1, 1e-15);    // the tangential velocity is kept
  // Sticky: the plate's velocity; Coulomb friction mu = 0.2 removes mu |v_n|
  // = 0.2 * 2.5 m/s of the 1 m/s tangential speed.
  const MpmCollider sticky(plate, up, {BoundaryMode::Sticky, 0});
  Vec3d xs{0.01, 0.02, 0.003}, vs{1, 0, -2};
  ASSERT_TRUE(sticky.projectOut(s, xs, vs));
  EXPECT_NEAR(norm(vs - Vec3d{0, 0, 0.5}), 0, 1e-15);
  const MpmCollider rough(plate, up, {BoundaryMode::Separate, 0.2});
  Vec3d xr{0.01, 0.02, -0.003}, vr{1, 0, 2};  // 1 mm into the bottom face, moving up through it
  ASSERT_TRUE(rough.projectOut(s, xr, vr));
  EXPECT_NEAR(xr.z, -0.004, 1e-15);
  EXPECT_NEAR(vr.x, 1 - 0.2 * 1.5, 1e-14);
  EXPECT_NEAR(vr.z, 0.5, 1e-15);
  // Outside: nothing changes.
  Vec3d xo{0.01, 0.02, 0.0041}, vo{1, 0, -2};
  EXPECT_FALSE(slip.projectOut(s, xo, vo));
  EXPECT_EQ(xo.z, 0.0041);
  EXPECT_EQ(vo.z, -2);
}

namespace {

/// A 6 x 6 x 3 cm block of soft fluid (K = 2e4 Pa) on a plate 4 mm thick (less
/// than half a 1 cm cell) under 20 g, for 0.25 s. Returns the leak through
/// the plate: particles below its bottom face and the deepest penetration.
Leak fluidOnThinPlate(bool projection, MpmFrameReport* last = nullptr) {
  MpmSettings s;
  s.grid.dx = 0.01;
  s.grid.dims = {21, 21, 25};
  s.gravity = {0, 0, -196.2};
  s.colliderProjection = projection;
  MpmSolver solver(s);
  // The plate spans the domain from wall to wall: nothing can flow around it.
  const MpmCollider plate(ColliderShape::box({0.2, 0.2, 0.002}), ColliderMotion::fixed(Pose::at({0.1, 0.1, 0.1})),
                          {BoundaryMode::Separate, 0});
  solver.addCollider(plate);
  const std::uint32_t m = solver.addMaterial(viscousFluid(0.5, 2e4, 1000));
  solver.emit(EmitterShape::box(Pose::at({0.1, 0.1, 0.1 + 0.002 + 0.016}), {0.03, 0.03, 0.015}), m, {});
  for (int f = 0; f < 10; ++f) {
    const MpmFrameReport r = solver.advanceFrame(0.025);
    if (last) *last = r;
  }
  return leakOf(solver, plate, 0.1 - 0.002);
}

}  // namespace

TEST(ThinWalls, FluidPressedOntoAPlateThinnerThanACellStaysOnIt) {
  MpmFrameReport r;
  const Leak on = fluidOnThinPlate(true, &r);
  const Leak off = fluidOnThinPlate(false);
  std::printf("fluid on a 4 mm plate (dx 10 mm, 20 g): projection on: %zu below, deepest %.3g mm (%zu pushes in "
              "the last frame); off: %zu below, deepest %.3g mm\n",
              on.below, 1e3 * on.deepest, r.projected, off.below, 1e3 * off.deepest);
  // Without the projection the plate is invisible to most of the grid (no
  // node lies inside it) and the fluid falls through: the scene is hard.
  ASSERT_GT(off.below, 100u);
  EXPECT_EQ(on.below, 0u);
  // After every substep no particle is deeper in the plate than the
  // allowance, half the plate's half-thickness (1 mm) here.
  EXPECT_LE(on.deepest, 0.001 + 1e-12);
  EXPECT_GT(r.projected, 0u);
}

namespace {

/// A paddle 3 mm thick (y half-thickness 1.5 mm), 8 cm wide and 6 cm tall,
/// moving along +y at 3 m/s through a 2 cm layer of fluid resting on the floor
/// (no gravity, so only the paddle moves it), for 40 ms (12 cm of travel).
/// Returns the particles left behind the paddle: y below its rear face within
/// its width and height (the layer spans y in [0.05, 0.15] m).
std::size_t leftBehindPaddle(bool projection, int* limited = nullptr) {
  MpmSettings s;
  s.grid.dx = 0.01;
  s.grid.dims = {21, 31, 16};
  s.gravity = {0, 0, 0};
  s.colliderProjection = projection;
  MpmSolver solver(s);
  const Vec3d start{0.1, 0.03, 0.05};
  const MpmCollider paddle(ColliderShape::box({0.04, 0.0015, 0.03}),
                           ColliderMotion::constantVelocity(Pose::at(start), {0, 3, 0}, {}),
                           {BoundaryMode::Sticky, 0});
  solver.addCollider(paddle);
  const std::uint32_t m = solver.addMaterial(viscousFluid(0.1, 1e5, 1000));
  solver.emit(EmitterShape::box(Pose::at({0.1, 0.1, 0.04}), {0.03, 0.05, 0.01}), m, {});
  int shortened = 0;
  for (int f = 0; f < 4; ++f) shortened += solver.advanceFrame(0.01).dtLimitedByColliders;
  if (limited) *limited = shortened;
  const double rear = start.y + 3 * solver.time() - 0.0015;
  std::size_t behind = 0;
  const MpmParticles& p = solver.particles();
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.x[i].y < rear - 1e-9 && std::fabs(p.x[i].x - 0.1) < 0.03 && p.x[i].z < 0.05 + 0.03) ++behind;
  return behind;
}

}  // namespace

TEST(ThinWalls, AFastThinPaddleSweepsTheFluidInsteadOfPassingThrough) {
  int limited = 0;
  const std::size_t on = leftBehindPaddle(true, &limited);
  const std::size_t off = leftBehindPaddle(false);
  std::printf("3 mm paddle at 3 m/s through a fluid layer: left behind with projection %zu (%d substeps shortened "
              "by the crossing limit), without %zu\n",
              on, limited, off);
  ASSERT_GT(off, 100u);  // the paddle slips through the layer without the projection
  EXPECT_EQ(on, 0u);
  // The crossing limit set the substep: 0.4 * (1.5 - 0.75) mm (the
  // half-thickness less the allowance) / (3 m/s + the swept fluid's speed)
  // <= 0.1 ms, below the fluid's own CFL step (0.4 * 1 cm / (10 m/s sound
  // speed + 3 m/s) = 0.31 ms).
  EXPECT_GT(limited, 0);
}

namespace {

/// Magnetic fluid (the paper's law, K = 1e5 Pa) in a level-set bowl with a
/// 15 mm wall sampled every 3 mm; a sphere magnet (remanence 1.2 T) just
/// under the bowl pulls it down for 0.3 s. Returns the deepest penetration
/// into the wall and the particles that left the bowl through it.
Leak magneticFluidInBowl(bool projection) {
  const double a = 0.08, b = 0.095;
  MpmSettings s;
  s.grid.dx = 0.008;
  s.grid.origin = {-0.12, -0.12, 0.0};
  s.grid.dims = {31, 31, 31};
  s.colliderProjection = projection;
  s.magnetic.solve.tolerance = 1e-4;
  MpmSolver solver(s);
  const Vec3d centre{0, 0, 0.2};
  const MpmCollider bowl(ColliderShape::levelSetShape(sampled(
                             cube({0, 0, 0}, 0.11, 0.003), [&](const Vec3d& x) { return bowlDistance(x, a, b); })),
                         ColliderMotion::fixed(Pose::at(centre)), {BoundaryMode::Slip, 0});
  solver.addCollider(bowl);
  solver.addNonCollidingMagnet(
      SphereMagnet(Pose::at({0, 0, 0.2 - b - 0.03}), 0.025, {0, 0, magnetizationFromRemanence(1.2)}),
      ColliderMotion::fixed(Pose::at({0, 0, 0.2 - b - 0.03})));
  const std::uint32_t m = solver.addMaterial(viscousFluid(0.5, 1e5, 1200, paperMaterial()));
  solver.emit(EmitterShape::sphere(Pose::at({0, 0, 0.2 - a + 0.03}), 0.025), m, {});
  for (int f = 0; f < 12; ++f) solver.advanceFrame(0.025);
  // Particles that crossed the wall lie outside the outer sphere below the rim.
  Leak l = leakOf(solver, bowl, -1);
  for (const Vec3d& x : solver.particles().x)
    if (x.z < centre.z && norm(x - centre) > b) ++l.below;
  return l;
}

}  // namespace

TEST(ThinWalls, MagneticFluidPulledAgainstAThinBowlWallStaysInTheBowl) {
  const Leak on = magneticFluidInBowl(true);
  const Leak off = magneticFluidInBowl(false);
  std::printf("magnetic fluid in a 15 mm bowl wall over a magnet: projection on: deepest %.3g mm, %zu out; off: "
              "deepest %.3g mm, %zu out\n",
              1e3 * on.deepest, on.below, 1e3 * off.deepest, off.below);
  ASSERT_GT(off.deepest, 0.003);  // the grid condition alone lets the pull drive fluid into the wall
  EXPECT_EQ(on.below, 0u);
  // No deeper than the allowance, half the wall's half-thickness (dx / 2 = 4
  // mm is larger), up to the trilinear interpolant's curvature error (far
  // below a voxel).
  EXPECT_LE(on.deepest, 0.5 * 0.0075 + 1e-4);
}
