// The distributed MPM (dist/mpm_partition.h): a viscous fluid block of
// about --particles particles (8 per cell) thrown down and sideways in a box
// of --nodes^3 nodes, split over the ranks of the mpirun job; one timed run
// per call: --substeps substeps of fixed dt after 5 untimed ones. Prints the
// figures and appends a CSV row; tests/bench/dist_mpm_scaling.sh runs the
// strong and weak series (docs/distributed.md).
//   mpirun -n R lodestone-bench-dist-mpm --nodes N --particles P [--substeps S] [--series S] [--csv FILE]
#include <malloc.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include <mpi.h>
#include <tbb/global_control.h>

#include "lodestone/cli/command_line.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/dist/mpm_partition.h"
#include "lodestone/dist/petsc_session.h"

using namespace lodestone;

namespace {
/// Resident memory now, MB (Linux /proc/self/statm; 0 elsewhere), after
/// handing the heap's free memory back (glibc keeps freed blocks otherwise).
double residentMb() {
  malloc_trim(0);
  FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return 0;
  long pages = 0, resident = 0;
  const bool ok = std::fscanf(f, "%ld %ld", &pages, &resident) == 2;
  std::fclose(f);
  return ok ? double(resident) * double(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0) : 0;
}
}  // namespace

int main(int argc, char** argv) {
  PetscSession session(&argc, &argv);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  int nodes = 65, substeps = 20, threads = 1;
  double particles = 1e5;
  std::string series = "single", csv;
  CLI::App app("The distributed MPM on a thrown fluid block: one timed run (run it under mpirun)",
               "lodestone-bench-dist-mpm");
  cli::helpLayout(app, 24);
  cli::addNumber(app, "--nodes", nodes, "grid nodes per axis")->check(cli::wholeNumber(17, 1025, "nodes per axis"));
  cli::addNumber(app, "--particles", particles, "particles (about; 8 per cell)")->check(cli::numberAbove(100, ""));
  cli::addNumber(app, "--substeps", substeps, "timed substeps")->check(cli::wholeNumber(1, 100000, "substeps"));
  cli::addNumber(app, "--threads", threads, "worker threads per rank")->check(cli::wholeNumber(1, 1024, "threads"));
  app.add_option("--series", series, "label of the CSV row (strong, weak)")->default_str(series);
  app.add_option("--csv", csv, "append a CSV row to this file");
  app.allow_extras();  // PETSc options
  if (const auto code = cli::parse(app, argc, argv)) return rank == 0 ? *code : 0;
  try {
    const tbb::global_control threadLimit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    MpmSettings s;
    s.grid.dx = 1.0 / (nodes - 1);  // a 1 m box
    s.grid.dims = {nodes, nodes, nodes};
    s.fixedDt = 0.2 * s.grid.dx / 3.0;  // s: a fifth of a cell per substep at 3 m/s
    MpmSolver solver(s);
    // Split before emitting: each rank keeps its part of the block.
    auto partition = std::make_shared<PetscMpmPartition>(MPI_COMM_WORLD, s.grid);
    solver.setPartition(partition);
    const std::uint32_t m = solver.addMaterial(viscousFluid(0.01, 1e4, 1000));
    // A cube of `particles` / 8 cells, centred low in the box.
    const double side = std::min(0.8, std::cbrt(particles / 8.0) * s.grid.dx);
    EmitterSettings e;
    e.velocity = {1.5, 1.0, -2.0};
    solver.emit(EmitterShape::box(Pose::at({0.45, 0.45, 0.5}), Vec3d{1, 1, 1} * (0.5 * side)), m, e);
    const double total = double(solver.totalParticles());
    for (int i = 0; i < 5; ++i) solver.step(s.fixedDt);
    MPI_Barrier(MPI_COMM_WORLD);
    const std::size_t sentBefore = partition->sent();
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < substeps; ++i) solver.step(s.fixedDt);
    MPI_Barrier(MPI_COMM_WORLD);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / substeps;
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    // Peak (the set-up emits the whole block on every rank, one body at a time) and now.
    double local[3] = {double(usage.ru_maxrss) / 1024.0, double(solver.particles().size()), residentMb()};
    double maxima[3] = {0, 0, 0};
    MPI_Reduce(local, maxima, 3, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
    double sent = double(partition->sent() - sentBefore);
    partition->sumOverRanks(&sent, 1);
    const std::string what = partition->describe();
    if (rank == 0) {
      const double cells = double(nodes - 1) * (nodes - 1) * (nodes - 1);
      const double perParticle = seconds / total * 1e9 * ranks;  // ns of rank time per particle-substep
      std::printf(
          "%s\nseries %s ranks %d nodes %d^3 particles %.0f (%.0f per rank, largest rank %.0f): %.4f s per "
          "substep, %.0f ns of rank time per particle-substep, %.0f migrations per substep, RSS %.1f MB "
          "per rank after the set-up's peak of %.1f MB\n",
          what.c_str(), series.c_str(), ranks, nodes, total, total / ranks, maxima[1], seconds, perParticle,
          sent / substeps, maxima[2], maxima[0]);
      if (!csv.empty()) {
        FILE* f = std::fopen(csv.c_str(), "a");
        if (!f) throw Error(concat("cannot open ", csv));
        std::fprintf(f, "%s,%d,%d,%.0f,%.0f,%.0f,%.5f,%.0f,%.1f,%.1f,%.1f\n", series.c_str(), ranks, nodes, cells,
                     total, maxima[1], seconds, perParticle, sent / substeps, maxima[2], maxima[0]);
        std::fclose(f);
      }
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone-bench-dist-mpm: %s\n", e.what());
    MPI_Abort(MPI_COMM_WORLD, 2);
    return 2;
  }
}
