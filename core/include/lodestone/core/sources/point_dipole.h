#pragma once
// The field of an ideal magnetic point dipole of moment m (A*m^2):
//   H(r) = (3 r_hat (r_hat . m) - m) / (4 pi |r|^3)      (A/m)
// Also the exact exterior field of a uniformly magnetized sphere and the
// leading far-field term of every magnet.
#include <cmath>
#include <memory>
#include <string>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/hostdev.h"
#include "lodestone/core/sources/field_source.h"
#include "lodestone/core/sources/time_profile.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace sources {

/// H (A/m) at offset r (m) from a point dipole of moment m (A*m^2).
/// The singular point r = 0 is excluded: there (and wherever |r| is so small
/// that the field overflows a double) the result is zero, never NaN or inf.
LODESTONE_HOSTDEV inline Vec3d dipoleField(const Vec3d& moment, const Vec3d& r) {
  using std::isfinite;
  const double d = norm(r);  // rescaled, so no overflow for huge |r|
  if (!(d > 0)) return {};
  const double inv = 1.0 / d;
  const double inv3 = inv * inv * inv / (4.0 * kPi);
  if (!isfinite(inv3)) return {};
  const Vec3d u = r * inv;
  const Vec3d H = ((3.0 * dot(u, moment)) * u - moment) * inv3;
  return isFinite(H) ? H : Vec3d{};
}

class PointDipole final : public FieldSource {
 public:
  /// Dipole at `position` (m, world frame) with moment `moment` (A*m^2, world
  /// frame), scaled in time by `scale`. Both vectors must be finite.
  PointDipole(const Vec3d& position, const Vec3d& moment, TimeProfile scale = TimeProfile());

  /// dipoleField(s(t) m, x - position); zero at x == position.
  Vec3d field(const Vec3d& x, double t) const override;
  void accumulateField(const Vec3d* x, std::size_t count, double t, Vec3d* out) const override;
  std::string describe() const override;
  std::unique_ptr<FieldSource> clone() const override;
  /// Instance and s(t).
  bool appendFieldSignature(double t, std::vector<double>& out) const override;

  const Vec3d& position() const { return position_; }  ///< m
  const Vec3d& moment() const { return moment_; }      ///< A*m^2, before scaling
  const TimeProfile& profile() const { return scale_; }

 private:
  Vec3d position_, moment_;
  TimeProfile scale_;
};

}  // namespace sources
}  // namespace lodestone
