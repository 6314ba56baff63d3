#pragma once
// A field solve of a solver's state outside its substeps, and the OpenVDB
// file of a magnetic stage's grids (export-fields; run's fields output).
#include <memory>
#include <string>
#include <vector>

#include "lodestone/plugin/scene.h"

namespace lodestone::examples {

/// The law of the solver's magnetic materials (null when there is none).
const MpmMaterial* magneticLaw(const MpmSolver& solver);

/// One field solve of the solver's state through the stage's public entry
/// points, on the scene's magnetic grid: of the magnetic particles, or of the
/// density n (1/m^3) of `density` (a .vdb file, grid `densityGrid`) when
/// given. The solver must have a magnetic material.
std::unique_ptr<MagneticForceStage> solveFieldsNow(const plugin::Scene& scene, const MpmSolver& solver,
                                                   MagneticStageReport& report, const std::string& density = "",
                                                   const std::string& densityGrid = "n",
                                                   const std::vector<Vec3d>* cacheX = nullptr,
                                                   const std::vector<double>* cacheN = nullptr);

/// The grids of the scene's output.vdb (sceneGrids) or the six field grids
/// n, phi, H, M, B and force (export-fields). `solver` (may be null)
/// supplies the MPM grid's mass and velocity when the scene's output.vdb
/// lists them.
void writeFields(const std::string& path, const plugin::Scene& scene, const MagneticForceStage& stage, int frame,
                 double time, const MpmSolver* solver, bool sceneGrids);

}  // namespace lodestone::examples
