#pragma once
// Analytic colliders of the reference MLS-MPM: a shape (plane, box, sphere,
// capped cylinder) in its body frame, a rigid motion giving its Pose over
// time (static, keyframed, or constant linear + angular velocity), and a
// boundary condition applied to grid velocities at nodes inside the solid.
//
// Shapes, in the body frame (x_body = R^T (x - position)), with the signed
// distance phi (m) negative inside the solid:
//   plane:    the half-space z_body <= 0, phi = z_body, outward normal +z_body;
//   box:      |x_body| <= halfSize per axis;
//   sphere:   |x_body| <= radius;
//   cylinder: sqrt(x^2 + y^2) <= radius and |z| <= halfLength (axis = body z);
//   level set: phi <= 0 of a SampledSdf (sampled_sdf.h) in the body frame,
//              e.g. a VDB level set or a mesh converted by vdb_io; host only
//              (its samples live in host memory; device code must not use it).
// An inverted shape is solid outside (a container): phi and the normal flip.
// Distances are exact Euclidean distances for plane, sphere and (outside)
// box and cylinder; inside a box or cylinder phi is minus the distance to the
// nearest face, exact as well. A level set gives the trilinear interpolant of
// its samples and the normalised gradient of that interpolant.
//
// Boundary conditions (Stomakhin et al. 2013, Sec. 8), applied to the
// velocity relative to the collider, v_rel = v - v_c, with outward normal n
// and v_n = v_rel . n:
//   Sticky:   v = v_c;
//   Slip:     v_rel <- v_rel - v_n n (the tangential part is kept);
//   Separate: as Slip, but only when v_n < 0 (approaching); leaving is free.
// Coulomb friction mu (Slip and Separate, when v_n < 0): the tangential speed
// |v_t| shrinks by mu |v_n|, and to zero if that exceeds it.
#include <cmath>
#include <memory>
#include <optional>
#include <vector>

#include "lodestone/core/base/hostdev.h"
#include "lodestone/core/base/pose.h"
#include "lodestone/core/mpm/rigid_body.h"
#include "lodestone/core/mpm/sampled_sdf.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace mpm {

enum class BoundaryMode : int { Sticky = 0, Slip = 1, Separate = 2 };
const char* toString(BoundaryMode mode);

struct BoundaryCondition {
  BoundaryMode mode = BoundaryMode::Separate;
  double friction = 0;  ///< Coulomb coefficient mu (dimensionless, >= 0)

  /// Throws InvalidArgument naming the bad value.
  void validate(const char* who) const;
};

/// The velocity (m/s) of a grid node inside a collider after applying `bc`:
/// v the node's velocity, wallVelocity the collider's velocity at the node,
/// n the collider's outward unit normal there (see the header comment).
LODESTONE_HOSTDEV inline Vec3d applyBoundaryCondition(const Vec3d& v, const Vec3d& wallVelocity, const Vec3d& n,
                                                      const BoundaryCondition& bc) {
  if (bc.mode == BoundaryMode::Sticky) return wallVelocity;
  const Vec3d rel = v - wallVelocity;
  const double vn = dot(rel, n);
  if (bc.mode == BoundaryMode::Separate && vn >= 0) return v;
  Vec3d vt = rel - vn * n;
  if (vn < 0 && bc.friction > 0) {
    const double speed = norm(vt);
    const double reduced = speed + bc.friction * vn;  // vn < 0: friction slows the tangential motion
    vt = reduced > 0 ? vt * (reduced / speed) : Vec3d{};
  }
  return wallVelocity + vt;
}

/// The domain walls: node (idx[0], idx[1], idx[2]) of a grid of dims[]
/// nodes lies in the wall layer of an axis when it is within `wallNodes`
/// nodes of either end; the wall's condition `bc` (walls at rest, inward
/// normal) is applied for each such axis in turn.
LODESTONE_HOSTDEV inline Vec3d applyDomainWalls(Vec3d v, const int idx[3], const int dims[3], int wallNodes,
                                                const BoundaryCondition& bc) {
  for (int a = 0; a < 3; ++a) {
    Vec3d nrm{};
    if (idx[a] < wallNodes) {
      nrm[a] = 1;
    } else if (idx[a] > dims[a] - 1 - wallNodes) {
      nrm[a] = -1;
    } else {
      continue;
    }
    v = applyBoundaryCondition(v, Vec3d{}, nrm, bc);
  }
  return v;
}

enum class ColliderShapeKind : int { Plane = 0, Box = 1, Sphere = 2, Cylinder = 3, LevelSet = 4 };
const char* toString(ColliderShapeKind kind);

/// A collider shape in its body frame. Plain data; use the factories.
struct ColliderShape {
  ColliderShapeKind kind = ColliderShapeKind::Plane;
  Vec3d halfSize;         ///< box half-sizes, m
  double radius = 0;      ///< sphere / cylinder radius, m
  double halfLength = 0;  ///< cylinder half-length along body z, m
  bool inverted = false;  ///< solid outside the shape (a container)
  /// Level set: the sampled signed distance (body frame), shared, immutable.
  std::shared_ptr<const SampledSdf> levelSet;

  static ColliderShape plane();
  static ColliderShape box(const Vec3d& halfSize);
  static ColliderShape sphere(double radius);
  static ColliderShape cylinder(double radius, double halfLength);
  /// Throws InvalidArgument when `sdf` is null.
  static ColliderShape levelSetShape(std::shared_ptr<const SampledSdf> sdf);
  /// The same shape, solid on the other side.
  ColliderShape invertedShape() const;
  void validate(const char* who) const;

  /// Signed distance (m) of body-frame point xb, negative inside the solid.
  LODESTONE_HOSTDEV double signedDistance(const Vec3d& xb) const;
  /// The solid's thinnest half-thickness, m: a point that has entered the
  /// solid by less than this is still nearest the face it came through, so
  /// pushing it out along the normal returns it to its own side. The radius
  /// of a sphere, the smallest half-size of a box, min(radius, half length)
  /// of a cylinder, the shallowest ridge of a level set's solid side
  /// (SampledSdf::insideRidgeDepth / outsideRidgeDepth); infinite for a plane
  /// and for the inverted analytic shapes (their solid has no far side).
  double halfThickness() const;
  /// Radius (m) of a sphere about the body origin that holds the solid:
  /// infinite for a plane and the inverted shapes.
  double boundingRadius() const;
  /// Outward unit normal of the solid (body frame) at body-frame point xb:
  /// the gradient of signedDistance where it is defined, a consistent choice
  /// on ridges and the centre.
  LODESTONE_HOSTDEV Vec3d normal(const Vec3d& xb) const;
};

LODESTONE_HOSTDEV inline double ColliderShape::signedDistance(const Vec3d& xb) const {
  using std::fabs;
  using std::fmax;
  using std::fmin;
  using std::sqrt;
  double d = 0;
  switch (kind) {
    case ColliderShapeKind::Plane:
      d = xb.z;
      break;
    case ColliderShapeKind::Sphere:
      d = norm(xb) - radius;
      break;
    case ColliderShapeKind::Box: {
      const Vec3d q{fabs(xb.x) - halfSize.x, fabs(xb.y) - halfSize.y, fabs(xb.z) - halfSize.z};
      const Vec3d out{fmax(q.x, 0.0), fmax(q.y, 0.0), fmax(q.z, 0.0)};
      d = norm(out) + fmin(fmax(q.x, fmax(q.y, q.z)), 0.0);
      break;
    }
    case ColliderShapeKind::Cylinder: {
      const double r = sqrt(xb.x * xb.x + xb.y * xb.y);
      const double qr = r - radius, qz = fabs(xb.z) - halfLength;
      const double orr = fmax(qr, 0.0), oz = fmax(qz, 0.0);
      d = sqrt(orr * orr + oz * oz) + fmin(fmax(qr, qz), 0.0);
      break;
    }
    case ColliderShapeKind::LevelSet:
#if !defined(__CUDA_ARCH__)  // a sampled SDF lives in host memory only
      d = levelSet->signedDistance(xb);
#endif
      break;
  }
  return inverted ? -d : d;
}

LODESTONE_HOSTDEV inline Vec3d ColliderShape::normal(const Vec3d& xb) const {
  using std::fabs;
  using std::fmax;
  using std::sqrt;
  Vec3d n{0, 0, 1};
  switch (kind) {
    case ColliderShapeKind::Plane:
      break;
    case ColliderShapeKind::Sphere: {
      const double r = norm(xb);
      if (r > 0) n = xb / r;
      break;
    }
    case ColliderShapeKind::Box: {
      const Vec3d q{fabs(xb.x) - halfSize.x, fabs(xb.y) - halfSize.y, fabs(xb.z) - halfSize.z};
      const Vec3d s{xb.x < 0 ? -1.0 : 1.0, xb.y < 0 ? -1.0 : 1.0, xb.z < 0 ? -1.0 : 1.0};
      if (q.x > 0 || q.y > 0 || q.z > 0) {
        const Vec3d out{fmax(q.x, 0.0) * s.x, fmax(q.y, 0.0) * s.y, fmax(q.z, 0.0) * s.z};
        n = out / norm(out);
      } else if (q.x >= q.y && q.x >= q.z) {
        n = {s.x, 0, 0};
      } else if (q.y >= q.z) {
        n = {0, s.y, 0};
      } else {
        n = {0, 0, s.z};
      }
      break;
    }
    case ColliderShapeKind::Cylinder: {
      const double r = sqrt(xb.x * xb.x + xb.y * xb.y);
      const Vec3d er = r > 0 ? Vec3d{xb.x / r, xb.y / r, 0} : Vec3d{1, 0, 0};
      const Vec3d ez{0, 0, xb.z < 0 ? -1.0 : 1.0};
      const double qr = r - radius, qz = fabs(xb.z) - halfLength;
      if (qr > 0 || qz > 0) {
        const Vec3d out = fmax(qr, 0.0) * er + fmax(qz, 0.0) * ez;
        n = out / norm(out);
      } else {
        n = qr >= qz ? er : ez;
      }
      break;
    }
    case ColliderShapeKind::LevelSet:
#if !defined(__CUDA_ARCH__)  // a sampled SDF lives in host memory only
      n = levelSet->normal(xb);
#endif
      break;
  }
  return inverted ? -n : n;
}

/// Rigid motion of a collider: Pose(t) and the velocity of its body origin.
class ColliderMotion {
 public:
  /// Dynamic: moved by the solver (mpm/rigid_body.h), not by time.
  enum class Kind : int { Static = 0, Keyframed = 1, ConstantVelocity = 2, Dynamic = 3 };

  /// At rest at `pose` (identity at the origin by default).
  ColliderMotion() = default;
  static ColliderMotion fixed(const Pose& pose);
  /// Piecewise motion through keyframes (times in s, strictly increasing,
  /// finite; poses with proper rotations): positions interpolated linearly,
  /// orientations by slerp (shortest arc), held before the first and after
  /// the last keyframe (at rest there).
  static ColliderMotion keyframed(std::vector<double> times, std::vector<Pose> poses);
  /// Moves with constant linear velocity (m/s) and angular velocity (rad/s,
  /// world frame, about the body origin) from `pose` at time t0 (s):
  /// position(t) = p0 + v (t - t0), rotation(t) = exp([w] (t - t0)) R0.
  static ColliderMotion constantVelocity(const Pose& pose, const Vec3d& velocity, const Vec3d& angularVelocity,
                                         double t0 = 0.0);

  /// The state of a dynamic body: the pose, the velocity of the body origin
  /// (m/s) and the angular velocity (rad/s, world frame), whatever the time.
  static ColliderMotion dynamic(const Pose& pose, const Vec3d& velocity, const Vec3d& angularVelocity);

  Kind kind() const { return kind_; }
  /// Body-to-world pose at time t (s).
  Pose poseAt(double t) const;
  /// Linear velocity of the body origin (m/s) and angular velocity (rad/s,
  /// world frame) at time t (s). On a keyframe the velocity of the segment
  /// that starts there is used.
  void velocityAt(double t, Vec3d& linear, Vec3d& angular) const;

 private:
  Kind kind_ = Kind::Static;
  Pose pose_;                 // Static, Dynamic, and ConstantVelocity at t0
  Vec3d velocity_, angular_;  // ConstantVelocity, Dynamic
  double t0_ = 0;
  std::vector<double> times_;  // Keyframed
  std::vector<Pose> poses_;
};

/// A collider's placement at one time: everything a grid update needs.
struct ColliderState {
  Pose pose;
  Vec3d velocity;         ///< of the body origin, m/s
  Vec3d angularVelocity;  ///< rad/s, world frame
};

class MpmCollider {
 public:
  /// Validates the shape and the boundary condition.
  MpmCollider(const ColliderShape& shape, const ColliderMotion& motion = ColliderMotion(),
              const BoundaryCondition& boundary = BoundaryCondition());

  const ColliderShape& shape() const { return shape_; }
  const ColliderMotion& motion() const { return motion_; }
  const BoundaryCondition& boundary() const { return boundary_; }
  /// For a dynamic collider, a Dynamic motion sets its state; any other
  /// motion gives its starting pose and velocities at the time the solver
  /// first steps it.
  void setMotion(const ColliderMotion& motion);
  void setBoundary(const BoundaryCondition& boundary);

  /// Makes the collider a dynamic rigid body (mpm/rigid_body.h). It starts
  /// from its motion's pose and velocities at the solver's time when the
  /// solver first steps it: a constant-velocity motion gives it an initial
  /// velocity and spin, a keyframed one its pose at that time. Throws
  /// InvalidArgument for a plane or an inverted shape, or bad settings
  /// (naming the value).
  void setDynamics(const RigidBodySettings& settings);
  bool isDynamic() const { return body_.has_value(); }
  /// The body's mass properties and settings; throws unless isDynamic().
  const RigidBody& body() const;

  ColliderState stateAt(double t) const;
  /// Signed distance (m) of world point x at time t (s), negative inside.
  double signedDistance(const Vec3d& x, double t) const;
  /// Outward unit normal (world frame) at world point x, time t.
  Vec3d normal(const Vec3d& x, double t) const;
  /// Velocity (m/s) of the collider's material at world point x, time t.
  Vec3d velocity(const Vec3d& x, double t) const;
  /// The grid velocity v (m/s) at world point x after the boundary condition
  /// at time t: unchanged when x is outside the solid (phi > 0).
  Vec3d apply(const Vec3d& x, const Vec3d& v, double t) const;

  /// As the above, with the state evaluated once (for loops over nodes).
  double signedDistance(const ColliderState& s, const Vec3d& x) const;
  Vec3d apply(const ColliderState& s, const Vec3d& x, const Vec3d& v) const;
  /// A particle at x (m) with velocity v (m/s) found deeper than `allowed`
  /// (m, >= 0) inside the solid (phi < -allowed) at state s is moved out
  /// along the normal to that depth (phi = -allowed; 0: onto the surface),
  /// and the boundary condition is applied to its velocity relative to the
  /// collider there. Returns false, changing nothing, otherwise. This is
  /// what keeps particles out of walls thinner than the grid's reach
  /// (MpmSolver's collider projection).
  bool projectOut(const ColliderState& s, Vec3d& x, Vec3d& v, double allowed = 0.0) const;
  /// The positional part of projectOut: moves x out to depth `allowed` and
  /// gives the outward normal (world frame) there; false, changing nothing,
  /// when x is not deeper than that.
  bool pushOut(const ColliderState& s, Vec3d& x, double allowed, Vec3d& normal) const;

 private:
  ColliderShape shape_;
  ColliderMotion motion_;
  BoundaryCondition boundary_;
  std::optional<RigidBody> body_;
};

}  // namespace mpm
}  // namespace lodestone
