#pragma once
// MPM material points as an OpenVDB PointDataGrid (see docs/vdb.md for the
// grid name, attribute names, units, codecs and metadata keys). No OpenVDB
// types here.
#include <cstdint>
#include <string>
#include <vector>

#include "lodestone/core/base/mat3.h"
#include "lodestone/core/mpm/particles.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {

/// Options of writeParticlesVdb.
struct PointFileOptions {
  /// Voxel size of the point grid's transform, m (e.g. the MPM dx); > 0.
  /// Positions are stored as 16-bit fixed-point offsets within their voxel,
  /// so the position error is at most about voxelSize / 65535.
  double voxelSize = 0;
  bool deformationGradient = false;  ///< also write F (Mat3s attribute "F")
  bool compressVelocity = false;     ///< v as half floats (TruncateCodec) instead of 32-bit floats
  std::int64_t frame = 0;            ///< [frame]
  double time = 0;                   ///< [time_s] simulation time, s
};

/// The points of a particle file, in file order (grouped by voxel, not the
/// order they were written in: match them by id).
struct ParticleVdbData {
  std::vector<Vec3d> x;                 ///< [P] position, m (world space)
  std::vector<Vec3d> v;                 ///< [v] velocity, m/s
  std::vector<double> count;            ///< [n_p] micro-particles carried
  std::vector<double> J;                ///< [J] volume ratio
  std::vector<std::uint32_t> material;  ///< [material]
  std::vector<std::uint64_t> id;        ///< [id]
  std::vector<double> pscale;           ///< [pscale] radius of the particle's volume J V0, m
  std::vector<Mat3d> F;                 ///< [F] empty when the file has no F
  double voxelSize = 0;                 ///< of the grid's transform, m
  std::int64_t frame = 0;
  double time = 0;
  std::size_t size() const { return x.size(); }
};

/// Writes the particles to one .vdb file holding a PointDataGrid named
/// "points" (Houdini's name), atomically (temporary file in the same directory, then
/// rename). Throws InvalidArgument naming the file on failure; the target is
/// untouched then.
void writeParticlesVdb(const std::string& path, const MpmParticles& particles, const PointFileOptions& options);

/// Reads a file written by writeParticlesVdb. Throws InvalidArgument naming
/// the file when it cannot be read or lacks the grid or an attribute.
ParticleVdbData readParticlesVdb(const std::string& path);

}  // namespace lodestone
