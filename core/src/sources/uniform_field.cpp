#include "lodestone/core/sources/uniform_field.h"

#include <utility>

#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace sources {

UniformField::UniformField(const Vec3d& H, TimeProfile scale) : H_(H), scale_(std::move(scale)) {
  require(isFinite(H), "uniform field: H must be finite (A/m), got (", H.x, ", ", H.y, ", ", H.z,
          ")");
}

Vec3d UniformField::field(const Vec3d& /*x*/, double t) const { return H_ * scale_(t); }

bool UniformField::appendFieldSignature(double t, std::vector<double>& out) const {
  out.push_back(double(instanceId()));
  out.push_back(scale_(t));
  return true;
}

void UniformField::accumulateField(const Vec3d* /*x*/, std::size_t count, double t,
                                   Vec3d* out) const {
  const Vec3d H = H_ * scale_(t);
  for (std::size_t n = 0; n < count; ++n) out[n] += H;
}

std::string UniformField::describe() const {
  return concat("uniform field H = (", H_.x, ", ", H_.y, ", ", H_.z, ") A/m, scaled by ",
                scale_.describe());
}

std::unique_ptr<FieldSource> UniformField::clone() const {
  return std::make_unique<UniformField>(*this);
}

}  // namespace sources
}  // namespace lodestone
