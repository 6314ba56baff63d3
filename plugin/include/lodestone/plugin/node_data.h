#pragma once
// What flows along a node network's connections. Each port has one of these
// types; values are immutable once a node has cooked them (shared, never
// copied on the way downstream).
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "lodestone/core/sources/field_source_set.h"
#include "lodestone/core/sources/magnet_source.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/core/mpm/collider.h"
#include "lodestone/core/mpm/emitter.h"
#include "lodestone/core/mpm/material.h"
#include "lodestone/core/mpm/particles.h"
#include "lodestone/core/mpm/rate_emitter.h"

namespace lodestone {
inline namespace mpm {
class MpmSolver;
}  // namespace mpm
}  // namespace lodestone

namespace lodestone::plugin {

enum class PortType : int { Particles, Material, Sources, Colliders, Density, Field, Forces, Simulation };
const char* toString(PortType type);

/// How the surface and mesh_export nodes (and the scene's output.surface)
/// turn particles into a surface (vdb_io/particle_surface.h).
struct SurfaceSettings {
  std::string method = "density";  ///< "density" (smoothed volume fraction) or "splat" (union of spheres)
  double voxelSize = 0;            ///< m; 0: the particle spacing (cube root of the mean particle volume)
  double kernelWidth = 1.5;        ///< density: kernel width over the particle spacing
  double radiusScale = 1;          ///< splat: sphere radius over the particle's radius
  int smoothing = 1;               ///< splat: Gaussian filter width, voxels
  int closing = 1;                 ///< splat: dilation then erosion, voxels
};

/// A named MPM material.
struct MaterialData {
  std::string name;
  MpmMaterial material;
};

/// One body of material points: where they come from (shape, emission) and
/// the points themselves (emitted with the material index 0; an MPM solver
/// node renumbers materials when it merges bodies).
struct ParticlesData {
  struct Body {
    std::string name;
    MaterialData material;
    EmitterShape shape;
    EmitterSettings emit;
  };
  /// A source that emits material over time (a particle_emitter node; the
  /// scene's `emitters`); the MPM solver node adds it to the solver.
  struct Emitter {
    std::string name;
    std::uint32_t material = 0;  ///< index into materials
    EmitterShape shape;          ///< at its rest pose
    RateEmitterSettings settings;
  };
  std::vector<Body> bodies;
  std::vector<Emitter> emitters;
  MpmParticles particles;
  std::vector<MpmMaterial> materials;  ///< indexed by particles.material and Emitter::material
};

/// Applied-field sources: fields (uniform, dipole, VDB...) and magnets, which
/// may also be colliders of the MPM.
struct SourcesData {
  struct Magnet {
    std::shared_ptr<const MagnetSource> magnet;
    ColliderMotion motion;
    BoundaryCondition boundary{BoundaryMode::Sticky, 0.0};
    bool collider = true;
    /// Set: a free magnet, moved by the material's pull, the other magnets,
    /// gravity and contacts (MpmSolver's rigid bodies).
    std::optional<RigidBodySettings> dynamics;
  };
  FieldSourceSet fields;
  std::vector<Magnet> magnets;
  /// Fields plus magnets, as one source.
  FieldSourceSet all() const;
};

struct CollidersData {
  std::vector<MpmCollider> colliders;
};

/// Nodal micro-particle density n (1/m^3) on a grid.
struct DensityData {
  DenseGrid<double> density;
  MagneticMaterial material;  ///< the law shared by the deposited particles
  double totalCount = 0;      ///< micro-particles deposited
};

/// A solved field: the stage holds phi, H, M, B, forces of its last run.
struct FieldData {
  std::shared_ptr<MagneticForceStage> stage;
  MagneticStageReport report;
};

/// Magnetic forces on material points (N), in the order of the particles.
struct ForcesData {
  std::vector<Vec3d> particleForces;
  Vec3d total;  ///< N
  MagneticStageReport report;
};

/// A reference MLS-MPM after some frames.
struct SimulationData {
  std::shared_ptr<MpmSolver> solver;
  int startFrame = 1;               ///< the number of the first simulated frame (time.start_frame)
  int frames = 0;
  double time = 0;                  ///< s, scene time
  std::vector<double> frameTimes;   ///< s, scene time of the initial state and of each frame's end
  std::vector<Vec3d> centreOfMass;  ///< of the magnetic material per frame, m
};

using NodeValue =
    std::variant<std::monostate, std::shared_ptr<const ParticlesData>, std::shared_ptr<const MaterialData>,
                 std::shared_ptr<const SourcesData>, std::shared_ptr<const CollidersData>,
                 std::shared_ptr<const DensityData>, std::shared_ptr<const FieldData>,
                 std::shared_ptr<const ForcesData>, std::shared_ptr<const SimulationData>>;

/// The port type a value carries (throws for an empty value).
PortType typeOf(const NodeValue& value);

}  // namespace lodestone::plugin
