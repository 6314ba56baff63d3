// The MPM solver's dynamic rigid bodies: external forces, contacts, the
// momentum exchange with the grid and the pose update. See "Rigid bodies" in
// mpm/solver.h.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <tbb/parallel_for.h>

#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/sources/sphere_magnet.h"

namespace lodestone {
inline namespace mpm {

namespace {

/// How far (in cells) outside a dynamic body the grid nodes exchange
/// momentum with it. The material's stress reaches the body through the
/// nodes the body takes; a particle at distance s from the coupled nodes
/// pushes on them with the weight chi(s) = sum of their kernel weights. With
/// the nodes inside the body alone, chi at the surface is 0.5 on average
/// over the surface's place between nodes (0.125 to 0.875), and a body
/// feels half the pressure on it (a floating 8-cell cube sat 2.1 cells
/// low); with the nodes up to one cell out it is 0.98 (0.875 to 1), and the
/// cube floats 0.24 cells low. The price: sticky material within a cell of
/// the body moves with it (a body drags a little more fluid).
constexpr double kCouplingBand = 1.0;

/// Force and torque of magnet a on magnet b, for bodies that may touch or
/// overlap slightly in contact: two spheres by their dipoles (exact while
/// they are apart); other shapes by the surface-charge integral of order 8
/// (about 1e-7 relative at 1.5 edge lengths, docs/physics.md), and by their
/// dipoles where contact made them overlap (the integral refuses overlap).
MagnetWrench touchingMagnetInteraction(const MagnetSource& a, const MagnetSource& b, double t) {
  const bool spheres = dynamic_cast<const SphereMagnet*>(&a) && dynamic_cast<const SphereMagnet*>(&b);
  if (!spheres) {
    try {
      return magnetInteraction(a, b, t, MagnetInteractionMethod::SurfaceCharge, 8);
    } catch (const InvalidArgument&) {
      // overlapping in contact: the dipoles below
    }
  }
  const Vec3d r = b.pose().position - a.pose().position;
  if (!(norm(r) > 0)) return {};
  return {dipoleDipoleForce(a.moment(t), b.moment(t), r), dipoleDipoleTorque(a.moment(t), b.moment(t), r)};
}

/// A body's coupling points over the processes of a partition (collective):
/// every process's points with their keys (a grid node's flat index in the
/// whole grid, or a particle's id), sorted by key, on every process. Sorted,
/// the nodes come in the order one process visits them, so the exchange sums
/// them in the same order.
struct GatheredPoints {
  std::vector<std::uint64_t> keys;
  std::vector<RigidCouplingPoint> points;
  /// The position of `key` in keys, or keys.size().
  std::size_t find(std::uint64_t key) const {
    const auto it = std::lower_bound(keys.begin(), keys.end(), key);
    return it != keys.end() && *it == key ? std::size_t(it - keys.begin()) : keys.size();
  }
};

GatheredPoints gatherPoints(MpmPartition& partition, const std::vector<std::uint64_t>& keys,
                            const std::vector<RigidCouplingPoint>& points) {
  constexpr std::size_t R = 11;  // key, m, x, n, v
  std::vector<double> local;
  local.reserve(R * points.size());
  for (std::size_t q = 0; q < points.size(); ++q) {
    const RigidCouplingPoint& c = points[q];
    local.insert(local.end(),
                 {keyAsDouble(keys[q]), c.m, c.x.x, c.x.y, c.x.z, c.n.x, c.n.y, c.n.z, c.v.x, c.v.y, c.v.z});
  }
  const std::vector<double> all = allGatherByKey(partition, local, R);
  GatheredPoints g;
  for (std::size_t q = 0; q < all.size() / R; ++q) {
    const double* r = &all[q * R];
    g.keys.push_back(keyOf(r[0]));
    g.points.push_back({r[1], {r[2], r[3], r[4]}, {r[5], r[6], r[7]}, {r[8], r[9], r[10]}});
  }
  return g;
}

}  // namespace

bool MpmSolver::anyDynamicBodies() const {
  for (const MpmCollider& c : colliders_)
    if (c.isDynamic()) return true;
  return false;
}

std::size_t MpmSolver::colliderMagnet(std::size_t c) const {
  for (std::size_t m = 0; m < magnetCollider_.size(); ++m)
    if (magnetCollider_[m] == c) return m;
  return magnets_.size();
}

MagnetWrench MpmSolver::magnetWrench(std::size_t m) const {
  require(m < magnets_.size(), "MPM solver: magnet ", m, " out of range (", magnets_.size(), " magnets)");
  return m < magnetWrench_.size() ? magnetWrench_[m] : MagnetWrench{};
}

void MpmSolver::updateMagnetWrenches() {
  magnetWrench_.assign(magnets_.size(), MagnetWrench{});
  std::vector<bool> dynamic(magnets_.size(), false);
  bool any = false;
  for (std::size_t m = 0; m < magnets_.size(); ++m) {
    dynamic[m] = magnetCollider_[m] != kNoCollider && colliders_[magnetCollider_[m]].isDynamic();
    any = any || dynamic[m];
  }
  if (!any) return;
  for (std::size_t m = 0; m < magnets_.size() && m < magnetReaction_.size(); ++m)
    if (dynamic[m]) magnetWrench_[m] = magnetReaction_[m];
  poseMagnetsAt(time_);
  for (std::size_t a = 0; a < magnets_.size(); ++a)
    for (std::size_t b = 0; b < magnets_.size(); ++b) {
      if (a == b || !dynamic[b]) continue;
      const MagnetWrench w = touchingMagnetInteraction(*magnets_[a], *magnets_[b], time_);
      magnetWrench_[b].force += w.force;
      magnetWrench_[b].torque += w.torque;
    }
}

void MpmSolver::predictRigidBodies(double dt) {
  const std::size_t nc = colliders_.size();
  rigid_.assign(nc + 1, RigidBodyState{});
  if (materialImpulse_.size() != nc) {
    materialImpulse_.assign(nc, Vec3d{});
    contactImpulse_.assign(nc, Vec3d{});
  }
  if (contactSamples_.size() != nc) contactSamples_.assign(nc, {});
  // A dynamic collider not stepped yet starts from its scripted motion now.
  for (MpmCollider& col : colliders_)
    if (col.isDynamic() && col.motion().kind() != ColliderMotion::Kind::Dynamic) {
      const ColliderState s = col.stateAt(time_);
      col.setMotion(ColliderMotion::dynamic(s.pose, s.velocity, s.angularVelocity));
    }
  updateMagnetWrenches();
  const double spacing = 0.5 * settings_.grid.dx;
  for (std::size_t c = 0; c < nc; ++c) {
    const MpmCollider& col = colliders_[c];
    if (!col.isDynamic()) {
      rigid_[c] = RigidBodyState::kinematic(col.stateAt(time_));
      continue;
    }
    RigidBodyState& b = rigid_[c];
    b = RigidBodyState::dynamic(col.body(), col.stateAt(time_));
    b.v += dt * settings_.gravity;
    const std::size_t m = colliderMagnet(c);
    if (m < magnets_.size()) {
      b.v += (dt * b.inverseMass) * magnetWrench_[m].force;
      b.w += b.inverseInertia * (dt * magnetWrench_[m].torque);
    }
  }
  // The domain walls: the solid outside the domain box.
  const Vec3d lo = domainLower(), hi = domainUpper();
  const ColliderShape walls = ColliderShape::box(0.5 * (hi - lo)).invertedShape();
  ColliderState wallState;
  wallState.pose = Pose::at(0.5 * (lo + hi));
  rigid_[nc] = RigidBodyState::kinematic(wallState);

  std::vector<RigidContact> contacts;
  const auto bodyOf = [&](std::size_t c) {
    RigidContactBody b;
    b.shape = &colliders_[c].shape();
    b.state = colliders_[c].stateAt(time_);
    if (contactSamples_[c].empty() && colliders_[c].isDynamic())
      contactSamples_[c] = contactSamples(colliders_[c].shape(), spacing);
    b.samples = &contactSamples_[c];
    return b;
  };
  for (std::size_t a = 0; a < nc; ++a) {
    if (!colliders_[a].isDynamic()) continue;
    const RigidBodySettings& sa = colliders_[a].body().settings;
    const RigidContactBody A = bodyOf(a);
    for (std::size_t b = 0; b < nc; ++b) {
      if (b == a || (colliders_[b].isDynamic() && b < a)) continue;
      const RigidContactBody B = bodyOf(b);
      double mu = sa.friction, e = sa.restitution;
      if (colliders_[b].isDynamic()) {
        const RigidBodySettings& sb = colliders_[b].body().settings;
        mu = std::sqrt(sa.friction * sb.friction);
        e = std::max(sa.restitution, sb.restitution);
      }
      findContacts(A, a, B, b, mu, e, contacts);
      findContacts(B, b, A, a, mu, e, contacts);
    }
    if (settings_.wallNodes > 0) {
      RigidContactBody W;
      W.shape = &walls;
      W.state = wallState;
      findContacts(A, a, W, nc, sa.friction, sa.restitution, contacts);
    }
  }
  if (contacts.empty()) return;
  std::vector<Vec3d> before(nc);
  for (std::size_t c = 0; c < nc; ++c) before[c] = rigid_[c].momentum();
  RigidContactSettings cs;
  cs.slop = 0.01 * settings_.grid.dx;
  cs.restitutionSpeed = 2 * norm(settings_.gravity) * dt + 1e-6;
  solveContacts(rigid_, contacts, dt, cs);
  for (std::size_t c = 0; c < nc; ++c) contactImpulse_[c] += rigid_[c].momentum() - before[c];
}

void MpmSolver::exchangeWithRigidBodies(double dt) {
  const GridSpec& g = settings_.grid;
  const Index3 off = partition_ ? partition_->windowLo() : Index3{0, 0, 0};
  const Index3 boxLo = partition_ ? partition_->boxLo() : Index3{0, 0, 0};
  const Index3 boxHi = partition_ ? partition_->boxHi() : g.dims;
  const Index3 lo = grid_.activeLo(), hi = grid_.activeHi();
  const PageArray<MpmNode>& nodes = grid_.nodes();
  PageArray<Vec3d>& vel = grid_.velocity();
  std::vector<std::size_t> index;
  std::vector<RigidCouplingPoint> inside;
  std::vector<std::uint64_t> keys, ownedKeys;  // with a partition: the nodes' flat indices in the whole grid
  std::vector<RigidCouplingPoint> owned;
  for (std::size_t c = 0; c < colliders_.size(); ++c) {
    const MpmCollider& col = colliders_[c];
    if (!col.isDynamic()) continue;
    RigidBodyState& body = rigid_[c];
    const ColliderState pose = body.colliderState();
    // The nodes with mass within kCouplingBand cells of the body (phi <=
    // band), within its bounding sphere. Those inside it (phi <= 0) lose the
    // substep's gravity: their mass is the kernels' reach of material
    // outside, and with its weight the body would carry the weight of the
    // material around it (a box that floats sank). Those in the band outside
    // keep it: their material is there.
    const double R = col.shape().boundingRadius() + g.dx;
    const Vec3d o = pose.pose.position;
    // Grid indices (the whole grid's) over the active box.
    int from[3], to[3];
    const int alo[3] = {lo.i + off.i, lo.j + off.j, lo.k + off.k}, ahi[3] = {hi.i + off.i, hi.j + off.j, hi.k + off.k};
    for (int a = 0; a < 3; ++a) {
      from[a] = std::max(alo[a], int(std::floor((o[a] - R - g.origin[a]) / g.dx)));
      to[a] = std::min(ahi[a], int(std::ceil((o[a] + R - g.origin[a]) / g.dx)) + 1);
    }
    index.clear();
    inside.clear();
    keys.clear();
    ownedKeys.clear();
    owned.clear();
    for (int k = from[2]; k < to[2]; ++k)
      for (int j = from[1]; j < to[1]; ++j) {
        int first = 0, end = 0;  // the row's run: every other node is zero (mpm/grid.h)
        grid_.activeRun(j - off.j, k - off.k, first, end);
        for (int i = std::max(from[0], first + off.i); i < std::min(to[0], end + off.i); ++i) {
          const std::size_t n = grid_.nodeIndex(i - off.i, j - off.j, k - off.k);
          if (!(nodes[n].mass > 0)) continue;
          const Vec3d x = g.nodePosition(i, j, k);
          const Vec3d xb = pose.pose.toLocal(x);
          const double phi = col.shape().signedDistance(xb);
          if (phi > kCouplingBand * g.dx) continue;
          index.push_back(n);
          inside.push_back({nodes[n].mass, x, pose.pose.vectorToWorld(col.shape().normal(xb)),
                            phi > 0 ? vel[n] : vel[n] - dt * settings_.gravity});
          if (!partition_) continue;
          keys.push_back(g.index(i, j, k));
          if (i >= boxLo.i && j >= boxLo.j && k >= boxLo.k && i < boxHi.i && j < boxHi.j && k < boxHi.k) {
            ownedKeys.push_back(keys.back());
            owned.push_back(inside.back());
          }
        }
      }
    if (partition_) {
      // Each node once, from its owner; every window that holds it takes its velocity.
      GatheredPoints all = gatherPoints(*partition_, ownedKeys, owned);
      if (all.points.empty()) continue;
      materialImpulse_[c] -= exchangeMomentum(body, col.boundary(), all.points);
      for (std::size_t q = 0; q < index.size(); ++q) {
        const std::size_t at = all.find(keys[q]);
        if (at < all.keys.size()) vel[index[q]] = all.points[at].v;
      }
      continue;
    }
    if (inside.empty()) continue;
    materialImpulse_[c] -= exchangeMomentum(body, col.boundary(), inside);
    for (std::size_t q = 0; q < index.size(); ++q) vel[index[q]] = inside[q].v;
  }
}

void MpmSolver::advanceRigidBodies(double dt) {
  for (std::size_t c = 0; c < colliders_.size(); ++c) {
    MpmCollider& col = colliders_[c];
    if (!col.isDynamic()) continue;
    RigidBodyState& b = rigid_[c];
    b.advance(col.body(), dt);
    if (!isFinite(b.x) || !isFinite(b.v) || !isFinite(b.w))
      throw Error(concat("rigid body of collider ", c, " (", toString(col.shape().kind), ", ", col.body().mass.mass,
                         " kg): non-finite state at t = ", time_ + dt, " s"));
    const ColliderState s = b.colliderState();
    col.setMotion(ColliderMotion::dynamic(s.pose, s.velocity, s.angularVelocity));
  }
}

std::size_t MpmSolver::pushOutOfBody(std::size_t c, const ColliderState& s, double allowed,
                                     const ParticleBounds& bounds, std::size_t& outside) {
  // Pushed out to the allowance, then the particles and the body exchange
  // momentum as the grid nodes inside it do (exchangeMomentum): implicit, so
  // a light body is not thrown by the material's weight.
  MpmCollider& col = colliders_[c];
  Vec3d* X = particles_.x.data();
  const std::size_t np = particles_.size();
  std::vector<std::uint8_t> deep(np, 0);
  std::vector<Vec3d> normal(np);
  tbb::parallel_for(std::size_t(0), np, [&](std::size_t p) { deep[p] = col.pushOut(s, X[p], allowed, normal[p]); });
  std::vector<std::size_t> index;
  std::vector<RigidCouplingPoint> points;
  std::vector<std::uint64_t> ids;
  for (std::size_t p = 0; p < np; ++p) {
    if (!deep[p]) continue;
    index.push_back(p);
    points.push_back({particles_.mass[p], X[p], normal[p], particles_.v[p]});
    ids.push_back(particles_.id[p]);
    if (bounds.excludes(X[p])) ++outside;
  }
  RigidBodyState body = RigidBodyState::dynamic(col.body(), s);
  Vec3d given;
  if (partition_) {
    // Every process's pushed particles, in id order; each takes back its own.
    GatheredPoints all = gatherPoints(*partition_, ids, points);
    if (all.points.empty()) return 0;
    given = exchangeMomentum(body, col.boundary(), all.points);
    for (std::size_t q = 0; q < index.size(); ++q) particles_.v[index[q]] = all.points[all.find(ids[q])].v;
  } else {
    if (points.empty()) return 0;
    given = exchangeMomentum(body, col.boundary(), points);
    for (std::size_t q = 0; q < index.size(); ++q) particles_.v[index[q]] = points[q].v;
  }
  const ColliderState after = body.colliderState();
  col.setMotion(ColliderMotion::dynamic(after.pose, after.velocity, after.angularVelocity));
  if (c < materialImpulse_.size()) materialImpulse_[c] -= given;
  return points.size();
}

std::vector<RigidBodyReport> MpmSolver::rigidBodies() const {
  std::vector<RigidBodyReport> out;
  for (std::size_t c = 0; c < colliders_.size(); ++c) {
    const MpmCollider& col = colliders_[c];
    if (!col.isDynamic()) continue;
    RigidBodyReport r;
    r.collider = c;
    const std::size_t m = colliderMagnet(c);
    const ColliderState now = col.stateAt(time_);
    const RigidBodyState s = RigidBodyState::dynamic(col.body(), now);
    r.pose = now.pose;
    r.velocity = s.v;
    r.angularVelocity = s.w;
    if (m < magnets_.size()) {
      r.magnet = long(m);
      if (m < magnetWrench_.size()) {
        r.magneticForce = magnetWrench_[m].force;
        r.magneticTorque = magnetWrench_[m].torque;
      }
    }
    if (c < materialImpulse_.size()) {
      r.materialImpulse = materialImpulse_[c];
      r.contactImpulse = contactImpulse_[c];
    }
    out.push_back(r);
  }
  return out;
}

}  // namespace mpm
}  // namespace lodestone
