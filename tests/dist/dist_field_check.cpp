// The distributed field solve (dist/) against core's single-process solve,
// run under mpirun with 1, 2 and 4 ranks (tests labelled mpi):
//   sphere: the Langevin sphere of tests/core/test_field_solve.cpp (radius a,
//           box of half-width 2a, uniform H0 along z);
//   pair:   two Langevin balls side by side along x in a uniform field along
//           x, which attract each other.
// Both solves run to relative residual 1e-10; rank 0 then recovers the nodal
// fields and forces of the gathered distributed potential through the
// magnetic stage (MagneticForceStage::runOnPotential) and compares them with
// those of core's own solve. Prints the measured differences; exits 1 when
// one exceeds its bound.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <mpi.h>

#include "lodestone/core/field/material.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/core/stage/density_raster.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/dist/distributed_field_solve.h"
#include "lodestone/dist/petsc_session.h"
#include "lodestone_test/scenes.h"

using namespace lodestone;
using namespace lodestone::test;

namespace {

constexpr double kRadius = 0.05;  // m
constexpr double kTolerance = 1e-10;

struct Options {
  std::string scene = "sphere", wall = "open", pc = "mg";
  int nodes = 33;
  double H0 = 1e5;  // A/m
};

Options parse(int argc, char** argv) {
  Options o;
  for (int a = 1; a + 1 < argc; a += 2) {
    const std::string key = argv[a], value = argv[a + 1];
    if (key == "--scene") o.scene = value;
    else if (key == "--wall") o.wall = value;
    else if (key == "--pc") o.pc = value;
    else if (key == "--nodes") o.nodes = std::atoi(value.c_str());
    else if (key == "--H0") o.H0 = std::atof(value.c_str());
  }
  return o;
}

int run(const Options& o) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  const bool pair = o.scene == "pair";
  const BoundaryKind wall = o.wall == "shield" ? BoundaryKind::Shield : BoundaryKind::Open;
  const MagneticMaterial material = paperMaterial();
  const GridSpec g = cubeGrid(o.nodes, 2 * kRadius);
  const double r = pair ? 0.6 * kRadius : kRadius, offset = pair ? 0.9 * kRadius : 0.0;
  const auto inside = pair ? std::function<bool(const Vec3d&)>([&](const Vec3d& x) {
                               return norm(x - Vec3d{-offset, 0, 0}) < r || norm(x - Vec3d{offset, 0, 0}) < r;
                             })
                           : ball({}, r);
  const DenseGrid<double> n = rasterizeDensity(g, material.numberDensity, inside);
  const UniformField applied(pair ? Vec3d{o.H0, 0, 0} : Vec3d{0, 0, o.H0});

  DistributedSolveSettings ds;
  ds.tolerance = kTolerance;
  ds.preconditioner = parseDistributedPreconditioner(o.pc);
  DistributedFieldSolve solve(MPI_COMM_WORLD, g, material.law, wall, ds);
  solve.setMaterial(n.view(), appliedFieldOf(applied, 0.0));
  const DistributedSolveReport rep = solve.solve();
  const std::vector<double> phiDist = solve.gatherPotential(0);
  if (rank == 0) std::printf("%s\n%s\n", solve.describe().c_str(), rep.summary().c_str());
  if (rank != 0) return rep.converged ? 0 : 1;

  MagneticStageSettings settings;
  settings.boundary = wall;
  settings.solve.tolerance = kTolerance;
  MagneticForceStage core(g, material, settings), dist(g, material, settings);
  const MagneticStageReport coreRep = core.runOnDensity(n.view(), applied, 0.0);
  FieldSolveReport given;
  given.status = rep.converged ? SolveStatus::Converged : SolveStatus::IterationCap;
  dist.runOnPotential(n.view(), GridView<const double>{phiDist.data(), g}, given, applied, 0.0);
  std::printf("core: %s\n", coreRep.solve.message.c_str());

  double phiMax = 0, dPhi = 0, dH = 0;
  for (std::size_t m = 0; m < g.nodeCount(); ++m) {
    phiMax = std::max(phiMax, std::fabs(core.potential()[m]));
    dPhi = std::max(dPhi, std::fabs(core.potential()[m] - phiDist[m]));
    dH = std::max(dH, norm(core.field()[m] - dist.field()[m]));
  }
  const double phiRel = dPhi / phiMax, hRel = dH / o.H0;
  std::printf("max |phi_dist - phi_core| / max |phi_core| = %.3e\nmax |H_dist - H_core| / H0 = %.3e\n", phiRel, hRel);
  bool ok = rep.converged && coreRep.solve.converged() && phiRel < 1e-6 && hRel < 1e-6;
  if (pair) {
    // Force on each ball: the nodal forces on either side of x = 0.
    Vec3d fc[2], fd[2];
    for (int k = 0; k < o.nodes; ++k)
      for (int j = 0; j < o.nodes; ++j)
        for (int i = 0; i < o.nodes; ++i) {
          const double x = g.nodePosition(i, j, k).x;
          if (x == 0) continue;
          fc[x > 0] += core.nodalForce()(i, j, k);
          fd[x > 0] += dist.nodalForce()(i, j, k);
        }
    const double fRel = std::max(norm(fc[0] - fd[0]), norm(fc[1] - fd[1])) / norm(fc[0]);
    std::printf("force on the left ball: core (%.6e, %.3e, %.3e) N, distributed (%.6e, %.3e, %.3e) N\n", fc[0].x,
                fc[0].y, fc[0].z, fd[0].x, fd[0].y, fd[0].z);
    std::printf("max |F_dist - F_core| / |F_core| over the two balls = %.3e\n", fRel);
    ok = ok && fc[0].x > 0 && fc[1].x < 0 && fRel < 1e-6;  // they attract
  } else {
    double sc = 0, sd = 0;
    int count = 0;
    for (int k = 0; k < o.nodes; ++k)
      for (int j = 0; j < o.nodes; ++j)
        for (int i = 0; i < o.nodes; ++i)
          if (norm(g.nodePosition(i, j, k)) < 0.5 * kRadius) {
            sc += core.field()(i, j, k).z;
            sd += dist.field()(i, j, k).z;
            ++count;
          }
    const double exact = sphereInteriorField(material, o.H0);
    std::printf("mean interior H_z: core %.8e, distributed %.8e, closed form %.8e A/m (relative error %.3e)\n",
                sc / count, sd / count, exact, std::fabs(sd / count - exact) / (o.H0 - exact));
  }
  std::printf("%s\n", ok ? "PASS" : "FAIL");
  return ok ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  PetscSession session(&argc, &argv);
  try {
    return run(parse(argc, argv));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dist_field_check: %s\n", e.what());
    return 2;
  }
}
