#pragma once
// A spatially uniform applied field H(t) = s(t) H0, e.g. the interior of a
// large Helmholtz pair or solenoid (PHYSICS.md section 2: curl- and
// divergence-free everywhere).
#include <memory>
#include <string>

#include "lodestone/core/sources/field_source.h"
#include "lodestone/core/sources/time_profile.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace sources {

class UniformField final : public FieldSource {
 public:
  /// H0 in A/m (finite), scaled in time by `scale`.
  explicit UniformField(const Vec3d& H, TimeProfile scale = TimeProfile());

  Vec3d field(const Vec3d& x, double t) const override;
  void accumulateField(const Vec3d* x, std::size_t count, double t, Vec3d* out) const override;
  bool isUniform() const override { return true; }
  /// Instance and s(t).
  bool appendFieldSignature(double t, std::vector<double>& out) const override;
  std::string describe() const override;
  std::unique_ptr<FieldSource> clone() const override;

  const Vec3d& amplitude() const { return H_; }  ///< H0, A/m
  const TimeProfile& profile() const { return scale_; }

 private:
  Vec3d H_;
  TimeProfile scale_;
};

}  // namespace sources
}  // namespace lodestone
