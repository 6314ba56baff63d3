#include "lodestone/core/sources/point_dipole.h"

#include <cmath>
#include <utility>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace sources {

PointDipole::PointDipole(const Vec3d& position, const Vec3d& moment, TimeProfile scale)
    : position_(position), moment_(moment), scale_(std::move(scale)) {
  require(isFinite(position), "point dipole: position must be finite (m), got (", position.x, ", ",
          position.y, ", ", position.z, ")");
  require(isFinite(moment), "point dipole: moment must be finite (A*m^2), got (", moment.x, ", ",
          moment.y, ", ", moment.z, ")");
}

Vec3d PointDipole::field(const Vec3d& x, double t) const {
  return dipoleField(moment_ * scale_(t), x - position_);
}

bool PointDipole::appendFieldSignature(double t, std::vector<double>& out) const {
  out.push_back(double(instanceId()));
  out.push_back(scale_(t));
  return true;
}

void PointDipole::accumulateField(const Vec3d* x, std::size_t count, double t, Vec3d* out) const {
  const Vec3d m = moment_ * scale_(t);
  for (std::size_t n = 0; n < count; ++n) out[n] += dipoleField(m, x[n] - position_);
}

std::string PointDipole::describe() const {
  return concat("point dipole at (", position_.x, ", ", position_.y, ", ", position_.z,
                ") m, moment (", moment_.x, ", ", moment_.y, ", ", moment_.z, ") A*m^2, scaled by ",
                scale_.describe());
}

std::unique_ptr<FieldSource> PointDipole::clone() const {
  return std::make_unique<PointDipole>(*this);
}

}  // namespace sources
}  // namespace lodestone
