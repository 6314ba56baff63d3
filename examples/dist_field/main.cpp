// lodestone-dist-field: the field solve of a scene's state at a frame across
// MPI ranks (dist/, docs/distributed.md), written as the OpenVDB grids of
// `lodestone export-fields` (n, phi, H, M, B, force):
//   mpirun -n 4 lodestone-dist-field SCENE --out fields.vdb [--frame N] [--pc mg|gamg|hypre]
// Every rank reads the scene; with --frame, the ranks run the MPM up to that
// frame split over them (dist/mpm_partition.h; replicated on every rank for
// a scene that does not run partitioned: surface tension, dynamic bodies);
// rank 0 gathers the particles, deposits the magnetic particles' density n on the magnetic grid (or
// reads it from --density FILE.vdb) and sends it to all. The nonlinear field
// solve runs across the ranks (each owns a box of the grid); rank 0 gathers
// phi, recovers H, M, B and the force (MagneticForceStage::runOnPotential,
// one process) and writes the file.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <mpi.h>

#include "lodestone/cli/command_line.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/core/stage/transfer.h"
#include "lodestone/dist/distributed_field_solve.h"
#include "lodestone/dist/mpm_partition.h"
#include "lodestone/dist/petsc_session.h"
#include "lodestone/plugin/scene.h"
#include "lodestone/vdb_io/field_file.h"

using namespace lodestone;
using namespace lodestone::plugin;

namespace {

struct Options {
  std::string scene, out, density, densityGrid = "n", pc = "mg";
  double tolerance = 0;  // 0: the scene's
  int frame = -1;        // -1: the initial state
};

int run(const Options& o, int rank) {
  const Scene scene = loadScene(o.scene);
  const std::unique_ptr<MpmSolver> solver = buildSolver(scene);
  const int frame = o.frame < 0 ? scene.initialFrame() : o.frame;
  if (frame < scene.initialFrame() || frame > scene.lastFrame())
    throw InvalidArgument(concat("--frame ", frame, ": the scene has frames ", scene.initialFrame(), "..",
                                 scene.lastFrame()));
  int ranks = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  if (frame > scene.initialFrame() && ranks > 1) {
    // The MPM up to the frame across the ranks too, where the scene allows.
    try {
      solver->setPartition(std::make_shared<PetscMpmPartition>(MPI_COMM_WORLD, scene.settings.grid));
    } catch (const InvalidArgument& e) {
      if (rank == 0) std::printf("the MPM runs on every rank (replicated): %s\n", e.what());
    }
  }
  for (int f = scene.initialFrame(); f < frame; ++f) solver->advanceFrame(scene.frameDuration());
  solver->gatherParticlesToRoot();  // rank 0 deposits the density of every particle
  const MpmMaterial* law = nullptr;
  for (const MpmMaterial& m : solver->materials())
    if (m.isMagnetic()) law = &m;
  if (!law) throw InvalidArgument(concat(o.scene, ": the scene has no magnetic material; there is no field to solve"));
  const GridSpec grid = scene.settings.magneticGrid ? *scene.settings.magneticGrid : scene.settings.grid;
  MagneticStageSettings settings = scene.settings.magnetic;
  if (o.tolerance > 0) settings.solve.tolerance = o.tolerance;

  // n (1/m^3) on the field grid, on every rank.
  DenseGrid<double> n(grid, 0.0);
  if (rank != 0) {
    // Sent by rank 0 below.
  } else if (!o.density.empty()) {
    n = readDensityVdb(o.density, grid, o.densityGrid);
  } else {
    const MpmParticles& p = solver->particles();
    std::vector<Vec3d> x;
    std::vector<double> counts;
    for (std::size_t i = 0; i < p.size(); ++i)
      if (solver->materials()[p.material[i]].isMagnetic()) {
        x.push_back(p.x[i]);
        counts.push_back(p.count[i]);
      }
    depositNumberDensity({x.data(), counts.data(), x.size()}, n.view(), OutOfGridPolicy::Skip);
  }
  MPI_Bcast(n.data(), int(grid.nodeCount()), MPI_DOUBLE, 0, MPI_COMM_WORLD);

  DistributedSolveSettings ds;
  ds.tolerance = settings.solve.tolerance;
  ds.maxNewtonIterations = settings.solve.maxNewtonIterations;
  ds.preconditioner = parseDistributedPreconditioner(o.pc);
  DistributedFieldSolve solve(MPI_COMM_WORLD, grid, law->magnetic.law, settings.boundary, ds);
  solve.setMaterial(n.view(), appliedFieldOf(solver->appliedField(), solver->time()));
  const DistributedSolveReport rep = solve.solve();
  const std::vector<double> phi = solve.gatherPotential(0);
  if (rank != 0) return rep.converged ? 0 : 1;

  std::printf("%s\n%s\n", solve.describe().c_str(), rep.summary().c_str());
  FieldSolveReport given;
  given.status = rep.trivial ? SolveStatus::Trivial : rep.converged ? SolveStatus::Converged : SolveStatus::IterationCap;
  given.newtonIterations = rep.newtonIterations;
  given.cgIterations = rep.linearIterations;
  given.relativeResidual = rep.relativeResidual;
  given.seconds = rep.seconds;
  given.message = rep.summary();
  MagneticForceStage stage(grid, law->magnetic, settings);
  const MagneticStageReport stageRep = stage.runOnPotential(n.view(), GridView<const double>{phi.data(), grid},
                                                            given, solver->appliedField(), solver->time());
  std::printf("%s", stageRep.summary().c_str());
  VdbFrameMetadata meta;
  meta.frame = frame;
  meta.time = solver->time();
  writeFieldsVdb(o.out, stage, meta);
  std::printf("wrote %s (frame %d, t = %g s)\n", o.out.c_str(), frame, solver->time());
  return rep.converged ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  PetscSession session(&argc, &argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  Options o;
  CLI::App app("The field solve of a scene's initial state across MPI ranks (PETSc), written as OpenVDB grids "
               "n, phi, H, M, B and force. Run it under mpirun -n N.",
               "lodestone-dist-field");
  cli::helpLayout(app, 24);
  app.add_option("scene", o.scene, "scene file (.json)")->required();
  app.add_option("--out", o.out, "output .vdb file")->required();
  app.add_option("--frame", o.frame, "scene frame (default: the initial state); the MPM runs split over the ranks");
  app.add_option("--density", o.density, "read n (1/m^3) from this .vdb instead of depositing the particles");
  app.add_option("--density-grid", o.densityGrid, "grid name in --density")->default_str(o.densityGrid);
  app.add_option("--pc", o.pc, "preconditioner of the CG solves")
      ->check(cli::oneOf({"mg", "gamg", "hypre"}))
      ->default_str(o.pc);
  cli::addNumber(app, "--tolerance", o.tolerance, "Newton stop: relative residual (default: the scene's)")
      ->check(cli::numberIn(1e-14, 1e-2));
  // PETSc's own options (-snes_monitor, -ksp_view, ...) pass through.
  app.allow_extras();
  if (const auto code = cli::parse(app, argc, argv)) return rank == 0 ? *code : 0;
  try {
    return run(o, rank);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone-dist-field (rank %d): %s\n", rank, e.what());
    MPI_Abort(MPI_COMM_WORLD, 2);
    return 2;
  }
}
