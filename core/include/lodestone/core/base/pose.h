#pragma once
// Rigid placement of a source body: x_world = position + rotation * x_local.
#include "lodestone/core/base/mat3.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace base {

struct Pose {
  Vec3d position;                          ///< m
  Mat3d rotation = Mat3d::identity();      ///< body-to-world, orthonormal

  static Pose at(const Vec3d& position) { return Pose{position, Mat3d::identity()}; }
  /// Rotation by `angle` (rad) about `axis` (any length > 0), then translation.
  static Pose fromAxisAngle(const Vec3d& position, const Vec3d& axis, double angle);
  /// Unit quaternion (w, x, y, z); normalised here, throws if zero or not finite.
  static Pose fromQuaternion(const Vec3d& position, double w, double x, double y, double z);

  Vec3d toLocal(const Vec3d& xWorld) const { return rotation.transposeTimes(xWorld - position); }
  Vec3d toWorld(const Vec3d& xLocal) const { return position + rotation * xLocal; }
  Vec3d vectorToLocal(const Vec3d& v) const { return rotation.transposeTimes(v); }
  Vec3d vectorToWorld(const Vec3d& v) const { return rotation * v; }
};

/// The rotation exp([r]) of the rotation vector r (axis times angle, rad).
Mat3d rotationFromVector(const Vec3d& r);
/// The proper rotation nearest a rotation matrix that has drifted by
/// round-off (Gram-Schmidt on its columns).
Mat3d orthonormalized(const Mat3d& R);

}  // namespace base
}  // namespace lodestone
