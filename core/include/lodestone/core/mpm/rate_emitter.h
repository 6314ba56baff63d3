#pragma once
// Emission over time: a source that adds material at a rate from a shape
// (box, sphere, cylinder; a nozzle is a cylinder whose axis is the body z)
// whose pose follows a ColliderMotion, with an on/off time line.
//
// Timing. The material comes in chunks: one chunk is the shape's whole
// emitter lattice (emitterLattice, spacing h = dx / ppc^(1/3)), of volume
// V_c = (points of the lattice) V_p. The schedule's active time a(t) is the
// on-time in [0, t] (s); chunk k = 0, 1, ... is born when a reaches k T,
// T = V_c / Q the chunk period (Q the volume rate, m^3/s). The chunks born by
// time t are therefore N(t) = #{k >= 0 : k T < a(t)} = ceil(a(t) / T): a pure
// function of time, so a run resumed from a checkpoint at time t emits
// exactly what an uninterrupted run emits, without any emitter state in the
// checkpoint. The volume born by t is N(t) V_c, within one chunk of Q a(t):
// Q a(t) <= N(t) V_c < Q a(t) + V_c. A rate in particles per second R is the
// volume rate Q = R V_p. A "stream" rate is Q = u V_c / L, u the emission
// speed along the body z axis and L = cells.k * spacing.z the lattice's
// length along it: each chunk is then born as the previous one has moved
// exactly L, so a jet is a continuous column of lattice layers h apart.
//
// Placement. A chunk born at t_k inside a substep [t0, t1] gets the lattice
// at the emitter's pose at t_k, moved by its emission velocity for the part
// of the substep since t_k: x = pose(t_k) x_b + v_e (t1 - t_k). The emission
// velocity v_e is given in the world frame or in the body frame (a nozzle's
// speed along its axis: (0, 0, u), turned with the nozzle), plus, with
// inheritMotion, the velocity of the emitter's own material point there
// (a hose on a moving cart; off: material is laid along the emitter's path).
//
// Full space. A point closer than 0.9 h (1 - jitter) to any material point
// (already there, or of another chunk placed earlier in the same emission) is
// not emitted: material there would be compressed by more than 1/0.9^3 =
// 1.37. Nor is one outside the domain. Such points are counted (blocked,
// outside) and never emitted later. An emitter pouring into a full container,
// or faster than its material leaves the shape, therefore adds no more than
// the space takes instead of stacking points; the volume identity above is
// then an upper bound. A consistent stream (consecutive chunks h apart) is
// never blocked by itself. Colliders are not consulted: an emitter placed
// inside one emits there and the collider's boundary condition acts on the
// material from the next substep, so a nozzle belongs outside solids.
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "lodestone/core/mpm/collider.h"
#include "lodestone/core/mpm/emitter.h"
#include "lodestone/core/mpm/grid.h"
#include "lodestone/core/mpm/material.h"
#include "lodestone/core/mpm/particles.h"

namespace lodestone {
inline namespace mpm {

/// When an emitter is on: a list of intervals [on, off) of simulation time
/// (s), sorted, disjoint, on >= 0, off > on (off may be infinite).
class EmissionSchedule {
 public:
  /// On from time 0, never off.
  EmissionSchedule() : intervals_{{0.0, kForever}} {}
  /// On in [start, end) (end may be kForever). Throws InvalidArgument naming
  /// the values unless 0 <= start < end.
  static EmissionSchedule between(double start, double end = kForever);
  /// On in each interval; throws InvalidArgument naming the first interval
  /// that is empty, negative, not after the one before or not finite at its start.
  static EmissionSchedule intervals(std::vector<std::pair<double, double>> onOff);

  static constexpr double kForever = 1e300;  ///< an off time that never comes, s

  const std::vector<std::pair<double, double>>& list() const { return intervals_; }
  /// On-time in [0, t], s.
  double activeTime(double t) const;
  /// The earliest time (s) at which the active time exceeds `active` (s): the
  /// start of the on-interval in which it is passed plus what is left.
  double timeAtActive(double active) const;
  /// On at time t (s).
  bool isOn(double t) const;
  /// On at some time in [t0, t1) (s).
  bool onWithin(double t0, double t1) const;
  /// The last off time (s); kForever when the last interval never ends.
  double end() const { return intervals_.back().second; }

 private:
  std::vector<std::pair<double, double>> intervals_;
};

enum class EmissionRateKind : int {
  VolumePerSecond = 0,     ///< m^3/s
  ParticlesPerSecond = 1,  ///< 1/s
  Stream = 2               ///< speed along the axis times the chunk's cross-section (see the header)
};
const char* toString(EmissionRateKind kind);

struct RateEmitterSettings {
  EmissionRateKind rateKind = EmissionRateKind::VolumePerSecond;
  double rate = 0;  ///< m^3/s or 1/s (> 0; unused for Stream)
  EmissionSchedule schedule;
  /// Pose over time; Static motions keep the shape's own pose.
  ColliderMotion motion;
  bool followsMotion = false;  ///< false: the shape's pose at all times (motion unused)
  /// Lattice (cellSize, particlesPerCell, jitter, seed; cellSize 0 = the MPM
  /// grid's dx when added to a solver) and emission velocity `velocity`
  /// (m/s); angularVelocity must be zero.
  EmitterSettings lattice;
  bool velocityInBodyFrame = false;  ///< velocity is in the emitter's body frame (a nozzle: (0, 0, speed))
  bool inheritMotion = false;        ///< add the emitter's own velocity at each point
  /// Refuse a substep that would emit more than this many points (a rate
  /// far beyond what the shape can pass): InvalidArgument, nothing added.
  std::size_t maxParticlesPerStep = 2000000;

  /// Throws InvalidArgument naming the first bad value.
  void validate() const;
};

/// What an emission added (and left out).
struct RateEmitReport {
  long long chunks = 0;       ///< chunks born
  std::size_t particles = 0;  ///< points added
  std::size_t blocked = 0;    ///< points not emitted: closer than 0.9 h (1 - jitter) to material
  std::size_t outside = 0;    ///< points not emitted: outside the domain
  double volume = 0;          ///< m^3 added
  double mass = 0;            ///< kg added

  RateEmitReport& operator+=(const RateEmitReport& o);
};

class RateEmitter {
 public:
  /// Builds the lattice of `shape` (its pose is the rest pose) for material
  /// `material` (index `materialIndex` in the solver). Throws
  /// InvalidArgument on bad settings (cellSize must be set), a lattice
  /// without points, or a stream without a positive speed along the axis.
  RateEmitter(const EmitterShape& shape, const RateEmitterSettings& settings, const MpmMaterial& material,
              std::uint32_t materialIndex);

  const EmitterShape& shape() const { return shape_; }
  const RateEmitterSettings& settings() const { return settings_; }
  std::uint32_t materialIndex() const { return materialIndex_; }
  /// Body-to-world pose at time t (s).
  Pose poseAt(double t) const;

  /// Volume rate Q, m^3/s.
  double volumeRate() const { return rate_; }
  /// Points of one chunk and its volume (m^3).
  std::size_t chunkParticles() const { return lattice_.points.size(); }
  double chunkVolume() const { return double(lattice_.points.size()) * point_.volume; }
  /// Chunk period T = V_c / Q, s of active time.
  double chunkPeriod() const { return chunkVolume() / rate_; }
  /// Lattice spacing per body axis, m.
  const Vec3d& spacing() const { return lattice_.spacing; }
  /// Chunks born by time t (s): ceil(a(t) / T) (see the header).
  long long chunksBy(double t) const;
  /// Birth time (s) of chunk k.
  double birthTime(long long k) const;
  /// Points born by time t (s), before any is blocked: chunksBy(t) * chunkParticles().
  double particlesBy(double t) const { return double(chunksBy(t)) * double(chunkParticles()); }
  /// Largest speed (m/s) of the material it emits in [t0, t1] (s); 0 when off then.
  double emissionSpeed(double t0, double t1) const;

  /// Appends the chunks born in (t0, t1] (s), placed at time t1, skipping
  /// points where the space is full (see the header) or outside `bounds`. Throws
  /// InvalidArgument before adding anything when more than
  /// maxParticlesPerStep points are due.
  RateEmitReport emitBetween(MpmParticles& particles, double t0, double t1, const ParticleBounds& bounds) const;

  /// One line: shape, rate, chunk, time line.
  std::string describe() const;

 private:
  Vec3d velocityAt(const Pose& pose, const Vec3d& x, double t) const;  // emission velocity at world point x, m/s

  EmitterShape shape_;
  RateEmitterSettings settings_;
  std::uint32_t materialIndex_ = 0;
  EmitterLattice lattice_;
  EmittedPoint point_;
  double rate_ = 0;  // m^3/s
};

}  // namespace mpm
}  // namespace lodestone
