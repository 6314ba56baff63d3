#pragma once
// Seeding material points in a box, a sphere, a capped cylinder or a level
// set (a SampledSdf, e.g. read from a VDB file or converted from a mesh).
//
// Points are placed on a lattice of spacing h = dx / ppc^(1/3) (dx the MPM
// cell size, ppc the particles per cell, e.g. 8 -> h = dx/2), in the shape's
// body frame, one point at the centre of each lattice cell whose centre lies
// inside the shape, optionally jittered within its lattice cell. Each point
// gets the volume of its lattice cell V_p, the mass rho V_p and, for magnetic
// materials, n_p = n0 V_p micro-particles (the paper's "micro-particles of a
// filled cell evenly distributed to the MPM particles within it").
//
// For a box the lattice is fitted to the box: round(2 a_k / h) cells along
// axis k, so the points' volumes sum to the box volume exactly. For spheres
// and cylinders the lattice is centred on the body origin and the volumes sum
// to the shape's volume up to the staircase error O(h / size). For a level
// set the lattice starts at the low corner of the SDF's interior bounds
// (SampledSdf::interiorBounds) and a point is kept where the trilinear
// signed distance is <= 0; volume() is then the SDF's smoothed-Heaviside
// estimate, and the points' volumes match it up to the same staircase error.
//
// Jitter is reproducible: the offsets come from a 64-bit SplitMix generator
// seeded with `seed`, so a given seed gives the same points on every platform.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "lodestone/core/mpm/material.h"
#include "lodestone/core/mpm/particles.h"
#include "lodestone/core/base/grid.h"
#include "lodestone/core/base/pose.h"
#include "lodestone/core/mpm/sampled_sdf.h"

namespace lodestone {
inline namespace mpm {

enum class EmitterShapeKind : int { Box = 0, Sphere = 1, Cylinder = 2, LevelSet = 3 };

struct EmitterShape {
  EmitterShapeKind kind = EmitterShapeKind::Box;
  Pose pose;              ///< body-to-world placement
  Vec3d halfSize;         ///< box half-sizes, m
  double radius = 0;      ///< sphere / cylinder radius, m
  double halfLength = 0;  ///< cylinder half-length along body z, m
  std::shared_ptr<const SampledSdf> levelSet;  ///< level set (body frame), shared, immutable

  static EmitterShape box(const Pose& pose, const Vec3d& halfSize);
  static EmitterShape sphere(const Pose& pose, double radius);
  static EmitterShape cylinder(const Pose& pose, double radius, double halfLength);
  /// The inside (phi <= 0) of `sdf`, placed by `pose` (body frame = the SDF's frame).
  static EmitterShape levelSetShape(const Pose& pose, std::shared_ptr<const SampledSdf> sdf);
  /// Volume of the shape, m^3: exact for the analytic shapes, the SDF's
  /// estimate SampledSdf::volume() for a level set.
  double volume() const;
  /// True when the body-frame point xb (m) is inside (closed).
  bool containsBody(const Vec3d& xb) const;
  /// The world-axis box [lo, hi] (m) holding the shape: its body-frame box
  /// placed by the pose.
  void worldBounds(Vec3d& lo, Vec3d& hi) const;
  void validate() const;
};

struct EmitterSettings {
  double cellSize = 0;       ///< MPM grid spacing dx, m (> 0)
  int particlesPerCell = 8;  ///< ppc >= 1 (8 or 27 give exact lattices of dx/2, dx/3)
  double jitter = 0;         ///< 0 = regular; 1 = anywhere in the lattice cell (fraction of h)
  std::uint64_t seed = 1;    ///< jitter seed
  Vec3d velocity;            ///< initial velocity, m/s
  Vec3d angularVelocity;     ///< initial spin about the shape's centre, rad/s (v += w x (x - centre), C = [w]x)

  void validate() const;
};

/// Summary of one emission.
struct EmitReport {
  std::size_t particles = 0;  ///< points added
  double volume = 0;          ///< sum of V_p, m^3
  double mass = 0;            ///< sum of m_p, kg
  double count = 0;           ///< sum of n_p (micro-particles)
  double spacing = 0;         ///< lattice spacing h, m (mean over axes for boxes)
};

/// The lattice of an emission in the shape's body frame: the (jittered)
/// points inside the shape, in the order emitParticles adds them.
struct EmitterLattice {
  std::vector<Vec3d> points;  ///< body frame, m
  Vec3d spacing;              ///< lattice spacing per body axis, m
  Index3 cells;               ///< lattice cells per body axis (of the shape's bounding box)
  double pointVolume = 0;     ///< V_p of each point, m^3
};

/// The lattice emitParticles fills `shape` with (validates both arguments).
EmitterLattice emitterLattice(const EmitterShape& shape, const EmitterSettings& settings);

/// Volume (m^3), mass rho V_p (kg) and micro-particles n0 V_p of one point.
struct EmittedPoint {
  double volume = 0, mass = 0, count = 0;
};
/// The point of `volume` (m^3) of `material`; throws InvalidArgument for a
/// mass that is not positive and finite.
EmittedPoint emittedPoint(const MpmMaterial& material, double volume);

/// Appends points filling `shape` to `particles` with material index
/// `materialIndex` (whose parameters are `material`). Throws InvalidArgument
/// on bad settings, shapes or materials; adds nothing then. With `keep`,
/// only the points at positions x (m) with keep(x) are added (a partitioned
/// solver's own, mpm/partition.h): the others still take their id, so that
/// ids do not depend on it, and the report counts every point of the shape.
EmitReport emitParticles(MpmParticles& particles, const EmitterShape& shape, const MpmMaterial& material,
                         std::uint32_t materialIndex, const EmitterSettings& settings,
                         const std::function<bool(const Vec3d&)>& keep = {});

}  // namespace mpm
}  // namespace lodestone
