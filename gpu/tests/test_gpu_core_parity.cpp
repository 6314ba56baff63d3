// The host reference of lodestone::gpu against lodestone::core on the same
// inputs: the residual and Jacobian of the field problem, a full Newton solve
// (shield wall), the nodal fields and force, and the MPM transfers. This is
// what makes the device-against-host-reference tests device-against-core
// tests. Built only inside the full Lodestone tree (it links the core).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "field_backend.h"
#include "gpu_test_support.h"
#include "lodestone/core/field/field_solver.h"
#include "lodestone/core/stage/magnetic_force.h"
#include "lodestone/core/field/magnetostatic_problem.h"
#include "lodestone/core/mpm/constitutive.h"
#include "lodestone/core/mpm/grid.h"
#include "lodestone/core/mpm/material.h"
#include "lodestone/core/mpm/surface_tension.h"
#include "lodestone/core/stage/nodal_field.h"
#include "lodestone/gpu/field_solver.h"
#include "lodestone/gpu/magnetic_force.h"
#include "lodestone/gpu/mpm.h"

using namespace lodestone;
using namespace lodestone::gpu::test;
namespace g = lodestone::gpu;

namespace {

const GridSpec kGrid{{-0.06, -0.05, -0.055}, 0.01, {13, 12, 11}};

// A graded ball of the paper's material; r = 0.035 m touches the wall,
// 0.025 m leaves it 1-2 cells of clearance (the open wall is then predicted).
std::vector<double> blob(double radius = 0.035) {
  std::vector<double> n(kGrid.nodeCount(), 0.0);
  for (int k = 0; k < kGrid.dims.k; ++k)
    for (int j = 0; j < kGrid.dims.j; ++j)
      for (int i = 0; i < kGrid.dims.i; ++i) {
        const double r = norm(kGrid.nodePosition(i, j, k) - Vec3d{0.01, 0.0, -0.01});
        if (r < radius) n[kGrid.index(i, j, k)] = paperDensity() * (1.0 - 0.5 * r / radius);
      }
  return n;
}

void applied(const Vec3d* x, std::size_t count, Vec3d* H) {
  for (std::size_t m = 0; m < count; ++m) H[m] = Vec3d{2e4 + 1e5 * x[m].y, -1e4, 8e4 + 3e6 * x[m].z};
}

}  // namespace

TEST(GpuCoreParity, ResidualAndJacobianMatchTheCore) {
  const std::vector<double> n = blob();
  for (BoundaryKind b : {BoundaryKind::Shield, BoundaryKind::Open}) {
    MagnetostaticProblem core(kGrid, paperLaw(), b);
    core.setMaterial(GridView<const double>{n.data(), kGrid}, applied);
    auto host = g::detail::makeHostFieldBackend();
    host->setProblem(g::detail::prepareProblem(kGrid, paperLaw(), b == BoundaryKind::Shield, n.data(), applied));
    ASSERT_EQ(host->materialCellCount(), core.materialCellCount());
    const std::size_t N = kGrid.nodeCount();
    std::vector<double> phi(N), v(N), Fc(N), Jc(N);
    for (std::size_t m = 0; m < N; ++m) {
      phi[m] = 200.0 * std::sin(0.37 * double(m));
      v[m] = std::cos(0.11 * double(m));
    }
    const MagnetostaticProblem::Evaluation ec = core.evaluate(phi.data(), Fc.data(), true);
    core.applyJacobian(v.data(), Jc.data());
    double* hp = host->allocate(N);
    double* hv = host->allocate(N);
    double* hF = host->allocate(N);
    double* hJ = host->allocate(N);
    host->upload(phi.data(), N, hp);
    host->upload(v.data(), N, hv);
    const g::detail::Evaluation eh = host->evaluate(hp, hF, true);
    host->applyLevel(0, hv, hJ);
    EXPECT_LT(relativeDifference(hF, Fc.data(), N), 1e-13) << toString(b);
    EXPECT_LT(relativeDifference(hJ, Jc.data(), N), 1e-13) << toString(b);
    EXPECT_LT(relativeScalar(eh.energy, ec.materialEnergy), 1e-13);
    std::vector<double> F0c(N);
    core.residualAtZero(F0c.data());
    host->residualAtZero(hF);
    EXPECT_LT(relativeDifference(hF, F0c.data(), N), 1e-13);
  }
}

TEST(GpuCoreParity, ShieldSolveMatchesTheCore) {
  const std::vector<double> n = blob();
  MagnetostaticProblem core(kGrid, paperLaw(), BoundaryKind::Shield);
  core.setMaterial(GridView<const double>{n.data(), kGrid}, applied);
  FieldSolveSettings cs;
  cs.tolerance = 1e-11;
  cs.multigrid.singlePrecision = false;  // the gpu levels are double
  std::vector<double> phiCore(kGrid.nodeCount(), 0.0);
  const FieldSolveReport rc = solveField(core, phiCore, cs);
  g::FieldSolver solver(kGrid, paperLaw(), BoundaryKind::Shield, g::Backend::Cpu);
  solver.setMaterial(n.data(), applied);
  FieldSolveSettings gs;
  gs.tolerance = 1e-11;
  std::vector<double> phi(kGrid.nodeCount(), 0.0);
  const FieldSolveReport rg = solver.solve(phi.data(), gs);
  ASSERT_EQ(rc.status, SolveStatus::Converged) << rc.message;
  ASSERT_EQ(rg.status, SolveStatus::Converged) << rg.message;
  EXPECT_EQ(rg.newtonIterations, rc.newtonIterations);
  EXPECT_EQ(rg.cgIterations, rc.cgIterations);
  EXPECT_LT(relativeDifference(phi, phiCore), 1e-9);
  EXPECT_LT(relativeScalar(rg.materialEnergy, rc.materialEnergy), 1e-10);
}

// The open wall through the one Newton solver on both backends: the gpu
// solver gets core's block-multipole wall values and their linearization from
// the host, so the wall moves with each Newton step (predictWall) exactly as
// in core, and both take the same Newton steps.
FieldSolveReport solveOpenOnHostReference(const std::vector<double>& n, const FieldSolveSettings& gs,
                                          std::vector<double>& phi) {
  MagnetostaticProblem walls(kGrid, paperLaw(), BoundaryKind::Open);
  walls.setMaterial(GridView<const double>{n.data(), kGrid}, applied);
  std::vector<double> scratch(kGrid.nodeCount());
  g::FieldSolver solver(kGrid, paperLaw(), BoundaryKind::Open, g::Backend::Cpu);
  solver.setMaterial(n.data(), applied);
  solver.setWallUpdate(
      [&](const double* p, double* wall) {
        const MagnetostaticProblem::Evaluation e = walls.evaluate(p, scratch.data(), true);
        walls.applyOpenBoundary(e.multipoles, wall);
      },
      [&](const double* d, double* wall) { walls.applyOpenBoundary(walls.linearizedMultipoles(d), wall); });
  phi.assign(kGrid.nodeCount(), 0.0);
  return solver.solve(phi.data(), gs);
}

TEST(GpuCoreParity, OpenSolveWithThePredictedWallMatchesTheCore) {
  const std::vector<double> n = blob(0.025);
  for (bool predict : {true, false}) {
    MagnetostaticProblem core(kGrid, paperLaw(), BoundaryKind::Open);
    core.setMaterial(GridView<const double>{n.data(), kGrid}, applied);
    FieldSolveSettings cs;
    cs.tolerance = 1e-11;
    cs.predictWall = predict;
    cs.multigrid.singlePrecision = false;  // the gpu levels are double
    std::vector<double> phiCore(kGrid.nodeCount(), 0.0);
    const FieldSolveReport rc = solveField(core, phiCore, cs);
    std::vector<double> phi;
    const FieldSolveReport rg = solveOpenOnHostReference(n, cs, phi);
    ASSERT_EQ(rc.status, SolveStatus::Converged) << rc.message;
    ASSERT_EQ(rg.status, SolveStatus::Converged) << rg.message;
    EXPECT_EQ(rg.backend, "host");
    EXPECT_EQ(rc.backend, "cpu");
    ASSERT_EQ(rg.history.size(), rc.history.size()) << "predictWall " << predict;
    for (std::size_t i = 0; i < rc.history.size(); ++i) {
      EXPECT_EQ(rg.history[i].wallPredicted, rc.history[i].wallPredicted) << "iteration " << i;
      EXPECT_NEAR(rg.history[i].relativeResidual, rc.history[i].relativeResidual,
                  1e-6 * rc.history[i].relativeResidual + 1e-13)
          << "iteration " << i;
    }
    // The wall moved with the steps (not merely followed them).
    if (predict) {
      int predicted = 0;
      for (const NewtonIterationRecord& r : rg.history) predicted += r.wallPredicted;
      EXPECT_GT(predicted, 0);
    }
    EXPECT_LT(relativeDifference(phi, phiCore), 1e-8) << "predictWall " << predict;
  }
}

TEST(GpuCoreParity, NodalFieldsAndForceMatchTheCore) {
  const std::vector<double> n = blob();
  const std::size_t N = kGrid.nodeCount();
  std::vector<double> phi(N);
  std::vector<Vec3d> hext(N), x(N);
  for (std::size_t m = 0; m < N; ++m) phi[m] = 200.0 * std::sin(0.37 * double(m));
  for (int k = 0; k < kGrid.dims.k; ++k)
    for (int j = 0; j < kGrid.dims.j; ++j)
      for (int i = 0; i < kGrid.dims.i; ++i) x[kGrid.index(i, j, k)] = kGrid.nodePosition(i, j, k);
  applied(x.data(), N, hext.data());
  std::vector<Vec3d> Hc(N), Bc(N), tc(N), fc(N), Hg(N), Bg(N), fg(N);
  recoverNodalFields({phi.data(), kGrid}, {hext.data(), kGrid}, {n.data(), kGrid}, paperLaw(), {Hc.data(), kGrid},
                     {nullptr, kGrid}, {Bc.data(), kGrid});
  stressDivergence({Hc.data(), kGrid}, {Bc.data(), kGrid}, {hext.data(), kGrid}, {n.data(), kGrid}, ForceMask::Material,
                   {tc.data(), kGrid}, 2);
  spreadForce({tc.data(), kGrid}, {fc.data(), kGrid});
  g::MagneticForceInput in;
  in.phi = phi.data();
  in.hext = hext.data();
  in.n = n.data();
  g::magneticForce(kGrid, paperLaw(), in, {Hg.data(), Bg.data(), fg.data()}, g::Backend::Cpu);
  EXPECT_LT(relativeDifference(Hg, Hc), 1e-14);
  EXPECT_LT(relativeDifference(Bg, Bc), 1e-14);
  EXPECT_LT(relativeDifference(fg, fc), 1e-12);
}

TEST(GpuCoreParity, MpmTransfersMatchTheCore) {
  const GridSpec grid{{0.0, 0.0, 0.0}, 0.01, {16, 16, 16}};
  std::vector<MpmMaterial> mats = {neoHookeanSolid(1e5, 0.3, 1000.0), viscousFluid(0.1, 1e5, 1000.0)};
  std::vector<g::MpmMaterialParams> params(2);
  params[0].mu = mats[0].mu;
  params[0].lambda = mats[0].lambda;
  params[1].fluid = true;
  params[1].viscosity = mats[1].viscosity;
  params[1].bulkModulus = mats[1].bulkModulus;
  MpmParticles p;
  for (int c = 0; c < 12; ++c)
    for (int b = 0; b < 12; ++b)
      for (int a = 0; a < 12; ++a) {
        const Vec3d x{0.03 + 0.0051 * a, 0.03 + 0.0049 * b, 0.03 + 0.005 * c};
        p.add(x, {0.1 * std::sin(double(a)), -0.2, 0.05 * double(c % 3)}, 1e-4, 1.25e-7, 0.0,
              std::uint32_t((a + b) % 2));
      }
  for (std::size_t i = 0; i < p.size(); ++i) {
    p.C[i] = Mat3d::outer({0.3, -0.1, 0.2}, {1.0, 0.5, -0.7});
    p.F[i] = Mat3d::identity();
    p.F[i](0, 1) = 0.05;
    p.J[i] = determinant(p.F[i]);
  }
  const double dt = 1e-4;
  MpmGrid core(grid);
  core.particleToGrid(p, mats, dt);
  g::MpmStepper host(grid, params, g::Backend::Cpu);
  host.upload({p.x.data(), p.v.data(), p.C.data(), p.F.data(), p.J.data(), p.mass.data(), p.volume0.data(), nullptr,
               p.material.data(), p.size()});
  host.particleToGrid(dt);
  g::MpmStepSettings s;
  s.wallNodes = 2;
  host.gridUpdate(dt, s);
  std::vector<double> mass(grid.nodeCount());
  std::vector<Vec3d> mom(grid.nodeCount()), vel(grid.nodeCount());
  host.downloadGrid(mass.data(), mom.data(), vel.data(), nullptr);
  std::vector<double> cm(grid.nodeCount());
  std::vector<Vec3d> cp(grid.nodeCount());
  for (std::size_t m = 0; m < grid.nodeCount(); ++m) {
    cm[m] = core.nodes()[m].mass;
    cp[m] = core.nodes()[m].momentum;
  }
  EXPECT_LT(relativeDifference(mass, cm), 1e-14);
  EXPECT_LT(relativeDifference(mom, cp), 1e-13);
  std::copy(vel.begin(), vel.end(), core.velocity().begin());
  core.gridToParticle(p, mats, dt);
  host.gridToParticle(dt, s);
  MpmParticles q = p;
  host.download({q.x.data(), q.v.data(), q.C.data(), q.F.data(), q.J.data(), q.size()});
  EXPECT_LT(relativeDifference(q.x, p.x), 1e-15);
  EXPECT_LT(relativeDifference(q.v, p.v), 1e-14);
  EXPECT_LT(relativeDifference(&q.C[0](0, 0), &p.C[0](0, 0), 9 * p.size()), 1e-13);
  EXPECT_LT(relativeDifference(&q.F[0](0, 0), &p.F[0](0, 0), 9 * p.size()), 1e-14);
  EXPECT_LT(relativeDifference(q.J, p.J), 1e-14);
}

TEST(GpuCoreParity, SurfaceTensionMatchesTheCoreOverFortySteps) {
  // A cube of liquid with surface tension (sigma = 0.5 N/m, 4 cells a side,
  // 2 particles per cell and axis) beside an elastic block, no gravity: the
  // colour field, the capillary stress and the transfers of the host stepper
  // against core's MpmGrid, one P2G and then 40 steps. Without the capillary
  // stress the first P2G differs by far more than the bound (checked).
  const GridSpec grid{{0.0, 0.0, 0.0}, 0.01, {16, 16, 16}};
  MpmMaterial liquid = viscousFluid(0.02, 2e4, 1000.0);
  liquid.surfaceTension = 0.5;
  std::vector<MpmMaterial> mats = {neoHookeanSolid(1e5, 0.3, 1000.0), liquid};
  std::vector<g::MpmMaterialParams> params(2);
  params[0].mu = mats[0].mu;
  params[0].lambda = mats[0].lambda;
  params[1].fluid = true;
  params[1].viscosity = liquid.viscosity;
  params[1].bulkModulus = liquid.bulkModulus;
  params[1].surfaceTension = liquid.surfaceTension;
  std::vector<g::MpmMaterialParams> noTension = params;
  noTension[1].surfaceTension = 0;
  MpmParticles p;
  const double h = 0.005;
  for (int c = 0; c < 8; ++c)
    for (int b = 0; b < 8; ++b)
      for (int a = 0; a < 8; ++a) {
        p.add({0.04 + h * (a + 0.5), 0.05 + h * (b + 0.5), 0.045 + h * (c + 0.5)}, {}, 1000.0 * h * h * h, h * h * h,
              0.0, 1);
        if (a < 4 && b < 4 && c < 4)
          p.add({0.1 + h * (a + 0.5), 0.05 + h * (b + 0.5), 0.05 + h * (c + 0.5)}, {0.0, 0.0, 0.1},
                1000.0 * h * h * h, h * h * h, 0.0, 0);
      }
  const double dt = 2e-4;  // the capillary limit is 1.8e-2 s, the sound speed's 3.5e-3 s
  ASSERT_LT(dt, capillaryTimeStep(1000.0, grid.dx, liquid.surfaceTension));
  const auto input = [](const MpmParticles& q) {
    return g::ParticleInput{q.x.data(),    q.v.data(),       q.C.data(), q.F.data(),        q.J.data(),
                            q.mass.data(), q.volume0.data(), nullptr,    q.material.data(), q.size()};
  };
  g::MpmStepper host(grid, params, g::Backend::Cpu), plain(grid, noTension, g::Backend::Cpu);
  host.upload(input(p));
  plain.upload(input(p));
  MpmGrid core(grid);
  g::MpmStepSettings s;
  s.wallNodes = 0;
  s.gravity = Vec3d{};
  std::vector<Vec3d> mom(grid.nodeCount()), momPlain(grid.nodeCount()), vel(grid.nodeCount());
  std::vector<Vec3d> cp(grid.nodeCount());
  for (int step = 0; step < 40; ++step) {
    core.particleToGrid(p, mats, dt);
    host.particleToGrid(dt);
    host.downloadGrid(nullptr, mom.data(), nullptr, nullptr);
    for (std::size_t m = 0; m < grid.nodeCount(); ++m) cp[m] = core.nodes()[m].momentum;
    if (step == 0) {
      plain.particleToGrid(dt);
      plain.downloadGrid(nullptr, momPlain.data(), nullptr, nullptr);
      EXPECT_GT(relativeDifference(momPlain, cp), 1e-3) << "the capillary stress should move the momentum";
    }
    ASSERT_LT(relativeDifference(mom, cp), 1e-12) << "P2G momentum at step " << step;
    host.gridUpdate(dt, s);
    host.downloadGrid(nullptr, nullptr, vel.data(), nullptr);
    for (std::size_t m = 0; m < grid.nodeCount(); ++m) {
      const MpmNode& n = core.nodes()[m];
      core.velocity()[m] = n.mass > 0 ? n.momentum / n.mass : Vec3d{};
    }
    core.gridToParticle(p, mats, dt);
    host.gridToParticle(dt, s);
  }
  MpmParticles q = p;
  host.download({q.x.data(), q.v.data(), q.C.data(), q.F.data(), q.J.data(), q.size()});
  double top = 0, dx = 0, dv = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    top = std::max(top, norm(p.v[i]));
    dx = std::max(dx, norm(q.x[i] - p.x[i]));
    dv = std::max(dv, norm(q.v[i] - p.v[i]));
  }
  std::printf("40 steps with surface tension: max |dx| = %.3e m, max |dv| = %.3e m/s (top speed %.3e m/s)\n", dx, dv,
              top);
  EXPECT_LT(dx, 1e-12 * grid.dx);
  EXPECT_LT(dv, 1e-10 * top);
  EXPECT_LT(relativeDifference(q.J, p.J), 1e-12);
}
