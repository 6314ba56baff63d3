// The scene summary and the substep limit. See scene_summary.h.
#include "scene_summary.h"

#include <cstdio>
#include <string>

#include "lodestone/core/base/error.h"
#include "plan_report.h"

namespace lodestone::examples {

using namespace lodestone::plugin;

namespace {

/// Substeps per frame the time step takes: time.dt's, or (CFL) the first
/// step's, which changes as the material moves.
std::string substepText(const Scene& scene, const MpmSolver& solver) {
  char text[256];
  const double n = substepsPerFrame(scene, solver);
  std::snprintf(text, sizeof text, "%s = %.3g s takes %.4g substeps per frame of %.4g s (%.4g for the %d frames)",
                scene.settings.fixedDt > 0 ? "time.dt" : "the first CFL step", solver.suggestedDt(), n,
                scene.frameDuration(), n * scene.frames, scene.frames);
  return text;
}

}  // namespace

void checkSubsteps(const Args& a, const Scene& scene, const MpmSolver& solver) {
  if (substepsPerFrame(scene, solver) > double(a.maxSubsteps))
    throw InvalidArgument(concat(a.scene, ": ", substepText(scene, solver), ", more than --max-substeps ",
                                 a.maxSubsteps, ": raise time.dt (or lower the scene's stiffness), or allow them with "
                                                "--max-substeps N"));
  const int limit = scene.settings.maxSubsteps;
  if (limit > 0 && substepsPerFrame(scene, solver) > double(limit))
    throw InvalidArgument(concat(a.scene, ": ", substepText(scene, solver), ", more than time.max_substeps ", limit,
                                 ": raise time.dt (or lower the scene's stiffness), or raise time.max_substeps"));
}

void printSceneSummary(const Scene& scene, const MpmSolver& solver) {
  const GridSpec& g = scene.settings.grid;
  std::printf("scene '%s' (%s)\n", scene.name.c_str(), scene.file.c_str());
  if (!scene.description.empty()) std::printf("  %s\n", scene.description.c_str());
  std::printf("  grid %d x %d x %d nodes, dx = %.4g m, origin (%.4g, %.4g, %.4g) m\n", g.dims.i, g.dims.j, g.dims.k,
              g.dx, g.origin.x, g.origin.y, g.origin.z);
  std::printf("  %zu particles, %zu materials, %zu magnets, %zu colliders, %zu applied fields\n",
              solver.totalParticles(), solver.materials().size(), solver.magnetCount(), solver.colliderCount(),
              scene.fields.size());
  for (std::size_t m = 0; m < scene.materials.size(); ++m)
    std::printf("  material '%s': %s\n", scene.materialNames[m].c_str(), scene.materials[m].describe().c_str());
  const double end = solver.time() + scene.frames * scene.frameDuration();
  for (std::size_t e = 0; e < solver.emitterCount(); ++e)
    std::printf("  emitter '%s' (%s): %s; up to %.0f particles by t = %.4g s\n", scene.emitters[e].name.c_str(),
                scene.materialNames[solver.emitter(e).materialIndex()].c_str(), solver.emitter(e).describe().c_str(),
                solver.emitter(e).particlesBy(end) - solver.emitter(e).particlesBy(solver.time()), end);
  std::printf("  %d frames at %.4g fps; %s; field solved %s\n", scene.frames, scene.fps,
              scene.settings.fixedDt > 0 ? concat("dt = ", scene.settings.fixedDt, " s").c_str()
                                         : concat("CFL ", scene.settings.cfl, ", dt <= ", scene.settings.dtMax, " s").c_str(),
              scene.settings.magneticSolveInterval == 0
                  ? (scene.settings.magneticSolveDistance > 0
                         ? concat("once per frame and whenever material or a magnet moved ",
                                  scene.settings.magneticSolveDistance, " cells")
                         : std::string("once per frame"))
                        .c_str()
                  : concat("every ", scene.settings.magneticSolveInterval, " substeps").c_str());
  std::printf("  frames %d..%d from the initial state, frame %d at t = %.6g s (frame f ends at t = f / fps)\n",
              scene.startFrame, scene.lastFrame(), scene.initialFrame(), scene.startTime());
  std::printf("  %s\n", substepText(scene, solver).c_str());
}

}  // namespace lodestone::examples
