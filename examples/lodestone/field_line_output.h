#pragma once
// Field lines of a `lodestone run` frame (field_lines_NNNN.ply / .obj): B of
// the solver's magnetic stage (its nodal B inside the stage's grid plus the
// sources' closed form; the sources alone before the first field solve),
// traced in the MPM domain from seeds on the magnets and on the boundary of
// the magnetic material.
#include <string>
#include <vector>

#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/stage/field_lines.h"
#include "lodestone/plugin/scene.h"

namespace lodestone::examples {

struct FieldLineOptions {
  std::size_t seedsPerMagnet = 24;
  std::size_t materialSeeds = 48;
  double separationCells = 0.5;  ///< seeds this close (in MPM cells) to a line traced before are dropped
};

/// The lines of the solver's current state.
std::vector<FieldLine> solverFieldLines(const plugin::Scene& scene, const MpmSolver& solver,
                                        const FieldLineOptions& options = {});

/// Writes DIR/field_lines_NNNN.ply and .obj (NNNN: `number`) of `lines`.
void writeFieldLineFiles(const std::string& dir, const std::string& number, const std::vector<FieldLine>& lines,
                         const plugin::Scene& scene, int frame, double time);

}  // namespace lodestone::examples
