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

}  // namespace base
}  // namespace lodestone
