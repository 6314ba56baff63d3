#pragma once
// Core objects built from node parameter values: the shared glue between the
// nodes' cooks and scene files (whose entries are nodes' parameters). Each
// builder is the only place its parameters become a core object.
#include <memory>
#include <optional>
#include <vector>

#include "lodestone/core/base/pose.h"
#include "lodestone/core/base/triangle_mesh.h"
#include "lodestone/core/mpm/collider.h"
#include "lodestone/core/mpm/emitter.h"
#include "lodestone/core/mpm/rate_emitter.h"
#include "lodestone/core/mpm/sampled_sdf.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/plugin/memory_estimate.h"
#include "lodestone/core/sources/field_source.h"
#include "lodestone/core/sources/magnet_source.h"
#include "lodestone/plugin/node_data.h"
#include "lodestone/plugin/param.h"

namespace lodestone::plugin {

/// A pose at `centre` (m) whose body z axis points along the unit vector `axis`.
Pose poseAlong(const Vec3d& centre, const Vec3d& axis);

/// Whether a shape choice is stored in a file ("level_set": a VDB level set,
/// "mesh": an OBJ mesh).
bool isFileShape(const std::string& shape);

/// The level set of a file shape: grid `grid` of a .vdb file, or an OBJ mesh
/// sampled at `voxelSize` (m). Throws NotBuilt without OpenVDB.
std::shared_ptr<const SampledSdf> loadShapeFile(const std::string& shape, const std::string& path,
                                                const std::string& grid, double voxelSize);

/// The emitter shape of particle_source parameters (shape, center, axis, sizes,
/// file). File shapes are placed by their own frame, turned by `axis`.
EmitterShape shapeFrom(const ParamSet& params);

/// The emission of particle_source parameters (cell_size, particles_per_cell,
/// jitter, seed, velocity).
EmitterSettings emitterSettingsFrom(const ParamSet& params);

/// The emission of particle_emitter parameters: the lattice (cell_size,
/// particles_per_cell, jitter, seed), the rate (rate, volume_rate,
/// particle_rate), the velocity (velocity in the world frame, or speed along
/// the axis), inherit_motion and the time line (start and end, or
/// intervals), with the emitter's `motion`. Throws InvalidArgument naming a
/// bad time line.
RateEmitterSettings rateEmitterSettingsFrom(const ParamSet& params, const ColliderMotion& motion);

/// The material points an emitter adds from scene time `start` to `end` (s)
/// when none is blocked, estimated from volumes before its lattice is built
/// (for the memory check): its points per second times its on-time within
/// [start, end], plus one chunk.
double estimatedEmittedParticles(const EmitterShape& shape, const RateEmitterSettings& settings, double start,
                                 double end);

/// The MPM material of material parameters (model, density, moduli, magnetic.*).
MpmMaterial materialFrom(const ParamSet& params);

/// The applied field of applied_field parameters (type, H, position, moment, file, grid, ramp).
std::unique_ptr<FieldSource> appliedFieldFrom(const ParamSet& params);

/// The collider shape and rest pose of collider parameters (shape, point, normal, center, axis, sizes, file, inverted).
ColliderShape colliderShapeFrom(const ParamSet& params, Pose& pose);

/// The boundary condition of `boundary` and `friction` parameters (named
/// `prefix` + "boundary" and so on: "domain." for the MPM walls).
BoundaryCondition boundaryFrom(const ParamSet& params, const std::string& prefix = "");

/// The field-solve settings of `boundary`, `tolerance`, `preconditioner` and
/// `max_newton_iterations` parameters (with `prefix`: "magnetic." for an
/// mpm_solver's stage); the other settings keep their defaults.
MagneticStageSettings solveSettingsFrom(const ParamSet& params, const std::string& prefix = "");

/// The magnet of magnet parameters (shape, sizes, magnetization or remanence) at `pose`.
std::unique_ptr<MagnetSource> makeMagnet(const ParamSet& params, const Pose& pose);

/// The motion of motion.velocity and motion.angular_velocity parameters
/// (m/s, rad/s about the body origin) from the rest pose; fixed when both are zero.
ColliderMotion motionFrom(const ParamSet& params, const Pose& rest);
/// The rigid-body settings of a collider or magnet node whose `dynamic` is
/// on (density, mass, restitution, contact_friction); empty when it is off.
std::optional<RigidBodySettings> rigidBodyFrom(const ParamSet& params);

/// A magnet node's magnet: the source at its pose (center, axis), its motion,
/// whether it is also a collider and its boundary condition; the rest pose
/// goes to `restPose` when given.
SourcesData::Magnet magnetFrom(const ParamSet& params, Pose* restPose = nullptr);

/// What the nodes of a grid hold, for its memory estimate.
enum class GridUse {
  MpmAndFieldSolve,  ///< unknown: counted as both (kMpmNodeBytes + kFieldNodeBytes)
  Mpm,               ///< the MPM grid (address space; memory where the material is, sceneMemory)
  FieldSolve,        ///< a field solve's grid (kFieldNodeBytes)
};

/// Throws TooLarge "<what>: a grid of a x b x c nodes at dx = h m [and N
/// particles] is too large (needs about G GiB at B B a node ...; limit ...)"
/// when the estimate (memory_estimate.h: the nodes at what `use` holds, each
/// particle counted as magnetic) exceeds memoryLimitBytes(), when an axis has
/// more than 2^20 nodes, or when an MPM grid has 2^32 - 1 stencil bins or
/// more: the guard before anything is allocated. An MPM grid alone
/// (GridUse::Mpm) reserves address space only: its memory follows the
/// material (sceneMemory), so only the particles count here.
/// Node counts are doubles, so a tiny dx or a huge count is named rather
/// than overflowing; a zero count leaves the grid out of the message.
void requireFitsInMemory(const std::string& what, const double nodes[3], double dx, double particles,
                         GridUse use = GridUse::MpmAndFieldSolve);

/// Throws TooLarge "<what> needs about G GiB: MPM grid ..., more than <limit>"
/// when the estimate exceeds memoryLimitBytes().
void requireFitsInMemory(const std::string& what, const MemoryEstimate& estimate);

/// The material points a body of `volume` (m^3) gets at `particlesPerCell`
/// in cells of `cellSize` (m): the estimate before emission.
double estimatedParticles(double volume, double cellSize, int particlesPerCell);

/// MPM settings of mpm_solver parameters (domain.*, time.*, gravity, magnetic.*):
/// the grid covers [domain.min, domain.max] at domain.dx, the field solve's
/// grid adds magnetic.padding cells of free space on every side. Throws
/// InvalidArgument "domain: ..." for an empty box, TooLarge when the grid and
/// `particles` material points do not fit in memory (requireFitsInMemory),
/// and MpmSettings::validate's errors.
MpmSettings mpmSettingsFrom(const ParamSet& params, double particles = 0);

/// Adds the applied fields, the magnets (field sources, and colliders where
/// `collider` is set) and the colliders to `solver`, in that order.
void addSourcesAndColliders(MpmSolver& solver, const FieldSourceSet& fields,
                            const std::vector<SourcesData::Magnet>& magnets, const std::vector<MpmCollider>& colliders);

/// Adds the vector grid `gridName` (A/m) of a .vdb file to `set`; throws
/// NotBuilt without OpenVDB, InvalidArgument when the file cannot be read.
void addVdbField(FieldSourceSet& set, const std::string& path, const std::string& gridName);

/// Writes all fields of the stage's last run to one .vdb file (atomically);
/// throws NotBuilt without OpenVDB, InvalidArgument when it cannot be written.
void writeStageVdb(const std::string& path, const MagneticForceStage& stage, const std::string& solverSummary,
                   bool doublePrecision = false);

/// The surfacing parameters of the surface and mesh_export nodes (and of
/// the scene's output.surface), declared once.
void addSurfaceParams(std::vector<ParamDecl>& params);
SurfaceSettings surfaceSettingsFrom(const ParamSet& params);

/// What writeRenderOutputs writes: empty paths are skipped.
struct RenderOutputPaths {
  std::string surface;  ///< level sets surface, surface_<material> (.vdb)
  std::string volume;   ///< density, vel (.vdb)
  std::string meshPly;  ///< the surface's mesh, binary PLY
  std::string meshObj;  ///< the surface's mesh, OBJ
};
/// Where the volume file's `magnetization` comes from (none when both are empty).
struct MagnetizationInput {
  GridView<const Vec3d> grid;  ///< M, A/m, on its own node grid (null data: none)
  std::string file;            ///< or the `M` grid of this field file
};
/// What each output cost, s, and the mesh's size.
struct RenderOutputCost {
  double surface = 0, volume = 0, mesh = 0;
  std::size_t triangles = 0;
  double voxelSize = 0;  ///< m, the one used
};
/// Surfaces, volumes and meshes of the particles (vdb_io). `materialNames`
/// names the materials in grid names. When a mesh file is written and
/// `meshOut` is given, the mesh is copied there too (for a preview).
/// Throws NotBuilt without OpenVDB.
RenderOutputCost writeRenderOutputs(const RenderOutputPaths& paths, const MpmParticles& particles,
                                    const std::vector<std::string>& materialNames, const SurfaceSettings& settings,
                                    int frame, double time, const MagnetizationInput& magnetization = {},
                                    TriangleMesh* meshOut = nullptr);

}  // namespace lodestone::plugin
