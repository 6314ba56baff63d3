#pragma once
// Uniformly, axially magnetized circular cylinder: radius R (m), half-length
// L (m) along the body z axis, centred on the body origin, magnetization
// M = Mz e_z (A/m, body frame). Transverse magnetization is not supported
// and is rejected at construction.
//
// Closed form: the magnet's B equals that of an ideal solenoid with surface
// current density Mz (Derby & Olbert 2010, Am. J. Phys. 78, 229, eqs. 3-4),
// written with Bulirsch's cel (elliptic_integral.h):
//   B_rho = (mu0 M / pi) [alpha+ cel(k+, 1, 1, -1) - alpha- cel(k-, 1, 1, -1)]
//   B_z   = (mu0 M / pi) R/(R+rho) [beta+ cel(k+, g^2, 1, g) - beta- cel(k-, g^2, 1, g)]
// with z+- = z +- L, alpha+- = R / sqrt(z+-^2 + (R+rho)^2), beta+- = z+- / sqrt(...),
// g = (R - rho)/(R + rho), k+- = sqrt(z+-^2 + (R-rho)^2) / sqrt(z+-^2 + (R+rho)^2).
// Then H = B/mu0 - M inside the body and B/mu0 outside (H is the field of the
// end-cap charges +-M). On the axis (rho == 0) the exact on-axis formula
//   Hz = (M/2) [(z+L)/sqrt((z+L)^2+R^2) - (z-L)/sqrt((z-L)^2+R^2)] - M (inside)
// is used. Beyond kFarFieldRadii circumscribed radii, the dipole + octupole
// expansion replaces the closed form, whose end-cap terms cancel there; both
// agree to ~3e-10 relative at the switch.
//
// Singular points: exactly on an end cap or the side wall, a jumping
// component is the mean of its one-sided limits. On the rim circles
// (rho = R, |z| = L) H diverges like ln(1/distance); there the distance to
// the rim is floored at kEdgeRegularization times max(R, L), so the result is
// large but finite (never NaN or inf).
#include <memory>
#include <string>

#include "lodestone/core/sources/magnet_source.h"

namespace lodestone {
inline namespace sources {

class CylinderMagnet final : public MagnetSource {
 public:
  /// Beyond this many circumscribed radii the far-field expansion is used.
  static constexpr double kFarFieldRadii = 250.0;
  /// Rim distance floor, relative to max(radius, half-length).
  static constexpr double kEdgeRegularization = 1e-12;

  /// Centre and orientation from `pose` (the axis is the body z axis);
  /// radius and half-length in m (finite, > 0); magnetization in A/m in the
  /// body frame, finite and along body z (x and y components must be zero).
  CylinderMagnet(const Pose& pose, double radius, double halfLength, const Vec3d& magnetization,
                 TimeProfile scale = TimeProfile());

  double radius() const { return radius_; }          ///< m
  double halfLength() const { return halfLength_; }  ///< m
  double volume() const override;
  bool containsBody(const Vec3d& xBody) const override;
  double surfaceDepth(const Vec3d& xBody, Vec3d& outwardNormal) const override;
  Vec3d bodyField(const Vec3d& xBody) const override;
  std::string describe() const override;
  std::unique_ptr<FieldSource> clone() const override;

 private:
  double radius_, halfLength_;
};

}  // namespace sources
}  // namespace lodestone
