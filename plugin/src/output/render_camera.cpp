// The preview camera: projection, rays, framing.
#include "lodestone/plugin/output/particle_render.h"

#include <algorithm>
#include <cmath>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "render_detail.h"

namespace lodestone::output {

using render_detail::normalised;

namespace {
constexpr int kMaxSide = 16384;
}  // namespace

// ---------------------------------------------------------------- camera

CameraProjection::CameraProjection(const Camera& camera) : camera_(camera) {
  require(isFinite(camera.position) && isFinite(camera.lookAt) && isFinite(camera.up),
          "camera: position, look-at and up must be finite");
  const Vec3d view = camera.lookAt - camera.position;
  require(norm(view) > 0, "camera: look-at point equals the position (", camera.position.x, ", ", camera.position.y,
          ", ", camera.position.z, ") m");
  require(norm(camera.up) > 0, "camera: up vector is zero");
  require(camera.verticalFovDegrees > 0 && camera.verticalFovDegrees < 180,
          "camera: vertical field of view must be in (0, 180) degrees, got ", camera.verticalFovDegrees);
  require(camera.width >= 1 && camera.height >= 1 && camera.width <= kMaxSide && camera.height <= kMaxSide,
          "camera: image size must be 1..", kMaxSide, " pixels per side, got ", camera.width, " x ", camera.height);
  forward_ = normalised(view);
  const Vec3d side = cross(forward_, normalised(camera.up));
  require(norm(side) > 1e-9, "camera: up vector (", camera.up.x, ", ", camera.up.y, ", ", camera.up.z,
          ") is parallel to the view direction");
  right_ = normalised(side);
  up_ = cross(right_, forward_);
  focal_ = 0.5 * camera.height / std::tan(0.5 * camera.verticalFovDegrees * kPi / 180.0);
}

Vec3d CameraProjection::toCamera(const Vec3d& world) const {
  const Vec3d d = world - camera_.position;
  return {dot(d, right_), dot(d, up_), dot(d, forward_)};
}

bool CameraProjection::project(const Vec3d& world, double& px, double& py, double& depth) const {
  const Vec3d c = toCamera(world);
  if (!(c.z > 0)) return false;
  depth = c.z;
  px = 0.5 * camera_.width + focal_ * c.x / c.z;
  py = 0.5 * camera_.height - focal_ * c.y / c.z;
  return true;
}

Vec3d CameraProjection::rayDirection(double px, double py) const {
  return normalised(forward_ + ((px - 0.5 * camera_.width) / focal_) * right_ -
                    ((py - 0.5 * camera_.height) / focal_) * up_);
}

double CameraProjection::sphereRadiusPixels(double radius, double depth) const {
  return focal_ * radius / std::sqrt((depth - radius) * (depth + radius));
}

void Bounds3::add(const Vec3d& p, double radius) {
  if (empty()) {
    min = p - Vec3d{radius, radius, radius};
    max = p + Vec3d{radius, radius, radius};
    return;
  }
  for (int a = 0; a < 3; ++a) {
    min[a] = std::min(min[a], p[a] - radius);
    max[a] = std::max(max[a], p[a] + radius);
  }
}

Camera frameCamera(const Bounds3& box, const Vec3d& viewDirection, const Vec3d& up, double verticalFovDegrees,
                   int width, int height, double margin) {
  require(!box.empty() && isFinite(box.min) && isFinite(box.max),
          "frameCamera: the bounding box is empty or not finite");
  require(isFinite(viewDirection) && norm(viewDirection) > 0,
          "frameCamera: view direction must be finite and non-zero");
  require(std::isfinite(margin) && margin >= 1, "frameCamera: margin must be >= 1, got ", margin);
  require(verticalFovDegrees > 0 && verticalFovDegrees < 180,
          "frameCamera: vertical field of view must be in (0, 180) degrees, got ", verticalFovDegrees);
  require(width >= 1 && height >= 1, "frameCamera: image size must be at least 1 x 1, got ", width, " x ", height);
  const Vec3d centre = 0.5 * (box.min + box.max);
  double radius = 0.5 * norm(box.max - box.min);
  if (!(radius > 0)) radius = 1e-3;
  const double halfV = 0.5 * verticalFovDegrees * kPi / 180.0;
  const double halfH = std::atan(std::tan(halfV) * width / height);
  const double distance = margin * radius / std::sin(std::min(halfV, halfH));
  Camera cam;
  cam.lookAt = centre;
  cam.position = centre - distance * normalised(viewDirection);
  cam.up = up;
  cam.verticalFovDegrees = verticalFovDegrees;
  cam.width = width;
  cam.height = height;
  (void)CameraProjection(cam);  // validates up against the view direction
  return cam;
}

Bounds3 boundsOf(const TriangleMesh& mesh) {
  Bounds3 b;
  for (const Vec3d& v : mesh.vertices) b.add(v);
  return b;
}

Bounds3 boundsOf(const ParticleView& particles) {
  Bounds3 b;
  for (std::size_t n = 0; n < particles.count; ++n)
    if (isFinite(particles.positions[n]))
      b.add(particles.positions[n], particles.radii ? particles.radii[n] : particles.radius);
  return b;
}

}  // namespace lodestone::output
