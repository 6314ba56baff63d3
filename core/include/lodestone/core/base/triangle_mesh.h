#pragma once
// A triangle mesh: vertices (m) and triangles as 0-based vertex indices, with
// optional per-vertex normals and velocities (empty, or one per vertex). The
// one mesh type of the project: OBJ input (vdb_io), surface meshes of
// particles, mesh files and mesh previews all use it.
#include <array>
#include <cstdint>
#include <vector>

#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace base {

struct TriangleMesh {
  std::vector<Vec3d> vertices;                          ///< m
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< counter-clockwise seen from outside
  std::vector<Vec3d> normals;                           ///< unit, per vertex; empty when not computed
  std::vector<Vec3d> velocities;                        ///< m/s, per vertex; empty when not known

  /// Signed enclosed volume, m^3 (divergence theorem; positive for a closed
  /// mesh with outward, counter-clockwise faces).
  double volume() const;
};

}  // namespace base
}  // namespace lodestone
