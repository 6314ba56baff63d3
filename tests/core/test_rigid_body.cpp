// Dynamic rigid bodies (mpm/rigid_body.h, mpm/rigid_contact.h) in the MPM
// solver without material: mass properties against closed forms, the
// torque-free rotation, a sphere rolling down an incline, collisions between
// spheres and a box coming to rest on the floor.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/mpm/collider.h"
#include "lodestone/core/mpm/rigid_body.h"
#include "lodestone/core/mpm/rigid_contact.h"
#include "lodestone/core/mpm/sampled_sdf.h"
#include "lodestone/core/mpm/solver.h"

using namespace lodestone;

namespace {

/// A sphere of radius r sampled as a level set every h, centred at `centre` (body frame).
std::shared_ptr<const SampledSdf> sampledSphere(double r, double h, const Vec3d& centre) {
  GridSpec g;
  g.dx = h;
  const int n = int(std::ceil(2 * (r + 3 * h) / h)) + 1;
  g.dims = {n, n, n};
  g.origin = centre - 0.5 * (n - 1) * h * Vec3d{1, 1, 1};
  std::vector<float> v(g.nodeCount());
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) v[g.index(i, j, k)] = float(norm(g.nodePosition(i, j, k) - centre) - r);
  return std::make_shared<const SampledSdf>(g, std::move(v), "sampled sphere");
}

MpmSettings emptyBox(int n, double dx, const Vec3d& gravity) {
  MpmSettings s;
  s.grid.dx = dx;
  s.grid.dims = {n, n, n};
  s.gravity = gravity;
  s.fixedDt = 1e-3;
  return s;
}

RigidBodySettings bodySettings(double density, double restitution, double friction) {
  RigidBodySettings b;
  b.density = density;
  b.restitution = restitution;
  b.friction = friction;
  return b;
}

}  // namespace

TEST(RigidBody, MassPropertiesOfTheAnalyticShapesAreTheClosedForms) {
  const double rho = 2000;
  const RigidMassProperties s = massProperties(ColliderShape::sphere(0.1), rho);
  EXPECT_NEAR(s.mass, rho * 4.0 / 3.0 * kPi * 1e-3, 1e-12);
  EXPECT_NEAR(s.inertia(0, 0), 0.4 * s.mass * 0.01, 1e-14);
  const RigidMassProperties b = massProperties(ColliderShape::box({0.1, 0.2, 0.3}), rho);
  EXPECT_NEAR(b.mass, rho * 0.2 * 0.4 * 0.6, 1e-12);
  EXPECT_NEAR(b.inertia(0, 0), b.mass / 12 * (0.16 + 0.36), 1e-12);
  EXPECT_NEAR(b.inertia(2, 2), b.mass / 12 * (0.04 + 0.16), 1e-12);
  const RigidMassProperties c = massProperties(ColliderShape::cylinder(0.1, 0.25), rho);
  EXPECT_NEAR(c.mass, rho * kPi * 0.01 * 0.5, 1e-12);
  EXPECT_NEAR(c.inertia(2, 2), 0.5 * c.mass * 0.01, 1e-14);
  EXPECT_NEAR(c.inertia(0, 0), c.mass * (3 * 0.01 + 0.25) / 12, 1e-14);
  // The inverse is the inverse.
  const Mat3d one = b.inertia * b.inverseInertia;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(one(i, j), i == j ? 1.0 : 0.0, 1e-12);
  EXPECT_THROW(massProperties(ColliderShape::plane(), rho), InvalidArgument);
  EXPECT_THROW(massProperties(ColliderShape::sphere(0.1).invertedShape(), rho), InvalidArgument);
  EXPECT_THROW(massProperties(ColliderShape::sphere(0.1), -1), InvalidArgument);
}

TEST(RigidBody, LevelSetMassPropertiesConvergeAtSecondOrder) {
  // A sphere of radius 5 cm sampled off-centre (centre of mass at (1, 2, 3)
  // cm in its body frame): mass, centre and inertia against the closed form
  // at h = r/5 and r/10; the error must fall by about 4 (second order).
  const double r = 0.05, rho = 1000;
  const Vec3d c{0.01, 0.02, 0.03};
  const RigidMassProperties exact = massProperties(ColliderShape::sphere(r), rho);
  double errMass[2], errInertia[2];
  for (int level = 0; level < 2; ++level) {
    const double h = r / (5 << level);
    const RigidMassProperties p = massProperties(ColliderShape::levelSetShape(sampledSphere(r, h, c)), rho);
    errMass[level] = std::fabs(p.mass / exact.mass - 1);
    errInertia[level] = std::fabs(p.inertia(1, 1) / exact.inertia(1, 1) - 1);
    EXPECT_LT(norm(p.centreOfMass - c), 1e-3 * h);
    EXPECT_LT(std::fabs(p.inertia(0, 1)), 1e-3 * exact.inertia(0, 0));
    std::printf("level-set sphere h = r/%d: mass error %.3g, inertia error %.3g\n", 5 << level, errMass[level],
                errInertia[level]);
  }
  EXPECT_LT(errMass[1], 0.01);
  EXPECT_LT(errInertia[1], 0.04);
  EXPECT_GT(errMass[0] / errMass[1], 2.5);
  EXPECT_GT(errInertia[0] / errInertia[1], 2.5);
}

TEST(RigidBody, ATorqueFreeBodyKeepsItsAngularMomentumAndEnergy) {
  // An asymmetric box spinning about a tilted axis (the intermediate axis is
  // unstable: the spin tumbles), no gravity, far from the walls: its angular
  // momentum stays to round-off, its kinetic energy to a small drift.
  MpmSolver solver(emptyBox(16, 0.05, {0, 0, 0}));
  MpmCollider box(ColliderShape::box({0.1, 0.05, 0.025}),
                  ColliderMotion::constantVelocity(Pose::at({0.4, 0.4, 0.4}), {0, 0, 0}, {0.3, 4.0, 0.2}));
  box.setDynamics(bodySettings(1000, 0, 0));
  const std::size_t c = solver.addCollider(box);
  const RigidBody& body = solver.collider(c).body();
  const auto state = [&] { return RigidBodyState::dynamic(body, solver.collider(c).stateAt(solver.time())); };
  const auto energy = [&](const RigidBodyState& s) {
    const Mat3d I = s.rotation * body.mass.inertia * s.rotation.transposed();
    return 0.5 * dot(s.w, I * s.w);
  };
  const RigidBodyState s0 = state();
  const Vec3d L0 = s0.angularMomentum();
  const double E0 = energy(s0);
  double wxMax = 0;
  for (int f = 0; f < 20; ++f) {
    solver.advanceFrame(0.1);
    wxMax = std::max(wxMax, std::fabs(state().w.x));
  }
  const RigidBodyState s1 = state();
  std::printf("torque-free box: |L - L0|/|L0| = %.3g, energy drift %.3g, max |w_x| %.3g rad/s\n",
              norm(s1.angularMomentum() - L0) / norm(L0), energy(s1) / E0 - 1, wxMax);
  EXPECT_LT(norm(s1.angularMomentum() - L0), 1e-10 * norm(L0));
  EXPECT_LT(std::fabs(energy(s1) / E0 - 1), 0.02);
  EXPECT_GT(wxMax, 1.0);  // it tumbled: the spin moved off the intermediate axis
  EXPECT_LT(norm(s1.v), 1e-12);
}

namespace {

/// Distance (m) a sphere of radius 2 cm travels down a plane inclined by
/// `angle` (rad) in `duration` (s), released at rest, with Coulomb friction mu.
double rollDistance(double angle, double mu, double duration) {
  MpmSolver solver(emptyBox(40, 0.02, {0, 0, -9.81}));
  // The incline through (0.4, 0.4, 0.4), rising along +x.
  const Pose plane = Pose::fromAxisAngle({0.4, 0.4, 0.4}, {0, 1, 0}, -angle);
  solver.addCollider(MpmCollider(ColliderShape::plane(), ColliderMotion::fixed(plane)));
  const double r = 0.02;
  const Vec3d n = plane.vectorToWorld({0, 0, 1});
  const Vec3d start = Vec3d{0.5, 0.4, 0.4 + 0.1 * std::tan(angle)} + r * n;
  MpmCollider sphere(ColliderShape::sphere(r), ColliderMotion::fixed(Pose::at(start)));
  sphere.setDynamics(bodySettings(1000, 0, mu));
  const std::size_t c = solver.addCollider(sphere);
  while (solver.time() < duration - 1e-12) solver.advanceFrame(0.05);
  return norm(solver.collider(c).stateAt(solver.time()).pose.position - start);
}

}  // namespace

TEST(RigidBody, ASphereRollsDownAnInclineAtFiveSeventhsOfGSinTheta) {
  // With mu >= 2/7 tan(theta) a solid sphere rolls without slipping,
  // a = 5/7 g sin(theta); without friction it slides, a = g sin(theta).
  const double theta = 20 * kPi / 180, t = 0.3, g = 9.81;
  const double rolled = rollDistance(theta, 0.5, t), slid = rollDistance(theta, 0.0, t);
  const double rollExact = 0.5 * 5.0 / 7.0 * g * std::sin(theta) * t * t;
  const double slideExact = 0.5 * g * std::sin(theta) * t * t;
  std::printf("incline 20 deg, 0.3 s: rolled %.5f m (closed form %.5f), slid %.5f m (%.5f)\n", rolled, rollExact, slid,
              slideExact);
  EXPECT_NEAR(rolled / rollExact, 1.0, 0.01);
  EXPECT_NEAR(slid / slideExact, 1.0, 0.01);
}

TEST(RigidBody, EqualSpheresExchangeVelocitiesInAnElasticHeadOnCollision) {
  for (const double e : {1.0, 0.0}) {
    MpmSolver solver(emptyBox(40, 0.02, {0, 0, 0}));
    MpmCollider a(ColliderShape::sphere(0.03), ColliderMotion::constantVelocity(Pose::at({0.3, 0.4, 0.4}), {1, 0, 0}, {}));
    MpmCollider b(ColliderShape::sphere(0.03), ColliderMotion::fixed(Pose::at({0.45, 0.4, 0.4})));
    a.setDynamics(bodySettings(1000, e, 0));
    b.setDynamics(bodySettings(1000, e, 0));
    const std::size_t ia = solver.addCollider(a), ib = solver.addCollider(b);
    solver.advanceFrame(0.2);
    const std::vector<RigidBodyReport> r = solver.rigidBodies();
    ASSERT_EQ(r.size(), 2u);
    EXPECT_EQ(r[0].collider, ia);
    EXPECT_EQ(r[1].collider, ib);
    std::printf("restitution %.0f: velocities after %.4f and %.4f m/s\n", e, r[0].velocity.x, r[1].velocity.x);
    // Momentum is kept whatever e is.
    EXPECT_NEAR(r[0].velocity.x + r[1].velocity.x, 1.0, 1e-9);
    if (e == 1.0) {
      EXPECT_NEAR(r[0].velocity.x, 0.0, 0.02);
      EXPECT_NEAR(r[1].velocity.x, 1.0, 0.02);
    } else {
      EXPECT_NEAR(r[0].velocity.x, 0.5, 0.02);
      EXPECT_NEAR(r[1].velocity.x, 0.5, 0.02);
    }
  }
}

TEST(RigidBody, ABoxDroppedOnTheFloorComesToRestFlatOnIt) {
  // A tilted box dropped onto the domain floor settles flat: its bottom at
  // the floor (within 2% of a cell) and at rest, with no drift along it.
  MpmSolver solver(emptyBox(20, 0.02, {0, 0, -9.81}));
  MpmCollider box(ColliderShape::box({0.05, 0.04, 0.02}),
                  ColliderMotion::fixed(Pose::fromAxisAngle({0.2, 0.2, 0.2}, {1, 1, 0}, 0.3)));
  box.setDynamics(bodySettings(500, 0.2, 0.5));
  const std::size_t c = solver.addCollider(box);
  for (int f = 0; f < 40; ++f) solver.advanceFrame(0.05);
  const ColliderState s = solver.collider(c).stateAt(solver.time());
  const Vec3d up = s.pose.vectorToWorld({0, 0, 1});
  const double floor = solver.domainLower().z;
  std::printf("box on floor: centre z %.5f m (rest %.5f), |up x z| %.3g, speed %.3g m/s\n", s.pose.position.z,
              floor + 0.02, norm(cross(up, Vec3d{0, 0, 1})), norm(s.velocity));
  EXPECT_NEAR(s.pose.position.z, floor + 0.02, 0.02 * 0.02);
  EXPECT_LT(norm(cross(up, Vec3d{0, 0, 1})), 1e-3);
  EXPECT_LT(norm(s.velocity), 1e-3);
  EXPECT_LT(norm(s.angularVelocity), 1e-2);
}

TEST(RigidBody, ABodyPlacedDeepInTheFloorRisesOutOfItWithoutBeingThrown) {
  // A sphere of radius 3 cm placed with its centre on the floor (3 cm deep,
  // 1.5 cells): the overlap push moves it out without giving it momentum,
  // and it rests on the floor, not thrown across the box (a push on the
  // velocity, 0.2 of the overlap per substep of 1 ms, gave it 6 m/s).
  MpmSolver solver(emptyBox(20, 0.02, {0, 0, -9.81}));
  const double floor = solver.domainLower().z;
  MpmCollider ball(ColliderShape::sphere(0.03), ColliderMotion::fixed(Pose::at({0.2, 0.2, floor})));
  ball.setDynamics(bodySettings(1000, 0.5, 0.4));
  const std::size_t c = solver.addCollider(ball);
  double fastest = 0;
  for (int f = 0; f < 10; ++f) {
    solver.advanceFrame(0.05);
    fastest = std::max(fastest, norm(solver.collider(c).stateAt(solver.time()).velocity));
  }
  const double z = solver.collider(c).stateAt(solver.time()).pose.position.z;
  std::printf("deep start: fastest %.4f m/s, centre z %.5f m (resting %.5f)\n", fastest, z, floor + 0.03);
  EXPECT_LT(fastest, 0.05);  // what gravity gives it before the floor stops it
  EXPECT_NEAR(z, floor + 0.03, 0.02 * 0.02);
}

TEST(RigidBody, TheMomentumExchangeIsImplicitForALightBody) {
  // A 1 g ball among four 1 kg material points moving at 1 m/s: sticky, it
  // takes their velocity (not a thousandfold kick); slip with friction 10,
  // the friction brings it at most to sticking. Momentum is kept in both.
  for (const BoundaryCondition bc : {BoundaryCondition{BoundaryMode::Sticky, 0.0},
                                     BoundaryCondition{BoundaryMode::Slip, 10.0}}) {
    RigidBody body = RigidBody::of(ColliderShape::sphere(0.01), bodySettings(1000, 0, 0));
    body.mass.mass = 1e-3;  // the state below takes its inverse
    ColliderState at;
    at.pose = Pose::at({0, 0, 0});
    RigidBodyState s = RigidBodyState::dynamic(body, at);
    std::vector<RigidCouplingPoint> points;
    for (const Vec3d n : {Vec3d{1, 0, 0}, Vec3d{-1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, -1, 0}})
      points.push_back({1.0, 0.009 * n, n, Vec3d{0.3, 0.4, 1.0} - 0.2 * n});
    Vec3d before = s.momentum();
    for (const RigidCouplingPoint& q : points) before += q.m * q.v;
    exchangeMomentum(s, bc, points);
    Vec3d after = s.momentum();
    for (const RigidCouplingPoint& q : points) after += q.m * q.v;
    std::printf("%s: light body velocity (%.4f %.4f %.4f) m/s\n", toString(bc.mode), s.v.x, s.v.y, s.v.z);
    EXPECT_LT(norm(after - before), 1e-12);
    EXPECT_LT(norm(s.v), 2.0);  // of the order of the points' speed
    if (bc.mode == BoundaryMode::Sticky) {
      EXPECT_LT(norm(s.v - Vec3d{0.3, 0.4, 1.0}), 1e-3);
    }
  }
}
