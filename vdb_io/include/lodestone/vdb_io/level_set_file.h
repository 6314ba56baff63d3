#pragma once
// Level sets (signed-distance VDB grids) and OBJ meshes as the core's
// SampledSdf, the shape of level-set colliders and emitters. No OpenVDB types
// here (grid_conversion.h has the conversion from an openvdb::FloatGrid).
//
// A level set is accepted when it is a FloatGrid whose grid class is
// GRID_LEVEL_SET and whose transform is a uniform scale plus a translation
// (no rotation, shear or frustum). Its voxel (i,j,k) becomes node (i,j,k) of
// the SampledSdf, in the file's world frame (m), over the active voxels'
// bounding box grown by two voxels; inactive voxels give +-background (the
// narrow band's sign is kept, as OpenVDB's level-set tools leave it).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "lodestone/core/base/triangle_mesh.h"
#include "lodestone/core/mpm/sampled_sdf.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {

/// Reads level set `gridName` of the .vdb file `path`. Throws InvalidArgument
/// naming the file and the grid when the file cannot be read, the grid is
/// missing, not a FloatGrid, not of class level set, its transform is not a
/// uniform scale and translation, or it has no voxel inside (phi <= 0).
SampledSdf readLevelSetVdb(const std::string& path, const std::string& gridName = "surface");


/// Parses Wavefront OBJ text: `v x y z [w]` and `f a b c ...` lines (indices
/// 1-based, negative = relative to the end, `a/t/n` forms accepted; polygons
/// are triangulated as fans); other statements (vn, vt, o, g, s, usemtl,
/// mtllib, comments) are ignored. Throws InvalidArgument naming `sourceName`
/// and the line on a malformed number, an index out of range, a face with
/// fewer than 3 vertices, or a file without faces.
TriangleMesh parseObj(const std::string& text, const std::string& sourceName);
/// Reads and parses the .obj file `path`; throws InvalidArgument naming the file.
TriangleMesh readObj(const std::string& path);

/// Options of meshToSampledSdf.
struct MeshLevelSetOptions {
  double voxelSize = 0;  ///< m, > 0
  int halfWidth = 3;     ///< narrow-band half width, voxels (>= 1)
};

/// The closed, consistently oriented mesh as a level set
/// (openvdb::tools::meshToLevelSet), then as a SampledSdf. `who` names the
/// mesh in messages. Throws InvalidArgument on a bad voxel size or when the
/// mesh encloses no voxel.
SampledSdf meshToSampledSdf(const TriangleMesh& mesh, const MeshLevelSetOptions& options, const std::string& who);
/// readObj then meshToSampledSdf with voxel size `voxelSize` (m).
SampledSdf levelSetFromObj(const std::string& path, double voxelSize);

/// Writes the mesh's level set as a FloatGrid of class level set named
/// `gridName` to the .vdb file `path` (atomically), e.g. to convert once and
/// load with readLevelSetVdb.
void writeMeshLevelSetVdb(const std::string& path, const TriangleMesh& mesh, const MeshLevelSetOptions& options,
                          const std::string& gridName = "surface");

}  // namespace lodestone
