// The reference MLS-MPM against closed forms and physical bounds: free fall
// (the symplectic-Euler closed form), a block resting on the floor, and the
// energy of an undamped elastic block; plus settings validation and the
// domain policy.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/solver.h"

using namespace lodestone;

namespace {

GridSpec boxGrid(int n, double dx) {
  GridSpec g;
  g.dx = dx;
  g.origin = {0, 0, 0};
  g.dims = {n, n, n};
  return g;
}

double maxSpeed(const MpmParticles& p) {
  double m = 0;
  for (const Vec3d& v : p.v) m = std::max(m, norm(v));
  return m;
}

}  // namespace

TEST(MpmSolver, FreeFallMatchesTheSymplecticEulerClosedForm) {
  // Uniform motion: APIC keeps C = 0, F = I, so the stress is zero and every
  // particle follows v_n = v_0 + n g dt, x_n = x_0 + dt sum_{k=1..n} v_k:
  //   x_n - x_0 = g (t^2/2 + t dt/2),  t = n dt,
  // i.e. the exact g t^2/2 plus a first-order error g t dt/2.
  MpmSettings s;
  s.grid = boxGrid(24, 0.02);
  const double dt = 1e-3;
  s.fixedDt = dt;
  MpmSolver solver(s);
  const std::uint32_t m = solver.addMaterial(neoHookeanSolid(1e5, 0.3, 1000));
  solver.emit(EmitterShape::box(Pose::at({0.23, 0.23, 0.36}), {0.04, 0.04, 0.04}), m, {});
  const Vec3d c0 = solver.particles().centreOfMass();
  const int steps = 200;
  for (int n = 0; n < steps; ++n) solver.step(dt);
  const double t = steps * dt;
  const double g = 9.81;
  const Vec3d c = solver.particles().centreOfMass();
  const double drop = c0.z - c.z;
  const double discrete = g * (0.5 * t * t + 0.5 * t * dt);
  std::printf("free fall: drop %.15g m, discrete closed form %.15g m, g t^2/2 = %.15g m\n", drop, discrete,
              0.5 * g * t * t);
  EXPECT_NEAR(drop, discrete, 1e-10);
  EXPECT_LE(std::fabs(drop - 0.5 * g * t * t), 0.5 * g * t * dt * (1 + 1e-9));
  EXPECT_NEAR(c.x, c0.x, 1e-12);
  EXPECT_NEAR(c.y, c0.y, 1e-12);
  double worstF = 0;
  for (const Mat3d& F : solver.particles().F)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) worstF = std::max(worstF, std::fabs(F(a, b) - (a == b ? 1.0 : 0.0)));
  EXPECT_LT(worstF, 1e-12);
  for (const Vec3d& v : solver.particles().v) ASSERT_NEAR(v.z, -g * t, 1e-12);
}

namespace {
struct RestRun {
  double delta = 0;      // continuum sag rho g h^2 / (3E), m
  double maxDrop = 0;    // largest centre-of-mass drop, m
  double maxRise = 0;    // m
  double lateMean = 0;   // mean drop over [0.5, 1] s, m
  double lateRange = 0;  // oscillation over [0.5, 1] s, m
  double drift = 0;      // horizontal centre-of-mass drift, m
  double vmax = 0;       // max particle speed at 1 s, m/s
};

// A 6 x 6 x 4 cm block (E, nu = 0.3, rho = 1000 kg/m^3) released from zero
// stress on the floor plane domainLower(), simulated for 1 s.
RestRun restingBlock(double E, BoundaryMode mode) {
  MpmSettings s;
  s.grid = boxGrid(20, 0.01);
  s.walls.mode = mode;
  MpmSolver solver(s);
  const double rho = 1000, h = 0.04;
  const std::uint32_t m = solver.addMaterial(neoHookeanSolid(E, 0.3, rho));
  const double floor = solver.domainLower().z;
  EXPECT_NEAR(floor, (s.wallNodes - 0.5) * s.grid.dx, 1e-15);
  solver.emit(EmitterShape::box(Pose::at({0.095, 0.095, floor + h / 2}), {0.03, 0.03, h / 2}), m, {});
  const Vec3d c0 = solver.particles().centreOfMass();
  RestRun r;
  r.delta = rho * 9.81 * h * h / (3 * E);
  double lateMin = 1e9, lateMax = -1e9, lateSum = 0;
  int lateCount = 0;
  while (solver.time() < 1.0 - 1e-12) {
    solver.advanceFrame(1.0 / 100);
    const Vec3d c = solver.particles().centreOfMass();
    r.maxDrop = std::max(r.maxDrop, c0.z - c.z);
    r.maxRise = std::max(r.maxRise, c.z - c0.z);
    if (solver.time() > 0.5) {
      lateMin = std::min(lateMin, c.z);
      lateMax = std::max(lateMax, c.z);
      lateSum += c0.z - c.z;
      ++lateCount;
    }
    r.drift = std::max(r.drift, norm(Vec3d{c.x - c0.x, c.y - c0.y, 0}));
  }
  r.lateMean = lateSum / lateCount;
  r.lateRange = lateMax - lateMin;
  r.vmax = maxSpeed(solver.particles());
  std::printf(
      "resting block (E = %.0e Pa, %s floor): delta %.3g m, settled drop %.3g m (%.2f delta), max drop "
      "%.2f delta, late range %.2f delta, max rise %.3g m, drift %.3g m, max speed at 1 s %.3g m/s\n",
      E, toString(mode), r.delta, r.lateMean, r.lateMean / r.delta, r.maxDrop / r.delta, r.lateRange / r.delta,
      r.maxRise, r.drift, r.vmax);
  return r;
}
}  // namespace

TEST(MpmSolver, BlockRestingOnTheFloorStaysAtRest) {
  // A block of height h resting on the floor sags elastically under its own
  // weight: the uniaxial strain rho g (h - z)/E lowers the centre of mass of
  // a continuum block by delta = rho g h^2 / (3E). The 4-cell-tall discrete
  // block is softer (its faces are smeared over the B-spline support): it
  // settles by about 2.1 delta for every E tried from 3e4 to 1e7 Pa, i.e.
  // elastically, not by sinking. Bounds:
  //   settled drop in [delta, 3 delta], and it scales as 1/E (the drop at
  //   E/3.33 is 3.33 times larger, within 15%), so nothing sinks;
  //   largest drop <= 5 delta (release from zero stress overshoots up to
  //   twice the settled value);
  //   late oscillation <= 2 delta, no rise, horizontal drift at round-off,
  //   speeds at 1 s below 1 mm/s (free fall would reach 9.8 m/s).
  const RestRun stiff = restingBlock(1e5, BoundaryMode::Separate);
  const RestRun soft = restingBlock(3e4, BoundaryMode::Separate);
  const RestRun sticky = restingBlock(1e5, BoundaryMode::Sticky);
  for (const RestRun* r : {&stiff, &soft, &sticky}) {
    EXPECT_GT(r->lateMean, r->delta);
    EXPECT_LT(r->lateMean, 3 * r->delta);
    EXPECT_LT(r->maxDrop, 5 * r->delta);
    EXPECT_LT(r->lateRange, 2 * r->delta);
    EXPECT_LT(r->maxRise, 1e-3 * r->delta);
    EXPECT_LT(r->drift, 1e-12);
    EXPECT_LT(r->vmax, 1e-3);
  }
  EXPECT_NEAR(soft.lateMean / stiff.lateMean, 1e5 / 3e4, 0.15 * 1e5 / 3e4);
}

namespace {
struct EnergyRun {
  double E0 = 0, maxFirst = 0, maxSecond = 0, maxElastic = 0, end = 0;
  int substeps = 0;
};

// A free elastic block (no gravity, no contact) set breathing by the
// velocity field v = (2 (x - cx), (y - cy), 0) 1/s (with the matching C).
EnergyRun breathingBlock(double cfl) {
  MpmSettings s;
  s.grid = boxGrid(16, 0.01);
  s.gravity = {0, 0, 0};
  s.cfl = cfl;
  s.dtMax = 1e-2;
  MpmSolver solver(s);
  const std::uint32_t m = solver.addMaterial(neoHookeanSolid(1e3, 0.3, 1000));
  const Vec3d c = 0.5 * s.grid.maxCorner();
  solver.emit(EmitterShape::box(Pose::at(c), {0.04, 0.04, 0.04}), m, {});
  MpmParticles& p = solver.particles();
  for (std::size_t q = 0; q < p.size(); ++q) {
    p.v[q] = Vec3d{2 * (p.x[q].x - c.x), p.x[q].y - c.y, 0};
    p.C[q](0, 0) = 2;
    p.C[q](1, 1) = 1;
  }
  EnergyRun r;
  r.E0 = solver.energies().total();
  while (solver.time() < 2.0 - 1e-12) {
    solver.step(std::min(solver.suggestedDt(), 2.0 - solver.time()));
    ++r.substeps;
    const MpmEnergies e = solver.energies();
    double& mx = solver.time() <= 1.0 ? r.maxFirst : r.maxSecond;
    mx = std::max(mx, e.total());
    r.maxElastic = std::max(r.maxElastic, e.elastic);
  }
  r.end = solver.energies().total();
  return r;
}
}  // namespace

TEST(MpmSolver, UndampedElasticBlockEnergyDoesNotGrow) {
  // Without damping the energy E = kinetic + elastic of a free block can only
  // be lost (APIC transfers dissipate what the per-particle affine field
  // cannot carry), apart from the O(omega dt) oscillation of the symplectic
  // Euler step around its conserved shadow energy. Bounds, checked after
  // every substep over 2 s (about 14 periods of the breathing mode):
  //   E(t) <= (1 + cfl/4) E0, the oscillation term at the CFL number used;
  //   halving the CFL number at least nearly halves the overshoot (it is the
  //   O(dt) integrator term, not growth);
  //   the second second stays below the first (no late growth);
  //   the elastic energy reaches a good part of E0 (the stress is active).
  const EnergyRun a = breathingBlock(0.4);
  const EnergyRun b = breathingBlock(0.2);
  for (const EnergyRun* r : {&a, &b})
    std::printf(
        "breathing block: E0 %.4g J, max E in [0,1] s %.5f E0, in [1,2] s %.5f E0, E(2 s) %.4f E0, "
        "max elastic %.3f E0, %d substeps\n",
        r->E0, r->maxFirst / r->E0, r->maxSecond / r->E0, r->end / r->E0, r->maxElastic / r->E0, r->substeps);
  EXPECT_LE(a.maxFirst, (1 + 0.4 / 4) * a.E0);
  EXPECT_LE(b.maxFirst, (1 + 0.2 / 4) * b.E0);
  EXPECT_LT(b.maxFirst - b.E0, 0.65 * (a.maxFirst - a.E0));
  EXPECT_LE(a.maxSecond, a.maxFirst);
  EXPECT_LE(b.maxSecond, b.maxFirst);
  EXPECT_GT(a.maxElastic, 0.5 * a.E0);
}

TEST(MpmSolver, RejectsBadSettingsNamingTheValue) {
  MpmSettings s;
  s.grid = boxGrid(16, 0.01);
  {
    MpmSettings b = s;
    b.cfl = 0;
    try {
      MpmSolver bad(b);
      FAIL();
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find("cfl"), std::string::npos) << e.what();
    }
  }
  {
    MpmSettings b = s;
    b.dtMin = 1.0;
    EXPECT_THROW(MpmSolver bad(b), InvalidArgument);
  }
  {
    MpmSettings b = s;
    b.wallNodes = 8;
    EXPECT_THROW(MpmSolver bad(b), InvalidArgument);
  }
  {
    MpmSettings b = s;
    b.gravity.z = NAN;
    EXPECT_THROW(MpmSolver bad(b), InvalidArgument);
  }
  MpmSolver ok(s);
  EXPECT_THROW(ok.step(0.0), InvalidArgument);
  EXPECT_THROW(ok.step(-1e-3), InvalidArgument);
  EXPECT_THROW(ok.advanceFrame(0.0), InvalidArgument);
  EXPECT_THROW(ok.emit(EmitterShape::sphere(Pose::at({0.08, 0.08, 0.08}), 0.02), 3, {}), InvalidArgument);
  // All magnetic materials must share one law.
  ok.addMaterial(neoHookeanSolid(1e5, 0.3, 2500, paperMaterial()));
  EXPECT_THROW(ok.addMaterial(viscousFluid(1, 1e5, 2500, linearized(paperMaterial()))), InvalidArgument);
  EXPECT_NO_THROW(ok.addMaterial(viscousFluid(1, 1e5, 2500, paperMaterial())));
}

TEST(MpmSolver, ParticlesLeavingTheDomainAreClampedOrRemovedAndCounted) {
  for (OutOfDomainPolicy policy : {OutOfDomainPolicy::Clamp, OutOfDomainPolicy::Remove}) {
    MpmSettings s;
    s.grid = boxGrid(12, 0.01);
    s.wallNodes = 0;  // nothing stops them
    s.gravity = {0, 0, 0};
    s.outOfDomain = policy;
    MpmSolver solver(s);
    const std::uint32_t m = solver.addMaterial(viscousFluid(0, 1e4, 1000));
    EmitterSettings e;
    e.velocity = {3.0, 0, 0};  // m/s: leaves the 0.11 m box within 0.03 s
    solver.emit(EmitterShape::box(Pose::at({0.05, 0.055, 0.055}), {0.01, 0.01, 0.01}), m, e);
    const std::size_t n0 = solver.particles().size();
    // A particle placed outside the grid, and one with a NaN velocity.
    solver.particles().add({0.5, 0.05, 0.05}, {}, 1e-3, 1e-6, 0, m);
    solver.particles().add({0.05, 0.05, 0.05}, {}, 1e-3, 1e-6, 0, m);
    solver.particles().v.back().x = NAN;
    std::size_t clamped = 0, removed = 0, nonFinite = 0;
    for (int f = 0; f < 5; ++f) {
      const MpmFrameReport r = solver.advanceFrame(0.01);
      clamped += r.clamped;
      removed += r.removed;
      nonFinite += r.nonFinite;
    }
    EXPECT_EQ(nonFinite, 1u);
    const Vec3d hi = s.grid.nodePosition(10, 10, 10);
    for (std::size_t q = 0; q < solver.particles().size(); ++q) {
      ASSERT_TRUE(isFinite(solver.particles().x[q]) && isFinite(solver.particles().v[q]));
      ASSERT_LE(solver.particles().x[q].x, hi.x + 1e-15);
    }
    if (policy == OutOfDomainPolicy::Clamp) {
      EXPECT_EQ(solver.particles().size(), n0 + 1);
      EXPECT_EQ(removed, 1u);
      EXPECT_GE(clamped, n0 + 1);
    } else {
      EXPECT_EQ(removed, n0 + 2);
      EXPECT_EQ(solver.particles().size(), 0u);
    }
  }
}

TEST(MpmSolver, SubstepsPerFrameStayWithinTheLimits) {
  // A stiff block (c = sqrt((lambda + 2 mu)/rho) = 11.6 m/s for E = 1e5 Pa,
  // nu = 0.3, rho = 1000 kg/m^3) on a 1 cm grid: the CFL step is 0.4 cm /
  // 11.6 m/s = 0.345 ms, 121 substeps in a 1/24 s frame (no gravity: the
  // block stays at rest and the step stays the same).
  MpmSettings s;
  s.grid = boxGrid(16, 0.01);
  s.gravity = {0, 0, 0};
  const auto block = [](MpmSolver& solver) {
    const std::uint32_t m = solver.addMaterial(neoHookeanSolid(1e5, 0.3, 1000));
    solver.emit(EmitterShape::box(Pose::at({0.075, 0.075, 0.05}), {0.03, 0.03, 0.03}), m, {});
  };
  const double frame = 1.0 / 24;
  {
    MpmSolver free(s);
    block(free);
    const MpmFrameReport r = free.advanceFrame(frame);
    EXPECT_NEAR(r.substeps, std::ceil(frame / (0.4 * 0.01 / std::sqrt((1e5 * 0.3 / (1.3 * 0.4) + 1e5 / 1.3) / 1000))),
                2);
  }
  {
    // At least 500 substeps: no step longer than frame / 500, and no more
    // substeps than that needs.
    MpmSettings m = s;
    m.minSubsteps = 500;
    MpmSolver fine(m);
    block(fine);
    const MpmFrameReport r = fine.advanceFrame(frame);
    EXPECT_LE(r.maxDt, frame / 500 * (1 + 1e-12));
    EXPECT_GE(r.substeps, 500);
    EXPECT_LE(r.substeps, 501);
  }
  {
    // At most 50: the frame stops with a message naming the limit, the
    // step and the fastest particle; the solver holds a consistent state.
    MpmSettings m = s;
    m.maxSubsteps = 50;
    MpmSolver capped(m);
    block(capped);
    try {
      capped.advanceFrame(frame);
      FAIL() << "a frame of about 121 substeps ran under a limit of 50";
    } catch (const Error& e) {
      const std::string w = e.what();
      EXPECT_NE(w.find("50 substeps reached the limit of 50 per frame"), std::string::npos) << w;
      EXPECT_NE(w.find("m/s"), std::string::npos) << w;
      EXPECT_NE(w.find("time.max_substeps"), std::string::npos) << w;
    }
    EXPECT_EQ(capped.substepCount(), 50);
  }
  {
    MpmSettings b = s;
    b.minSubsteps = 0;
    EXPECT_THROW(MpmSolver bad(b), InvalidArgument);
    b.minSubsteps = 10;
    b.maxSubsteps = 5;
    EXPECT_THROW(MpmSolver bad(b), InvalidArgument);
  }
}

TEST(MpmSolver, TheStepFromTheLastG2PsSpeedIsTheStepFromEveryParticle) {
  // A stream from a nozzle (3 m/s at emission) falls at 20 g onto a pool
  // resting on a plate thinner than a cell, which a paddle sweeps:
  // projections, emissions and the pool's slow points. After each substep the CFL step comes from G2P's
  // maximum speed where that still holds; handing the particles out makes
  // the solver find it from every particle again. The two must agree bit
  // for bit.
  MpmSettings s;
  s.grid = boxGrid(21, 0.01);
  s.gravity = {0, 0, -196.2};  // m/s^2
  s.colliderProjection = true;
  MpmSolver solver(s);
  solver.addCollider(MpmCollider(ColliderShape::box({0.2, 0.2, 0.002}), ColliderMotion::fixed(Pose::at({0.1, 0.1, 0.06})),
                                 {BoundaryMode::Separate, 0}));
  // A paddle 3 mm thick sweeping the pool along +x at 4 m/s: the points it
  // pushes are the fastest, and their speed is the projection's.
  solver.addCollider(MpmCollider(ColliderShape::box({0.0015, 0.03, 0.02}),
                                 ColliderMotion::constantVelocity(Pose::at({0.03, 0.1, 0.08}), {4.0, 0, 0}, {}),
                                 {BoundaryMode::Sticky, 0}));
  const std::uint32_t m = solver.addMaterial(viscousFluid(0.5, 2e4, 1000));
  solver.emit(EmitterShape::box(Pose::at({0.1, 0.1, 0.075}), {0.05, 0.05, 0.012}), m, {});
  RateEmitterSettings nozzle;
  nozzle.lattice.cellSize = s.grid.dx;
  nozzle.lattice.velocity = {0, 0, -3.0};  // m/s
  nozzle.rate = 2e-4;                      // m^3/s
  nozzle.schedule = EmissionSchedule::intervals({{0.0, 0.05}});
  solver.addEmitter(EmitterShape::cylinder(Pose::at({0.1, 0.1, 0.16}), 0.01, 0.005), m, nozzle);
  std::size_t projected = 0, emitted = 0;
  for (int n = 0; n < 500; ++n) {
    const double fromG2P = solver.suggestedDt();
    (void)solver.particles();
    const double fromParticles = solver.suggestedDt();
    ASSERT_EQ(fromG2P, fromParticles) << "substep " << n;
    const MpmStepReport r = solver.step(fromG2P);
    projected += r.projected;
    emitted += r.emitted.particles;
  }
  std::printf("500 substeps to t = %.3f s: %zu projections, %zu points emitted\n", solver.time(), projected, emitted);
  EXPECT_GT(projected, 0u) << "no projection: the test would not reach its case";
  EXPECT_GT(emitted, 0u) << "no emission: the test would not reach its case";
}
