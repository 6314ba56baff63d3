// MLS-MPM kernels: the host reference against exact properties (P2G
// conserves mass, momentum and micro-particle count; an affine velocity field
// survives P2G + G2P exactly), and the device against the host reference,
// kernel by kernel and over 100 steps (skipped without a device).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "gpu_test_support.h"
#include "lodestone/core/base/error.h"
#include "lodestone/gpu/mpm.h"

using namespace lodestone;
using namespace lodestone::gpu;
using namespace lodestone::gpu::test;

namespace {

struct Particles {
  std::vector<Vec3d> x, v;
  std::vector<Mat3d> C, F;
  std::vector<double> J, mass, volume0, count;
  std::vector<std::uint32_t> material;
  std::size_t size() const { return x.size(); }
  ParticleInput input() const {
    return {x.data(),    v.data(),       C.data(),     F.data(),        J.data(),
            mass.data(), volume0.data(), count.data(), material.data(), size()};
  }
  ParticleOutput output() { return {x.data(), v.data(), C.data(), F.data(), J.data(), size()}; }
};

const GridSpec kGrid{{0.0, 0.0, 0.0}, 0.01, {24, 24, 24}};

std::vector<MpmMaterialParams> materials(double surfaceTension = 0.0) {
  MpmMaterialParams solid;  // E = 1e5 Pa, nu = 0.3
  solid.mu = 1e5 / (2 * 1.3);
  solid.lambda = 1e5 * 0.3 / (1.3 * 0.4);
  MpmMaterialParams fluid;
  fluid.fluid = true;
  fluid.viscosity = 0.1;
  fluid.bulkModulus = 1e5;
  fluid.surfaceTension = surfaceTension;  // N/m
  return {solid, fluid};
}

// Fills [lo, hi) (m) with 2 particles per cell and axis, jittered.
void fill(Particles& p, const Vec3d& lo, const Vec3d& hi, std::uint32_t material, const Vec3d& velocity, double count) {
  const double h = kGrid.dx / 2, rho = 1000.0;
  unsigned seed = 12345u + unsigned(p.size());
  for (double z = lo.z + h / 2; z < hi.z; z += h)
    for (double y = lo.y + h / 2; y < hi.y; y += h)
      for (double x = lo.x + h / 2; x < hi.x; x += h) {
        seed = seed * 1664525u + 1013904223u;
        const double j = 0.1 * h * (double(seed >> 8) / double(1u << 24) - 0.5);
        p.x.push_back({x + j, y - j, z + 0.5 * j});
        p.v.push_back(velocity);
        p.C.push_back(Mat3d{});
        p.F.push_back(Mat3d::identity());
        p.J.push_back(1.0);
        p.mass.push_back(rho * h * h * h);
        p.volume0.push_back(h * h * h);
        p.count.push_back(count);
        p.material.push_back(material);
      }
}

Particles scene() {
  Particles p;
  fill(p, {0.05, 0.05, 0.1}, {0.13, 0.13, 0.18}, 0, {0.3, -0.2, -1.0}, 0.0);  // a falling elastic block
  fill(p, {0.03, 0.03, 0.025}, {0.2, 0.2, 0.06}, 1, {0.0, 0.0, 0.0}, 2.5e3);  // a magnetic fluid layer
  return p;
}

MpmStepSettings stepSettings() {
  MpmStepSettings s;
  s.wallNodes = 2;
  s.wallMode = WallMode::Separate;
  s.wallFriction = 0.2;
  s.bounded = true;
  s.lo = Vec3d{0.015, 0.015, 0.015};
  s.hi = Vec3d{0.215, 0.215, 0.215};
  return s;
}

}  // namespace

TEST(GpuMpmHost, ParticleToGridConservesMassMomentumAndCount) {
  Particles p = scene();
  for (std::size_t i = 0; i < p.size(); ++i) p.C[i] = Mat3d::outer({1.0, -2.0, 0.5}, {0.3, 0.1, -0.4});
  std::vector<Vec3d> f(p.size(), Vec3d{0.0, 0.0, 0.0});
  for (std::size_t i = 0; i < p.size(); ++i) f[i] = Vec3d{1e-3 * double(i % 7), 0.0, -2e-3};
  MpmStepper mpm(kGrid, materials(), Backend::Cpu);
  mpm.upload(p.input());
  const double dt = 1e-3;
  mpm.particleToGrid(dt, f.data());
  std::vector<double> mass(kGrid.nodeCount()), n(kGrid.nodeCount());
  std::vector<Vec3d> mom(kGrid.nodeCount());
  mpm.downloadGrid(mass.data(), mom.data(), nullptr, n.data());
  double mp = 0, mg = 0, cp = 0, cg = 0;
  Vec3d pp{}, pg{};
  for (std::size_t i = 0; i < p.size(); ++i) {
    mp += p.mass[i];
    pp += p.mass[i] * p.v[i] + dt * f[i];
    cp += p.count[i];
  }
  for (std::size_t m = 0; m < kGrid.nodeCount(); ++m) {
    mg += mass[m];
    pg += mom[m];
    cg += n[m] * kGrid.cellVolume();
  }
  EXPECT_LT(relativeScalar(mg, mp), 1e-12);
  EXPECT_LT(norm(pg - pp) / norm(pp), 1e-12);  // stress and affine terms carry no net momentum
  EXPECT_LT(relativeScalar(cg, cp), 1e-12);
}

TEST(GpuMpmHost, AnAffineVelocityFieldSurvivesTheTransfers) {
  // v(x) = v0 + W x with W skew (a rigid motion): APIC carries it exactly.
  Particles p = scene();
  const Vec3d v0{0.1, -0.3, 0.2};
  Mat3d W;
  W(0, 1) = -0.7;
  W(1, 0) = 0.7;
  W(0, 2) = 0.4;
  W(2, 0) = -0.4;
  for (std::size_t i = 0; i < p.size(); ++i) {
    p.v[i] = v0 + W * p.x[i];
    p.C[i] = W;
  }
  const std::vector<Vec3d> x0 = p.x;
  MpmStepper mpm(kGrid, materials(), Backend::Cpu);
  mpm.upload(p.input());
  MpmStepSettings s;
  s.gravity = Vec3d{};
  s.wallNodes = 0;
  const double dt = 1e-12;  // no stress, no motion to speak of
  mpm.step(dt, s);
  mpm.download(p.output());
  double errV = 0, errC = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    errV = std::max(errV, norm(p.v[i] - (v0 + W * x0[i])));
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) errC = std::max(errC, std::fabs(p.C[i](a, b) - W(a, b)));
  }
  EXPECT_LT(errV, 1e-12);  // m/s, speeds ~0.3
  EXPECT_LT(errC, 1e-10);  // 1/s, entries ~0.7
}

TEST(GpuMpmHost, AParticleOutsideTheGridIsNamed) {
  Particles p = scene();
  p.x[17] = Vec3d{0.5, 0.1, 0.1};
  MpmStepper mpm(kGrid, materials(), Backend::Cpu);
  mpm.upload(p.input());
  try {
    mpm.particleToGrid(1e-4);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("particle 17"), std::string::npos) << e.what();
  }
}

TEST(GpuMpmHost, WithSurfaceTensionAParticleOutsideTheGridIsNamed) {
  // The colour pass meets the stray particle first.
  Particles p = scene();
  p.x[23] = Vec3d{0.1, -0.3, 0.1};
  MpmStepper mpm(kGrid, materials(0.5), Backend::Cpu);
  mpm.upload(p.input());
  try {
    mpm.particleToGrid(1e-4);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("particle 23"), std::string::npos) << e.what();
  }
}

TEST(GpuMpmHost, ABadSurfaceTensionIsRefusedNamingTheValue) {
  for (const double sigma : {-0.1, 11.0, std::nan("")}) {
    try {
      MpmStepper mpm(kGrid, materials(sigma), Backend::Cpu);
      FAIL() << "expected InvalidArgument for " << sigma;
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find("surface tension"), std::string::npos) << e.what();
    }
  }
  std::vector<MpmMaterialParams> m = materials();
  m[0].surfaceTension = 0.07;  // on the solid
  EXPECT_THROW(MpmStepper(kGrid, m, Backend::Cpu), InvalidArgument);
}

TEST(GpuMpmHost, TheHundredStepSceneFallsAndStaysFinite) {
  // The scene of the device comparison below, on the host alone: the block
  // falls under gravity (its centre moves down by at least half the
  // free-fall distance of its initial velocity and gravity over 0.02 s, less
  // what the fluid layer absorbs), nothing leaves the domain or turns
  // non-finite, and the mass is unchanged.
  Particles p = scene();
  MpmStepper mpm(kGrid, materials(), Backend::Cpu);
  mpm.upload(p.input());
  const MpmStepSettings s = stepSettings();
  auto blockZ = [&](const Particles& q) {
    double z = 0;
    int c = 0;
    for (std::size_t i = 0; i < q.size(); ++i)
      if (q.material[i] == 0) {
        z += q.x[i].z;
        ++c;
      }
    return z / c;
  };
  const double z0 = blockZ(p);
  for (int step = 0; step < 100; ++step) {
    const MpmStepReport r = mpm.step(2e-4, s);
    ASSERT_EQ(r.nonFinite, 0u) << "step " << step;
    ASSERT_LT(r.maxSpeed, 5.0) << "step " << step;
  }
  mpm.download(p.output());
  const double drop = z0 - blockZ(p);
  const double t = 0.02, freeFall = 1.0 * t + 0.5 * 9.81 * t * t;  // m
  EXPECT_GT(drop, 0.5 * freeFall);
  EXPECT_LT(drop, 1.01 * freeFall);
  for (std::size_t i = 0; i < p.size(); ++i) ASSERT_TRUE(isFinite(p.x[i]) && std::isfinite(p.J[i]));
}

// Device against host. Per-kernel bounds: relative 1e-12 (atomic summation
// order and fused multiply-adds only).
// Each kernel of the device against the host reference, without surface
// tension and with it (sigma = 0.5 N/m on the fluid: the colour field and the
// capillary stress come before the deposit).
class GpuMpmDeviceKernels : public ::testing::TestWithParam<double> {};

TEST_P(GpuMpmDeviceKernels, EachKernelMatchesTheHostReference) {
  LODESTONE_REQUIRE_DEVICE();
  Particles p = scene();
  for (std::size_t i = 0; i < p.size(); ++i) p.C[i] = Mat3d::outer({1.0, -2.0, 0.5}, {0.3, 0.1, -0.4});
  const double sigma = GetParam();
  MpmStepper host(kGrid, materials(sigma), Backend::Cpu), dev(kGrid, materials(sigma), Backend::Cuda);
  const MpmStepSettings s = stepSettings();
  const double dt = 2e-4;
  std::vector<Vec3d> nodalForce(kGrid.nodeCount(), Vec3d{0.0, 0.0, 0.0});
  for (std::size_t m = 0; m < nodalForce.size(); ++m) nodalForce[m] = Vec3d{1e-4, 0.0, 2e-4 * double(m % 5)};
  MpmStepper* both[2] = {&host, &dev};
  std::vector<double> mass[2], n[2];
  std::vector<Vec3d> mom[2], vel[2];
  Particles out[2] = {p, p};
  MpmStepReport rep[2];
  for (int b = 0; b < 2; ++b) {
    both[b]->upload(p.input());
    both[b]->particleToGrid(dt);
    both[b]->gridUpdate(dt, s, nodalForce.data());
    mass[b].resize(kGrid.nodeCount());
    n[b].resize(kGrid.nodeCount());
    mom[b].resize(kGrid.nodeCount());
    vel[b].resize(kGrid.nodeCount());
    both[b]->downloadGrid(mass[b].data(), mom[b].data(), vel[b].data(), n[b].data());
    rep[b] = both[b]->gridToParticle(dt, s);
    both[b]->download(out[b].output());
  }
  EXPECT_LT(relativeDifference(mass[1], mass[0]), 1e-12) << "P2G mass";
  EXPECT_LT(relativeDifference(mom[1], mom[0]), 1e-12) << "P2G momentum";
  EXPECT_LT(relativeDifference(n[1], n[0]), 1e-12) << "P2G density";
  EXPECT_LT(relativeDifference(vel[1], vel[0]), 1e-12) << "grid velocity";
  EXPECT_LT(relativeDifference(out[1].x, out[0].x), 1e-12) << "G2P x";
  EXPECT_LT(relativeDifference(out[1].v, out[0].v), 1e-12) << "G2P v";
  EXPECT_LT(relativeDifference(&out[1].C[0](0, 0), &out[0].C[0](0, 0), 9 * p.size()), 1e-12) << "G2P C";
  EXPECT_LT(relativeDifference(&out[1].F[0](0, 0), &out[0].F[0](0, 0), 9 * p.size()), 1e-12) << "G2P F";
  EXPECT_LT(relativeDifference(out[1].J, out[0].J), 1e-12) << "G2P J";
  EXPECT_LT(relativeScalar(rep[1].maxSpeed, rep[0].maxSpeed), 1e-12);
  EXPECT_EQ(rep[1].clamped, rep[0].clamped);
  EXPECT_EQ(rep[1].nonFinite, rep[0].nonFinite);
}

INSTANTIATE_TEST_SUITE_P(SurfaceTension, GpuMpmDeviceKernels, ::testing::Values(0.0, 0.5));

// A falling elastic block above a fluid layer, walls with friction, the fluid
// without and with surface tension (0.5 N/m): after 100 steps of 2e-4 s the
// device state agrees with the host within 1e-7 dx in position, 1e-7 of the
// top speed in velocity and 1e-9 in F, J.
class GpuMpmDeviceSteps : public ::testing::TestWithParam<double> {};

TEST_P(GpuMpmDeviceSteps, HundredStepsMatchTheHostReference) {
  LODESTONE_REQUIRE_DEVICE();
  Particles p = scene();
  const double sigma = GetParam();
  MpmStepper host(kGrid, materials(sigma), Backend::Cpu), dev(kGrid, materials(sigma), Backend::Cuda);
  host.upload(p.input());
  dev.upload(p.input());
  const MpmStepSettings s = stepSettings();
  double top = 0;
  for (int step = 0; step < 100; ++step) {
    const MpmStepReport h = host.step(2e-4, s);
    const MpmStepReport d = dev.step(2e-4, s);
    ASSERT_EQ(d.nonFinite, 0u);
    ASSERT_EQ(h.nonFinite, 0u);
    top = std::max(top, h.maxSpeed);
  }
  Particles a = p, b = p;
  host.download(a.output());
  dev.download(b.output());
  double dx = 0, dv = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    dx = std::max(dx, norm(a.x[i] - b.x[i]));
    dv = std::max(dv, norm(a.v[i] - b.v[i]));
  }
  std::printf("100 steps: max |dx| = %.3e m, max |dv| = %.3e m/s (top speed %.3f m/s)\n", dx, dv, top);
  EXPECT_LT(dx, 1e-7 * kGrid.dx);
  EXPECT_LT(dv, 1e-7 * top);
  EXPECT_LT(relativeDifference(b.J, a.J), 1e-9);
  EXPECT_LT(relativeDifference(&b.F[0](0, 0), &a.F[0](0, 0), 9 * p.size()), 1e-9);
}

INSTANTIATE_TEST_SUITE_P(SurfaceTension, GpuMpmDeviceSteps, ::testing::Values(0.0, 0.5));
