#include "lodestone/core/sources/sphere_magnet.h"

#include <cmath>
#include <utility>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/sources/point_dipole.h"

namespace lodestone {
inline namespace sources {

namespace {
double checkedRadius(double radius) {
  require(std::isfinite(radius) && radius > 0,
          "sphere magnet: radius must be a positive finite value in m, got ", radius);
  return radius;
}
}  // namespace

SphereMagnet::SphereMagnet(const Pose& pose, double radius, const Vec3d& magnetization,
                           TimeProfile scale)
    : MagnetSource("sphere magnet", pose, magnetization, std::move(scale)),
      radius_(checkedRadius(radius)) {}

double SphereMagnet::volume() const { return 4.0 / 3.0 * kPi * radius_ * radius_ * radius_; }

bool SphereMagnet::containsBody(const Vec3d& xBody) const { return norm(xBody) <= radius_; }

double SphereMagnet::surfaceDepth(const Vec3d& xBody, Vec3d& outwardNormal) const {
  const double r = norm(xBody);
  outwardNormal = r > 0 ? xBody / r : Vec3d{0, 0, 1};
  return radius_ - r;
}

Vec3d SphereMagnet::bodyField(const Vec3d& xBody) const {
  const Vec3d& M = bodyMagnetization();
  const double r = norm(xBody);
  const Vec3d inside = M * (-1.0 / 3.0);
  if (r < radius_) return inside;
  const Vec3d outside = dipoleField(M * volume(), xBody);
  if (r > radius_) return outside;
  return (inside + outside) * 0.5;  // on the surface: mean of the one-sided limits
}

std::string SphereMagnet::describe() const {
  return concat("sphere magnet, radius ", radius_, " m, ", describeCommon());
}

std::unique_ptr<FieldSource> SphereMagnet::clone() const {
  return std::make_unique<SphereMagnet>(*this);
}

}  // namespace sources
}  // namespace lodestone
