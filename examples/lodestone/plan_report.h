#pragma once
// What the effects planner decided, for people and for stats.json: the
// mechanical stages (run or idle, from the scene's content) and the magnetic
// plan of MpmSolver::planMagneticNow / lastMagneticPlan (docs/planner.md).
#include <cstdio>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lodestone/core/planner/effects_planner.h"
#include "lodestone/plugin/scene.h"
#include "outputs.h"

namespace lodestone::examples {

/// Mechanical stages with nothing to do in this scene (no gravity, no
/// colliders, no fluid, no solid, no emitter on during the run) and why; the
/// MPM core is always on.
std::vector<StageDecision> mechanicsDecisions(const plugin::Scene& scene, const MpmSolver& solver);

/// When emitter `e` of `solver` is on over the scene's frames, in scene
/// frame numbers (time.start_frame on): "on in frames 1-30, idle in frames 31-48".
std::string emitterTimeline(const plugin::Scene& scene, const MpmSolver& solver, std::size_t e);

/// Substeps per frame with the scene's first substep (fixed, or the CFL step now).
double substepsPerFrame(const plugin::Scene& scene, const MpmSolver& solver);

/// A fluid compressed by more than this fraction under its pressure is warned about (dimensionless).
inline constexpr double kFluidCompressionLimit = 0.1;
/// The compression the advised bulk modulus gives (dimensionless).
inline constexpr double kFluidCompressionTarget = 0.05;

/// One warning per fluid material whose bulk modulus K lets its pressure
/// (hydrostatic rho |g| h over the material's height, plus mu0 W(peakField)
/// for a magnetic fluid, peakField the largest applied field at the material
/// in A/m) compress it by more than kFluidCompressionLimit; each names the
/// pressure, the compression, the advised K and its cost in substeps.
std::vector<std::string> fluidCompressionWarnings(const plugin::Scene& scene, const MpmSolver& solver,
                                                  double peakField);

/// Prints the estimated peak memory of a run of the scene (plugin::sceneMemory,
/// with `processBytes` what the process held besides: residentBytes() after
/// loadScene, which counts the scene's loaded meshes) writing `outputs`, by
/// part, against the limit:
/// "  estimated peak memory: 1.19 GiB: MPM grid 0.13, ... (GiB) for ...;
/// limit 18.8 GiB (80% of this machine's memory, 23.5 GiB)"; returns the
/// estimate.
plugin::MemoryEstimate printMemoryEstimate(const plugin::Scene& scene, const MpmSolver& solver, double processBytes,
                                           const OutputSelection& outputs, std::FILE* out);

/// Prints the plan of `solver` over the scene's whole time line (the
/// sources sampled at up to 16 frames, the material where it is now): every
/// stage, on or off, the reason, the predicted error; substeps and field
/// solves per frame, the estimated run time, and warnings (resolution, a
/// time step above the stable one, a field solved once per many substeps, a
/// fluid too soft for its pressure).
void printPlan(const plugin::Scene& scene, const MpmSolver& solver, std::FILE* out);

/// The decisions as JSON (stage, on, choice, reason, predicted_error, estimated_s).
nlohmann::json decisionsJson(const std::vector<StageDecision>& decisions);

/// A short string that changes when any decision's choice changes.
std::string planSignature(const MagneticPlan& plan);

}  // namespace lodestone::examples
