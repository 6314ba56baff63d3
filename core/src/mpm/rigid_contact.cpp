// Contacts of rigid bodies: surface samples, detection against signed
// distances, sequential impulses. See mpm/rigid_contact.h.
#include "lodestone/core/mpm/rigid_contact.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_set>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace mpm {

namespace {

/// Points from a to b (both included), at most `spacing` apart.
void segment(const Vec3d& a, const Vec3d& b, double spacing, std::vector<Vec3d>& out) {
  const int n = std::max(1, int(std::ceil(norm(b - a) / spacing)));
  for (int i = 0; i <= n; ++i) out.push_back(a + (b - a) * (double(i) / n));
}

void boxSamples(const Vec3d& h, double spacing, std::vector<Vec3d>& out) {
  // The 12 edges: along each axis, at the four (+-, +-) positions of the other two.
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, w = (axis + 2) % 3;
    for (int s = 0; s < 4; ++s) {
      Vec3d a, b;
      a[u] = b[u] = (s & 1) ? h[u] : -h[u];
      a[w] = b[w] = (s & 2) ? h[w] : -h[w];
      a[axis] = -h[axis];
      b[axis] = h[axis];
      segment(a, b, spacing, out);
    }
  }
}

void cylinderSamples(double r, double hl, double spacing, std::vector<Vec3d>& out) {
  const int n = std::max(8, int(std::ceil(2 * kPi * r / spacing)));
  for (const double z : {-hl, hl}) {
    for (int i = 0; i < n; ++i) {
      const double a = 2 * kPi * i / n;
      out.push_back({r * std::cos(a), r * std::sin(a), z});
    }
    segment({-r, 0, z}, {r, 0, z}, spacing, out);
    segment({0, -r, z}, {0, r, z}, spacing, out);
  }
}

void levelSetSamples(const SampledSdf& sdf, double spacing, std::vector<Vec3d>& out) {
  const GridSpec& g = sdf.spec();
  const double band = 0.5 * std::max(spacing, g.dx);
  std::unordered_set<std::uint64_t> taken;
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) {
        const double phi = sdf.values()[g.index(i, j, k)];
        if (std::fabs(phi) > band) continue;
        const Vec3d x = g.nodePosition(i, j, k);
        const Vec3d p = x - phi * sdf.normal(x);
        const auto cell = [&](double c) { return std::uint64_t(std::int64_t(std::floor(c / spacing)) & 0x1fffff); };
        const std::uint64_t key = cell(p.x) | (cell(p.y) << 21) | (cell(p.z) << 42);
        if (taken.insert(key).second) out.push_back(p);
      }
}

}  // namespace

std::vector<Vec3d> contactSamples(const ColliderShape& shape, double spacing) {
  require(std::isfinite(spacing) && spacing > 0, "contact samples: spacing must be a positive finite length in m, got ",
          spacing);
  std::vector<Vec3d> out;
  if (shape.inverted) return out;
  switch (shape.kind) {
    case ColliderShapeKind::Plane:
    case ColliderShapeKind::Sphere:
      break;
    case ColliderShapeKind::Box:
      boxSamples(shape.halfSize, spacing, out);
      break;
    case ColliderShapeKind::Cylinder:
      cylinderSamples(shape.radius, shape.halfLength, spacing, out);
      break;
    case ColliderShapeKind::LevelSet:
      levelSetSamples(*shape.levelSet, spacing, out);
      break;
  }
  return out;
}

void findContacts(const RigidContactBody& A, std::size_t ia, const RigidContactBody& B, std::size_t ib,
                  double friction, double restitution, std::vector<RigidContact>& out) {
  const double ra = A.shape->boundingRadius(), rb = B.shape->boundingRadius();
  if (std::isfinite(ra) && std::isfinite(rb) && norm(A.state.pose.position - B.state.pose.position) > ra + rb) return;
  const auto contactAt = [&](const Vec3d& p, double reach) {
    const Vec3d xb = B.state.pose.toLocal(p);
    const double phi = B.shape->signedDistance(xb) - reach;
    if (!(phi < 0)) return;
    RigidContact c;
    c.a = ia;
    c.b = ib;
    c.normal = B.state.pose.vectorToWorld(B.shape->normal(xb));
    c.point = p - reach * c.normal;
    c.depth = -phi;
    c.friction = friction;
    c.restitution = restitution;
    out.push_back(c);
  };
  if (A.shape->kind == ColliderShapeKind::Sphere && !A.shape->inverted) {
    contactAt(A.state.pose.position, A.shape->radius);
    return;
  }
  if (!A.samples) return;
  for (const Vec3d& s : *A.samples) contactAt(A.state.pose.toWorld(s), 0.0);
}

double solveContacts(std::vector<RigidBodyState>& bodies, const std::vector<RigidContact>& contacts, double dt,
                     const RigidContactSettings& settings) {
  require(std::isfinite(dt) && dt > 0, "rigid contacts: dt must be a positive finite time in s, got ", dt);
  struct Row {
    double kn = 0;       // inverse effective mass along the normal, 1/kg
    double target = 0;   // normal relative velocity to reach, m/s
    double push = 0;     // normal separation speed the overlap push asks for, m/s
    double Pn = 0;       // accumulated normal impulse, N*s
    double Pp = 0;       // accumulated push impulse, N*s
    Vec3d Pt;            // accumulated friction impulse, N*s
  };
  std::vector<Row> rows(contacts.size());
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    const RigidContact& k = contacts[c];
    const RigidBodyState &a = bodies[k.a], &b = bodies[k.b];
    Row& r = rows[c];
    r.kn = a.inverseEffectiveMass(k.normal, k.point) + b.inverseEffectiveMass(k.normal, k.point);
    const double vn = dot(a.velocityAt(k.point) - b.velocityAt(k.point), k.normal);
    const double bounce = -vn > settings.restitutionSpeed ? -k.restitution * vn : 0.0;
    r.target = bounce;
    r.push = settings.baumgarte * std::max(k.depth - settings.slop, 0.0) / dt;
  }
  double largest = 0;
  for (int it = 0; it < settings.iterations; ++it) {
    for (std::size_t c = 0; c < contacts.size(); ++c) {
      const RigidContact& k = contacts[c];
      Row& r = rows[c];
      if (!(r.kn > 0)) continue;
      RigidBodyState &a = bodies[k.a], &b = bodies[k.b];
      // Normal.
      Vec3d rel = a.velocityAt(k.point) - b.velocityAt(k.point);
      const double vn = dot(rel, k.normal);
      const double Pn = std::max(r.Pn + (r.target - vn) / r.kn, 0.0);
      const Vec3d dPn = (Pn - r.Pn) * k.normal;
      r.Pn = Pn;
      a.applyImpulse(dPn, k.point);
      b.applyImpulse(-1.0 * dPn, k.point);
      // Friction, within the Coulomb disc of the accumulated normal impulse.
      if (k.friction > 0) {
        rel = a.velocityAt(k.point) - b.velocityAt(k.point);
        const Vec3d vt = rel - dot(rel, k.normal) * k.normal;
        const double speed = norm(vt);
        if (speed > 0) {
          const Vec3d t = vt / speed;
          const double kt = a.inverseEffectiveMass(t, k.point) + b.inverseEffectiveMass(t, k.point);
          Vec3d Pt = r.Pt - (speed / kt) * t;
          const double limit = k.friction * r.Pn, size = norm(Pt);
          if (size > limit) Pt = Pt * (limit / size);
          const Vec3d dPt = Pt - r.Pt;
          r.Pt = Pt;
          a.applyImpulse(dPt, k.point);
          b.applyImpulse(-1.0 * dPt, k.point);
        }
      }
    }
  }
  // The overlap push, normal only, on the push velocities.
  for (int it = 0; it < settings.iterations; ++it) {
    for (std::size_t c = 0; c < contacts.size(); ++c) {
      const RigidContact& k = contacts[c];
      Row& r = rows[c];
      if (!(r.kn > 0) || (r.push == 0 && r.Pp == 0)) continue;
      RigidBodyState &a = bodies[k.a], &b = bodies[k.b];
      const double vn = dot(a.pushVelocityAt(k.point) - b.pushVelocityAt(k.point), k.normal);
      const double Pp = std::max(r.Pp + (r.push - vn) / r.kn, 0.0);
      const Vec3d dP = (Pp - r.Pp) * k.normal;
      r.Pp = Pp;
      a.applyPushImpulse(dP, k.point);
      b.applyPushImpulse(-1.0 * dP, k.point);
    }
  }
  for (const Row& r : rows) largest = std::max(largest, r.Pn);
  return largest;
}

}  // namespace mpm
}  // namespace lodestone
