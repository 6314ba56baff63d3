// A field solve of a state and the .vdb file of its grids. See field_export.h.
#include "field_export.h"

#include <algorithm>
#include <cstdio>

#include "lodestone/core/base/error.h"
#if LODESTONE_HAVE_VDB
#include "lodestone/vdb_io/field_file.h"
#endif

namespace lodestone::examples {

using namespace lodestone::plugin;

#if LODESTONE_HAVE_VDB
namespace {

/// The MPM grid's node mass (kg) and velocity (m/s) after the last substep;
/// zero outside the box the last transfer touched (all zero before the first).
void mpmGridData(const MpmSolver& solver, DenseGrid<double>& mass, DenseGrid<Vec3d>& velocity) {
  const MpmGrid& g = solver.grid();
  const GridSpec& s = g.spec();
  mass.reset(s, 0.0);
  velocity.reset(s, Vec3d{});
  if (g.nodes().size() != s.nodeCount() || g.velocity().size() != s.nodeCount()) return;
  const Index3 lo = g.activeLo(), hi = g.activeHi();
  for (int k = lo.k; k < hi.k; ++k)
    for (int j = lo.j; j < hi.j; ++j) {
      int first = 0, end = 0;  // every node outside the row's run is zero
      g.activeRun(j, k, first, end);
      for (int i = first; i < end; ++i) {
        const std::size_t n = g.nodeIndex(i, j, k);
        if (!(g.nodes()[n].mass > 0)) continue;
        mass(i, j, k) = g.nodes()[n].mass;
        velocity(i, j, k) = g.velocity()[n];
      }
    }
}

}  // namespace
#endif

void writeFields(const std::string& path, const Scene& scene, const MagneticForceStage& stage, int frame,
                 double time, const MpmSolver* solver, bool sceneGrids) {
#if LODESTONE_HAVE_VDB
  VdbWriteOptions o;
  const auto listed = [&](const char* g) {
    return sceneGrids && std::find(scene.output.vdbFields.begin(), scene.output.vdbFields.end(), g) !=
                             scene.output.vdbFields.end();
  };
  const auto has = [&](const char* g) { return !sceneGrids || scene.output.vdbFields.empty() || listed(g); };
  o.fields = {has("n"), has("phi"), has("H"), has("M"), has("B"), has("force")};
  o.fields.mass = listed("mass");
  o.fields.velocity = listed("velocity");
  o.displayAliases = sceneGrids && scene.output.vdbAliases;
  if (solver && solver->partition() && (o.fields.mass || o.fields.velocity)) {
    // Several processes: rank 0 holds only its window of the MPM grid.
    static bool said = false;
    if (!said)
      std::fprintf(stderr, "lodestone: %s: the MPM grids (mass, velocity) are not written on several processes\n",
                   path.c_str());
    said = true;
    o.fields.mass = o.fields.velocity = false;
  }
  DenseGrid<double> mass;
  DenseGrid<Vec3d> velocity;
  if (solver && !solver->partition() && (o.fields.mass || o.fields.velocity || o.displayAliases)) {
    mpmGridData(*solver, mass, velocity);
    o.mpm = {mass.view(), velocity.view()};
  }
  require(solver || !(o.fields.mass || o.fields.velocity), path, ": the mass and velocity grids need a simulated state");
  VdbFrameMetadata meta;
  meta.frame = frame;
  meta.time = time;
  writeFieldsVdb(path, stage, meta, o);
#else
  (void)scene, (void)stage, (void)frame, (void)time, (void)solver, (void)sceneGrids;
  throw Error(concat("cannot write ", path, ": this lodestone was built without OpenVDB"));
#endif
}

const MpmMaterial* magneticLaw(const MpmSolver& solver) {
  for (const MpmMaterial& m : solver.materials())
    if (m.isMagnetic()) return &m;
  return nullptr;
}

std::unique_ptr<MagneticForceStage> solveFieldsNow(const Scene& scene, const MpmSolver& solver,
                                                   MagneticStageReport& report, const std::string& density,
                                                   const std::string& densityGrid,
                                                   const std::vector<Vec3d>* cacheX,
                                                   const std::vector<double>* cacheN) {
  const MpmMaterial* law = magneticLaw(solver);
  if (!law)
    throw InvalidArgument(concat(scene.file, ": the scene has no magnetic material; there is no field to solve"));
  const GridSpec grid = scene.settings.magneticGrid ? *scene.settings.magneticGrid : scene.settings.grid;
  MagneticStageSettings settings = scene.settings.magnetic;
  settings.outOfGrid = OutOfGridPolicy::Skip;
  auto stage = std::make_unique<MagneticForceStage>(grid, law->magnetic, settings);
  if (!density.empty()) {
    // A host's own particle-to-grid transfer: n (1/m^3) on the field grid.
#if LODESTONE_HAVE_VDB
    const DenseGrid<double> n = readDensityVdb(density, grid, densityGrid);
    report = stage->runOnDensity(n.view(), solver.appliedField(), solver.time());
#else
    (void)densityGrid;
    throw Error(concat("cannot read ", density, ": this lodestone was built without OpenVDB"));
#endif
  } else if (cacheX) {
    report = stage->run({cacheX->data(), cacheN->data(), cacheX->size()}, solver.appliedField(), solver.time());
  } else {
    const MpmParticles& p = solver.particles();
    std::vector<Vec3d> x;
    std::vector<double> n;
    for (std::size_t i = 0; i < p.size(); ++i)
      if (solver.materials()[p.material[i]].isMagnetic()) {
        x.push_back(p.x[i]);
        n.push_back(p.count[i]);
      }
    report = stage->run({x.data(), n.data(), x.size()}, solver.appliedField(), solver.time());
  }
  return stage;
}

}  // namespace lodestone::examples
