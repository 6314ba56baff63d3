// lodestone: the command-line host. Runs scene files with the reference
// MLS-MPM and the magnetic-force stage, writes per-frame particles (PLY),
// previews (PNG) and stats.json. Its commands and options are declared in
// parseArgs() (command_args.cpp); `lodestone --help` and `lodestone COMMAND
// --help` print them.
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "lodestone/core/base/error.h"
#if LODESTONE_HAVE_DIST
#include "lodestone/dist/allocator_defaults.h"
#endif
#include "lodestone/plugin/node_registry.h"
#include "lodestone/plugin/scene.h"
#if LODESTONE_HAVE_VDB
#include "lodestone/vdb_io/point_file.h"
#endif
#include "command_args.h"
#include "farm_commands.h"
#include "field_export.h"
#include "plan_report.h"
#include "run_command.h"
#include "scene_summary.h"
#include "surface_command.h"

using namespace lodestone;
using namespace lodestone::examples;
using namespace lodestone::plugin;

namespace {

#if LODESTONE_HAVE_VDB
/// The magnetic particles of a cache file (x, n) and its frame and time.
ParticleVdbData magneticParticles(const std::string& path, const MpmSolver& solver, std::vector<Vec3d>& x,
                                  std::vector<double>& n) {
  ParticleVdbData d = readParticlesVdb(path);
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (d.material[i] >= solver.materials().size())
      throw InvalidArgument(concat(path, ": particle ", d.id[i], " has material ", d.material[i], " but the scene has ",
                                   solver.materials().size(), " materials: is it a cache of this scene?"));
    if (solver.materials()[d.material[i]].isMagnetic()) {
      x.push_back(d.x[i]);
      n.push_back(d.count[i]);
    }
  }
  return d;
}
#endif

int exportFields(const Args& a) {
  if (a.out.empty()) usageError("export-fields needs --out FILE.vdb");
  const Scene scene = loadScene(a.scene, a.options);
  if (!a.particles.empty()) {
    // A frame of a particle cache: its particles at its time, no simulation.
#if LODESTONE_HAVE_VDB
    auto solver = buildSolver(scene);
    std::vector<Vec3d> x;
    std::vector<double> n;
    const ParticleVdbData d = magneticParticles(a.particles, *solver, x, n);
    solver->setTime(d.time);
    MagneticStageReport rep;
    const std::unique_ptr<MagneticForceStage> stage = solveFieldsNow(scene, *solver, rep, "", "n", &x, &n);
    std::printf("%s", rep.summary().c_str());
    writeFields(a.out, scene, *stage, int(d.frame), d.time, nullptr, false);
    std::printf("wrote %s (frame %d, t = %g s, %zu magnetic particles of %s)\n", a.out.c_str(), int(d.frame), d.time,
                x.size(), a.particles.c_str());
    return rep.converged() ? 0 : 1;
#else
    throw Error(concat("cannot read ", a.particles, ": this lodestone was built without OpenVDB"));
#endif
  }
  const int frame = a.frameGiven ? a.frame : scene.initialFrame();
  if (frame < scene.initialFrame() || frame > scene.lastFrame())
    usageError(concat("--frame ", frame, ": the scene has ", scene.frames, " frames (", scene.startFrame, "..",
                      scene.lastFrame(), ") after its initial state, frame ", scene.initialFrame(),
                      "; N must be in ", scene.initialFrame(), "..", scene.lastFrame()));
  auto solver = buildSolver(scene);
  if (frame > scene.initialFrame()) checkSubsteps(a, scene, *solver);
  for (int f = scene.initialFrame(); f < frame; ++f) solver->advanceFrame(scene.frameDuration());
  MagneticStageReport rep;
  const std::unique_ptr<MagneticForceStage> stage = solveFieldsNow(scene, *solver, rep, a.density, a.densityGrid);
  std::printf("%s", rep.summary().c_str());
  writeFields(a.out, scene, *stage, frame, solver->time(), solver.get(), false);
  std::printf("wrote %s (frame %d, t = %g s)\n", a.out.c_str(), frame, solver->time());
  return rep.converged() ? 0 : 1;
}

int plan(const Args& a) {
  const Scene scene = loadScene(a.scene, a.options);
  const double loadedBytes = residentBytes();
  auto solver = buildSolver(scene);
  printSceneSummary(scene, *solver);
  printPlan(scene, *solver, stdout);
  printMemoryEstimate(scene, *solver, loadedBytes, OutputSelection::sceneDefault(scene.output), stdout);
  return 0;
}

int validate(const Args& a) {
  const Scene scene = loadScene(a.scene, a.options);
  const double loadedBytes = residentBytes();
  auto solver = buildSolver(scene);
  printSceneSummary(scene, *solver);
  requireFitsInMemory(concat("scene '", scene.name, "'"),
                      printMemoryEstimate(scene, *solver, loadedBytes, OutputSelection::sceneDefault(scene.output), stdout));
  if (substepsPerFrame(scene, *solver) > double(a.maxSubsteps))
    std::printf("warning: more than %lld substeps per frame: lodestone run refuses it without --max-substeps\n",
                a.maxSubsteps);
  std::printf("%s: valid\n", a.scene.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
#if LODESTONE_HAVE_DIST
  lodestone::dist::restoreAllocatorDefaults();
#endif
  try {
    Args a;
    if (const std::optional<int> code = parseArgs(argc, argv, a)) return *code;
    if (a.command == "nodes") {
      // The node library, generated from the node declarations.
      std::cout << (a.markdown ? plugin::nodesMarkdown() : plugin::nodesText());
      return 0;
    }
    if (a.command == "run") return run(a);
    if (a.command == "validate") return validate(a);
    if (a.command == "plan") return plan(a);
    if (a.command == "export-fields") return exportFields(a);
    if (const std::optional<int> code = runFarmCommand(a.command, a.farm)) return *code;
    if (a.command == "surface") {
#if LODESTONE_HAVE_VDB
      return surfaceCommand(a.surface);
#else
      throw Error("lodestone surface needs OpenVDB: this lodestone was built without it");
#endif
    }
    usageError(concat("unknown command '", a.command, "'"));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone: %s\n", e.what());
    return 1;
  }
}
