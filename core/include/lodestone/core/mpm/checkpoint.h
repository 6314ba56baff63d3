#pragma once
// Checkpoints of the reference MLS-MPM: the solver's whole evolving state as
// bytes (core does no file I/O; the host writes them, atomically), so that a
// solver built again from the same scene and restored from them continues
// exactly where the saved one was.
//
// Contents: the particles (x, v, C, F, J, mass, V^0, n_p, material, id, the
// per-particle magnetic force, the next id), time, frame, substep counters,
// the cached magnetic nodal force and its bookkeeping (reused between field
// solves when magneticSolveInterval > 0), the magnets' poses, the dynamic
// rigid bodies' poses and velocities, the material's pull on each magnet at
// the last field solve, the effects
// planner's reuse records, and the magnetic stage's grid and potential phi
// (A) when a stage exists. Kinematic colliders and
// magnets move by analytic motions of time, so time restores them; the
// materials, colliders and sources come from the scene and are checked by
// count and grid. Rate emitters need no state either: the chunks they have
// emitted by time t are a function of t (mpm/rate_emitter.h), and what they
// emitted is in the particles. The restored stage (on its saved grid) starts its next
// solve from phi = 0:
// callers that want a resumed run to repeat the uninterrupted one bit for bit
// call MpmSolver::resetMagneticWarmStart() after saving (the saved phi is
// kept in the file for inspection and future warm restarts).
//
// Layout (little-endian):
//   8 bytes  magic "LDSTCKPT"
//   u32      format version (kMpmCheckpointVersion)
//   u32      byte-order mark 0x01020304
//   u64      payload size in bytes
//   u64      FNV-1a 64-bit checksum of the payload
//   payload  (fixed order; see mpm_checkpoint.cpp)
// Any mismatch (magic, version, size, checksum, grid, counts) throws
// InvalidArgument naming what differs; a truncated or corrupted file is
// never half-restored (the solver is changed only after everything parsed).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "lodestone/core/mpm/solver.h"

namespace lodestone {
inline namespace mpm {

inline constexpr std::uint32_t kMpmCheckpointVersion = 2;

/// What a checkpoint says about itself.
struct MpmCheckpointInfo {
  std::uint32_t version = 0;
  std::int64_t frame = 0;  ///< the host's frame number at the save
  double time = 0;         ///< solver time, s
  long long substeps = 0;  ///< substeps taken
  std::size_t particles = 0;
  std::string tag;  ///< the host's identification of the scene (checked on restore)
};

/// The solver's state as checkpoint bytes; `frame` and `tag` are stored for
/// the host (tag: e.g. scene name and options; at most 64 KiB).
std::vector<std::uint8_t> saveMpmCheckpoint(const MpmSolver& solver, std::int64_t frame, const std::string& tag);

/// The header and summary of checkpoint bytes, after checking magic,
/// version, size and checksum (throws InvalidArgument otherwise).
MpmCheckpointInfo readMpmCheckpointInfo(const std::uint8_t* data, std::size_t size);

/// Restores `solver` (built from the same scene: same grid, materials,
/// colliders and magnets) from checkpoint bytes. When `expectedTag` is not
/// empty it must equal the stored tag. Throws InvalidArgument and leaves the
/// solver unchanged on any mismatch or corruption.
MpmCheckpointInfo restoreMpmCheckpoint(MpmSolver& solver, const std::uint8_t* data, std::size_t size,
                                       const std::string& expectedTag = {});

}  // namespace mpm
}  // namespace lodestone
