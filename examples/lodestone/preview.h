#pragma once
// Per-frame preview of a simulation state: particles shaded by material
// (magnetic materials dark, like ferrofluid), magnets drawn as solid shapes
// (red north half is not modelled: one colour), colliders as wireframes, over
// a ground grid at the bottom of the domain.
#include <string>

#include "lodestone/plugin/output/colormap.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/plugin/scene.h"

namespace lodestone::examples {

/// Renders the solver's current state as the scene's output settings ask.
output::RgbImage renderPreview(const plugin::Scene& scene, const MpmSolver& solver);

}  // namespace lodestone::examples
