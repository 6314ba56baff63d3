#pragma once
// Triangle meshes (lodestone::TriangleMesh) as files: binary PLY (through the
// one PLY writer, ply_writer.h) and Wavefront OBJ text, written atomically.
//
// PLY: vertex properties x y z (m), nx ny nz (unit normal, when the mesh has
// normals), vx vy vz (m/s, when it has velocities), then the faces
// (`vertex_indices`, counter-clockwise seen from outside).
// OBJ: `v x y z` (m), `vn` per vertex when the mesh has normals, and faces
// `f a//a b//b c//c` (1-based; `f a b c` without normals). OBJ has no
// per-vertex velocity; use the PLY for motion blur.
#include <string>

#include "lodestone/core/base/triangle_mesh.h"
#include "lodestone/plugin/output/ply_writer.h"

namespace lodestone::output {

/// The mesh as a PLY (vertices, normals and velocities when present, faces).
/// Throws InvalidArgument for a non-finite vertex, a normal or velocity
/// array of the wrong length or a vertex index out of range.
PlyPointCloud meshPly(const TriangleMesh& mesh);
/// meshPly(mesh) with a header comment, written to `path`.
void writeMeshPly(const std::string& path, const TriangleMesh& mesh, const std::string& comment = "");
/// The mesh as OBJ text; `comment` (one line) heads it when not empty.
std::string meshObj(const TriangleMesh& mesh, const std::string& comment = "");
void writeMeshObj(const std::string& path, const TriangleMesh& mesh, const std::string& comment = "");

}  // namespace lodestone::output
