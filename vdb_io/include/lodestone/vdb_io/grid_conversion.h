#pragma once
// Conversion between core node grids and OpenVDB grids.
//
// Transform convention (node-centred): VDB voxel (i,j,k) in index space is
// grid node (i,j,k) in world space, i.e. the linear transform is
//   world = origin + dx * (i,j,k)      (scale by dx, then translate by origin)
// built by nodeCentredTransform(). VDB voxel *centres* are the node positions;
// nothing is shifted by half a cell.
//
// Sparsity: the background value is zero; nodes with |v| <= tolerance (absolute,
// in the field's own unit; |v| is the Euclidean length for vectors) stay
// inactive, and the tree is pruned. Tolerance 0 keeps every nonzero value.
//
// This header includes <openvdb/openvdb.h> because its API is made of OpenVDB
// types; field_file.h offers the same I/O without OpenVDB in the interface.
#include <string>

#include <openvdb/openvdb.h>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/mpm/sampled_sdf.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {

/// Calls openvdb::initialize() once (thread-safe). Every function here calls it.
void initializeVdb();

/// The node-centred linear transform of `spec`: scale(dx) then translate(origin).
/// Share the returned pointer among the grids of one frame.
openvdb::math::Transform::Ptr nodeCentredTransform(const GridSpec& spec);

/// Options for core -> VDB conversion.
struct VdbConversionOptions {
  double tolerance = 0;  ///< absolute; |v| <= tolerance stays inactive (background 0)
  openvdb::math::Transform::Ptr transform;  ///< null: nodeCentredTransform(spec)
  openvdb::VecType vecType = openvdb::VEC_INVARIANT;  ///< vector grids only
};

openvdb::FloatGrid::Ptr toVdbFloatGrid(GridView<const double> values, const std::string& name,
                                       const VdbConversionOptions& options = {});
openvdb::DoubleGrid::Ptr toVdbDoubleGrid(GridView<const double> values, const std::string& name,
                                         const VdbConversionOptions& options = {});
openvdb::Vec3fGrid::Ptr toVdbVec3fGrid(GridView<const Vec3d> values, const std::string& name,
                                       const VdbConversionOptions& options = {});
openvdb::Vec3dGrid::Ptr toVdbVec3dGrid(GridView<const Vec3d> values, const std::string& name,
                                       const VdbConversionOptions& options = {});

/// True when the grid's transform is exactly nodeCentredTransform(spec)
/// (uniform scale dx, translation origin, no rotation), so that voxel (i,j,k)
/// is node (i,j,k) bit for bit.
bool transformMatches(const openvdb::math::Transform& transform, const GridSpec& spec);

/// VDB -> dense grid over `spec`. When transformMatches(), values are read by
/// index (inactive voxels give the grid's background); otherwise each node is
/// sampled trilinearly in world space (openvdb::tools::BoxSampler).
/// Throws InvalidArgument naming the grid when its transform is not a
/// uniform-scale linear map, or when `spec` is invalid.
DenseGrid<double> toDenseGrid(const openvdb::FloatGrid& grid, const GridSpec& spec);
DenseGrid<double> toDenseGrid(const openvdb::DoubleGrid& grid, const GridSpec& spec);
DenseGrid<Vec3d> toDenseGrid(const openvdb::Vec3fGrid& grid, const GridSpec& spec);
DenseGrid<Vec3d> toDenseGrid(const openvdb::Vec3dGrid& grid, const GridSpec& spec);

/// Reads one grid from a .vdb file. The scalar reader accepts FloatGrid or
/// DoubleGrid, the vector reader Vec3fGrid or Vec3dGrid. Throws
/// InvalidArgument naming the file and the grid when the file is missing,
/// unreadable or corrupt, or the grid is absent or of another type.
openvdb::GridBase::Ptr readVdbScalarGrid(const std::string& path, const std::string& gridName);
openvdb::GridBase::Ptr readVdbVec3Grid(const std::string& path, const std::string& gridName);
/// Reads FloatGrid `gridName` (of any class); errors as the readers above.
openvdb::FloatGrid::Ptr readVdbFloatGrid(const std::string& path, const std::string& gridName);

/// A level set as a dense SampledSdf over its active voxels' bounding box
/// grown by two voxels (node (i,j,k) = voxel (i,j,k), world frame; inactive
/// voxels give the tree's value, +-background). Throws InvalidArgument,
/// prefixed with `who`, when the grid class is not GRID_LEVEL_SET, the
/// transform is not a uniform scale plus translation, the grid has no active
/// voxel, or no voxel is inside.
SampledSdf toSampledSdf(const openvdb::FloatGrid& levelSet, const std::string& who);

}  // namespace lodestone
