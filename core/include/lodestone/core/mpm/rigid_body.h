#pragma once
// Dynamic rigid bodies of the reference MLS-MPM: a collider (or a colliding
// magnet) that the material, gravity, contacts and magnetic forces move.
// Units: m, kg, s; forces N, torques N*m, impulses N*s.
//
// A dynamic collider's motion is ColliderMotion::Kind::Dynamic: its pose and
// velocities are state that MpmSolver advances every substep (mpm/solver.h,
// "Rigid bodies"), not a function of time. This header holds what the state
// update needs: the body's mass properties, its contact parameters, and the
// working state of one substep (RigidBodyState) with its symplectic update.
//
// The update (semi-implicit Euler, in the order MpmSolver applies it):
//   v += dt F / m,  L += dt tau            (gravity, magnetic forces)
//   contact and grid impulses change v and L (impulses P at points p:
//   v += P / m, L += (p - x) x P)
//   x += dt (v + v_push),  R <- exp(dt [w + w_push]) R,  w = I_w(R)^-1 L
// with x the centre of mass, L = I_w w the angular momentum about it and
// I_w = R I R^T the world inertia. Keeping L (not w) across the rotation
// makes a torque-free body conserve its angular momentum exactly; the
// rotation is re-orthonormalised every substep. (v_push, w_push) is the
// contacts' overlap push (rigid_contact.h): it moves the pose in this
// substep only and never enters the momentum, so a body placed deep in
// another is moved out of it, not thrown.
#include <cstddef>
#include <vector>

#include "lodestone/core/base/mat3.h"
#include "lodestone/core/base/pose.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace mpm {

struct ColliderShape;
struct ColliderState;
struct BoundaryCondition;

/// Mass properties of a rigid body, in its body frame.
struct RigidMassProperties {
  double mass = 0;     ///< kg
  Vec3d centreOfMass;  ///< body frame, m (the origin for the symmetric analytic shapes)
  Mat3d inertia;       ///< about the centre of mass, body frame, kg*m^2
  Mat3d inverseInertia;  ///< its inverse, kg^-1 m^-2
};

/// Mass properties of a solid of uniform `density` (kg/m^3) filling `shape`:
/// closed forms for a box, a sphere and a cylinder (axis body z); for a
/// level set, sums over its samples with the smoothed Heaviside of
/// SampledSdf::volume (second order in the sample spacing for a smooth,
/// resolved surface). Throws InvalidArgument, naming the value, for a
/// plane, an inverted shape (infinite solids), or a density that is not a
/// positive finite value.
RigidMassProperties massProperties(const ColliderShape& shape, double density);

/// What makes a collider dynamic.
struct RigidBodySettings {
  /// kg/m^3; the mass properties follow from it and the shape.
  double density = 1000;
  /// kg; > 0 gives the body this mass instead (density scaled to match).
  double mass = 0;
  /// Coefficient of restitution of contacts with other bodies, colliders
  /// and the domain walls, 0 (plastic) .. 1 (elastic).
  double restitution = 0.2;
  /// Coulomb friction coefficient of those contacts (dimensionless, >= 0).
  /// The material's friction on the body is the collider's BoundaryCondition.
  double friction = 0.4;

  /// Throws InvalidArgument naming the first bad value.
  void validate(const char* who) const;
};

/// A dynamic body's constant part: its settings and mass properties.
struct RigidBody {
  RigidBodySettings settings;
  RigidMassProperties mass;

  /// Validates the settings, computes the mass properties of `shape`.
  static RigidBody of(const ColliderShape& shape, const RigidBodySettings& settings);
};

/// A body's state within one substep: centre of mass, rotation, velocities
/// and inverse mass properties (zero for kinematic and static colliders,
/// which impulses do not move).
struct RigidBodyState {
  Vec3d x;                                ///< centre of mass, world, m
  Mat3d rotation = Mat3d::identity();     ///< body-to-world
  Vec3d v;                                ///< centre-of-mass velocity, m/s
  Vec3d w;                                ///< angular velocity, world, rad/s
  double inverseMass = 0;                 ///< 1/kg; 0: not moved by impulses
  Mat3d inverseInertia;                   ///< world frame, kg^-1 m^-2; zero with inverseMass 0
  Vec3d originOffset;                     ///< body origin minus centre of mass, body frame, m
  Vec3d pushV, pushW;                     ///< overlap push of this substep (m/s, rad/s): pose only

  /// The dynamic body `body` at the collider state `s` (pose of the body
  /// origin, velocity of the origin, angular velocity).
  static RigidBodyState dynamic(const RigidBody& body, const ColliderState& s);
  /// A kinematic collider at state `s`: infinite mass, moving as `s` says.
  static RigidBodyState kinematic(const ColliderState& s);

  bool movable() const { return inverseMass > 0; }
  /// Velocity (m/s) of the body's material at world point p.
  Vec3d velocityAt(const Vec3d& p) const { return v + cross(w, p - x); }
  /// Applies impulse P (N*s) at world point p.
  void applyImpulse(const Vec3d& P, const Vec3d& p);
  /// The overlap push's velocity at world point p, and a push impulse
  /// (kg m/s, changing pushV and pushW as applyImpulse changes v and w).
  Vec3d pushVelocityAt(const Vec3d& p) const { return pushV + cross(pushW, p - x); }
  void applyPushImpulse(const Vec3d& P, const Vec3d& p);
  /// Inverse effective mass (1/kg) for an impulse along unit direction n at
  /// world point p: 1/m + n . (I_w^-1 (r x n)) x r.
  double inverseEffectiveMass(const Vec3d& n, const Vec3d& p) const;
  /// Momentum (kg m/s) and angular momentum about the world origin (kg m^2/s).
  Vec3d momentum() const;
  Vec3d angularMomentum() const;
  /// The collider state (pose of the body origin, its velocity, w).
  ColliderState colliderState() const;
  /// Semi-implicit Euler position update over dt (s), see the header
  /// comment (the push is used and cleared); `body` gives the body-frame
  /// inertia.
  void advance(const RigidBody& body, double dt);
};

/// A point of material (a grid node or a particle) in contact with a body.
struct RigidCouplingPoint {
  double m = 0;  ///< mass, kg
  Vec3d x;       ///< position, m
  Vec3d n;       ///< the body's outward unit normal there
  Vec3d v;       ///< velocity, m/s (replaced by the velocity after the exchange)
};

/// The momentum exchange of a dynamic body with material points inside it:
/// the body's velocity solves (M + sum m J^T P J) V = M V_body + sum m J^T P
/// v (J V the body's velocity at a point, P = I for sticky, n n^T for slip
/// and for separate where the point approaches), the boundary condition `bc`
/// is applied to the points with that velocity, and the body takes exactly
/// the opposite of their momentum change (linear and angular momentum are
/// kept to round-off). Friction's part is scaled down, if needed, so that it
/// brings body and points at most to sticking: the explicit friction
/// impulse cannot throw a light body about. Implicit in the body's
/// velocity, so a body far lighter than the material stays stable.
/// Returns the momentum given to the points (N*s).
Vec3d exchangeMomentum(RigidBodyState& body, const BoundaryCondition& bc, std::vector<RigidCouplingPoint>& points);

}  // namespace mpm
}  // namespace lodestone
