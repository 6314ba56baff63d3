#pragma once
// Contacts of dynamic rigid bodies with each other, with kinematic
// colliders and with the domain walls, resolved by impulses.
//
// Detection: each body's surface is sampled (contactSamples: a box's
// corners and edges, a cylinder's rims and cap diameters, a level set's
// surface; a sphere by its centre and radius) and the samples are tested
// against the other body's signed distance. A sample inside the other solid
// (phi < 0; for a sphere: centre closer than its radius) is a contact at the
// sample, with the other solid's outward normal there and depth -phi.
// Exact for sphere-sphere, sphere-anything and a box or cylinder on a plane;
// for two boxes, edge-on-edge touching between samples is found up to the
// sample spacing.
//
// Resolution: sequential impulses (projected Gauss-Seidel with accumulated
// impulses, Catto 2005) on the velocities of one substep. Per contact, the
// normal impulse P_n >= 0 drives the normal relative velocity to
// -e v_n0 (restitution e, v_n0 the approach speed before the iterations,
// when it exceeds restitutionSpeed; 0 otherwise); the friction impulse
// opposes the tangential relative velocity with |P_t| <= mu P_n (Coulomb).
// Overlap is removed by a split push: the same sweeps on the bodies' push
// velocities (RigidBodyState::pushV, pushW) toward a normal separation of
// beta (depth - slop) / dt, which move the poses in the substep's update and
// never the momenta (a Baumgarte push on the velocities threw a body placed
// 3 cm deep in the floor out at 6 m/s). A sphere rolling down an incline thus
// accelerates at 5/7 g sin(theta) when mu >= 2/7 tan(theta).
#include <cstddef>
#include <vector>

#include "lodestone/core/base/vec3.h"
#include "lodestone/core/mpm/collider.h"
#include "lodestone/core/mpm/rigid_body.h"

namespace lodestone {
inline namespace mpm {

/// Body-frame surface samples (m) of `shape` about `spacing` (m) apart:
/// a box's 8 corners and points along its 12 edges, a cylinder's two rims
/// and the diameters of its caps, a level set's surface (nodes within half a
/// sample spacing of phi = 0, moved onto it, one per spacing-sized cell).
/// Empty for a sphere and a plane. Throws InvalidArgument for a spacing that
/// is not positive and finite.
std::vector<Vec3d> contactSamples(const ColliderShape& shape, double spacing);

/// One body as the contact finder sees it.
struct RigidContactBody {
  const ColliderShape* shape = nullptr;
  ColliderState state;                         ///< pose (of the body origin)
  const std::vector<Vec3d>* samples = nullptr;  ///< contactSamples of the shape (may be null: none)
};

struct RigidContact {
  std::size_t a = 0, b = 0;  ///< indices of the two bodies (a's surface touches b's solid)
  Vec3d point;               ///< world, m
  Vec3d normal;              ///< unit, out of b's solid (the direction that separates a from b)
  double depth = 0;          ///< overlap, m (>= 0)
  double friction = 0;       ///< Coulomb coefficient
  double restitution = 0;    ///< 0..1
};

/// Appends to `out` the contacts of body A's surface (index ia) with body
/// B's solid (index ib), with the given friction and restitution: A's
/// samples (or, for a sphere, its centre) against B's signed distance.
/// Bodies whose bounding spheres do not meet give none.
void findContacts(const RigidContactBody& A, std::size_t ia, const RigidContactBody& B, std::size_t ib,
                  double friction, double restitution, std::vector<RigidContact>& out);

struct RigidContactSettings {
  int iterations = 16;             ///< Gauss-Seidel sweeps over the contacts
  double baumgarte = 0.2;          ///< fraction of the overlap removed per substep
  double slop = 0;                 ///< overlap left alone, m
  double restitutionSpeed = 0;     ///< approach speeds below this (m/s) do not bounce
};

/// Applies the contact impulses to `bodies` (indexed by the contacts' a, b;
/// bodies with inverseMass 0 are not moved) over a substep of dt (s).
/// Returns the largest normal impulse (N*s).
double solveContacts(std::vector<RigidBodyState>& bodies, const std::vector<RigidContact>& contacts, double dt,
                     const RigidContactSettings& settings);

}  // namespace mpm
}  // namespace lodestone
