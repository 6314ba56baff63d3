#include "field_line_output.h"

#include <filesystem>

#include "lodestone/core/base/error.h"
#include "lodestone/core/stage/induction_field.h"
#include "lodestone/plugin/output/field_line_files.h"

namespace lodestone::examples {

std::vector<FieldLine> solverFieldLines(const plugin::Scene& scene, const MpmSolver& solver,
                                        const FieldLineOptions& options) {
  const GridSpec& g = scene.settings.grid;
  const FieldSource& sources = solver.appliedField();
  const InductionField B = solver.magneticStage()
                               ? InductionField::ofStage(*solver.magneticStage(), sources, solver.time())
                               : InductionField(sources, solver.time());
  std::vector<const MagnetSource*> magnets;
  for (std::size_t i = 0; i < solver.magnetCount(); ++i) magnets.push_back(&solver.magnet(i));
  const MpmParticles& p = solver.particles();
  std::vector<Vec3d> material;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (solver.materials()[p.material[i]].isMagnetic()) material.push_back(p.x[i]);
  const std::vector<Vec3d> seeds = sceneFieldLineSeeds(magnets, material.data(), material.size(), g.dx,
                                                       options.seedsPerMagnet, options.materialSeeds);
  FieldLineSettings s;
  s.domainMin = g.origin;
  s.domainMax = g.maxCorner();
  s.separation = options.separationCells * g.dx;
  return traceFieldLines([&](const Vec3d& x) { return B(x); }, seeds, s);
}

void writeFieldLineFiles(const std::string& dir, const std::string& number, const std::vector<FieldLine>& lines,
                         const plugin::Scene& scene, int frame, double time) {
  const std::string comment = concat("lodestone ", LODESTONE_VERSION_STRING, " scene ", scene.name, " frame ", frame,
                                     " time ", time, " s, ", lines.size(), " lines");
  const std::filesystem::path base = std::filesystem::path(dir) / ("field_lines_" + number);
  output::writeFieldLines(base.string() + ".ply", lines, comment);
  output::writeFieldLines(base.string() + ".obj", lines, comment);
}

}  // namespace lodestone::examples
