// Dynamic rigid bodies: mass properties of the collider shapes and the
// semi-implicit Euler state update. See mpm/rigid_body.h.
#include "lodestone/core/mpm/rigid_body.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/symmetric_eigen.h"
#include "lodestone/core/mpm/collider.h"

namespace lodestone {
inline namespace mpm {

namespace {

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
  return rotated(e.vectors, Mat3d::diagonal(1 / e.values[0], 1 / e.values[1], 1 / e.values[2]));
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

/// Solves the symmetric positive definite 6x6 system A x = b in place
/// (Cholesky); false when A is not positive definite.
bool solveSpd6(double A[6][6], double b[6]) {
  for (int j = 0; j < 6; ++j) {
    double d = A[j][j];
    for (int k = 0; k < j; ++k) d -= A[j][k] * A[j][k];
    if (!(d > 0)) return false;
    A[j][j] = std::sqrt(d);
    for (int i = j + 1; i < 6; ++i) {
      double s = A[i][j];
      for (int k = 0; k < j; ++k) s -= A[i][k] * A[j][k];
      A[i][j] = s / A[j][j];
    }
  }
  for (int i = 0; i < 6; ++i) {
    double s = b[i];
    for (int k = 0; k < i; ++k) s -= A[i][k] * b[k];
    b[i] = s / A[i][i];
  }
  for (int i = 5; i >= 0; --i) {
    double s = b[i];
    for (int k = i + 1; k < 6; ++k) s -= A[k][i] * b[k];
    b[i] = s / A[i][i];
  }
  return true;
}

/// The velocity V = (v, w) of the body coupled with the points: the
/// solution of (M + sum m J^T P J) V = M V_body + sum m J^T P v over the
/// `active` points, P = I (`sticky`) or n n^T.
bool coupledVelocity(const RigidBodyState& body, const std::vector<std::uint8_t>& active, bool sticky,
                     const std::vector<RigidCouplingPoint>& points, Vec3d& v, Vec3d& w) {
  const Mat3d Iw = inverseOfInertia(body.inverseInertia, "rigid coupling");
  double A[6][6] = {}, b[6] = {};
  const double mass = 1 / body.inverseMass;
  const Vec3d L = Iw * body.w;
  for (int a = 0; a < 3; ++a) {
    A[a][a] = mass;
    for (int e = 0; e < 3; ++e) A[3 + a][3 + e] = Iw(a, e);
    b[a] = mass * body.v[a];
    b[3 + a] = L[a];
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!active[i]) continue;
    const RigidCouplingPoint& q = points[i];
    const Mat3d P = sticky ? Mat3d::identity() : Mat3d::outer(q.n, q.n);
    // J = [I, -[r]x]; J^T P J = [[P, -P[r]x], [[r]x P, -[r]x P [r]x]].
    const Vec3d r = q.x - body.x;
    const Mat3d Rx = Mat3d::cross(r);
    const Mat3d PR = P * Rx, RP = Rx * P, RPR = Rx * P * Rx;
    const Vec3d Pv = P * q.v, rPv = cross(r, Pv);
    for (int a = 0; a < 3; ++a) {
      for (int e = 0; e < 3; ++e) {
        A[a][e] += q.m * P(a, e);
        A[a][3 + e] -= q.m * PR(a, e);
        A[3 + a][e] += q.m * RP(a, e);
        A[3 + a][3 + e] -= q.m * RPR(a, e);
      }
      b[a] += q.m * Pv[a];
      b[3 + a] += q.m * rPv[a];
    }
  }
  if (!solveSpd6(A, b)) return false;
  v = {b[0], b[1], b[2]};
  w = {b[3], b[4], b[5]};
  return true;
}

}  // namespace

Vec3d exchangeMomentum(RigidBodyState& body, const BoundaryCondition& bc, std::vector<RigidCouplingPoint>& points) {
  require(body.movable(), "rigid coupling: the body has infinite mass");
  const bool sticky = bc.mode == BoundaryMode::Sticky;
  // The points the condition acts on: all, but for separate only those
  // approaching the body. The condition is then applied to exactly these
  // (a point that starts to approach only at the coupled velocity is left
  // alone: acting on it would be an explicit impulse, which threw light
  // bodies about), so the body's velocity is the solve's.
  std::vector<std::uint8_t> active(points.size(), 1);
  if (bc.mode == BoundaryMode::Separate)
    for (std::size_t i = 0; i < points.size(); ++i)
      active[i] = dot(points[i].v - body.velocityAt(points[i].x), points[i].n) < 0;
  RigidBodyState coupled = body;
  if (!coupledVelocity(body, active, sticky, points, coupled.v, coupled.w))
    throw Error("rigid coupling: the coupled momentum system is singular (a body of zero inertia?)");
  // The normal part (or all, sticky) at the coupled velocity, then
  // friction's part, scaled so that it brings body and points at most to
  // sticking.
  const BoundaryCondition slip{BoundaryMode::Slip, 0.0}, rubbing{BoundaryMode::Slip, bc.friction};
  std::vector<Vec3d> normal(points.size()), withFriction(points.size());
  Vec3d Pn{}, Ln{}, Pf{}, Lf{};
  for (std::size_t i = 0; i < points.size(); ++i) {
    const RigidCouplingPoint& q = points[i];
    if (!active[i]) {
      normal[i] = withFriction[i] = q.v;
      continue;
    }
    const Vec3d u = coupled.velocityAt(q.x);
    normal[i] = sticky ? u : applyBoundaryCondition(q.v, u, q.n, slip);
    withFriction[i] = sticky || bc.friction == 0 ? normal[i] : applyBoundaryCondition(q.v, u, q.n, rubbing);
    const Vec3d dn = q.m * (normal[i] - q.v), df = q.m * (withFriction[i] - normal[i]);
    Pn += dn;
    Ln += cross(q.x - body.x, dn);
    Pf += df;
    Lf += cross(q.x - body.x, df);
  }
  double s = 1;
  if (norm2(Pf) + norm2(Lf) > 0) {
    RigidBodyState stuck = body;
    if (coupledVelocity(body, active, true, points, stuck.v, stuck.w)) {
      // Velocity change of the body from friction against the room to sticking, compared as
      // velocities at the farthest point (|dv| + |dw| R).
      double R = 0;
      for (const RigidCouplingPoint& q : points) R = std::max(R, norm(q.x - body.x));
      const Vec3d dvF = -body.inverseMass * Pf, dwF = -1.0 * (body.inverseInertia * Lf);
      const Vec3d afterV = body.v - body.inverseMass * Pn, afterW = body.w - body.inverseInertia * Ln;
      const double room = norm(stuck.v - afterV) + norm(stuck.w - afterW) * R;
      const double step = norm(dvF) + norm(dwF) * R;
      if (step > room) s = room / step;
    }
  }
  Vec3d P{}, L{};
  for (std::size_t i = 0; i < points.size(); ++i) {
    RigidCouplingPoint& q = points[i];
    const Vec3d v = normal[i] + s * (withFriction[i] - normal[i]);
    const Vec3d dp = q.m * (v - q.v);
    q.v = v;
    P += dp;
    L += cross(q.x - body.x, dp);
  }
  body.v -= body.inverseMass * P;
  body.w -= body.inverseInertia * L;
  return P;
}

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
      p.inertia = Mat3d::diagonal(i, i, i);
      break;
    }
    case ColliderShapeKind::Box: {
      const Vec3d a = shape.halfSize;
      p.mass = density * 8 * a.x * a.y * a.z;
      p.inertia = Mat3d::diagonal(p.mass / 3 * (a.y * a.y + a.z * a.z), p.mass / 3 * (a.x * a.x + a.z * a.z),
                           p.mass / 3 * (a.x * a.x + a.y * a.y));
      break;
    }
    case ColliderShapeKind::Cylinder: {
      const double r = shape.radius, L = 2 * shape.halfLength;
      p.mass = density * kPi * r * r * L;
      const double side = p.mass * (3 * r * r + L * L) / 12;
      p.inertia = Mat3d::diagonal(side, side, 0.5 * p.mass * r * r);
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

void RigidBodyState::applyPushImpulse(const Vec3d& P, const Vec3d& p) {
  if (!movable()) return;
  pushV += inverseMass * P;
  pushW += inverseInertia * cross(p - x, P);
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
  x += dt * (v + pushV);
  rotation = orthonormalized(rotationFromVector(dt * (w + pushW)) * rotation);
  pushV = pushW = Vec3d{};
  inverseInertia = rotated(rotation, body.mass.inverseInertia);
  w = inverseInertia * L;
}

}  // namespace mpm
}  // namespace lodestone
