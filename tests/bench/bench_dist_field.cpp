// The distributed field solve (dist/) on the Langevin sphere of the field
// tests (radius a, box of half-width 2a, uniform H0 = 1e5 A/m along z, open
// wall, tolerance 1e-8): one run per call, under mpirun; prints the figures
// and appends a CSV row. tests/bench/dist_scaling.sh runs the strong and
// weak scaling series (docs/distributed.md).
//   mpirun -n R lodestone-bench-dist-field --nodes N --pc mg|gamg|hypre [--series S] [--csv FILE]
#include <sys/resource.h>

#include <cstdio>
#include <string>

#include <mpi.h>

#include "lodestone/cli/command_line.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/core/stage/density_raster.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/dist/distributed_field_solve.h"
#include "lodestone/dist/petsc_session.h"

using namespace lodestone;

int main(int argc, char** argv) {
  PetscSession session(&argc, &argv);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  int nodes = 33;
  std::string pc = "mg", series = "single", csv;
  CLI::App app("The distributed field solve on the Langevin sphere: one timed run (run it under mpirun)",
               "lodestone-bench-dist-field");
  cli::helpLayout(app, 24);
  cli::addNumber(app, "--nodes", nodes, "grid nodes per axis")->check(cli::wholeNumber(9, 1025, "nodes per axis"));
  app.add_option("--pc", pc, "preconditioner")->check(cli::oneOf({"mg", "gamg", "hypre"}))->default_str(pc);
  app.add_option("--series", series, "label of the CSV row (strong, weak)")->default_str(series);
  app.add_option("--csv", csv, "append a CSV row to this file");
  app.allow_extras();  // PETSc options
  if (const auto code = cli::parse(app, argc, argv)) return rank == 0 ? *code : 0;
  try {
    constexpr double a = 0.05, H0 = 1e5;  // m, A/m
    GridSpec g;
    g.dims = {nodes, nodes, nodes};
    g.dx = 4 * a / (nodes - 1);
    g.origin = {-2 * a, -2 * a, -2 * a};
    const MagneticMaterial material = paperMaterial();
    const DenseGrid<double> n =
        rasterizeDensity(g, material.numberDensity, [&](const Vec3d& x) { return norm(x) < a; });
    const UniformField applied({0, 0, H0});
    DistributedSolveSettings ds;
    ds.preconditioner = parseDistributedPreconditioner(pc);
    DistributedFieldSolve solve(MPI_COMM_WORLD, g, material.law, BoundaryKind::Open, ds);
    solve.setMaterial(n.view(), appliedFieldOf(applied, 0.0));
    const DistributedSolveReport rep = solve.solve();
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    double rssMb = double(usage.ru_maxrss) / 1024.0, rssMax = 0;
    MPI_Reduce(&rssMb, &rssMax, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
    const std::string what = solve.describe();
    if (rank == 0) {
      const double perRank = double(g.nodeCount()) / ranks;
      std::printf("%s\n%s\n", what.c_str(), rep.summary().c_str());
      std::printf("series %s ranks %d nodes %d^3 (%.0f per rank) pc %s: setup %.3f s, solve %.3f s, %d Newton, %d CG, "
                  "peak RSS %.1f MB per rank\n",
                  series.c_str(), ranks, nodes, perRank, pc.c_str(), rep.setupSeconds, rep.seconds,
                  rep.newtonIterations, rep.linearIterations, rssMax);
      if (!csv.empty()) {
        FILE* f = std::fopen(csv.c_str(), "a");
        if (!f) throw Error(concat("cannot open ", csv));
        std::fprintf(f, "%s,%d,%d,%.0f,%s,%d,%d,%.4f,%.4f,%.1f,%d\n", series.c_str(), ranks, nodes, perRank, pc.c_str(),
                     rep.newtonIterations, rep.linearIterations, rep.setupSeconds, rep.seconds, rssMax,
                     rep.converged ? 1 : 0);
        std::fclose(f);
      }
    }
    return rep.converged ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone-bench-dist-field: %s\n", e.what());
    return 2;
  }
}
