#pragma once
// Uniformly magnetized sphere of radius a (m) and magnetization M (A/m):
//   inside  (r < a): H = -M/3 (demagnetizing factor 1/3), so B = (2/3) mu0 M;
//   outside (r > a): the field of a point dipole m = (4/3) pi a^3 M at the centre;
//   on the surface (r == a): the mean of the two one-sided limits.
// PHYSICS.md section 6.
#include <memory>
#include <string>

#include "lodestone/core/sources/magnet_source.h"

namespace lodestone {
inline namespace sources {

class SphereMagnet final : public MagnetSource {
 public:
  /// Centre and orientation from `pose`; radius in m (finite, > 0);
  /// magnetization in A/m in the body frame (finite).
  SphereMagnet(const Pose& pose, double radius, const Vec3d& magnetization,
               TimeProfile scale = TimeProfile());

  double radius() const { return radius_; }  ///< m
  double volume() const override;
  bool containsBody(const Vec3d& xBody) const override;
  double surfaceDepth(const Vec3d& xBody, Vec3d& outwardNormal) const override;
  Vec3d bodyField(const Vec3d& xBody) const override;
  std::string describe() const override;
  std::unique_ptr<FieldSource> clone() const override;

 private:
  double radius_;
};

}  // namespace sources
}  // namespace lodestone
