// The primitives of a preview: their ray casting and their line drawings.
#include "lodestone/plugin/output/particle_render.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "render_detail.h"

namespace lodestone::output {
namespace render_detail {
namespace {

bool finitePose(const Pose& p) {
  if (!isFinite(p.position)) return false;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (!std::isfinite(p.rotation(i, j))) return false;
  return true;
}

// ---- ray casting of primitives, in the body frame

void considerHit(Hit& best, double t, const Vec3d& normal) {
  if (t > 0 && t < best.t) {
    best.t = t;
    best.normal = normal;
  }
}

Hit intersectSphere(const Vec3d& o, const Vec3d& d, double radius) {
  Hit h;
  const double b = dot(o, d), c = norm2(o) - radius * radius;
  const double disc = b * b - c;
  if (disc < 0) return h;
  const double q = std::sqrt(disc);
  const double t = -b - q > 0 ? -b - q : -b + q;
  considerHit(h, t, (o + t * d) / radius);
  return h;
}

Hit intersectBox(const Vec3d& o, const Vec3d& d, const Vec3d& half) {
  Hit h;
  double tNear = -kInf, tFar = kInf;
  int nearAxis = -1, farAxis = -1;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (std::abs(o[a]) > half[a]) return h;
      continue;
    }
    double t1 = (-half[a] - o[a]) / d[a], t2 = (half[a] - o[a]) / d[a];
    if (t1 > t2) std::swap(t1, t2);
    if (t1 > tNear) {
      tNear = t1;
      nearAxis = a;
    }
    if (t2 < tFar) {
      tFar = t2;
      farAxis = a;
    }
  }
  if (tNear > tFar || !(tFar > 0)) return h;
  const bool outside = tNear > 0;
  const int axis = outside ? nearAxis : farAxis;
  Vec3d n;
  if (axis >= 0) n[axis] = (d[axis] > 0) == outside ? -1.0 : 1.0;
  considerHit(h, outside ? tNear : tFar, n);
  return h;
}

Hit intersectCylinder(const Vec3d& o, const Vec3d& d, double radius, double halfLength) {
  Hit h;
  const double a = d.x * d.x + d.y * d.y;
  if (a > 0) {
    const double b = o.x * d.x + o.y * d.y, c = o.x * o.x + o.y * o.y - radius * radius;
    const double disc = b * b - a * c;
    if (disc >= 0) {
      const double q = std::sqrt(disc);
      for (double t : {(-b - q) / a, (-b + q) / a}) {
        const Vec3d p = o + t * d;
        if (t > 0 && std::abs(p.z) <= halfLength) considerHit(h, t, Vec3d{p.x / radius, p.y / radius, 0.0});
      }
    }
  }
  if (d.z != 0.0) {
    for (double zc : {-halfLength, halfLength}) {
      const double t = (zc - o.z) / d.z;
      const Vec3d p = o + t * d;
      if (p.x * p.x + p.y * p.y <= radius * radius) considerHit(h, t, Vec3d{0.0, 0.0, zc > 0 ? 1.0 : -1.0});
    }
  }
  return h;
}

std::vector<Vec3d> circle(const Pose& pose, const Vec3d& centre, const Vec3d& e1, const Vec3d& e2, double r,
                          int segments = 64) {
  std::vector<Vec3d> pts;
  for (int k = 0; k < segments; ++k) {
    const double phi = 2 * kPi * k / segments;
    pts.push_back(pose.toWorld(centre + r * std::cos(phi) * e1 + r * std::sin(phi) * e2));
  }
  return pts;
}

}  // namespace

Hit intersect(const Primitive& prim, const Vec3d& oLocal, const Vec3d& dLocal) {
  switch (prim.shape) {
    case Primitive::Shape::Box:
      return intersectBox(oLocal, dLocal, prim.halfSize);
    case Primitive::Shape::Sphere:
      return intersectSphere(oLocal, dLocal, prim.radius);
    case Primitive::Shape::Cylinder:
      return intersectCylinder(oLocal, dLocal, prim.radius, prim.halfLength);
  }
  return {};
}

void checkPrimitive(const Primitive& p, std::size_t k) {
  require(finitePose(p.pose), "renderScene: primitive ", k, " has a non-finite pose");
  switch (p.shape) {
    case Primitive::Shape::Box:
      require(isFinite(p.halfSize) && p.halfSize.x > 0 && p.halfSize.y > 0 && p.halfSize.z > 0, "renderScene: box ", k,
              " needs finite half-sizes > 0 m, got (", p.halfSize.x, ", ", p.halfSize.y, ", ", p.halfSize.z, ")");
      break;
    case Primitive::Shape::Sphere:
      require(std::isfinite(p.radius) && p.radius > 0, "renderScene: sphere ", k, " needs a finite radius > 0 m, got ",
              p.radius);
      break;
    case Primitive::Shape::Cylinder:
      require(std::isfinite(p.radius) && p.radius > 0 && std::isfinite(p.halfLength) && p.halfLength > 0,
              "renderScene: cylinder ", k, " needs a finite radius and half-length > 0 m, got ", p.radius, " and ",
              p.halfLength);
      break;
  }
}

// ---- wireframes

LineDrawer::LineDrawer(const CameraProjection& cam, RgbImage& image, const std::vector<float>& depth,
                       double hiddenAlpha)
    : cam_(cam),
      image_(image),
      depth_(depth),
      hiddenAlpha_(hiddenAlpha),
      mask_(std::size_t(image.width) * std::size_t(image.height), 0) {
  near_ = 1e-4 * norm(cam.camera().lookAt - cam.camera().position);
}

void LineDrawer::segment(const Vec3d& aWorld, const Vec3d& bWorld, Rgb colour) {
  Vec3d a = cam_.toCamera(aWorld), b = cam_.toCamera(bWorld);
  // Clip against the near plane and the four side planes (with 2 pixels to
  // spare), each a linear constraint g(s) >= 0 along the segment.
  const double F = cam_.focalPixels();
  const double hx = 0.5 * image_.width + 2, hy = 0.5 * image_.height + 2;
  auto g = [&](int plane, const Vec3d& p) {
    switch (plane) {
      case 0:
        return p.z - near_;
      case 1:
        return hx * p.z - F * p.x;
      case 2:
        return hx * p.z + F * p.x;
      case 3:
        return hy * p.z - F * p.y;
      default:
        return hy * p.z + F * p.y;
    }
  };
  double s0 = 0, s1 = 1;
  for (int plane = 0; plane < 5; ++plane) {
    const double ga = g(plane, a), gb = g(plane, b);
    if (ga < 0 && gb < 0) return;
    if (ga < 0) s0 = std::max(s0, ga / (ga - gb));
    if (gb < 0) s1 = std::min(s1, ga / (ga - gb));
  }
  if (s0 >= s1) return;
  const Vec3d a1 = a + s0 * (b - a), b1 = a + s1 * (b - a);
  const double W2 = 0.5 * image_.width, H2 = 0.5 * image_.height;
  const double ax = W2 + F * a1.x / a1.z, ay = H2 - F * a1.y / a1.z;
  const double bx = W2 + F * b1.x / b1.z, by = H2 - F * b1.y / b1.z;
  const int steps = 1 + int(std::ceil(2.0 * std::max(std::abs(bx - ax), std::abs(by - ay))));
  for (int k = 0; k <= steps; ++k) {
    const double sigma = double(k) / steps;
    // 1/z is linear in screen space.
    const double z = 1.0 / ((1 - sigma) / a1.z + sigma / b1.z);
    plot(int(std::floor(ax + sigma * (bx - ax))), int(std::floor(ay + sigma * (by - ay))), z, colour);
  }
}

void LineDrawer::polyline(const std::vector<Vec3d>& points, Rgb colour, bool closed) {
  for (std::size_t i = 0; i + 1 < points.size(); ++i) segment(points[i], points[i + 1], colour);
  if (closed && points.size() > 2) segment(points.back(), points.front(), colour);
}

void LineDrawer::plot(int i, int j, double z, Rgb colour) {
  if (i < 0 || j < 0 || i >= image_.width || j >= image_.height) return;
  const std::size_t at = std::size_t(j) * std::size_t(image_.width) + std::size_t(i);
  const bool visible = z <= double(depth_[at]) * (1 + 1e-4);
  if (visible) {
    if (mask_[at] < 2) image_.set(i, j, colour);
    mask_[at] = 2;
  } else if (mask_[at] == 0) {
    image_.set(i, j, mix(image_.get(i, j), colour, hiddenAlpha_));
    mask_[at] = 1;
  }
}

void drawWireframe(LineDrawer& lines, const Primitive& p, const Vec3d& cameraLocal) {
  const Vec3d ex{1, 0, 0}, ey{0, 1, 0}, ez{0, 0, 1};
  switch (p.shape) {
    case Primitive::Shape::Box: {
      const Vec3d& h = p.halfSize;
      auto corner = [&](int c) {
        return p.pose.toWorld({(c & 1) ? h.x : -h.x, (c & 2) ? h.y : -h.y, (c & 4) ? h.z : -h.z});
      };
      for (int c = 0; c < 8; ++c)
        for (int bit : {1, 2, 4})
          if (!(c & bit)) lines.segment(corner(c), corner(c | bit), p.colour);
      break;
    }
    case Primitive::Shape::Sphere: {
      lines.polyline(circle(p.pose, {}, ex, ey, p.radius), p.colour, true);
      lines.polyline(circle(p.pose, {}, ey, ez, p.radius), p.colour, true);
      lines.polyline(circle(p.pose, {}, ez, ex, p.radius), p.colour, true);
      // The silhouette: the circle where the view cone touches the sphere.
      const double D = norm(cameraLocal);
      if (D > p.radius) {
        const Vec3d w = cameraLocal / D;
        const Vec3d e1 = normalised(std::abs(w.x) < 0.9 ? cross(w, ex) : cross(w, ey));
        const Vec3d e2 = cross(w, e1);
        const double r = p.radius * std::sqrt(1 - (p.radius / D) * (p.radius / D));
        lines.polyline(circle(p.pose, (p.radius * p.radius / D) * w, e1, e2, r), p.colour, true);
      }
      break;
    }
    case Primitive::Shape::Cylinder: {
      lines.polyline(circle(p.pose, {0, 0, -p.halfLength}, ex, ey, p.radius), p.colour, true);
      lines.polyline(circle(p.pose, {0, 0, p.halfLength}, ex, ey, p.radius), p.colour, true);
      // Silhouette generators: side normal perpendicular to the line of sight,
      // cos(phi) cx + sin(phi) cy = R.
      const double rho = std::hypot(cameraLocal.x, cameraLocal.y);
      if (rho > p.radius) {
        const double base = std::atan2(cameraLocal.y, cameraLocal.x), spread = std::acos(p.radius / rho);
        for (double phi : {base - spread, base + spread}) {
          const double x = p.radius * std::cos(phi), y = p.radius * std::sin(phi);
          lines.segment(p.pose.toWorld({x, y, -p.halfLength}), p.pose.toWorld({x, y, p.halfLength}), p.colour);
        }
      }
      break;
    }
  }
}

}  // namespace render_detail

// ---------------------------------------------------------------- primitives

namespace {
Primitive primitiveOf(Primitive::Shape shape, const Pose& pose, Rgb colour, Primitive::Style style) {
  Primitive p;
  p.shape = shape;
  p.pose = pose;
  p.colour = colour;
  p.style = style;
  return p;
}
}  // namespace

Primitive Primitive::box(const Pose& pose, const Vec3d& halfSize, Rgb colour, Style style) {
  Primitive p = primitiveOf(Shape::Box, pose, colour, style);
  p.halfSize = halfSize;
  return p;
}

Primitive Primitive::sphere(const Pose& pose, double radius, Rgb colour, Style style) {
  Primitive p = primitiveOf(Shape::Sphere, pose, colour, style);
  p.radius = radius;
  return p;
}

Primitive Primitive::cylinder(const Pose& pose, double radius, double halfLength, Rgb colour, Style style) {
  Primitive p = primitiveOf(Shape::Cylinder, pose, colour, style);
  p.radius = radius;
  p.halfLength = halfLength;
  return p;
}

}  // namespace lodestone::output
