// The multigrid preconditioner: a symmetric positive definite operator (as
// PCG requires) whose iteration counts do not grow with resolution, giving the
// same field as Jacobi-PCG.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <vector>

#include "lodestone/core/field_solver.h"
#include "lodestone/core/magnetic_stage.h"
#include "lodestone/core/material.h"
#include "lodestone/core/multigrid.h"
#include "lodestone/core/parallel.h"
#include "lodestone/core/uniform_field.h"
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
    n = rasterize(grid, paperMaterial().numberDensity, ball({0.01, 0.0, -0.005}, 0.05), 3);
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
  for (BoundaryKind b : {BoundaryKind::Open, BoundaryKind::Shield})
    for (int N : {20, 21}) {  // even sizes exercise the ghost node of the coarse grids
      SphereProblem sp(N, b, 1e5, N + 3);
      MultigridPreconditioner mg;
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
      SCOPED_TRACE(::testing::Message() << toString(b) << " N = " << N);
      EXPECT_NEAR(vMu, uMv, 1e-9 * std::fabs(vMu));
      EXPECT_GT(deterministicDot(u.data(), Mu.data(), n), 0.0);
      EXPECT_GT(deterministicDot(v.data(), Mv.data(), n), 0.0);
    }
}

TEST(Multigrid, IterationsDoNotGrowWithResolution) {
  std::vector<int> mgIts, jacobiIts;
  for (int N : {17, 33, 65}) {
    SphereProblem sp(N, BoundaryKind::Open);
    MultigridPreconditioner mg;
    mg.update(*sp.problem);
    JacobiPreconditioner jacobi;
    jacobi.update(*sp.problem);
    mgIts.push_back(pcgIterations(*sp.problem, mg, 1e-8));
    jacobiIts.push_back(pcgIterations(*sp.problem, jacobi, 1e-8));
  }
  SCOPED_TRACE(::testing::Message() << "multigrid " << mgIts[0] << " " << mgIts[1] << " " << mgIts[2] << ", jacobi "
                                    << jacobiIts[0] << " " << jacobiIts[1] << " " << jacobiIts[2]);
  std::printf("PCG iterations to 1e-8 at N = 17, 33, 65: multigrid %d %d %d, jacobi %d %d %d\n", mgIts[0], mgIts[1],
              mgIts[2], jacobiIts[0], jacobiIts[1], jacobiIts[2]);
  EXPECT_LE(mgIts[2], 20);
  EXPECT_LE(mgIts[2], mgIts[0] + 4);
  EXPECT_GT(jacobiIts[2], 3 * jacobiIts[0] / 2);  // Jacobi grows with N
  EXPECT_GT(jacobiIts[2], 4 * mgIts[2]);
}

TEST(Multigrid, SameFieldAsJacobi) {
  for (BoundaryKind b : {BoundaryKind::Open, BoundaryKind::Shield}) {
    const GridSpec g = cubeGrid(29, 0.1);
    const DenseGrid<double> n = rasterize(g, paperMaterial().numberDensity, ball({0, 0, 0}, 0.05), 3);
    std::vector<Vec3d> H[2];
    for (int k = 0; k < 2; ++k) {
      MagneticStageSettings s;
      s.boundary = b;
      s.solve.tolerance = 1e-11;
      s.solve.preconditioner = k ? PreconditionerKind::Multigrid : PreconditionerKind::Jacobi;
      MagneticForceStage stage(g, paperMaterial(), s);
      const auto rep = stage.runOnDensity(n.view(), UniformField({0, 0, 1e5}), 0.0);
      ASSERT_TRUE(rep.converged()) << rep.solve.message;
      H[k].assign(stage.field().data, stage.field().data + g.nodeCount());
    }
    double err = 0;
    for (std::size_t m = 0; m < g.nodeCount(); ++m) err = std::max(err, norm(H[0][m] - H[1][m]));
    EXPECT_LT(err, 1e-6 * 1e5) << toString(b);
  }
}
