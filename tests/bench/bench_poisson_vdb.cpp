// Our field solve next to OpenVDB's Poisson solver (openvdb::tools::poisson)
// on the same grid: the sphere of the accuracy benchmark (radius a = 5 cm in a
// box of half-width 2a, N nodes per axis, default 129 = 128 cells).
//
// What each solves:
//   ours     the coupled magnetostatic problem div((1 + chi) grad phi) = ...
//            (Q1 finite elements, 27-point stencil, M depends on H), linear or
//            Langevin law, Newton-PCG with a multigrid or Jacobi
//            preconditioner, open (far-field) boundary, stopped at a relative
//            residual (2-norm, against the residual at phi = 0) of `tol`;
//            timed as the whole stage (applied field, solve, nodal H, M, B,
//            force) and the solve alone;
//   OpenVDB  one constant-coefficient Poisson problem lap(phi) = div(M) for
//            the given (closed-form, uniform) magnetization of the linear
//            sphere: the compact 7-point Laplacian (OpenVDB's "staggered"
//            stencil; its collocated one is the 2-cell-wide stencil of the
//            divergence of a central-difference gradient) over the same N^3
//            nodes (all active),
//            homogeneous Dirichlet phi = 0 just outside the box, CG with the
//            incomplete-Cholesky (and, second, Jacobi) preconditioner,
//            stopped at an infinity-norm residual relative to ||b||_inf of
//            `tol`; timed as the matrix and preconditioner set-up plus CG.
// With --active-region M (default 4) ours also runs, multigrid, on the grid
// the MPM solver's planner solves this sphere on (effects_planner.h): the
// ball's box plus the stencil's 3 cells, M free cells and the solver's 4
// cells of slack, on the box's lattice, with the same open wall; its H error
// is against the same closed form.
// The OpenVDB problem is the linear solve inside one Newton step of ours for
// a material with chi = 0 (no coupling, no boundary update), so it is a lower
// bound on what any solve of the magnetized sphere costs on this grid.
// Each solve runs --solves times (default 2): the first on fresh storage,
// then again (ours: the same stage from phi = 0, as an MPM run reuses it;
// OpenVDB: from scratch, as every call is); "again" is the fastest repeat.
// `lodestone-bench-poisson-vdb --help` lists the options.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <openvdb/math/ConjGradient.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/PoissonSolver.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include "lodestone/cli/command_line.h"
#include "lodestone/core/base/stopwatch.h"

#include "lodestone/core/base/error.h"
#include "lodestone/core/field/langevin.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/planner/effects_planner.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/core/stage/magnetic_stage.h"

using namespace lodestone;

namespace {

using Clock = std::chrono::steady_clock;

constexpr double kRadius = 0.05;  // m

/// Volume fraction of each node's dual cell inside the ball of radius a at
/// the origin (8^3 samples near the surface).
DenseGrid<double> ballFraction(const GridSpec& g) {
  DenseGrid<double> f(g, 0.0);
  const int S = 8;
  const double half = 0.5 * std::sqrt(3.0) * g.dx;
  tbb::parallel_for(0, g.dims.k, [&](int k) {
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) {
        const Vec3d x = g.nodePosition(i, j, k);
        const double r = norm(x);
        if (r > kRadius + half) continue;
        if (r < kRadius - half) {
          f(i, j, k) = 1;
          continue;
        }
        int in = 0;
        for (int c = 0; c < S; ++c)
          for (int b = 0; b < S; ++b)
            for (int a = 0; a < S; ++a)
              in += norm2(x + g.dx * Vec3d{(a + 0.5) / S - 0.5, (b + 0.5) / S - 0.5, (c + 0.5) / S - 0.5}) <
                    kRadius * kRadius;
        f(i, j, k) = in / double(S * S * S);
      }
  });
  return f;
}

double sphereInteriorField(const MagneticMaterial& mat, double H0) {
  if (mat.law.kind == LawKind::Linear) return 3 * H0 / (3 + mat.lowFieldSusceptibility());
  double lo = 0, hi = H0;
  for (int it = 0; it < 200; ++it) {
    const double m = 0.5 * (lo + hi);
    (m + mat.saturation() * langevin(mat.law.k2 * m) / 3 - H0 > 0 ? hi : lo) = m;
  }
  return 0.5 * (lo + hi);
}

struct Row {
  std::string solver, problem, preconditioner, boundary, norm;
  double tolerance = 0, achieved = 0;
  int iterations = 0;  // CG iterations (ours: total over Newton steps)
  int newton = 0;
  std::size_t solveNodes = 0;  // nodes of the grid solved on
  double secondsSetup = 0;     // OpenVDB: index tree, matrix, preconditioner
  double secondsSolve = 0;     // ours: Newton-PCG; OpenVDB: CG
  double secondsTotal = 0;     // ours: whole stage; OpenVDB: set-up + CG
  double interiorError = 0;    // |mean interior H_z - closed form| / closed form
  // The same solve run again (--solves K > 1), fastest of the K - 1 repeats:
  // ours on the same stage from phi = 0 (its storage reused, as in an MPM
  // run); OpenVDB's set-up and CG from scratch, as every call does. NaN: K = 1.
  double secondsSolveAgain = std::numeric_limits<double>::quiet_NaN();
  double secondsTotalAgain = std::numeric_limits<double>::quiet_NaN();
};

/// Runs `solve` (a Row-returning call) `solves` times: the first run's row,
/// with the fastest repeat's times as its "again" figures.
template <typename Solve>
Row repeated(int solves, const Solve& solve) {
  Row first = solve();
  for (int k = 1; k < solves; ++k) {
    const Row again = solve();
    if (!(again.secondsTotal >= first.secondsTotalAgain)) {  // NaN at the first repeat
      first.secondsTotalAgain = again.secondsTotal;
      first.secondsSolveAgain = again.secondsSolve;
    }
  }
  return first;
}

template <typename Precond>
Row vdbSolve(const GridSpec& g, const openvdb::DoubleTree& source, double tol, const char* name, double H0, double Mz,
             double Hexact) {
  using namespace openvdb;
  using namespace openvdb::tools::poisson;
  using VecT = math::pcg::Vector<double>;
  Row r;
  r.solver = "openvdb";
  r.solveNodes = g.nodeCount();
  r.problem = "lap phi = div M (M given)";
  r.preconditioner = name;
  r.boundary = "Dirichlet phi = 0 outside the box";
  r.norm = "inf-norm of residual / inf-norm of b";
  r.tolerance = tol;
  const auto t0 = Clock::now();
  const auto idxTree = createIndexTree(source);
  const auto b = createVectorFromTree<double>(source, *idxTree);
  BoolTree interior(*idxTree, false, TopologyCopy());
  tools::erodeActiveValues(interior, 1, tools::NN_FACE, tools::IGNORE_TILES);
  DirichletBoundaryOp<double> op;
  LaplacianMatrix::Ptr L = createISLaplacianWithBoundaryConditions(*idxTree, interior, op, *b, /*staggered=*/true);
  L->scale(-1.0);
  b->scale(-1.0);
  Precond precond(*L);
  r.secondsSetup = secondsSince(t0);
  VecT x(b->size(), 0.0);
  math::pcg::State term = math::pcg::terminationDefaults<double>();
  term.iterations = 100000;
  term.relativeError = tol;
  term.absoluteError = 0;
  util::NullInterrupter interrupter;
  const auto t1 = Clock::now();
  const math::pcg::State st = math::pcg::solve(*L, *b, x, precond, interrupter, term);
  r.secondsSolve = secondsSince(t1);
  r.secondsTotal = secondsSince(t0);
  r.iterations = st.iterations;
  r.achieved = st.relativeError;
  // Interior field H = H0 - d phi/dz, mean over nodes with r < a/2.
  const auto phi = createTreeFromVector<double>(x, *idxTree, 0.0);
  tree::ValueAccessor<const DoubleTree> acc(*phi);
  double sum = 0;
  long count = 0;
  for (int k = 1; k + 1 < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i)
        if (norm(g.nodePosition(i, j, k)) < 0.5 * kRadius) {
          sum += H0 - (acc.getValue(Coord(i, j, k + 1)) - acc.getValue(Coord(i, j, k - 1))) / (2 * g.dx);
          ++count;
        }
  (void)Mz;
  r.interiorError = std::fabs(sum / count - Hexact) / Hexact;
  return r;
}

/// Our stage on grid g (the whole box, or the planner's active region on
/// the box's lattice when `region`), frac: ballFraction(g).
Row oursSolve(const GridSpec& g, const DenseGrid<double>& frac, const MagneticMaterial& mat, PreconditionerKind pk,
              double tol, double H0, bool region, int solves) {
  DenseGrid<double> n(g, 0.0);
  for (std::size_t m = 0; m < g.nodeCount(); ++m) n[m] = frac[m] * mat.numberDensity;
  MagneticStageSettings s;
  s.solve.preconditioner = pk;
  s.solve.tolerance = tol;
  s.solve.maxCgIterations = 20000;
  MagneticForceStage stage(g, mat, s);
  MagneticStageReport rep;
  int run = 0;
  Row r = repeated(solves, [&] {
    if (run++ > 0) stage.resetWarmStart();  // again from phi = 0
    const auto t0 = Clock::now();
    rep = stage.runOnDensity(n.view(), UniformField({0, 0, H0}), 0.0);
    Row t;
    t.secondsTotal = secondsSince(t0);
    t.secondsSolve = rep.secondsSolve;
    return t;
  });
  r.solver = "lodestone";
  r.problem = concat("div((1+chi) grad) Newton, ", mat.law.kind == LawKind::Linear ? "linear" : "langevin", " law");
  r.preconditioner = concat(toString(pk), "-PCG");
  r.boundary = region ? concat("open (far-field multipole wall) on the planner's active region ", g.dims.i, "x",
                               g.dims.j, "x", g.dims.k)
                      : std::string("open (far-field multipole wall)");
  r.solveNodes = g.nodeCount();
  r.norm = "2-norm of Newton residual / residual at phi = 0";
  r.tolerance = tol;
  r.achieved = rep.solve.relativeResidual;
  r.iterations = rep.solve.cgIterations;
  r.newton = rep.solve.newtonIterations;
  const double exact = sphereInteriorField(mat, H0);
  double sum = 0;
  long count = 0;
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i)
        if (norm(g.nodePosition(i, j, k)) < 0.5 * kRadius) {
          sum += stage.field()(i, j, k).z;
          ++count;
        }
  r.interiorError = std::fabs(sum / count - exact) / exact;
  if (!rep.converged()) std::printf("  (not converged: %s)\n", rep.solve.message.c_str());
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    int N = 129;
    double tol = 1e-8;
    int activeMargin = 4;  // free cells (effects_planner.h)
    int solves = 2;
    std::string csvPath = "docs/data/solve_vs_openvdb.csv";
    CLI::App app("lodestone-bench-poisson-vdb: our field solve next to openvdb::tools::poisson on the same grid",
                 "lodestone-bench-poisson-vdb");
    cli::helpLayout(app, 36);
    cli::addNumber(app, "--nodes", N, "nodes per axis (129: 128 cells)")
        ->type_name("N")
        ->check(cli::wholeNumber(9, 385))
        ->default_str(cli::formatNumber(N));
    cli::addNumber(app, "--tolerance", tol, "relative residual of every solve, in (0, 1)")
        ->type_name("X")
        ->check(cli::number())
        ->default_str(cli::formatNumber(tol));
    cli::addNumber(app, "--active-region", activeMargin,
                   "also solve (multigrid, both laws) on the planner's active region with this margin of free cells "
                   "(4: the 0.5% decision share, 8: 0.1%; 0: not)")
        ->type_name("M")
        ->check(cli::wholeNumber(0, 64))
        ->default_str(cli::formatNumber(activeMargin));
    cli::addNumber(app, "--solves", solves,
                   "runs of each solve: the first, on fresh storage, and the fastest of the others (ours: the same "
                   "stage from phi = 0, its storage reused)")
        ->type_name("K")
        ->check(cli::wholeNumber(1, 10))
        ->default_str(cli::formatNumber(solves));
    app.add_option("--csv", csvPath, "CSV output")->type_name("FILE")->capture_default_str();
    if (const std::optional<int> code = cli::parse(app, argc, argv)) return *code;
    require(tol > 0 && tol < 1, "--tolerance: ", tol, " is not in (0, 1)");
    openvdb::initialize();

    GridSpec g;
    g.dx = 4 * kRadius / (N - 1);
    g.origin = {-2 * kRadius, -2 * kRadius, -2 * kRadius};
    g.dims = {N, N, N};
    const DenseGrid<double> frac = ballFraction(g);
    const double H0 = 1e5;
    const MagneticMaterial lang = paperMaterial(), lin = linearized(lang);
    // The given magnetization of the OpenVDB problem: the linear sphere's
    // closed form M = chi0 H_in, times the volume fraction.
    const double Hin = sphereInteriorField(lin, H0), Mz = lin.lowFieldSusceptibility() * Hin;
    openvdb::DoubleTree source(0.0);
    {
      openvdb::tree::ValueAccessor<openvdb::DoubleTree> acc(source);
      for (int k = 0; k < N; ++k)
        for (int j = 0; j < N; ++j)
          for (int i = 0; i < N; ++i) {
            const double up = k + 1 < N ? frac(i, j, k + 1) : 0, dn = k > 0 ? frac(i, j, k - 1) : 0;
            // dx^2 * div M with unit grid spacing in the solver's Laplacian.
            acc.setValueOn(openvdb::Coord(i, j, k), g.dx * Mz * (up - dn) / 2);
          }
    }

    std::printf(
        "Lodestone solve vs OpenVDB %s Poisson: %d^3 nodes (dx = %.4g m), sphere a = %.2f m, H0 = %.0e A/m, "
        "tolerance %.0e, %d threads\n",
        openvdb::getLibraryVersionString(), N, g.dx, kRadius, H0, tol, tbb::info::default_concurrency());
    std::vector<Row> rows;
    const auto show = [&](const Row& r) {
      char again[16] = "       -";  // --solves 1: no repeat
      if (solves > 1) std::snprintf(again, sizeof again, "%8.3f", r.secondsTotalAgain);
      std::printf("%-9s %-42s %-24s %6d %4d %9.2e %8.3f %8.3f %8.3f %s %9.2e\n", r.solver.c_str(), r.problem.c_str(),
                  r.preconditioner.c_str(), r.iterations, r.newton, r.achieved, r.secondsSetup, r.secondsSolve,
                  r.secondsTotal, again, r.interiorError);
      std::fflush(stdout);
      rows.push_back(r);
    };
    std::printf("%-9s %-42s %-24s %6s %4s %9s %8s %8s %8s %8s %9s\n", "solver", "problem", "preconditioner", "CG",
                "Nwt", "residual", "setup s", "solve s", "total s", "again s", "H error");
    show(repeated(solves, [&] {
      return vdbSolve<openvdb::math::pcg::IncompleteCholeskyPreconditioner<openvdb::tools::poisson::LaplacianMatrix>>(
          g, source, tol, "incomplete-Cholesky-PCG", H0, Mz, sphereInteriorField(lin, H0));
    }));
    show(repeated(solves, [&] {
      return vdbSolve<openvdb::math::pcg::JacobiPreconditioner<openvdb::tools::poisson::LaplacianMatrix>>(
          g, source, tol, "Jacobi-PCG", H0, Mz, sphereInteriorField(lin, H0));
    }));
    for (const MagneticMaterial* m : {&lin, &lang})
      for (PreconditionerKind pk : {PreconditionerKind::Multigrid, PreconditionerKind::Jacobi})
        show(oursSolve(g, frac, *m, pk, tol, H0, false, solves));
    if (activeMargin > 0) {
      // The grid the MPM solver's planner solves this sphere on: its box, the
      // stencil's 3 cells, `activeMargin` free cells and the solver's slack.
      const Vec3d a{kRadius, kRadius, kRadius};
      const GridSpec rg = widenedRegion(activeRegionGrid(g, -1.0 * a, a, activeMargin), g, kActiveRegionSlackCells);
      const DenseGrid<double> rfrac = ballFraction(rg);
      for (const MagneticMaterial* m : {&lin, &lang})
        show(oursSolve(rg, rfrac, *m, PreconditionerKind::Multigrid, tol, H0, true, solves));
    }

    const double vdb = rows[0].secondsTotal, vdbAgain = rows[0].secondsTotalAgain;
    std::printf("\nratios to OpenVDB incomplete-Cholesky-PCG (set-up + CG, %.3f s", vdb);
    if (solves > 1) std::printf("; again %.3f s", vdbAgain);
    std::printf("):\n");
    for (const Row& r : rows) {
      std::printf("  %-9s %-42s %-24s solve %6.2fx   total %6.2fx", r.solver.c_str(), r.problem.c_str(),
                  r.preconditioner.c_str(), r.secondsSolve / vdb, r.secondsTotal / vdb);
      if (solves > 1) std::printf("   again %6.2fx", r.secondsTotalAgain / vdbAgain);
      std::printf("  (%zu nodes)\n", r.solveNodes);
    }

    std::ofstream csv(csvPath);
    require(bool(csv), "cannot write ", csvPath);
    csv.precision(8);
    csv << "solver,problem,preconditioner,boundary,tolerance,tolerance_norm,achieved_residual,cg_iterations,"
           "newton_iterations,seconds_setup,seconds_solve,seconds_total,total_vs_openvdb_ic,interior_H_error,"
           "nodes_per_axis,threads,solve_nodes,solves,seconds_solve_again,seconds_total_again,again_vs_openvdb_ic_"
           "again\n";
    for (const Row& r : rows)
      csv << r.solver << ",\"" << r.problem << "\"," << r.preconditioner << ",\"" << r.boundary << "\"," << r.tolerance
          << ",\"" << r.norm << "\"," << r.achieved << ',' << r.iterations << ',' << r.newton << ',' << r.secondsSetup
          << ',' << r.secondsSolve << ',' << r.secondsTotal << ',' << r.secondsTotal / vdb << ',' << r.interiorError
          << ',' << N << ',' << tbb::info::default_concurrency() << ',' << r.solveNodes << ',' << solves << ','
          << r.secondsSolveAgain << ',' << r.secondsTotalAgain << ',' << r.secondsTotalAgain / vdbAgain << '\n';
    std::printf("CSV written to %s\n", csvPath.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone-bench-poisson-vdb: %s\n", e.what());
    return 1;
  }
}
