#include "lodestone/core/base/pose.h"

#include <cmath>

#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace base {

Pose Pose::fromQuaternion(const Vec3d& position, double w, double x, double y, double z) {
  require(isFinite(position), "pose: position must be finite");
  const double n = std::sqrt(w * w + x * x + y * y + z * z);
  require(std::isfinite(n) && n > 0, "pose: quaternion (", w, ", ", x, ", ", y, ", ", z,
          ") must be finite and non-zero");
  w /= n; x /= n; y /= n; z /= n;
  Pose p;
  p.position = position;
  Mat3d& R = p.rotation;
  R(0, 0) = 1 - 2 * (y * y + z * z); R(0, 1) = 2 * (x * y - w * z);     R(0, 2) = 2 * (x * z + w * y);
  R(1, 0) = 2 * (x * y + w * z);     R(1, 1) = 1 - 2 * (x * x + z * z); R(1, 2) = 2 * (y * z - w * x);
  R(2, 0) = 2 * (x * z - w * y);     R(2, 1) = 2 * (y * z + w * x);     R(2, 2) = 1 - 2 * (x * x + y * y);
  return p;
}

Pose Pose::fromAxisAngle(const Vec3d& position, const Vec3d& axis, double angle) {
  const double n = norm(axis);
  require(std::isfinite(n) && n > 0, "pose: rotation axis (", axis.x, ", ", axis.y, ", ", axis.z,
          ") must be finite and non-zero");
  require(std::isfinite(angle), "pose: rotation angle must be finite (rad), got ", angle);
  const double s = std::sin(0.5 * angle) / n;
  return fromQuaternion(position, std::cos(0.5 * angle), axis.x * s, axis.y * s, axis.z * s);
}

Mat3d rotationFromVector(const Vec3d& r) {
  const double angle = norm(r);
  if (angle == 0) return Mat3d::identity();
  return Pose::fromAxisAngle({}, r, angle).rotation;
}

Mat3d orthonormalized(const Mat3d& R) {
  // Gram-Schmidt on the columns; the third is the cross product of the first two.
  Vec3d c0{R(0, 0), R(1, 0), R(2, 0)}, c1{R(0, 1), R(1, 1), R(2, 1)};
  c0 = c0 / norm(c0);
  c1 = c1 - dot(c0, c1) * c0;
  c1 = c1 / norm(c1);
  const Vec3d c2 = cross(c0, c1);
  Mat3d Q;
  for (int i = 0; i < 3; ++i) {
    Q(i, 0) = c0[i];
    Q(i, 1) = c1[i];
    Q(i, 2) = c2[i];
  }
  return Q;
}

}  // namespace base
}  // namespace lodestone
