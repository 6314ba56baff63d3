#include "lodestone/plugin/output/mesh_render.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lodestone::output {

std::vector<Polyline> fieldLinePolylines(const std::vector<FieldLine>& lines, Colormap map) {
  double lo = std::numeric_limits<double>::infinity(), hi = 0;
  for (const FieldLine& l : lines)
    for (const double b : l.magnitude)
      if (std::isfinite(b) && b > 0) lo = std::min(lo, b), hi = std::max(hi, b);
  const double span = hi > lo ? std::log(hi / lo) : 0.0;
  std::vector<Polyline> out;
  for (const FieldLine& l : lines) {
    Polyline p;
    p.points = l.points;
    p.colours.reserve(l.points.size());
    for (const double b : l.magnitude)
      p.colours.push_back(mapColour(map, span > 0 && b > 0 ? std::log(b / lo) / span : 1.0));
    out.push_back(std::move(p));
  }
  return out;
}

RgbImage renderMesh(const Camera& camera, const TriangleMesh& mesh, const std::vector<Primitive>& primitives,
                    const std::vector<FieldLine>& fieldLines, const MeshRenderSettings& settings, RenderStats* stats) {
  SceneContent content;
  content.meshes.push_back({&mesh, settings.meshColour});
  content.primitives = primitives;
  content.polylines = fieldLinePolylines(fieldLines, settings.fieldLineColours);
  return renderScene(camera, content, settings.render, stats);
}

}  // namespace lodestone::output
