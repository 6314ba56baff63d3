#pragma once
// Uniformly magnetized rectangular box (cuboid) with half-sizes (hx, hy, hz)
// (m) along the body axes, centred on the body origin, magnetization M (A/m,
// body frame, any direction).
//
// Closed form from the surface-charge formulation: each component M_k puts
// the charge densities +M_k and -M_k on the faces x_k = +h_k and x_k = -h_k,
// and the H field of a uniformly charged rectangle is elementary (Furlani,
// "Permanent Magnet and Electromechanical Devices", 2001, sec. 4.3; Engel-
// Herbert & Hesjedal 2005, J. Appl. Phys. 97, 074504):
//   H = sigma/(4 pi) [ -[ln(V + R)] , -[ln(U + R)] , [atan(U V / (w R))] ]
// with U, V the in-plane offsets from the rectangle's corners, w the height
// above its plane, R = sqrt(U^2 + V^2 + w^2), and [.] the signed sum over the
// four corners. Inside the box this is the demagnetizing field (B = mu0(H+M)).
//
// Numerics: the log differences are evaluated in a cancellation-free form
// (log1p of exactly computed ratios, and ln(V + R) = ln(rho^2) - ln(R - V) for
// V < 0), so no argument cancels. Beyond kFarFieldRadii circumscribed radii
// the dipole + octupole expansion replaces the closed form, whose corner sums
// cancel as (size/r)^3 there; both agree to ~3e-9 relative at the switch.
// Singular points: exactly on a face the normal component is the mean of
// its one-sided limits. On an edge or corner H diverges like ln(1/distance);
// there the distance to the edge is floored at kEdgeRegularization times the
// largest half-size, so the result is large but finite (never NaN or inf).
#include <memory>
#include <string>

#include "lodestone/core/sources/magnet_source.h"

namespace lodestone {
inline namespace sources {

class CuboidMagnet final : public MagnetSource {
 public:
  /// Beyond this many circumscribed radii the far-field expansion is used.
  static constexpr double kFarFieldRadii = 150.0;
  /// Edge/corner distance floor, relative to the largest half-size.
  static constexpr double kEdgeRegularization = 1e-12;

  /// Centre and orientation from `pose`; half-sizes in m (finite, > 0 each);
  /// magnetization in A/m in the body frame (finite).
  CuboidMagnet(const Pose& pose, const Vec3d& halfSize, const Vec3d& magnetization,
               TimeProfile scale = TimeProfile());

  const Vec3d& halfSize() const { return half_; }  ///< m
  double volume() const override;
  bool containsBody(const Vec3d& xBody) const override;
  double surfaceDepth(const Vec3d& xBody, Vec3d& outwardNormal) const override;
  Vec3d bodyField(const Vec3d& xBody) const override;
  std::string describe() const override;
  std::unique_ptr<FieldSource> clone() const override;

 private:
  Vec3d half_;
};

}  // namespace sources
}  // namespace lodestone
