#pragma once
// Scene files: a JSON description of an MLS-MPM simulation with magnetism
// (domain, materials, bodies, emitters, magnets, applied fields, colliders,
// time stepping, outputs), read strictly (json_reader.h): unknown keys, wrong
// types and out-of-range values are rejected with the path of the entry and
// what was expected. The format is documented in docs/scenes.md. A scene is a
// network of the node library's nodes (docs/nodes.md) written out: the
// entries of materials, bodies, emitters, magnets, fields and colliders are
// material, particle_source, particle_emitter, magnet, applied_field and
// collider nodes, and the domain,
// time, gravity and magnetic objects are the mpm_solver node's settings;
// their keys are those nodes' declared parameters, read and checked from the
// declarations (param_json.h) and built by the nodes' own builders
// (node_builders.h).
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "lodestone/core/mpm/sampled_sdf.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/plugin/memory_estimate.h"
#include "lodestone/core/planner/accuracy_preset.h"
#include "lodestone/core/sources/field_source_set.h"
#include "lodestone/core/sources/magnet_source.h"
#include "lodestone/plugin/node_data.h"

namespace lodestone::plugin {

struct SceneBody {
  std::string name;
  std::uint32_t material = 0;  ///< index into Scene::materials
  EmitterShape shape;
  EmitterSettings emit;
};

/// A source emitting material over time (a particle_emitter node).
using SceneEmitter = ParticlesData::Emitter;

/// A permanent magnet: a field source, and an obstacle for the material
/// unless `collider` is false (what a magnet node gives).
using SceneMagnet = SourcesData::Magnet;

struct SceneOutput {
  bool ply = true;  ///< per-frame particle files
  bool png = true;  ///< per-frame preview renders
  std::vector<std::string>
      vdbFields;  ///< grids of the per-frame field file (n, phi, H, M, B, force, mass, velocity); empty = none
  bool vdbAliases = false;        ///< also write `density` (= n) and `vel` (= velocity) for Blender and Houdini
  bool vdbPoints = false;         ///< per-frame particles_NNNN.vdb (OpenVDB PointDataGrid)
  int checkpointEvery = 0;        ///< frames between checkpoint files (checkpoint_NNNN.lsck); 0 = none
  /// output.surface: how surface_NNNN.vdb, volume_NNNN.vdb and the mesh files
  /// are built (the surface node's parameters)
  SurfaceSettings surface;
  int width = 640, height = 480;  ///< preview size, pixels
  bool autoCamera = true;
  Vec3d cameraPosition, cameraLookAt;  ///< m (when not automatic)
  double fovDegrees = 35;
};

struct Scene {
  std::string file;
  std::uint64_t contentHash = 0;  ///< FNV-1a 64 of the scene file's bytes (core/base/hash.h)
  std::string name;
  std::string description;
  MpmSettings settings;
  double fullDx = 0;  ///< dx of the paper-scale variant (m), 0 when the scene has none
  std::vector<std::string> materialNames;
  std::vector<MpmMaterial> materials;
  std::vector<SceneBody> bodies;
  std::vector<SceneEmitter> emitters;
  std::vector<SceneMagnet> magnets;
  FieldSourceSet fields;
  std::vector<MpmCollider> colliders;
  std::optional<AccuracyPresetSettings> accuracy;  ///< the scene's accuracy preset, if it names one
  // The time line (time.start_frame, time.frames, time.fps): frame f ends
  // at scene time f / fps. The initial state is frame startFrame - 1, at
  // startTime(); the simulated frames are startFrame .. lastFrame().
  // Keyframes, time profiles and emitter time lines are in scene seconds.
  int startFrame = 1;  ///< the number of the first simulated frame
  int frames = 1;      ///< frames to simulate
  double fps = 24;     ///< frames per second
  SceneOutput output;

  double frameDuration() const { return 1.0 / fps; }
  /// The number of the initial state's frame: startFrame - 1.
  int initialFrame() const { return startFrame - 1; }
  /// The number of the last simulated frame.
  int lastFrame() const { return startFrame + frames - 1; }
  /// The scene time at the end of frame `frame` (s): frame / fps.
  double frameTime(int frame) const { return frame / fps; }
  /// The scene time of the initial state (s), where the simulation starts.
  double startTime() const { return frameTime(initialFrame()); }
};

/// Readers of shapes stored in files, for bodies and colliders of shape
/// "level_set" (a VDB level set) and "mesh" (an OBJ file). Left empty, the
/// node library's readers are used (loadShapeFile of node_builders.h:
/// vdb_io's readLevelSetVdb and levelSetFromObj), and without OpenVDB such
/// shapes are rejected with a message saying so; a host may install its own.
/// Paths arrive resolved against the scene file's directory. Both return
/// the shape in its own frame (the file's world frame), which the scene
/// entry's pose then places.
struct ShapeLoaders {
  /// Float level set `grid` of the .vdb file `path`.
  std::function<std::shared_ptr<const SampledSdf>(const std::string& path, const std::string& grid)> levelSet;
  /// The closed triangle mesh of the .obj file `path` as a level set of voxel size `voxelSize` (m).
  std::function<std::shared_ptr<const SampledSdf>(const std::string& path, double voxelSize)> mesh;
};

struct SceneOptions {
  bool full = false;     ///< use the scene's full-resolution dx (domain.full_dx)
  double dx = 0;         ///< > 0: override the grid spacing (m)
  ShapeLoaders loaders;  ///< readers for "level_set" and "mesh" shapes (empty: the node library's)
};

/// Reads and validates a scene file; throws InvalidArgument naming the file,
/// the path of the bad entry and what was expected (also for a file that
/// cannot be read, a JSON syntax error at line:column, and a grid too large
/// for memory, refused before anything is allocated).
Scene loadScene(const std::string& path, const SceneOptions& options = {});
/// The same from text (`sourceName` is used in messages and is the directory
/// relative file paths are resolved against).
Scene parseScene(const std::string& text, const std::string& sourceName, const SceneOptions& options = {});

/// A solver with the scene's materials, bodies, emitters, magnets, fields and
/// colliders (the particles emitted at the scene's dx), at the scene time
/// startTime(). Throws
/// InvalidArgument for a body wholly outside the domain, or an emitter whose
/// centre is outside it when it first switches on. With a partition
/// (mpm/partition.h; every process of it calls this, collective) the solver
/// is split before the bodies are emitted, and each process keeps only the
/// particles it owns.
std::unique_ptr<MpmSolver> buildSolver(const Scene& scene, std::shared_ptr<MpmPartition> partition = nullptr);

/// What a run of `scene` holds at its largest: the MPM grid; the field
/// solve's grid when some material is magnetic and the scene has a magnet or
/// an applied field; the particles, with all the emitters add by the scene's
/// last frame (an upper bound: blocked or removed particles are not
/// subtracted); the preview's pixels (no other frame file: the caller adds
/// those it writes). With `solver` (as buildSolver made it, or later) the
/// particles are its own from its time on; without, the bodies' are
/// estimated from their volumes (loadScene checks this estimate). For a
/// partitioned solver: this process's part (its window of the MPM grid, its
/// particles, its share of what the emitters add; the whole field grid,
/// which every process solves).
MemoryCounts sceneMemory(const Scene& scene, const MpmSolver* solver = nullptr);

}  // namespace lodestone::plugin
