// Analytic colliders: shapes, rigid motions (static, keyframed with slerp,
// constant velocity) and the grid boundary conditions. See mpm_collider.h.
#include "lodestone/core/mpm/collider.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "lodestone/core/base/error.h"
#include "lodestone/core/sources/magnet_source.h"

namespace lodestone {
inline namespace mpm {

namespace {

/// Unit quaternion (w, x, y, z).
struct Quat {
  double w = 1, x = 0, y = 0, z = 0;
};

Quat normalized(Quat q) {
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}

/// Quaternion of a proper rotation matrix (Shepperd's method: divides by the
/// largest of the four candidates, so it is stable for every rotation).
Quat fromMatrix(const Mat3d& R) {
  const double t = R(0, 0) + R(1, 1) + R(2, 2);
  Quat q;
  if (t >= R(0, 0) && t >= R(1, 1) && t >= R(2, 2)) {
    const double s = 2 * std::sqrt(1 + t);
    q = {0.25 * s, (R(2, 1) - R(1, 2)) / s, (R(0, 2) - R(2, 0)) / s, (R(1, 0) - R(0, 1)) / s};
  } else if (R(0, 0) >= R(1, 1) && R(0, 0) >= R(2, 2)) {
    const double s = 2 * std::sqrt(1 + R(0, 0) - R(1, 1) - R(2, 2));
    q = {(R(2, 1) - R(1, 2)) / s, 0.25 * s, (R(0, 1) + R(1, 0)) / s, (R(0, 2) + R(2, 0)) / s};
  } else if (R(1, 1) >= R(2, 2)) {
    const double s = 2 * std::sqrt(1 + R(1, 1) - R(0, 0) - R(2, 2));
    q = {(R(0, 2) - R(2, 0)) / s, (R(0, 1) + R(1, 0)) / s, 0.25 * s, (R(1, 2) + R(2, 1)) / s};
  } else {
    const double s = 2 * std::sqrt(1 + R(2, 2) - R(0, 0) - R(1, 1));
    q = {(R(1, 0) - R(0, 1)) / s, (R(0, 2) + R(2, 0)) / s, (R(1, 2) + R(2, 1)) / s, 0.25 * s};
  }
  return normalized(q);
}

Quat multiply(const Quat& a, const Quat& b) {
  return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

Quat conjugate(const Quat& q) { return {q.w, -q.x, -q.y, -q.z}; }

Mat3d toMatrix(const Quat& q) { return Pose::fromQuaternion({}, q.w, q.x, q.y, q.z).rotation; }

/// Rotation vector (axis * angle, rad) of the unit quaternion q, angle in [0, pi].
Vec3d rotationVector(Quat q) {
  if (q.w < 0) q = {-q.w, -q.x, -q.y, -q.z};
  const Vec3d v{q.x, q.y, q.z};
  const double s = norm(v);
  if (s == 0) return {};
  return v * (2 * std::atan2(s, q.w) / s);
}

/// Shortest-arc spherical interpolation between unit quaternions, s in [0, 1].
Quat slerp(const Quat& a, Quat b, double s) {
  double c = a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z;
  if (c < 0) {
    b = {-b.w, -b.x, -b.y, -b.z};
    c = -c;
  }
  double wa, wb;
  if (c > 1 - 1e-12) {  // nearly equal: linear interpolation, then normalise
    wa = 1 - s;
    wb = s;
  } else {
    const double theta = std::acos(c);
    const double sn = std::sin(theta);
    wa = std::sin((1 - s) * theta) / sn;
    wb = std::sin(s * theta) / sn;
  }
  return normalized({wa * a.w + wb * b.w, wa * a.x + wb * b.x, wa * a.y + wb * b.y, wa * a.z + wb * b.z});
}

}  // namespace

const char* toString(BoundaryMode mode) {
  switch (mode) {
    case BoundaryMode::Sticky:
      return "sticky";
    case BoundaryMode::Slip:
      return "slip";
    case BoundaryMode::Separate:
      return "separate";
  }
  return "unknown";
}

const char* toString(ColliderShapeKind kind) {
  switch (kind) {
    case ColliderShapeKind::Plane:
      return "plane";
    case ColliderShapeKind::Box:
      return "box";
    case ColliderShapeKind::Sphere:
      return "sphere";
    case ColliderShapeKind::Cylinder:
      return "cylinder";
    case ColliderShapeKind::LevelSet:
      return "level set";
  }
  return "unknown";
}

void BoundaryCondition::validate(const char* who) const {
  require(mode == BoundaryMode::Sticky || mode == BoundaryMode::Slip || mode == BoundaryMode::Separate, who,
          ": unknown boundary mode ", int(mode));
  require(std::isfinite(friction) && friction >= 0, who,
          ": Coulomb friction coefficient must be finite and >= 0 (dimensionless), got ", friction);
}

ColliderShape ColliderShape::plane() { return ColliderShape{}; }

ColliderShape ColliderShape::box(const Vec3d& halfSize) {
  ColliderShape s;
  s.kind = ColliderShapeKind::Box;
  s.halfSize = halfSize;
  s.validate("box collider");
  return s;
}

ColliderShape ColliderShape::sphere(double radius) {
  ColliderShape s;
  s.kind = ColliderShapeKind::Sphere;
  s.radius = radius;
  s.validate("sphere collider");
  return s;
}

ColliderShape ColliderShape::cylinder(double radius, double halfLength) {
  ColliderShape s;
  s.kind = ColliderShapeKind::Cylinder;
  s.radius = radius;
  s.halfLength = halfLength;
  s.validate("cylinder collider");
  return s;
}

ColliderShape ColliderShape::levelSetShape(std::shared_ptr<const SampledSdf> sdf) {
  ColliderShape s;
  s.kind = ColliderShapeKind::LevelSet;
  s.levelSet = std::move(sdf);
  s.validate("level-set collider");
  return s;
}

ColliderShape ColliderShape::invertedShape() const {
  ColliderShape s = *this;
  s.inverted = !inverted;
  return s;
}

double ColliderShape::halfThickness() const {
  const double infinite = std::numeric_limits<double>::infinity();
  switch (kind) {
    case ColliderShapeKind::Plane:
      return infinite;
    case ColliderShapeKind::Sphere:
      return inverted ? infinite : radius;
    case ColliderShapeKind::Box:
      return inverted ? infinite : std::min({halfSize.x, halfSize.y, halfSize.z});
    case ColliderShapeKind::Cylinder:
      return inverted ? infinite : std::min(radius, halfLength);
    case ColliderShapeKind::LevelSet:
      return inverted ? levelSet->outsideRidgeDepth() : levelSet->insideRidgeDepth();
  }
  return infinite;
}

double ColliderShape::boundingRadius() const {
  const double infinite = std::numeric_limits<double>::infinity();
  if (inverted) return infinite;
  switch (kind) {
    case ColliderShapeKind::Plane:
      return infinite;
    case ColliderShapeKind::Sphere:
      return radius;
    case ColliderShapeKind::Box:
      return norm(halfSize);
    case ColliderShapeKind::Cylinder:
      return std::sqrt(radius * radius + halfLength * halfLength);
    case ColliderShapeKind::LevelSet: {
      Vec3d lo, hi;
      levelSet->interiorBounds(lo, hi);
      double r = 0;
      for (int c = 0; c < 8; ++c) r = std::max(r, norm(Vec3d{c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z}));
      return r;
    }
  }
  return infinite;
}

void ColliderShape::validate(const char* who) const {
  switch (kind) {
    case ColliderShapeKind::Plane:
      return;
    case ColliderShapeKind::Box:
      require(isFinite(halfSize) && halfSize.x > 0 && halfSize.y > 0 && halfSize.z > 0, who,
              ": half-sizes must be positive finite lengths in m, got (", halfSize.x, ", ", halfSize.y, ", ",
              halfSize.z, ")");
      return;
    case ColliderShapeKind::Sphere:
      require(std::isfinite(radius) && radius > 0, who, ": radius must be a positive finite length in m, got ", radius);
      return;
    case ColliderShapeKind::Cylinder:
      require(std::isfinite(radius) && radius > 0, who, ": radius must be a positive finite length in m, got ", radius);
      require(std::isfinite(halfLength) && halfLength > 0, who,
              ": half-length must be a positive finite length in m, got ", halfLength);
      return;
    case ColliderShapeKind::LevelSet:
      require(levelSet != nullptr, who, ": level-set shape without a signed-distance grid");
      return;
  }
  throw InvalidArgument(concat(who, ": unknown shape kind ", int(kind)));
}

// ---------------------------------------------------------------------------
// Motion

ColliderMotion ColliderMotion::fixed(const Pose& pose) {
  validatePose(pose, "static collider");
  ColliderMotion m;
  m.pose_ = pose;
  return m;
}

ColliderMotion ColliderMotion::keyframed(std::vector<double> times, std::vector<Pose> poses) {
  require(!times.empty(), "keyframed collider: at least one keyframe is needed");
  require(times.size() == poses.size(), "keyframed collider: ", times.size(), " times but ", poses.size(), " poses");
  for (std::size_t i = 0; i < times.size(); ++i) {
    require(std::isfinite(times[i]), "keyframed collider: keyframe ", i, " time must be finite (s), got ", times[i]);
    // (require's arguments are evaluated eagerly: times[i - 1] only for i > 0)
    if (i > 0)
      require(times[i] > times[i - 1], "keyframed collider: keyframe times must increase strictly, got ",
              times[i - 1], " s then ", times[i], " s at keyframe ", i);
    validatePose(poses[i], "keyframed collider");
  }
  ColliderMotion m;
  m.kind_ = Kind::Keyframed;
  m.pose_ = poses.front();
  m.times_ = std::move(times);
  m.poses_ = std::move(poses);
  return m;
}

ColliderMotion ColliderMotion::constantVelocity(const Pose& pose, const Vec3d& velocity, const Vec3d& angularVelocity,
                                                double t0) {
  validatePose(pose, "moving collider");
  require(isFinite(velocity), "moving collider: velocity must be finite (m/s), got (", velocity.x, ", ", velocity.y,
          ", ", velocity.z, ")");
  require(isFinite(angularVelocity), "moving collider: angular velocity must be finite (rad/s), got (",
          angularVelocity.x, ", ", angularVelocity.y, ", ", angularVelocity.z, ")");
  require(std::isfinite(t0), "moving collider: start time must be finite (s), got ", t0);
  ColliderMotion m;
  m.kind_ = Kind::ConstantVelocity;
  m.pose_ = pose;
  m.velocity_ = velocity;
  m.angular_ = angularVelocity;
  m.t0_ = t0;
  return m;
}

ColliderMotion ColliderMotion::dynamic(const Pose& pose, const Vec3d& velocity, const Vec3d& angularVelocity) {
  ColliderMotion m = constantVelocity(pose, velocity, angularVelocity);
  m.kind_ = Kind::Dynamic;
  return m;
}

Pose ColliderMotion::poseAt(double t) const {
  switch (kind_) {
    case Kind::Static:
    case Kind::Dynamic:
      return pose_;
    case Kind::ConstantVelocity: {
      const double tau = t - t0_;
      Pose p;
      p.position = pose_.position + velocity_ * tau;
      p.rotation = rotationFromVector(angular_ * tau) * pose_.rotation;
      return p;
    }
    case Kind::Keyframed: {
      if (!(t > times_.front())) return poses_.front();
      if (!(t < times_.back())) return poses_.back();
      std::size_t k = 0;
      while (times_[k + 1] <= t) ++k;
      const double s = (t - times_[k]) / (times_[k + 1] - times_[k]);
      const Pose& a = poses_[k];
      const Pose& b = poses_[k + 1];
      Pose p;
      p.position = a.position + (b.position - a.position) * s;
      p.rotation = toMatrix(slerp(fromMatrix(a.rotation), fromMatrix(b.rotation), s));
      return p;
    }
  }
  return pose_;
}

void ColliderMotion::velocityAt(double t, Vec3d& linear, Vec3d& angular) const {
  linear = {};
  angular = {};
  switch (kind_) {
    case Kind::Static:
      return;
    case Kind::ConstantVelocity:
    case Kind::Dynamic:
      linear = velocity_;
      angular = angular_;
      return;
    case Kind::Keyframed: {
      if (!(t >= times_.front()) || !(t < times_.back())) return;
      std::size_t k = 0;
      while (times_[k + 1] <= t) ++k;
      const double dt = times_[k + 1] - times_[k];
      const Pose& a = poses_[k];
      const Pose& b = poses_[k + 1];
      linear = (b.position - a.position) / dt;
      // slerp(qa, qb, s) = (qb qa^-1)^s qa: a constant world-frame rotation rate.
      angular = rotationVector(multiply(fromMatrix(b.rotation), conjugate(fromMatrix(a.rotation)))) / dt;
      return;
    }
  }
}

// ---------------------------------------------------------------------------
// Collider

MpmCollider::MpmCollider(const ColliderShape& shape, const ColliderMotion& motion, const BoundaryCondition& boundary)
    : shape_(shape), motion_(motion), boundary_(boundary) {
  shape_.validate("collider");
  boundary_.validate("collider");
}

void MpmCollider::setMotion(const ColliderMotion& motion) { motion_ = motion; }

void MpmCollider::setDynamics(const RigidBodySettings& settings) { body_ = RigidBody::of(shape_, settings); }

const RigidBody& MpmCollider::body() const {
  require(body_.has_value(), "collider: not a dynamic rigid body (a ", toString(shape_.kind), " moving ",
          motion_.kind() == ColliderMotion::Kind::Static ? "nowhere" : "as scripted", ")");
  return *body_;
}

void MpmCollider::setBoundary(const BoundaryCondition& boundary) {
  boundary.validate("collider");
  boundary_ = boundary;
}

ColliderState MpmCollider::stateAt(double t) const {
  ColliderState s;
  s.pose = motion_.poseAt(t);
  motion_.velocityAt(t, s.velocity, s.angularVelocity);
  return s;
}

double MpmCollider::signedDistance(const ColliderState& s, const Vec3d& x) const {
  return shape_.signedDistance(s.pose.toLocal(x));
}

Vec3d MpmCollider::apply(const ColliderState& s, const Vec3d& x, const Vec3d& v) const {
  const Vec3d xb = s.pose.toLocal(x);
  if (shape_.signedDistance(xb) > 0) return v;
  const Vec3d n = s.pose.vectorToWorld(shape_.normal(xb));
  const Vec3d vc = s.velocity + cross(s.angularVelocity, x - s.pose.position);
  return applyBoundaryCondition(v, vc, n, boundary_);
}

bool MpmCollider::pushOut(const ColliderState& s, Vec3d& x, double allowed, Vec3d& normal) const {
  const Vec3d xb = s.pose.toLocal(x);
  const double phi = shape_.signedDistance(xb);
  if (!(phi < -allowed)) return false;
  normal = s.pose.vectorToWorld(shape_.normal(xb));
  x = x - (phi + allowed) * normal;
  return true;
}

bool MpmCollider::projectOut(const ColliderState& s, Vec3d& x, Vec3d& v, double allowed) const {
  Vec3d n;
  if (!pushOut(s, x, allowed, n)) return false;
  const Vec3d vc = s.velocity + cross(s.angularVelocity, x - s.pose.position);
  v = applyBoundaryCondition(v, vc, n, boundary_);
  return true;
}

double MpmCollider::signedDistance(const Vec3d& x, double t) const { return signedDistance(stateAt(t), x); }

Vec3d MpmCollider::normal(const Vec3d& x, double t) const {
  const Pose p = motion_.poseAt(t);
  return p.vectorToWorld(shape_.normal(p.toLocal(x)));
}

Vec3d MpmCollider::velocity(const Vec3d& x, double t) const {
  const ColliderState s = stateAt(t);
  return s.velocity + cross(s.angularVelocity, x - s.pose.position);
}

Vec3d MpmCollider::apply(const Vec3d& x, const Vec3d& v, double t) const { return apply(stateAt(t), x, v); }

}  // namespace mpm
}  // namespace lodestone
