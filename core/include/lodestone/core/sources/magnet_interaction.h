#pragma once
// Force and torque that one permanent magnet (A) exerts on another (B), for
// free (dynamic) magnets. Units: positions m, moments A*m^2, force N, torque
// N*m about the centre of the body it acts on (its pose position).
//
// Two methods (docs/physics.md, "Forces between magnets"):
//  - Dipole: both magnets as point dipoles m = s(t) V R M at their centres.
//    Exact for two spheres (a uniformly magnetized sphere's exterior field is
//    that of its dipole, and the force and torque on a sphere in an external
//    field depend only on its dipole moment); the leading term otherwise.
//  - SurfaceCharge: the force on B as the sum over B's surface charges
//    sigma = M.n of mu0 sigma H_A dA, H_A the exact field of magnet A, and the
//    torque from the same integral, mu0 int (x - c_B) x sigma H_A dA (this
//    already contains the mu0 m x H couple; no extra term). Quadrature of
//    `order` points per direction: n x n Gauss-Legendre on each cuboid face;
//    n radial Gauss-Legendre points times 2n equally spaced angles on each
//    cylinder cap (the side wall of an axial cylinder carries no charge);
//    n Gauss-Legendre points in cos(theta) times 2n angles on a sphere.
#include <cmath>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/hostdev.h"
#include "lodestone/core/base/vec3.h"
#include "lodestone/core/sources/magnet_source.h"
#include "lodestone/core/sources/point_dipole.h"

namespace lodestone {
inline namespace sources {

/// Force (N) on dipole mB (A*m^2) at offset r (m, from dipole A to dipole B)
/// from dipole mA:
///   F = 3 mu0 / (4 pi r^4) [ (mA.u) mB + (mB.u) mA + (mA.mB) u - 5 (mA.u)(mB.u) u ],  u = r/|r|.
/// Positive along u means repulsion. Zero for r = 0 (excluded point).
LODESTONE_HOSTDEV inline Vec3d dipoleDipoleForce(const Vec3d& mA, const Vec3d& mB, const Vec3d& r) {
  const double d2 = dot(r, r);
  if (!(d2 > 0)) return {};
  using std::sqrt;
  const double d = sqrt(d2);
  const Vec3d u = r / d;
  const double a = dot(mA, u), b = dot(mB, u);
  const double c = 3.0 * kMu0 / (4.0 * kPi * d2 * d2);
  return c * (a * mB + b * mA + (dot(mA, mB) - 5.0 * a * b) * u);
}

/// Torque (N*m, about B's centre) on dipole mB at offset r (m, from A to B)
/// from dipole mA: mu0 mB x H_A(r), H_A = dipoleField(mA, r) (point_dipole.h).
/// Zero for r = 0.
LODESTONE_HOSTDEV inline Vec3d dipoleDipoleTorque(const Vec3d& mA, const Vec3d& mB, const Vec3d& r) {
  return kMu0 * cross(mB, dipoleField(mA, r));
}

enum class MagnetInteractionMethod {
  Dipole,         ///< point dipoles at the centres (exact for two spheres)
  SurfaceCharge,  ///< B's surface charges in A's exact field
};

/// Force and torque on one body.
struct MagnetWrench {
  Vec3d force;   ///< N
  Vec3d torque;  ///< N*m, about the body's centre
};

/// Default quadrature order of the surface-charge method (points per
/// direction); the dipole-approximation figures in docs/physics.md are
/// converged to ~1e-10 relative at this order.
inline constexpr int kMagnetInteractionDefaultOrder = 24;

/// Force and torque that magnet `a` exerts on magnet `b` at time t (s).
/// Shapes: SphereMagnet, CuboidMagnet, CylinderMagnet (SurfaceCharge), any
/// MagnetSource (Dipole). `order` (1..256) is used by SurfaceCharge only.
/// The reaction on `a` is magnetInteraction(b, a, ...).
/// Throws InvalidArgument (naming the values) for coincident centres, for
/// overlapping bodies (two spheres: centre distance < sum of radii; other
/// shapes: a centre or a surface quadrature point of one body inside the
/// other, at the rule of `order`), for a bad order, or for a shape the
/// surface-charge method does not know.
MagnetWrench magnetInteraction(const MagnetSource& a, const MagnetSource& b, double t,
                               MagnetInteractionMethod method = MagnetInteractionMethod::Dipole,
                               int order = kMagnetInteractionDefaultOrder);

}  // namespace sources
}  // namespace lodestone
