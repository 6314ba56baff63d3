// Magnets as free rigid bodies ("Rigid bodies" in mpm/solver.h): two free
// spherical magnets against the closed form of two dipoles, and a free
// magnet and a magnetizable body pulling each other equally and oppositely.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/core/mpm/checkpoint.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/sources/magnet_interaction.h"
#include "lodestone/core/sources/sphere_magnet.h"

using namespace lodestone;

namespace {

MpmSettings emptyBox(int n, double dx) {
  MpmSettings s;
  s.grid.dx = dx;
  s.grid.dims = {n, n, n};
  s.gravity = {0, 0, 0};
  return s;
}

RigidBodySettings steel() {
  RigidBodySettings b;
  b.density = 7500;
  b.restitution = 0;
  b.friction = 0;
  return b;
}

}  // namespace

TEST(FreeMagnets, TwoSphericalMagnetsCloseInAsTheDipoleForceSaysUntilTheyTouch) {
  // Two 1 cm spheres magnetized along z (1 T remanence), coaxial 5 cm apart,
  // free, no gravity: the gap closes as the ODE of the dipole force
  // 3 mu0 m^2 / (2 pi d^4) gives (integrated here by RK4 at a fine step);
  // after contact they rest touching.
  const double r = 0.01, M = magnetizationFromRemanence(1.0);
  MpmSettings s = emptyBox(40, 0.005);
  s.fixedDt = 1e-4;
  MpmSolver solver(s);
  const Vec3d c{0.1, 0.1, 0.1};
  const std::size_t ca = solver.addMagnet(SphereMagnet(Pose::at(c - Vec3d{0, 0, 0.025}), r, {0, 0, M}));
  const std::size_t cb = solver.addMagnet(SphereMagnet(Pose::at(c + Vec3d{0, 0, 0.025}), r, {0, 0, M}));
  solver.collider(ca).setDynamics(steel());
  solver.collider(cb).setDynamics(steel());
  const double mass = solver.collider(ca).body().mass.mass;
  const double m = M * 4.0 / 3.0 * kPi * r * r * r;
  // The reduced problem: d'' = -2 F(d) / mass (each body takes F).
  const auto accel = [&](double d) { return -2 * 3 * kMu0 * m * m / (2 * kPi * d * d * d * d) / mass; };
  double d = 0.05, v = 0, t = 0;
  const double h = 1e-6;
  double worst = 0;
  bool checked = false, touched = false;
  for (int frame = 1; frame <= 40; ++frame) {
    solver.advanceFrame(0.005);
    while (t < solver.time() - 1e-12 && d > 2 * r) {
      const double k1v = accel(d), k1x = v;
      const double k2v = accel(d + 0.5 * h * k1x), k2x = v + 0.5 * h * k1v;
      const double k3v = accel(d + 0.5 * h * k2x), k3x = v + 0.5 * h * k2v;
      const double k4v = accel(d + h * k3x), k4x = v + h * k3v;
      d += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
      v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
      t += h;
    }
    const double gap = norm(solver.collider(cb).stateAt(t).pose.position - solver.collider(ca).stateAt(t).pose.position);
    if (d > 2.5 * r) {  // closing, before the last, steepest millimetres
      worst = std::max(worst, std::fabs(gap - d) / (0.05 - d + 1e-3));
      checked = true;
    }
    if (d <= 2 * r && !touched) {
      touched = true;
      std::printf("two magnets: touching at t = %.4f s (closed form), centres %.5f m apart\n", t, gap);
      EXPECT_NEAR(gap, 2 * r, 0.02 * r);
    }
  }
  ASSERT_TRUE(checked);
  std::printf("two magnets: worst error of the closing distance %.3g of the distance closed\n", worst);
  EXPECT_TRUE(touched);
  EXPECT_LT(worst, 0.015);
  const MagnetWrench wb = solver.magnetWrench(1);
  EXPECT_LT(norm(wb.torque), 1e-12);  // coaxial moments: no couple
}

TEST(FreeMagnets, ATiltedMagnetFeelsTheDipoleTorque) {
  // Side by side, B tilted by 30 degrees: the solver's torque on B is
  // mu0 mB x H_A (exact for spheres), and B starts to turn at torque / I.
  const double r = 0.01, M = magnetizationFromRemanence(1.0);
  MpmSolver solver(emptyBox(40, 0.005));
  const SphereMagnet a(Pose::at({0.07, 0.1, 0.1}), r, {0, 0, M});
  const SphereMagnet b(Pose::fromAxisAngle({0.13, 0.1, 0.1}, {0, 1, 0}, kPi / 6), r, {0, 0, M});
  solver.addMagnet(a);
  const std::size_t cb = solver.addMagnet(b);
  solver.collider(cb).setDynamics(steel());
  solver.step(1e-5);
  const MagnetWrench w = solver.magnetWrench(1);
  const Vec3d r_ab = b.pose().position - a.pose().position;
  const Vec3d exactT = dipoleDipoleTorque(a.moment(0), b.moment(0), r_ab);
  const Vec3d exactF = dipoleDipoleForce(a.moment(0), b.moment(0), r_ab);
  std::printf("tilted magnet: torque (%.4g %.4g %.4g) N m, closed form (%.4g %.4g %.4g)\n", w.torque.x, w.torque.y,
              w.torque.z, exactT.x, exactT.y, exactT.z);
  EXPECT_LT(norm(w.torque - exactT), 1e-9 * norm(exactT));
  EXPECT_LT(norm(w.force - exactF), 1e-9 * norm(exactF));
  const double I = solver.collider(cb).body().mass.inertia(0, 0);
  const Vec3d spin = solver.rigidBodies().at(0).angularVelocity;
  EXPECT_LT(norm(spin - (1e-5 / I) * exactT), 1e-6 * norm((1e-5 / I) * exactT));
}

TEST(FreeMagnets, AFreeMagnetAndAMagnetizableBodyPullEachOtherEquallyAndOppositely) {
  // A free 2 cm sphere magnet below a cube of magnetizable solid, no
  // gravity: the force on the magnet (the material's reaction) against the
  // stage's total force on the material, at two grid spacings. The applied-
  // field part is equal and opposite by construction; the rest is the
  // discrete self-force of the material (zero in the continuum).
  for (const double dx : {7.8e-3, 5.2e-3}) {
    const int n = int(std::lround(0.25 / dx));
    MpmSettings s = emptyBox(n, dx);
    s.magneticSolveDistance = 0;
    MpmSolver solver(s);
    const double c = 0.5 * (n - 1) * dx;
    const std::uint32_t mat = solver.addMaterial(neoHookeanSolid(1e5, 0.3, 2500, paperMaterial()));
    const std::size_t cm =
        solver.addMagnet(SphereMagnet(Pose::at({c, c, c - 0.03}), 0.02, {0, 0, magnetizationFromRemanence(1.2)}));
    solver.collider(cm).setDynamics(steel());
    solver.emit(EmitterShape::box(Pose::at({c, c, c + 0.02}), {0.0156, 0.0156, 0.0156}), mat, {});
    const MpmFrameReport r = solver.advanceFrame(1e-4);
    ASSERT_FALSE(r.magneticReports.empty());
    const Vec3d onMaterial = r.magneticReports.front().totalForce;
    const Vec3d onMagnet = solver.magnetWrench(0).force;
    const double mismatch = norm(onMagnet + onMaterial) / norm(onMaterial);
    std::printf("dx %.2f mm: force on the material (%.4g %.4g %.4g) N, on the magnet (%.4g %.4g %.4g) N, mismatch %.3g\n",
                dx * 1e3, onMaterial.x, onMaterial.y, onMaterial.z, onMagnet.x, onMagnet.y, onMagnet.z, mismatch);
    EXPECT_LT(onMaterial.z, 0);  // the cube is pulled down, toward the magnet
    EXPECT_GT(onMagnet.z, 0);    // the magnet up, toward the cube
    EXPECT_LT(mismatch, 1e-3);
    EXPECT_LT(norm(solver.magnetWrench(0).torque), 1e-3 * norm(onMagnet) * 0.02);  // on the axis: no couple
  }
}

TEST(FreeMagnets, ACheckpointKeepsTheBodiesAndTheMagnetsPull) {
  // A free magnet under a magnetizable cube and a falling dynamic box: a run
  // resumed from a checkpoint repeats the uninterrupted one bit for bit
  // (bodies' poses and velocities, particles), the field solved at every
  // frame's start and held in between.
  const auto build = [] {
    MpmSettings s = emptyBox(24, 0.01);
    s.gravity = {0, 0, -9.81};
    s.magneticSolveDistance = 0;
    auto solver = std::make_unique<MpmSolver>(s);
    const std::uint32_t mat = solver->addMaterial(neoHookeanSolid(1e5, 0.3, 2500, paperMaterial()));
    const std::size_t cm =
        solver->addMagnet(SphereMagnet(Pose::at({0.12, 0.12, 0.05}), 0.02, {0, 0, magnetizationFromRemanence(1.2)}));
    solver->collider(cm).setDynamics(steel());
    solver->emit(EmitterShape::box(Pose::at({0.12, 0.12, 0.11}), {0.02, 0.02, 0.02}), mat, {});
    MpmCollider box(ColliderShape::box({0.02, 0.015, 0.01}), ColliderMotion::fixed(Pose::at({0.06, 0.12, 0.15})));
    box.setDynamics(steel());
    solver->addCollider(box);
    return solver;
  };
  const double frame = 1.0 / 100;
  auto whole = build();
  for (int f = 0; f < 4; ++f) {
    whole->advanceFrame(frame);
    if (f == 1) whole->resetMagneticWarmStart();  // as a saving run does
  }
  auto first = build();
  for (int f = 0; f < 2; ++f) first->advanceFrame(frame);
  const std::vector<std::uint8_t> bytes = saveMpmCheckpoint(*first, 2, "bodies");
  auto resumed = build();
  restoreMpmCheckpoint(*resumed, bytes.data(), bytes.size(), "bodies");
  for (int f = 2; f < 4; ++f) resumed->advanceFrame(frame);
  const std::vector<RigidBodyReport> a = whole->rigidBodies(), b = resumed->rigidBodies();
  ASSERT_EQ(a.size(), 2u);
  ASSERT_EQ(b.size(), 2u);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].pose.position, b[i].pose.position) << i;
    EXPECT_EQ(a[i].velocity, b[i].velocity) << i;
    EXPECT_EQ(a[i].angularVelocity, b[i].angularVelocity) << i;
  }
  EXPECT_GT(norm(a[0].magneticForce), 0.1);  // the cube pulls the magnet
  const MpmParticles &pa = whole->particles(), &pb = resumed->particles();
  ASSERT_EQ(pa.size(), pb.size());
  for (std::size_t q = 0; q < pa.size(); ++q) ASSERT_EQ(pa.x[q], pb.x[q]) << q;
  // A solver whose collider is not dynamic refuses the checkpoint.
  MpmSettings s = emptyBox(24, 0.01);
  MpmSolver other(s);
  other.addMaterial(neoHookeanSolid(1e5, 0.3, 2500, paperMaterial()));
  other.addMagnet(SphereMagnet(Pose::at({0.12, 0.12, 0.05}), 0.02, {0, 0, magnetizationFromRemanence(1.2)}));
  other.addCollider(MpmCollider(ColliderShape::box({0.02, 0.015, 0.01}), ColliderMotion::fixed(Pose::at({0.06, 0.12, 0.15}))));
  EXPECT_THROW(restoreMpmCheckpoint(other, bytes.data(), bytes.size(), "bodies"), InvalidArgument);
}
