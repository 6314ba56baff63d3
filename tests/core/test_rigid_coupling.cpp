// Two-way coupling of dynamic rigid bodies with the MPM material ("Rigid
// bodies" in mpm/solver.h): momentum and angular momentum of material +
// body, and Archimedes' buoyancy.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/mpm/collider.h"
#include "lodestone/core/mpm/solver.h"

using namespace lodestone;

namespace {

MpmSettings box(int n, double dx, const Vec3d& gravity) {
  MpmSettings s;
  s.grid.dx = dx;
  s.grid.dims = {n, n, n};
  s.gravity = gravity;
  return s;
}

RigidBodySettings density(double rho) {
  RigidBodySettings b;
  b.density = rho;
  return b;
}

struct Momenta {
  Vec3d P, L;  // kg m/s, kg m^2/s about the origin
};

/// Material (APIC: x x m v plus the affine part (dx^2/4) m axial(C)) plus the dynamic bodies.
Momenta totalMomenta(const MpmSolver& solver) {
  Momenta m;
  const MpmParticles& p = solver.particles();
  const double D = 0.25 * solver.settings().grid.dx * solver.settings().grid.dx;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec3d mv = p.mass[i] * p.v[i];
    m.P += mv;
    const Mat3d& C = p.C[i];
    m.L += cross(p.x[i], mv) + (D * p.mass[i]) * Vec3d{C(2, 1) - C(1, 2), C(0, 2) - C(2, 0), C(1, 0) - C(0, 1)};
  }
  for (std::size_t c = 0; c < solver.colliderCount(); ++c) {
    const MpmCollider& col = solver.collider(c);
    if (!col.isDynamic()) continue;
    const RigidBodyState s = RigidBodyState::dynamic(col.body(), col.stateAt(solver.time()));
    m.P += s.momentum();
    m.L += s.angularMomentum();
  }
  return m;
}

}  // namespace

TEST(RigidCoupling, MaterialAndBodyKeepTheirTotalMomentum) {
  // No gravity, a ball of viscous fluid at rest in the middle of the domain
  // and a sphere shot into it at 0.5 m/s, for each boundary condition: the
  // body slows, the fluid takes up what it loses, and the sum stays.
  for (const BoundaryMode mode : {BoundaryMode::Sticky, BoundaryMode::Slip, BoundaryMode::Separate}) {
    MpmSolver solver(box(32, 0.01, {0, 0, 0}));
    const std::uint32_t fluid = solver.addMaterial(viscousFluid(0.1, 2e4, 1000));
    solver.emit(EmitterShape::sphere(Pose::at({0.17, 0.16, 0.16}), 0.06), fluid, {});
    MpmCollider ball(ColliderShape::sphere(0.025),
                     ColliderMotion::constantVelocity(Pose::at({0.06, 0.16, 0.16}), {0.5, 0, 0}, {}),
                     BoundaryCondition{mode, 0.3});
    ball.setDynamics(density(800));
    const std::size_t c = solver.addCollider(ball);
    const Momenta m0 = totalMomenta(solver);
    for (int f = 0; f < 10; ++f) solver.advanceFrame(0.02);
    const Momenta m1 = totalMomenta(solver);
    const RigidBodyReport r = solver.rigidBodies().at(0);
    EXPECT_EQ(r.collider, c);
    std::printf("%s: body speed 0.5 -> %.4f m/s; material impulse %.3g N s; |dP|/|P0| = %.3g\n", toString(mode),
                r.velocity.x, norm(r.materialImpulse), norm(m1.P - m0.P) / norm(m0.P));
    EXPECT_LT(r.velocity.x, 0.45);                     // the fluid slowed it
    EXPECT_LT(norm(m1.P - m0.P), 1e-9 * norm(m0.P));  // and took what it lost
  }
}

TEST(RigidCoupling, ASpinningBodyInFluidKeepsTheTotalAngularMomentum) {
  // A cylinder spinning about its axis in a ball of viscous fluid (sticky:
  // it drags the fluid round), no gravity: it slows, the fluid spins up,
  // and the total angular momentum stays.
  MpmSolver solver(box(32, 0.01, {0, 0, 0}));
  const std::uint32_t fluid = solver.addMaterial(viscousFluid(0.5, 2e4, 1000));
  solver.emit(EmitterShape::sphere(Pose::at({0.16, 0.16, 0.16}), 0.09), fluid, {});
  MpmCollider rotor(ColliderShape::cylinder(0.03, 0.05),
                    ColliderMotion::constantVelocity(Pose::at({0.16, 0.16, 0.16}), {}, {0, 0, 20}),
                    BoundaryCondition{BoundaryMode::Sticky, 0});
  rotor.setDynamics(density(1000));
  solver.addCollider(rotor);
  // Particles the emitter placed inside the rotor are pushed out in the
  // first substep; count from then on.
  solver.step(1e-5);
  const Momenta m0 = totalMomenta(solver);
  for (int f = 0; f < 10; ++f) solver.advanceFrame(0.02);
  const Momenta m1 = totalMomenta(solver);
  const double w = solver.rigidBodies().at(0).angularVelocity.z;
  std::printf("rotor: spin 20 -> %.3f rad/s; |dL|/|L0| = %.3g (L0 = %.4g kg m^2/s)\n", w, norm(m1.L - m0.L) / norm(m0.L),
              norm(m0.L));
  EXPECT_LT(w, 19.0);
  EXPECT_LT(norm(m1.L - m0.L), 1e-3 * norm(m0.L));
}

namespace {

/// Height (m) at which a cube of half side `half` (m) and density `rho`
/// comes to rest in a pool 10 cm deep of water-like fluid (1000 kg/m^3),
/// centre height; 1 cm cells, a 20 cm x 20 cm pool between the walls.
double restingHeight(double rho, double half, double& surface, double& floor) {
  MpmSettings s = box(24, 0.01, {0, 0, -9.81});
  MpmSolver solver(s);
  const std::uint32_t fluid = solver.addMaterial(viscousFluid(2.0, 4e4, 1000));
  floor = solver.domainLower().z;
  const double depth = 0.1;
  const Vec3d lo = solver.domainLower(), hi = solver.domainUpper();
  solver.emit(EmitterShape::box(Pose::at({0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), floor + 0.5 * depth}),
                                {0.5 * (hi.x - lo.x), 0.5 * (hi.y - lo.y), 0.5 * depth}),
              fluid, {});
  surface = floor + depth;
  MpmCollider cube(ColliderShape::box({half, half, half}),
                   ColliderMotion::fixed(Pose::at({0.115, 0.115, surface + half + 0.01})));
  cube.setDynamics(density(rho));
  const std::size_t c = solver.addCollider(cube);
  for (int f = 0; f < 30; ++f) solver.advanceFrame(0.05);
  return solver.collider(c).stateAt(solver.time()).pose.position.z;
}

}  // namespace

TEST(RigidCoupling, ALightBoxFloatsAtArchimedesDepthAndAHeavyOneSinks) {
  // An 8 cm cube (8 cells a side) of half the fluid's density floats half
  // submerged: Archimedes puts its centre at the surface the cube raised.
  // It comes to rest within a cell of it (0.24 cells low; coupling only the
  // nodes inside the body, it sat 2.1 cells low; a 4-cell cube sits 1.1
  // cells low). One twice as dense sinks to the floor.
  double surface = 0, floor = 0;
  const double half = 0.04;
  const double light = restingHeight(500, half, surface, floor);
  const double area = 0.20 * 0.20;  // the pool's cross-section between the walls, m^2
  const double archimedes = surface + 0.5 * std::pow(2 * half, 3) / area;  // half the cube below the surface
  const double heavy = restingHeight(2000, half, surface, floor);
  std::printf("buoyancy: light cube centre %.4f m (Archimedes %.4f m, %.2f cells lower), heavy cube centre %.4f m "
              "(floor + half side %.4f)\n",
              light, archimedes, (archimedes - light) / 0.01, heavy, floor + half);
  EXPECT_NEAR(light, archimedes, 0.01);
  EXPECT_NEAR(heavy, floor + half, 0.002);  // on the floor
}
