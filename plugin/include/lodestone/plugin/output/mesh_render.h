#pragma once
// Previews of a material's surface: the one renderer of particle_render.h
// drawing a TriangleMesh (shaded with its vertex normals), the magnets and
// colliders as primitives, and field lines as polylines coloured by |B|.
#include <vector>

#include "lodestone/core/base/triangle_mesh.h"
#include "lodestone/core/stage/field_lines.h"
#include "lodestone/plugin/output/colormap.h"
#include "lodestone/plugin/output/particle_render.h"

namespace lodestone::output {

struct MeshRenderSettings {
  RenderSettings render;
  Rgb meshColour{70, 130, 200};
  Colormap fieldLineColours = Colormap::Inferno;  ///< over log |B|, from the lines' smallest to largest |B|
};

/// Field lines as polylines, each vertex coloured by log |B| between the
/// smallest and the largest positive |B| of all the lines (one colour,
/// the map's top, when they are equal).
std::vector<Polyline> fieldLinePolylines(const std::vector<FieldLine>& lines, Colormap map = Colormap::Inferno);

/// Renders `mesh` with the primitives and the field lines (empty: none).
/// Throws as renderScene does.
RgbImage renderMesh(const Camera& camera, const TriangleMesh& mesh, const std::vector<Primitive>& primitives,
                    const std::vector<FieldLine>& fieldLines = {}, const MeshRenderSettings& settings = {},
                    RenderStats* stats = nullptr);

}  // namespace lodestone::output
