#pragma once
// The render outputs of one frame of particles, without OpenVDB in the
// interface (docs/vdb.md, "Render outputs"):
//   surface_NNNN.vdb  level sets `surface` (all material) then `surface_<material>`
//   volume_NNNN.vdb   `density` (volume fraction, first), `vel`, `magnetization`
//   a triangle mesh of `surface` with normals and velocities (mesh files:
//   lodestone/plugin/output/mesh_files.h)
// Each output is built when first asked for and kept, so the mesh and the
// surface file share one level set.
#include <memory>
#include <string>
#include <vector>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/base/triangle_mesh.h"
#include "lodestone/core/base/vec3.h"
#include "lodestone/vdb_io/field_file.h"
#include "lodestone/vdb_io/particle_surface.h"

namespace lodestone {

class RenderFrame {
 public:
  /// `materialNames[m]` names material index m in grid names
  /// (`surface_<name>`); a material without a name is `material<m>`.
  /// Throws InvalidArgument on bad options.
  RenderFrame(SurfaceParticles particles, const SurfaceOptions& options, std::vector<std::string> materialNames);
  ~RenderFrame();
  RenderFrame(const RenderFrame&) = delete;
  RenderFrame& operator=(const RenderFrame&) = delete;

  /// The magnetization (A/m) whose magnitude becomes the `magnetization`
  /// grid of the volume file, on its own node-centred grid.
  void setMagnetization(GridView<const Vec3d> magnetization);
  /// The same from the Vec3 grid `gridName` of a field file; false (and
  /// nothing set) when the file has no such grid. Throws InvalidArgument
  /// naming the file when it cannot be read.
  bool setMagnetizationFromFile(const std::string& path, const std::string& gridName = "M");

  /// Writes `surface` (all particles) then one `surface_<material>` per
  /// material present (when more than one is), atomically.
  void writeSurfaceVdb(const std::string& path, const VdbFrameMetadata& metadata) const;
  /// Writes `density` (volume fraction, clamped to [0, 1]), `vel` (m/s) and,
  /// when set, `magnetization` (|M|, A/m), atomically.
  void writeVolumeVdb(const std::string& path, const VdbFrameMetadata& metadata) const;
  /// The zero crossing of `surface` with unit normals and velocities.
  const TriangleMesh& mesh() const;

  /// Volume inside `surface`, m^3.
  double surfaceVolume() const;
  /// The particles' volume, m^3.
  double particleVolume() const;
  const SurfaceOptions& options() const { return options_; }

 private:
  struct Cache;
  SurfaceParticles particles_;
  SurfaceOptions options_;
  std::vector<std::string> names_;
  std::unique_ptr<Cache> cache_;
};

}  // namespace lodestone
