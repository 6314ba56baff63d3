// Dynamic rigid bodies: mass properties of the collider shapes and the
// semi-implicit Euler state update. See mpm/rigid_body.h.
#include "lodestone/core/mpm/rigid_body.h"

#include <cmath>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/symmetric_eigen.h"
#include "lodestone/core/mpm/collider.h"

namespace lodestone {
inline namespace mpm {

namespace {

Mat3d diagonal(double a, double b, double c) {
  Mat3d m;
  m(0, 0) = a;
  m(1, 1) = b;
  m(2, 2) = c;
  return m;
}

Mat3d scaled(const Mat3d& a, double s) {
  Mat3d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = s * a(i, j);
  return r;
}

/// R A R^T
Mat3d rotated(const Mat3d& R, const Mat3d& A) { return R * A * R.transposed(); }

/// Inverse of a symmetric positive definite inertia tensor.
Mat3d inverseOfInertia(const Mat3d& I, const char* who) {
  const SymmetricEigen3<double> e = symmetricEigen(I);
  for (const double l : e.values)
    require(std::isfinite(l) && l > 0, who, ": the inertia tensor is not positive definite (principal moment ", l,
            " kg m^2)");
  return rotated(e.vectors, diagonal(1 / e.values[0], 1 / e.values[1], 1 / e.values[2]));
}

/// Mass properties of a level set: sums over its samples with the smoothed
/// Heaviside of SampledSdf::volume.
RigidMassProperties levelSetMass(const SampledSdf& sdf, double density) {
  const GridSpec& g = sdf.spec();
  const double h = g.dx, eps = 1.5 * h;
  const std::vector<float>& phi = sdf.values();
  double w0 = 0;
  Vec3d w1;
  Mat3d w2;  // sum w x x^T
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) {
        const double w = smoothedInsideFraction(phi[g.index(i, j, k)], eps);
        if (w == 0) continue;
        const Vec3d x = g.nodePosition(i, j, k);
        w0 += w;
        w1 += w * x;
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) w2(a, b) += w * x[a] * x[b];
      }
  require(w0 > 0, "level-set rigid body: the level set '", sdf.description(), "' has no inside");
  RigidMassProperties p;
  const double cell = h * h * h;
  p.mass = density * w0 * cell;
  p.centreOfMass = w1 / w0;
  // Second moment about the centre: S = sum w x x^T - W c c^T; I = tr(S) 1 - S.
  Mat3d S;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) S(a, b) = density * cell * (w2(a, b) - w0 * p.centreOfMass[a] * p.centreOfMass[b]);
  const double tr = S(0, 0) + S(1, 1) + S(2, 2);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) p.inertia(a, b) = (a == b ? tr : 0.0) - S(a, b);
  return p;
}

}  // namespace

RigidMassProperties massProperties(const ColliderShape& shape, double density) {
  require(std::isfinite(density) && density > 0, "rigid body: density must be a positive finite value in kg/m^3, got ",
          density);
  shape.validate("rigid body");
  require(!shape.inverted, "rigid body: an inverted ", toString(shape.kind),
          " (solid outside the shape) has infinite mass and cannot be dynamic");
  RigidMassProperties p;
  switch (shape.kind) {
    case ColliderShapeKind::Plane:
      throw InvalidArgument("rigid body: a plane (a half-space) has infinite mass and cannot be dynamic");
    case ColliderShapeKind::Sphere: {
      const double r = shape.radius;
      p.mass = density * 4.0 / 3.0 * kPi * r * r * r;
      const double i = 0.4 * p.mass * r * r;
      p.inertia = diagonal(i, i, i);
      break;
    }
    case ColliderShapeKind::Box: {
      const Vec3d a = shape.halfSize;
      p.mass = density * 8 * a.x * a.y * a.z;
      p.inertia = diagonal(p.mass / 3 * (a.y * a.y + a.z * a.z), p.mass / 3 * (a.x * a.x + a.z * a.z),
                           p.mass / 3 * (a.x * a.x + a.y * a.y));
      break;
    }
    case ColliderShapeKind::Cylinder: {
      const double r = shape.radius, L = 2 * shape.halfLength;
      p.mass = density * kPi * r * r * L;
      const double side = p.mass * (3 * r * r + L * L) / 12;
      p.inertia = diagonal(side, side, 0.5 * p.mass * r * r);
      break;
    }
    case ColliderShapeKind::LevelSet:
      p = levelSetMass(*shape.levelSet, density);
      break;
  }
  p.inverseInertia = inverseOfInertia(p.inertia, "rigid body");
  return p;
}

void RigidBodySettings::validate(const char* who) const {
  require(std::isfinite(density) && density > 0, who, ": density must be a positive finite value in kg/m^3, got ",
          density);
  require(std::isfinite(mass) && mass >= 0, who, ": mass must be a finite value >= 0 in kg (0: from the density), got ",
          mass);
  require(std::isfinite(restitution) && restitution >= 0 && restitution <= 1, who,
          ": restitution must be in [0, 1], got ", restitution);
  require(std::isfinite(friction) && friction >= 0, who,
          ": friction must be a finite Coulomb coefficient >= 0 (dimensionless), got ", friction);
}

RigidBody RigidBody::of(const ColliderShape& shape, const RigidBodySettings& settings) {
  settings.validate("rigid body");
  RigidBody b;
  b.settings = settings;
  b.mass = massProperties(shape, settings.density);
  if (settings.mass > 0) {
    const double s = settings.mass / b.mass.mass;
    b.mass.mass = settings.mass;
    b.mass.inertia = scaled(b.mass.inertia, s);
    b.mass.inverseInertia = scaled(b.mass.inverseInertia, 1 / s);
    b.settings.density *= s;
  }
  return b;
}

RigidBodyState RigidBodyState::dynamic(const RigidBody& body, const ColliderState& s) {
  RigidBodyState b;
  b.rotation = s.pose.rotation;
  b.originOffset = -body.mass.centreOfMass;
  b.x = s.pose.toWorld(body.mass.centreOfMass);
  b.w = s.angularVelocity;
  b.v = s.velocity + cross(s.angularVelocity, b.x - s.pose.position);
  b.inverseMass = 1 / body.mass.mass;
  b.inverseInertia = rotated(b.rotation, body.mass.inverseInertia);
  return b;
}

RigidBodyState RigidBodyState::kinematic(const ColliderState& s) {
  RigidBodyState b;
  b.rotation = s.pose.rotation;
  b.x = s.pose.position;
  b.v = s.velocity;
  b.w = s.angularVelocity;
  return b;
}

void RigidBodyState::applyImpulse(const Vec3d& P, const Vec3d& p) {
  if (!movable()) return;
  v += inverseMass * P;
  w += inverseInertia * cross(p - x, P);
}

double RigidBodyState::inverseEffectiveMass(const Vec3d& n, const Vec3d& p) const {
  if (!movable()) return 0;
  const Vec3d r = p - x;
  return inverseMass + dot(n, cross(inverseInertia * cross(r, n), r));
}

Vec3d RigidBodyState::momentum() const { return movable() ? v / inverseMass : Vec3d{}; }

Vec3d RigidBodyState::angularMomentum() const {
  if (!movable()) return {};
  // L about the origin = x x (m v) + I_w w; I_w = (I_w^-1)^-1.
  return cross(x, momentum()) + inverseOfInertia(inverseInertia, "rigid body state") * w;
}

ColliderState RigidBodyState::colliderState() const {
  ColliderState s;
  s.pose.rotation = rotation;
  s.pose.position = x + rotation * originOffset;
  s.velocity = velocityAt(s.pose.position);
  s.angularVelocity = w;
  return s;
}

void RigidBodyState::advance(const RigidBody& body, double dt) {
  const Vec3d L = rotated(rotation, body.mass.inertia) * w;  // angular momentum about the centre
  x += dt * v;
  rotation = orthonormalized(rotationFromVector(dt * w) * rotation);
  inverseInertia = rotated(rotation, body.mass.inverseInertia);
  w = inverseInertia * L;
}

}  // namespace mpm
}  // namespace lodestone
