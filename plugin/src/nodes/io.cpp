// Nodes that write a solve's or a simulation's files.
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "lodestone/core/stage/field_lines.h"
#include "lodestone/core/stage/induction_field.h"
#include "lodestone/plugin/node_builders.h"
#include "lodestone/plugin/output/field_line_files.h"

#include "library.h"

namespace lodestone::plugin::nodes {

namespace {

// ---- Render outputs --------------------------------------------------------------------
/// A node that writes render outputs of a simulation's current particles:
/// `fileParams`, then the surfacing parameters; `paths` picks the files.
NodeDecl renderOutputNode(std::string type, std::string label, std::string help, std::vector<ParamDecl> fileParams,
                          std::function<RenderOutputPaths(const ParamSet&)> paths) {
  NodeDecl d = declareNode(std::move(type), std::move(label), "io", std::move(help));
  d.params = std::move(fileParams);
  addSurfaceParams(d.params);
  d.inputs = {{"simulation", PortType::Simulation, "A simulation; its current particles are surfaced."}};
  d.outputs = {{"simulation", PortType::Simulation, "The input, unchanged (after the files are written)."}};
  d.cook = [paths](const CookContext& c) {
    const auto sim = c.input<SimulationData>("simulation");
    writeRenderOutputs(paths(c.params()), sim->solver->particles(), {}, surfaceSettingsFrom(c.params()),
                       sim->startFrame + sim->frames - 1, sim->time);
    return CookOutputs{{"simulation", NodeValue(sim)}};
  };
  return d;
}

}  // namespace

// ---- VDB export ------------------------------------------------------------------------
NodeDecl vdbExportNode() {
  NodeDecl d = declareNode(
      "vdb_export", "VDB Export", "io",
      "Writes the fields of a solve (n, phi, H, M, B, force) to one .vdb file (docs/vdb.md); needs OpenVDB.");
  auto& q = d.params;
  q.push_back(required(stringParam("path", "Path", "fields.vdb", "File to write (atomically).")));
  q.push_back(boolParam("double_precision", "Double precision", false, "Write DoubleGrid/Vec3dGrid instead of float."));
  d.inputs = {{"field", PortType::Field, "A solved field."}};
  d.outputs = {{"field", PortType::Field, "The input, unchanged (after the file is written)."}};
  d.cook = [](const CookContext& c) {
    const auto field = c.input<FieldData>("field");
    writeStageVdb(c.params().getString("path"), *field->stage, field->report.summary(),
                  c.params().getBool("double_precision"));
    return CookOutputs{{"field", NodeValue(field)}};
  };
  return d;
}

// ---- field lines -----------------------------------------------------------------------
NodeDecl fieldLinesNode() {
  NodeDecl d = declareNode(
      "field_lines", "Field Lines", "io",
      "Traces lines of the magnetic induction B of a solve (its nodal B inside the grid plus the sources' closed "
      "form) from seeds spread on the magnets and on the material's boundary, and writes them as a .ply (vertices "
      "with |B| in T, edges) or .obj (l polylines) file (docs/vdb.md). Lines close, leave the grid's box or stop at "
      "10 box diagonals.");
  auto& q = d.params;
  q.push_back(required(stringParam("path", "Path", "field_lines.ply", "File to write (.ply or .obj, atomically).")));
  q.push_back(
      intParam("seeds_per_magnet", "Seeds per magnet", 24, 0, 100000, "Seeds spread on each magnet's surface."));
  q.push_back(intParam("material_seeds", "Material seeds", 48, 0, 100000,
                       "Seeds spread on the boundary of the material (nodes with density > 0)."));
  q.push_back(range(floatParam("separation", "Separation", 0.5, "cells",
                               "A seed closer than this to a line traced before is dropped (in grid cells)."),
                    0, 1000));
  q.push_back(range(floatParam("max_turn", "Max turn", FieldLineSettings().maxTurn, "rad",
                               "Largest turn of B's direction over one step (polyline smoothness)."),
                    1e-3, 1.0));
  q.push_back(floatParam("time", "Time", 0.0, "s", "Time at which the sources are evaluated (the solve's)."));
  d.inputs = {{"field", PortType::Field, "A solved field."},
              {"sources", PortType::Sources, "The sources of that solve (none: no field).", true, true}};
  d.outputs = {{"field", PortType::Field, "The input, unchanged (after the file is written)."}};
  d.cook = [](const CookContext& c) {
    const auto field = c.input<FieldData>("field");
    const SourcesData sources = mergeSources(c.inputs("sources"));
    const double time = c.params().getFloat("time");
    const MagneticForceStage& stage = *field->stage;
    const GridSpec& g = stage.grid();
    const InductionField B = InductionField::ofStage(stage, sources.all(), time);
    std::vector<const MagnetSource*> magnets;
    for (const SourcesData::Magnet& m : sources.magnets) magnets.push_back(m.magnet.get());
    std::vector<Vec3d> material;
    const GridView<const double> n = stage.density();
    for (int k = 0; k < g.dims.k; ++k)
      for (int j = 0; j < g.dims.j; ++j)
        for (int i = 0; i < g.dims.i; ++i)
          if (n(i, j, k) > 0) material.push_back(g.nodePosition(i, j, k));
    const std::vector<Vec3d> seeds = sceneFieldLineSeeds(magnets, material.data(), material.size(), g.dx,
                                                         std::size_t(c.params().getInt("seeds_per_magnet")),
                                                         std::size_t(c.params().getInt("material_seeds")));
    FieldLineSettings s;
    s.domainMin = g.origin;
    s.domainMax = g.maxCorner();
    s.separation = c.params().getFloat("separation") * g.dx;
    s.maxTurn = c.params().getFloat("max_turn");
    const std::vector<FieldLine> lines = traceFieldLines([&](const Vec3d& x) { return B(x); }, seeds, s);
    output::writeFieldLines(c.params().getString("path"), lines, concat(lines.size(), " lines, t = ", time, " s"));
    return CookOutputs{{"field", NodeValue(field)}};
  };
  return d;
}

NodeDecl surfaceNode() {
  return renderOutputNode(
      "surface", "Surface",
      "Writes the level sets of the simulation's particles (surface for all material, surface_<material> per "
      "material) and, optionally, the render volumes (density as volume fraction, vel) to .vdb files "
      "(docs/vdb.md); needs OpenVDB.",
      {required(stringParam("path", "Path", "surface.vdb", "Level-set file to write (atomically).")),
       stringParam("volume_path", "Volume path", "",
                   "Also write density (volume fraction 0..1) and vel (m/s) to this .vdb file; empty: no.")},
      [](const ParamSet& p) {
        RenderOutputPaths paths;
        paths.surface = p.getString("path");
        paths.volume = p.getString("volume_path");
        return paths;
      });
}

NodeDecl meshExportNode() {
  return renderOutputNode(
      "mesh_export", "Mesh Export",
      "Writes the surface of the simulation's particles as a triangle mesh with per-vertex normals and "
      "velocities: binary PLY, or OBJ (no velocities) when the path ends in .obj; needs OpenVDB.",
      {required(stringParam("path", "Path", "mesh.ply", "Mesh file to write (.ply or .obj, atomically)."))},
      [](const ParamSet& p) {
        const std::string& path = p.getString("path");
        RenderOutputPaths paths;
        (path.size() >= 4 && path.compare(path.size() - 4, 4, ".obj") == 0 ? paths.meshObj : paths.meshPly) = path;
        return paths;
      });
}

}  // namespace lodestone::plugin::nodes
