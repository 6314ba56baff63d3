#pragma once
// A latitude-longitude triangle mesh of a sphere, with outward unit normals:
// the reference surface of the mesh-preview tests and benchmark.
#include <cmath>
#include <cstdint>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/triangle_mesh.h"

namespace lodestone::test {

/// Sphere of radius r (m) about c: rings + 1 latitude circles of `segments`
/// vertices (the poles repeated), 2 rings segments triangles.
inline TriangleMesh latLongSphere(const Vec3d& c, double r, int rings, int segments) {
  TriangleMesh m;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double th = kPi * i / rings, ph = 2 * kPi * j / segments;
      const Vec3d n{std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
      m.vertices.push_back(c + r * n);
      m.normals.push_back(n);
    }
  const auto at = [&](int i, int j) { return std::uint32_t(i * segments + (j % segments)); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return m;
}

}  // namespace lodestone::test
