#include "lodestone/core/base/triangle_mesh.h"

namespace lodestone {
inline namespace base {

double TriangleMesh::volume() const {
  double sixV = 0;  // sum of a . (b x c) over the triangles = 6 V
  for (const auto& t : triangles) sixV += dot(vertices[t[0]], cross(vertices[t[1]], vertices[t[2]]));
  return sixV / 6;
}

}  // namespace base
}  // namespace lodestone
