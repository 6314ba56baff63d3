// The multigrid preconditioner: a symmetric positive definite operator (as
// PCG requires) whose iteration counts do not grow with resolution, giving the
// same field as Jacobi-PCG.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "lodestone/core/stage/density_raster.h"
#include "lodestone/core/field/field_solver.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/field/multigrid.h"
#include "lodestone/core/base/parallel.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone_test/scenes.h"

using namespace lodestone;
using namespace lodestone::test;

namespace {

AppliedFieldFunction uniform(const Vec3d& H) {
  return [H](const Vec3d*, std::size_t c, Vec3d* out) {
    for (std::size_t m = 0; m < c; ++m) out[m] = H;
  };
}

// A sphere problem evaluated at phi = 0 (so the Jacobian is the Newton one).
struct SphereProblem {
  GridSpec grid;
  DenseGrid<double> n;
  std::unique_ptr<MagnetostaticProblem> problem;
  SphereProblem(int N, BoundaryKind b, double H0 = 1e5, int Ny = 0) {
    grid = cubeGrid(N, 0.1);
    if (Ny) grid.dims.j = Ny;
    n = rasterizeDensity(grid, paperMaterial().numberDensity, ball({0.01, 0.0, -0.005}, 0.05), 3);
    problem = std::make_unique<MagnetostaticProblem>(grid, paperMaterial().law, b);
    problem->setMaterial(n.view(), uniform({0.3 * H0, 0, H0}));
    std::vector<double> phi(grid.nodeCount(), 0.0), F(grid.nodeCount());
    problem->evaluate(phi.data(), F.data());
  }
};

int pcgIterations(const MagnetostaticProblem& p, const Preconditioner& pre, double tol) {
  const std::size_t n = p.nodeCount();
  std::vector<double> b(n), x(n);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1, 1);
  for (double& v : b) v = U(rng);
  p.zeroFixed(b.data());
  std::function<void(double*)> project;
  if (p.boundary() == BoundaryKind::Shield) project = [&](double* v) { p.removeMean(v); };
  const PcgResult r = solvePcg(
      n, [&](const double* v, double* out) { p.applyJacobian(v, out); }, pre, b.data(), x.data(), tol, 2000,
      project);
  EXPECT_TRUE(r.converged);
  return r.iterations;
}

}  // namespace

TEST(Multigrid, CycleIsSymmetricPositiveDefinite) {
  for (bool single : {false, true})
  for (BoundaryKind b : {BoundaryKind::Open, BoundaryKind::Shield})
    for (int N : {20, 21}) {  // even sizes exercise the ghost node of the coarse grids
      SphereProblem sp(N, b, 1e5, N + 3);
      MultigridSettings settings;
      settings.singlePrecision = single;
      MultigridPreconditioner mg(settings);
      mg.update(*sp.problem);
      EXPECT_GE(mg.levelCount(), 3);
      const std::size_t n = sp.grid.nodeCount();
      std::vector<double> u(n), v(n), Mu(n), Mv(n);
      std::mt19937 rng(3);
      std::uniform_real_distribution<double> U(-1, 1);
      for (std::size_t m = 0; m < n; ++m) {
        u[m] = U(rng);
        v[m] = U(rng);
      }
      sp.problem->zeroFixed(u.data());
      sp.problem->zeroFixed(v.data());
      if (b == BoundaryKind::Shield) {
        sp.problem->removeMean(u.data());
        sp.problem->removeMean(v.data());
      }
      mg.apply(u.data(), Mu.data());
      mg.apply(v.data(), Mv.data());
      const double vMu = deterministicDot(v.data(), Mu.data(), n), uMv = deterministicDot(u.data(), Mv.data(), n);
      SCOPED_TRACE(::testing::Message() << toString(b) << " N = " << N << (single ? " float" : " double"));
      // Exactly symmetric in exact arithmetic; to round-off of the storage precision.
      EXPECT_NEAR(vMu, uMv, (single ? 1e-5 : 1e-9) * std::fabs(vMu));
      EXPECT_GT(deterministicDot(u.data(), Mu.data(), n), 0.0);
      EXPECT_GT(deterministicDot(v.data(), Mv.data(), n), 0.0);
    }
}

TEST(Multigrid, IterationsDoNotGrowWithResolution) {
  // Sphere of radius N/4 cells at 33^3, 65^3 and 129^3 nodes (32, 64, 128 cells).
  std::vector<int> mgIts, mgDoubleIts, jacobiIts;
  for (int N : {33, 65, 129}) {
    SphereProblem sp(N, BoundaryKind::Open);
    MultigridPreconditioner mg;
    mg.update(*sp.problem);
    mgIts.push_back(pcgIterations(*sp.problem, mg, 1e-8));
    MultigridSettings ds;
    ds.singlePrecision = false;
    MultigridPreconditioner mgDouble(ds);
    mgDouble.update(*sp.problem);
    mgDoubleIts.push_back(pcgIterations(*sp.problem, mgDouble, 1e-8));
    if (N < 129) {  // Jacobi at 129^3 takes hundreds of iterations
      JacobiPreconditioner jacobi;
      jacobi.update(*sp.problem);
      jacobiIts.push_back(pcgIterations(*sp.problem, jacobi, 1e-8));
    }
  }
  std::printf("PCG iterations to 1e-8 at 32^3, 64^3, 128^3 cells: multigrid (float) %d %d %d, (double) %d %d %d; "
              "jacobi %d %d\n",
              mgIts[0], mgIts[1], mgIts[2], mgDoubleIts[0], mgDoubleIts[1], mgDoubleIts[2], jacobiIts[0],
              jacobiIts[1]);
  for (int l = 0; l < 3; ++l) {
    EXPECT_LE(mgIts[std::size_t(l)], 20);
    EXPECT_LE(std::abs(mgIts[std::size_t(l)] - mgDoubleIts[std::size_t(l)]), 1);  // float storage costs no iterations
  }
  EXPECT_LE(mgIts[2], mgIts[0] + 3);
  EXPECT_GT(jacobiIts[1], 3 * jacobiIts[0] / 2);  // Jacobi grows with N
  EXPECT_GT(jacobiIts[1], 4 * mgIts[1]);
}

TEST(Multigrid, SameFieldAsJacobi) {
  for (BoundaryKind b : {BoundaryKind::Open, BoundaryKind::Shield}) {
    const GridSpec g = cubeGrid(29, 0.1);
    const DenseGrid<double> n = rasterizeDensity(g, paperMaterial().numberDensity, ball({0, 0, 0}, 0.05), 3);
    std::vector<Vec3d> H[3];  // Jacobi, multigrid (float), multigrid (double)
    for (int k = 0; k < 3; ++k) {
      MagneticStageSettings s;
      s.boundary = b;
      s.solve.tolerance = 1e-11;
      s.solve.preconditioner = k ? PreconditionerKind::Multigrid : PreconditionerKind::Jacobi;
      s.solve.multigrid.singlePrecision = k == 1;
      MagneticForceStage stage(g, paperMaterial(), s);
      const auto rep = stage.runOnDensity(n.view(), UniformField({0, 0, 1e5}), 0.0);
      ASSERT_TRUE(rep.converged()) << rep.solve.message;
      H[k].assign(stage.field().data, stage.field().data + g.nodeCount());
    }
    for (int k = 1; k < 3; ++k) {
      double err = 0;
      for (std::size_t m = 0; m < g.nodeCount(); ++m) err = std::max(err, norm(H[0][m] - H[k][m]));
      EXPECT_LT(err, 1e-6 * 1e5) << toString(b) << (k == 1 ? " float" : " double");
    }
  }
}

TEST(Multigrid, ReusedHierarchyMatchesFresh) {
  // update() keeps the levels' structure while the material cell set stays
  // the same and rebuilds it when it changes; either way the cycle must be
  // the one a fresh preconditioner builds.
  for (bool single : {true, false})
    for (BoundaryKind b : {BoundaryKind::Open, BoundaryKind::Shield}) {
      SCOPED_TRACE(::testing::Message() << toString(b) << (single ? " float" : " double"));
      SphereProblem sp(22, b, 1e5, 25);
      MultigridSettings settings;
      settings.singlePrecision = single;
      MultigridPreconditioner reused(settings);
      reused.update(*sp.problem);
      const std::size_t n = sp.grid.nodeCount();
      std::vector<double> r(n), zReused(n), zFresh(n), phi(n), F(n);
      std::mt19937 rng(5);
      std::uniform_real_distribution<double> U(-1, 1);
      for (double& v : r) v = U(rng);
      sp.problem->zeroFixed(r.data());
      auto expectSameAsFresh = [&](const char* what) {
        reused.update(*sp.problem);
        MultigridPreconditioner fresh(settings);
        fresh.update(*sp.problem);
        EXPECT_EQ(reused.levelCount(), fresh.levelCount()) << what;
        reused.apply(r.data(), zReused.data());
        fresh.apply(r.data(), zFresh.data());
        double diff = 0, scale = 0;
        for (std::size_t m = 0; m < n; ++m) {
          diff = std::max(diff, std::fabs(zReused[m] - zFresh[m]));
          scale = std::max(scale, std::fabs(zFresh[m]));
        }
        EXPECT_GT(scale, 0.0) << what;
        EXPECT_EQ(diff, 0.0) << what << ": max |z| " << scale;  // deterministic: bit for bit
      };
      // A new Newton state: same cells, new element matrices and tensors.
      for (std::size_t m = 0; m < n; ++m) phi[m] = 2e3 * U(rng);
      sp.problem->zeroFixed(phi.data());
      sp.problem->evaluate(phi.data(), F.data());
      expectSameAsFresh("new Newton state");
      // Denser material on a moved, larger ball: a different cell set.
      const DenseGrid<double> n2 =
          rasterizeDensity(sp.grid, 2 * paperMaterial().numberDensity, ball({-0.02, 0.01, 0.0}, 0.07), 3);
      sp.problem->setMaterial(n2.view(), uniform({0, 1e5, 0}));
      std::fill(phi.begin(), phi.end(), 0.0);
      sp.problem->evaluate(phi.data(), F.data());
      expectSameAsFresh("new material");
      // Back to the first material: the structure changes again.
      sp.problem->setMaterial(sp.n.view(), uniform({3e4, 0, 1e5}));
      sp.problem->evaluate(phi.data(), F.data());
      expectSameAsFresh("first material again");
    }
}

TEST(Multigrid, FusedApplyAndDotEqualTheSeparateOnes) {
  // applyDot sums r . z in the cycle's last fine sweep; the same z as
  // apply() and the same sum as a separate dot product.
  for (BoundaryKind b : {BoundaryKind::Open, BoundaryKind::Shield})
    for (bool single : {true, false}) {
      SphereProblem sp(33, b);
      MultigridSettings ms;
      ms.singlePrecision = single;
      MultigridPreconditioner mg(ms);
      mg.update(*sp.problem);
      const std::size_t n = sp.problem->nodeCount();
      std::vector<double> r(n), z(n), z2(n);
      std::mt19937 rng(4);
      std::uniform_real_distribution<double> U(-1, 1);
      for (double& x : r) x = U(rng);
      sp.problem->zeroFixed(r.data());
      mg.apply(r.data(), z.data());
      const double dot = mg.applyDot(n, r.data(), z2.data());
      for (std::size_t m = 0; m < n; ++m) ASSERT_EQ(z[m], z2[m]) << m;
      const double ref = deterministicDot(r.data(), z.data(), n);
      EXPECT_NEAR(dot, ref, 1e-12 * std::fabs(ref)) << toString(b) << (single ? " float" : " double");
      EXPECT_GT(dot, 0);
    }
}
