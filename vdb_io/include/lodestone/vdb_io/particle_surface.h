#pragma once
// Surfaces and render volumes from material points, with OpenVDB's own tools
// (docs/vdb.md, "Render outputs"). This header's API is made of OpenVDB
// types, like grid_conversion.h; render_files.h offers the per-frame files
// without OpenVDB in the interface.
//
// Two ways to a level set (negative inside, distance in m):
//  * Splat: tools::ParticlesToLevelSet with each particle's radius (the
//    sphere of its current volume J V0, times radiusScale), then
//    tools::LevelSetFilter: dilate by `closing` voxels, Gaussian of width
//    `smoothing` voxels, erode by `closing` voxels.
//  * SmoothedDensity: the particles' volume fraction (each particle's volume
//    spread with a quadratic B-spline of width kernelWidth times its cube
//    edge V^(1/3), normalised so that it keeps its volume exactly) and its
//    1/2 contour rebuilt as a level set (tools::levelSetRebuild). The kernel
//    is the smoothing: the surface is a smooth function of the particle
//    positions, lies half a spacing beyond a flat layer of particles, and
//    moves less from frame to frame than the union of spheres when material
//    moves (figures in docs/vdb.md).
// Every grid uses the linear transform of voxel size `voxelSize` at the
// origin: voxel (i,j,k) is centred at voxelSize * (i,j,k).
#include <cstdint>
#include <string>
#include <vector>

#include <openvdb/openvdb.h>

#include "lodestone/core/base/triangle_mesh.h"
#include "lodestone/core/base/vec3.h"
#include "lodestone/core/mpm/particles.h"

namespace lodestone {

/// The particle data surfacing needs.
struct SurfaceParticles {
  std::vector<Vec3d> x;                 ///< position, m
  std::vector<Vec3d> v;                 ///< velocity, m/s
  std::vector<double> volume;           ///< current volume J V0, m^3 (> 0)
  std::vector<std::uint32_t> material;  ///< material index
  std::size_t size() const { return x.size(); }
};
SurfaceParticles surfaceParticles(const MpmParticles& particles);
/// The particle spacing, m: the cube root of the mean particle volume (the
/// default voxel size; 0 without particles).
double particleSpacing(const SurfaceParticles& particles);

enum class SurfaceMethod { Splat, SmoothedDensity };
/// "splat", "density".
const char* surfaceMethodName(SurfaceMethod method);
/// The method named `name`; throws InvalidArgument naming the bad name.
SurfaceMethod surfaceMethodFromName(const std::string& name);

struct SurfaceOptions {
  double voxelSize = 0;  ///< m, > 0
  SurfaceMethod method = SurfaceMethod::SmoothedDensity;
  double radiusScale = 1.0;  ///< splat: sphere radius / radius of the particle's volume, 0.5 .. 4
  int smoothing = 1;         ///< splat: Gaussian filter width, voxels, 0 .. 4 (0: none)
  int closing = 1;           ///< splat: dilation then erosion, voxels, 0 .. 4
  double kernelWidth = 1.5;  ///< density: kernel width / cube edge of the particle's volume, 1 .. 4
  int halfWidth = 3;  ///< narrow band half width, voxels, 2 .. 8
  /// Throws InvalidArgument naming the bad value, prefixed with `who`.
  void check(const std::string& who) const;
};

/// The particles' volume fraction (1) and volume-weighted velocity sums on
/// voxels of size `voxelSize` (m), kernel of width `kernelWidth` particle
/// sizes as SmoothedDensity above.
struct ParticleVolumeGrids {
  openvdb::FloatGrid::Ptr fraction;    ///< sum of V w / voxel^3 (not clamped); sums to the particles' volume
  openvdb::Vec3fGrid::Ptr momentum;    ///< sum of V w v / voxel^3, m/s
};
/// Of the particles whose index is in `subset` (null: all).
ParticleVolumeGrids particleVolumeGrids(const SurfaceParticles& particles, double voxelSize, double kernelWidth,
                                        const std::vector<std::size_t>* subset = nullptr);

/// The level set (class level set, named `name`) of the particles in
/// `subset` (null: all); null when the subset is empty.
openvdb::FloatGrid::Ptr particleLevelSet(const SurfaceParticles& particles, const SurfaceOptions& options,
                                         const std::string& name, const std::vector<std::size_t>* subset = nullptr);

/// The zero crossing of `levelSet` as triangles (tools::volumeToMesh, quads
/// split), counter-clockwise seen from outside, with unit per-vertex normals
/// (the level set's gradient) and, when `volumes` is given, per-vertex
/// velocities (m/s: the kernel-weighted mean of the particles' velocities).
TriangleMesh levelSetMesh(const openvdb::FloatGrid& levelSet, const ParticleVolumeGrids* volumes = nullptr);

/// Volume (m^3) inside the level set (tools::levelSetVolume).
double levelSetVolume(const openvdb::FloatGrid& levelSet);

/// How much a surface changed between two frames, in voxels of `before`:
/// over the voxels of `before` within one voxel of its zero crossing, the
/// difference after(x + shift) - before(x) (trilinear; `shift`, m, is the
/// motion of a rigidly moving body, zero for material at rest).
struct SurfaceChange {
  double rms = 0;   ///< root mean square, voxels
  double max = 0;   ///< largest magnitude, voxels
  std::size_t samples = 0;
};
SurfaceChange surfaceChange(const openvdb::FloatGrid& before, const openvdb::FloatGrid& after,
                            const Vec3d& shift = {});

}  // namespace lodestone
