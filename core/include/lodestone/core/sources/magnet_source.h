#pragma once
// Common base of uniformly magnetized permanent-magnet bodies (sphere, cuboid,
// cylinder). A magnet carries a rigid Pose (body-to-world, so it can move
// between steps), a magnetization M fixed in its body frame (A/m) and a
// TimeProfile s(t) that scales M (an electromagnet-like ramp or AC drive).
//
// Frames: the shape's own closed form (bodyField) is written in the body
// frame, centred on the body; field() maps the world point into the body
// frame, evaluates there and rotates the result back to the world frame.
//
// Surface convention: exactly on a face the normal component of H is the
// mean of its two one-sided limits (the principal value of the surface-charge
// integral); magnetization() treats the body as closed (surface points are
// inside). Edges and corners, where H diverges logarithmically, are handled
// by each shape and documented there; the result is always finite.
#include <cstddef>
#include <string>

#include "lodestone/core/sources/field_source.h"
#include "lodestone/core/base/pose.h"
#include "lodestone/core/sources/time_profile.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace sources {

class MagnetSource : public FieldSource {
 public:
  /// H (A/m, world frame) at world point x (m), time t (s):
  /// s(t) * R * bodyField(R^T (x - p)).
  Vec3d field(const Vec3d& x, double t) const final;
  /// s(t) * R * M inside the closed body, zero outside (A/m, world frame).
  Vec3d magnetization(const Vec3d& x, double t) const final;
  /// s(t) * R * (M.n) n inside the body (n: outward normal of the nearest
  /// face), half that on the surface, zero outside (A/m, world frame).
  Vec3d exteriorContinuation(const Vec3d& x, double t) const final;
  void accumulateField(const Vec3d* x, std::size_t count, double t, Vec3d* out) const final;
  /// Instance, pose (position and rotation) and s(t).
  bool appendFieldSignature(double t, std::vector<double>& out) const final;

  const Pose& pose() const { return pose_; }
  /// Moves the magnet. Not synchronised: do not call while other threads
  /// evaluate this source. Throws InvalidArgument unless the position is
  /// finite and the rotation is a proper rotation (R^T R = I, det R = +1, to 1e-9).
  void setPose(const Pose& pose);

  /// M in the body frame before time scaling (A/m).
  const Vec3d& bodyMagnetization() const { return M_; }
  const TimeProfile& profile() const { return scale_; }

  /// Volume of the body (m^3).
  virtual double volume() const = 0;
  /// Total dipole moment s(t) * V * R * M (A*m^2, world frame).
  Vec3d moment(double t) const;

  /// True when the body-frame point xBody (m) lies in the closed body.
  virtual bool containsBody(const Vec3d& xBody) const = 0;
  /// Distance (m) from the body-frame point xBody to the nearest point of
  /// the surface, positive inside, zero on it, negative outside (or any
  /// negative value outside), and in `outwardNormal` the unit outward normal
  /// (body frame) of the surface there.
  virtual double surfaceDepth(const Vec3d& xBody, Vec3d& outwardNormal) const = 0;
  /// H (A/m, body frame) at body-frame point xBody (m) for the unscaled
  /// magnetization bodyMagnetization(). Inside the body this is the
  /// demagnetizing field, so B = mu0 (H + M) there.
  virtual Vec3d bodyField(const Vec3d& xBody) const = 0;

 protected:
  /// `kind` names the shape in error messages. Validates pose and M (finite).
  MagnetSource(const char* kind, const Pose& pose, const Vec3d& magnetization, TimeProfile scale);

  /// "M = (...) A/m (body frame), position (...) m, rotation [...], scaled by ...".
  std::string describeCommon() const;

 private:
  const char* kind_;
  Pose pose_;
  Vec3d M_;
  TimeProfile scale_;
};

/// Throws InvalidArgument unless `pose` has a finite position and a proper
/// rotation matrix (orthonormal to 1e-9, determinant +1). `who` prefixes the message.
void validatePose(const Pose& pose, const char* who);

/// Far field (A/m) at body-frame offset x (m) of a uniformly magnetized body
/// (M in A/m, volume V in m^3) that is symmetric under reflection of each
/// body axis, with second moments I = (int x^2 dV, int y^2 dV, int z^2 dV)
/// (m^5): the dipole term plus the octupole term from the body's second
/// moments (the quadrupole vanishes by symmetry). The neglected terms are
/// O((size/|x|)^4) relative to the dipole. Zero at x = 0; finite for any finite x.
Vec3d symmetricMagnetFarField(const Vec3d& M, double volume, const Vec3d& secondMoments,
                              const Vec3d& x);

}  // namespace sources
}  // namespace lodestone
