#pragma once
// Scene files: a JSON description of an MLS-MPM simulation with magnetism
// (domain, materials, bodies, magnets, applied fields, colliders, time
// stepping, outputs), read strictly: unknown keys, wrong types and
// out-of-range values are rejected with the path of the entry and what was
// expected. The format is documented in docs/scenes.md.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lodestone/core/field_source_set.h"
#include "lodestone/core/magnet_source.h"
#include "lodestone/core/mpm_solver.h"

namespace lodestone::examples {

struct SceneBody {
  std::string name;
  std::uint32_t material = 0;  ///< index into Scene::materials
  EmitterShape shape;
  EmitterSettings emit;
};

struct SceneMagnet {
  std::unique_ptr<MagnetSource> magnet;
  ColliderMotion motion;
  BoundaryCondition boundary;
  bool collider = true;  ///< also an obstacle for the material
};

struct SceneOutput {
  bool ply = true;           ///< per-frame particle files
  bool png = true;           ///< per-frame preview renders
  std::vector<std::string> vdbFields;  ///< grids of the per-frame field file (n, phi, H, M, B, force); empty = none
  bool vdbPoints = false;    ///< per-frame particles_NNNN.vdb (OpenVDB PointDataGrid)
  int width = 640, height = 480;  ///< preview size, pixels
  bool autoCamera = true;
  Vec3d cameraPosition, cameraLookAt;  ///< m (when not automatic)
  double fovDegrees = 35;
};

struct Scene {
  std::string file;
  std::string name;
  std::string description;
  MpmSettings settings;
  double fullDx = 0;   ///< dx of the paper-scale variant (m), 0 when the scene has none
  std::vector<std::string> materialNames;
  std::vector<MpmMaterial> materials;
  std::vector<SceneBody> bodies;
  std::vector<SceneMagnet> magnets;
  FieldSourceSet fields;
  std::vector<MpmCollider> colliders;
  int frames = 1;
  double fps = 24;     ///< frames per second
  SceneOutput output;

  double frameDuration() const { return 1.0 / fps; }
};

struct SceneOptions {
  bool full = false;   ///< use the scene's full-resolution dx (domain.full_dx)
  double dx = 0;       ///< > 0: override the grid spacing (m)
};

/// Reads and validates a scene file; throws InvalidArgument naming the file,
/// the path of the bad entry and what was expected.
Scene loadScene(const std::string& path, const SceneOptions& options = {});
/// The same from text (`sourceName` is used in messages).
Scene parseScene(const std::string& text, const std::string& sourceName, const SceneOptions& options = {});

/// A solver with the scene's materials, bodies, magnets, fields and colliders.
std::unique_ptr<MpmSolver> buildSolver(const Scene& scene);

}  // namespace lodestone::examples
