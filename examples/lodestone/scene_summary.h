#pragma once
// What a scene builds, printed for people (run, validate, plan), and the
// refusal of a time step that takes too many substeps per frame.
#include "command_args.h"
#include "lodestone/plugin/scene.h"

namespace lodestone::examples {

/// Refuses a time step that needs more than --max-substeps (or the scene's
/// time.max_substeps) substeps per frame.
void checkSubsteps(const Args& a, const plugin::Scene& scene, const MpmSolver& solver);

/// The scene's grid, particles, materials, emitters, frames and time step.
void printSceneSummary(const plugin::Scene& scene, const MpmSolver& solver);

}  // namespace lodestone::examples
