#include "lodestone/plugin/output/particle_render.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <utility>

#include "lodestone/core/base/error.h"

namespace lodestone::output {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::uint64_t kEmpty = ~std::uint64_t(0);
constexpr int kMaxSide = 16384;

double seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

Vec3d normalised(const Vec3d& v) { return v / norm(v); }

std::uint8_t toByte(double v) { return std::uint8_t(std::lround(std::clamp(v, 0.0, 255.0))); }

Rgb mix(Rgb a, Rgb b, double t) {
  return {toByte(a.r + (b.r - a.r) * t), toByte(a.g + (b.g - a.g) * t), toByte(a.b + (b.b - a.b) * t)};
}

std::uint32_t floatBits(float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}

float bitsFloat(std::uint32_t u) {
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

// The nearest fragment wins a pixel: atomic minimum of (depth bits << 32 | index).
void depositKey(std::atomic<std::uint64_t>& slot, float depth, std::size_t index) {
  const std::uint64_t key = (std::uint64_t(floatBits(depth)) << 32) | std::uint64_t(index);
  std::uint64_t current = slot.load(std::memory_order_relaxed);
  while (key < current && !slot.compare_exchange_weak(current, key, std::memory_order_relaxed)) {
  }
}

bool finitePose(const Pose& p) {
  if (!isFinite(p.position)) return false;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (!std::isfinite(p.rotation(i, j))) return false;
  return true;
}

// Headlight: Lambert + Blinn specular for a camera-space normal (x right,
// y up, z towards the viewer), light from the upper left, in front.
struct Lighting {
  Vec3d light = normalised(Vec3d{-0.4, 0.55, 0.73});
  Vec3d halfway = normalised(light + Vec3d{0.0, 0.0, 1.0});
  double ambient = 0.3, specular = 0.25;

  Rgb shade(Rgb base, const Vec3d& n) const {
    const double diffuse = std::max(0.0, dot(n, light));
    const double s = ambient + (1.0 - ambient) * diffuse;
    const double h = std::max(0.0, dot(n, halfway));
    const double h2 = h * h, h4 = h2 * h2, h8 = h4 * h4, h16 = h8 * h8;
    const double spec = 255.0 * specular * h16 * h16;  // exponent 32
    return {toByte(base.r * s + spec), toByte(base.g * s + spec), toByte(base.b * s + spec)};
  }
};

// Where a particle lands on the image; the same computation for rasterising
// and for shading, so both see identical numbers.
struct Splat {
  double sx = 0, sy = 0;  // projected centre, px
  double r = 0;           // disc radius, px
  double depth = 0;       // centre depth z, m
  double radius = 0;      // sphere radius R, m
};

bool splat(const CameraProjection& cam, const Vec3d& p, double radius, Splat& s) {
  if (!isFinite(p)) return false;
  const Vec3d c = cam.toCamera(p);
  if (!(c.z > radius)) return false;  // behind the camera, or the camera is inside it
  s.depth = c.z;
  s.radius = radius;
  s.r = cam.sphereRadiusPixels(radius, c.z);
  const double f = cam.focalPixels() / c.z;
  s.sx = 0.5 * cam.camera().width + f * c.x;
  s.sy = 0.5 * cam.camera().height - f * c.y;
  return std::isfinite(s.sx) && std::isfinite(s.sy) && std::isfinite(s.r);
}

// ---- ray casting of primitives, in the body frame

struct Hit {
  double t = kInf;  // along the unit ray, m
  Vec3d normal;     // body frame, unit
};

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

// ---- triangles

// Moller-Trumbore: the ray o + t d (t > 0) hits triangle (a, b, c) at
// barycentric (1 - u - v, u, v); both sides count.
bool rayTriangle(const Vec3d& o, const Vec3d& d, const Vec3d& a, const Vec3d& b, const Vec3d& c, double& t, double& u,
                 double& v) {
  const Vec3d e1 = b - a, e2 = c - a, p = cross(d, e2);
  const double det = dot(e1, p);
  if (!(std::abs(det) > 1e-300)) return false;
  const double inv = 1.0 / det;
  const Vec3d s = o - a;
  u = dot(s, p) * inv;
  if (u < 0 || u > 1) return false;
  const Vec3d q = cross(s, e1);
  v = dot(d, q) * inv;
  if (v < 0 || u + v > 1) return false;
  t = dot(e2, q) * inv;
  return t > 0;
}

// ---- wireframes

class LineDrawer {
 public:
  LineDrawer(const CameraProjection& cam, RgbImage& image, const std::vector<float>& depth, double hiddenAlpha)
      : cam_(cam),
        image_(image),
        depth_(depth),
        hiddenAlpha_(hiddenAlpha),
        mask_(std::size_t(image.width) * std::size_t(image.height), 0) {
    near_ = 1e-4 * norm(cam.camera().lookAt - cam.camera().position);
  }

  void segment(const Vec3d& aWorld, const Vec3d& bWorld, Rgb colour) {
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

  void polyline(const std::vector<Vec3d>& points, Rgb colour, bool closed) {
    for (std::size_t i = 0; i + 1 < points.size(); ++i) segment(points[i], points[i + 1], colour);
    if (closed && points.size() > 2) segment(points.back(), points.front(), colour);
  }

 private:
  void plot(int i, int j, double z, Rgb colour) {
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

  const CameraProjection& cam_;
  RgbImage& image_;
  const std::vector<float>& depth_;
  double hiddenAlpha_;
  double near_ = 0;
  std::vector<std::uint8_t> mask_;  // 1: hidden edge drawn, 2: visible edge drawn
};

std::vector<Vec3d> circle(const Pose& pose, const Vec3d& centre, const Vec3d& e1, const Vec3d& e2, double r,
                          int segments = 64) {
  std::vector<Vec3d> pts;
  for (int k = 0; k < segments; ++k) {
    const double phi = 2 * kPi * k / segments;
    pts.push_back(pose.toWorld(centre + r * std::cos(phi) * e1 + r * std::sin(phi) * e2));
  }
  return pts;
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

// ---------------------------------------------------------------- primitives

Primitive Primitive::box(const Pose& pose, const Vec3d& halfSize, Rgb colour, Style style) {
  Primitive p;
  p.shape = Shape::Box;
  p.pose = pose;
  p.halfSize = halfSize;
  p.colour = colour;
  p.style = style;
  return p;
}

Primitive Primitive::sphere(const Pose& pose, double radius, Rgb colour, Style style) {
  Primitive p;
  p.shape = Shape::Sphere;
  p.pose = pose;
  p.radius = radius;
  p.colour = colour;
  p.style = style;
  return p;
}

Primitive Primitive::cylinder(const Pose& pose, double radius, double halfLength, Rgb colour, Style style) {
  Primitive p;
  p.shape = Shape::Cylinder;
  p.pose = pose;
  p.radius = radius;
  p.halfLength = halfLength;
  p.colour = colour;
  p.style = style;
  return p;
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

// ---------------------------------------------------------------- rendering

RgbImage renderScene(const Camera& camera, const ParticleView& particles, const std::vector<Primitive>& primitives,
                     const RenderSettings& settings, RenderStats* stats) {
  SceneContent content;
  content.particles = particles;
  content.primitives = primitives;
  return renderScene(camera, content, settings, stats);
}

RgbImage renderScene(const Camera& camera, const SceneContent& content, const RenderSettings& settings,
                     RenderStats* stats) {
  const CameraProjection cam(camera);
  const ParticleView& particles = content.particles;
  const std::vector<Primitive>& primitives = content.primitives;
  const std::size_t count = particles.count;
  require(count == 0 || particles.positions != nullptr, "renderScene: ", count, " particles but no positions");
  // Triangles follow the particles in the visibility keys' index space.
  std::vector<std::size_t> firstTriangle{count};
  for (std::size_t m = 0; m < content.meshes.size(); ++m) {
    const TriangleMesh* mesh = content.meshes[m].mesh;
    require(mesh != nullptr, "renderScene: mesh ", m, " is null");
    const std::size_t nv = mesh->vertices.size();
    require(mesh->normals.empty() || mesh->normals.size() == nv, "renderScene: mesh ", m, " has ",
            mesh->normals.size(), " normals for ", nv, " vertices");
    for (std::size_t v = 0; v < nv; ++v)
      require(isFinite(mesh->vertices[v]), "renderScene: vertex ", v, " of mesh ", m, " is not finite");
    for (std::size_t t = 0; t < mesh->triangles.size(); ++t)
      for (const std::uint32_t k : mesh->triangles[t])
        require(k < nv, "renderScene: triangle ", t, " of mesh ", m, " names vertex ", k, " of ", nv);
    firstTriangle.push_back(firstTriangle.back() + mesh->triangles.size());
  }
  for (std::size_t l = 0; l < content.polylines.size(); ++l)
    require(content.polylines[l].colours.empty() || content.polylines[l].colours.size() == content.polylines[l].points.size(),
            "renderScene: polyline ", l, " has ", content.polylines[l].colours.size(), " colours for ",
            content.polylines[l].points.size(), " points");
  const std::size_t keys = firstTriangle.back();
  require(keys < std::size_t(0xffffffffu), "renderScene: at most 2^32 - 2 particles and triangles, got ", keys);
  // (mesh, triangle) of a key index >= count.
  const auto triangleOf = [&](std::size_t key, std::size_t& mesh, std::size_t& tri) {
    mesh = std::size_t(std::upper_bound(firstTriangle.begin(), firstTriangle.end(), key) - firstTriangle.begin()) - 1;
    tri = key - firstTriangle[mesh];
  };
  const auto corners = [&](std::size_t mesh, std::size_t tri, Vec3d (&p)[3]) {
    const TriangleMesh& m = *content.meshes[mesh].mesh;
    for (int c = 0; c < 3; ++c) p[c] = m.vertices[m.triangles[tri][std::size_t(c)]];
  };
  if (particles.radii == nullptr) {
    require(count == 0 || (std::isfinite(particles.radius) && particles.radius > 0),
            "renderScene: particle radius must be finite and > 0 m, got ", particles.radius);
  } else {
    for (std::size_t n = 0; n < count; ++n)
      require(std::isfinite(particles.radii[n]) && particles.radii[n] > 0, "renderScene: radius of particle ", n,
              " must be finite and > 0 m, got ", particles.radii[n]);
  }
  for (std::size_t k = 0; k < primitives.size(); ++k) checkPrimitive(primitives[k], k);
  require(settings.ambient >= 0 && settings.ambient <= 1, "renderScene: ambient must be in [0, 1], got ",
          settings.ambient);
  require(settings.specular >= 0 && settings.specular <= 1, "renderScene: specular must be in [0, 1], got ",
          settings.specular);
  require(settings.hiddenLineAlpha >= 0 && settings.hiddenLineAlpha <= 1,
          "renderScene: hiddenLineAlpha must be in [0, 1], got ", settings.hiddenLineAlpha);
  require(!settings.ground || (isFinite(settings.groundNormal) && norm(settings.groundNormal) > 0 &&
                               std::isfinite(settings.groundHeight)),
          "renderScene: the ground needs a finite non-zero normal and a finite height");
  require(std::isfinite(settings.gridSpacing) && settings.gridSpacing >= 0,
          "renderScene: gridSpacing must be finite and >= 0 m, got ", settings.gridSpacing);
  require(std::isfinite(settings.groundFadeDistance) && settings.groundFadeDistance >= 0,
          "renderScene: groundFadeDistance must be finite and >= 0 m, got ", settings.groundFadeDistance);

  const int W = camera.width, H = camera.height;
  const std::size_t pixels = std::size_t(W) * std::size_t(H);
  RenderStats local;
  auto clock = std::chrono::steady_clock::now();

  // ---- 1. particles -> visibility buffer (atomic min of depth|index keys)
  std::unique_ptr<std::atomic<std::uint64_t>[]> visibility(new std::atomic<std::uint64_t>[pixels]);
  for (std::size_t i = 0; i < pixels; ++i) visibility[i].store(kEmpty, std::memory_order_relaxed);

  auto radiusOf = [&](std::size_t n) { return particles.radii ? particles.radii[n] : particles.radius; };
  using Counts = std::pair<std::size_t, std::size_t>;  // particles (triangles) drawn, fragments
  const auto joinCounts = [](Counts a, const Counts& b) { return Counts{a.first + b.first, a.second + b.second}; };
  const Counts counts = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, count, 2048), Counts{0, 0},
      [&](const tbb::blocked_range<std::size_t>& range, Counts acc) {
        for (std::size_t n = range.begin(); n != range.end(); ++n) {
          Splat s;
          if (!splat(cam, particles.positions[n], radiusOf(n), s)) continue;
          // Pixels whose centre lies within r of (sx, sy), plus the one holding it.
          const double r2 = s.r * s.r;
          const double ci = std::floor(s.sx), cj = std::floor(s.sy);
          const double lo_i = std::min(std::ceil(s.sx - s.r - 0.5), ci),
                       hi_i = std::max(std::floor(s.sx + s.r - 0.5), ci);
          const double lo_j = std::min(std::ceil(s.sy - s.r - 0.5), cj),
                       hi_j = std::max(std::floor(s.sy + s.r - 0.5), cj);
          if (hi_i < 0 || hi_j < 0 || lo_i > W - 1 || lo_j > H - 1) continue;
          const int i0 = int(std::max(lo_i, 0.0)), i1 = int(std::min(hi_i, double(W - 1)));
          const int j0 = int(std::max(lo_j, 0.0)), j1 = int(std::min(hi_j, double(H - 1)));
          bool drawn = false;
          for (int j = j0; j <= j1; ++j) {
            const double dy = j + 0.5 - s.sy;
            std::atomic<std::uint64_t>* row = &visibility[std::size_t(j) * std::size_t(W)];
            for (int i = i0; i <= i1; ++i) {
              const double dx = i + 0.5 - s.sx;
              const double d2 = dx * dx + dy * dy;
              const bool inside = d2 <= r2;
              if (!inside && !(i == ci && j == cj)) continue;
              const double q = inside ? d2 / r2 : 1.0;
              const float depth = float(s.depth - s.radius * std::sqrt(1.0 - q));
              depositKey(row[i], depth, n);
              ++acc.second;
              drawn = true;
            }
          }
          if (drawn) ++acc.first;
        }
        return acc;
      },
      joinCounts);
  local.particlesDrawn = counts.first;
  local.fragments = counts.second;
  // Triangles: the pixels of each one's projected bounding box whose ray hits it.
  const Counts triCounts = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(count, keys, 512), Counts{0, 0},
      [&](const tbb::blocked_range<std::size_t>& range, Counts acc) {
        for (std::size_t n = range.begin(); n != range.end(); ++n) {
          std::size_t mesh = 0, tri = 0;
          triangleOf(n, mesh, tri);
          Vec3d p[3];
          corners(mesh, tri, p);
          double lo_x = kInf, hi_x = -kInf, lo_y = kInf, hi_y = -kInf;
          bool visible = true;
          for (const Vec3d& q : p) {
            double px = 0, py = 0, z = 0;
            if (!cam.project(q, px, py, z)) {
              visible = false;  // a corner behind the camera: not drawn (previews look at the scene)
              break;
            }
            lo_x = std::min(lo_x, px), hi_x = std::max(hi_x, px), lo_y = std::min(lo_y, py), hi_y = std::max(hi_y, py);
          }
          if (!visible || hi_x < 0 || hi_y < 0 || lo_x > W || lo_y > H) continue;
          const int i0 = std::max(0, int(std::floor(lo_x - 0.5))), i1 = std::min(W - 1, int(std::ceil(hi_x - 0.5)));
          const int j0 = std::max(0, int(std::floor(lo_y - 0.5))), j1 = std::min(H - 1, int(std::ceil(hi_y - 0.5)));
          bool drawn = false;
          for (int j = j0; j <= j1; ++j)
            for (int i = i0; i <= i1; ++i) {
              const Vec3d d = cam.rayDirection(i + 0.5, j + 0.5);
              double t = 0, u = 0, v = 0;
              if (!rayTriangle(camera.position, d, p[0], p[1], p[2], t, u, v)) continue;
              const float depth = float(t * dot(d, cam.forward()));
              depositKey(visibility[std::size_t(j) * std::size_t(W) + std::size_t(i)], depth, n);
              ++acc.second;
              drawn = true;
            }
          if (drawn) ++acc.first;
        }
        return acc;
      },
      joinCounts);
  local.trianglesDrawn = triCounts.first;
  local.fragments += triCounts.second;
  local.rasterSeconds = seconds(clock);
  clock = std::chrono::steady_clock::now();

  // ---- 2. per pixel: nearest of particle, solid primitives and ground; shade
  Lighting lighting;
  lighting.ambient = settings.ambient;
  lighting.specular = settings.specular;
  struct Solid {
    const Primitive* prim;
    Vec3d cameraLocal;
  };
  std::vector<Solid> solids;
  for (const Primitive& p : primitives)
    if (p.style == Primitive::Style::Solid) solids.push_back({&p, p.pose.toLocal(camera.position)});

  const Vec3d groundN = settings.ground ? normalised(settings.groundNormal) : Vec3d{0, 0, 1};
  const double cameraHeight = dot(camera.position, groundN) - settings.groundHeight;
  const bool drawGround = settings.ground && cameraHeight > 0;
  const Vec3d a0 = std::abs(groundN.x) < 0.9 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
  const Vec3d groundE2 = normalised(cross(groundN, a0)), groundE1 = cross(groundE2, groundN);
  const Vec3d groundOrigin = settings.groundHeight * groundN;
  const double fade =
      settings.groundFadeDistance > 0 ? settings.groundFadeDistance : 30.0 * norm(camera.lookAt - camera.position);
  const double spacing = settings.gridSpacing;

  // Ground coordinates (u, v) along the ray through (px, py); false if it misses.
  auto groundUv = [&](double px, double py, double& u, double& v, double& t) {
    const Vec3d d = cam.rayDirection(px, py);
    const double dn = dot(d, groundN);
    if (!(dn < 0)) return false;
    t = -cameraHeight / dn;
    const Vec3d rel = camera.position + t * d - groundOrigin;
    u = dot(rel, groundE1);
    v = dot(rel, groundE2);
    return std::isfinite(u) && std::isfinite(v);
  };
  // Coverage of the nearest grid line of one family, faded where lines crowd.
  auto gridLine = [&](double c, double cx, double cy) {
    const double w = std::max(std::abs(cx), std::abs(cy));  // footprint of one pixel along c
    if (!(w > 0)) return 0.0;
    const double dist = std::abs(c - spacing * std::round(c / spacing));
    const double coverage = std::clamp(1.0 - dist / w, 0.0, 1.0);
    const double sparse = std::clamp((spacing / w - 3.0) / 5.0, 0.0, 1.0);
    return coverage * sparse;
  };

  RgbImage image(W, H);
  std::vector<float> depthBuffer(pixels, std::numeric_limits<float>::infinity());
  tbb::parallel_for(tbb::blocked_range<int>(0, H, 8), [&](const tbb::blocked_range<int>& rows) {
    for (int j = rows.begin(); j != rows.end(); ++j) {
      const Rgb background = mix(settings.backgroundTop, settings.backgroundBottom, (j + 0.5) / H);
      for (int i = 0; i < W; ++i) {
        const std::size_t at = std::size_t(j) * std::size_t(W) + std::size_t(i);
        const double px = i + 0.5, py = j + 0.5;
        const Vec3d dir = cam.rayDirection(px, py);
        const double dirDepth = dot(dir, cam.forward());  // camera depth per unit of ray length
        enum { None, Particle, Triangle, Shape, Ground } kind = None;
        double best = kInf;
        const std::uint64_t key = visibility[at].load(std::memory_order_relaxed);
        if (key != kEmpty) {
          kind = (key & 0xffffffffu) < count ? Particle : Triangle;
          best = double(bitsFloat(std::uint32_t(key >> 32)));
        }
        const Solid* hitSolid = nullptr;
        Vec3d hitNormal;
        for (const Solid& s : solids) {
          const Hit h = intersect(*s.prim, s.cameraLocal, s.prim->pose.vectorToLocal(dir));
          const double z = h.t * dirDepth;
          if (h.t < kInf && z < best) {
            best = z;
            kind = Shape;
            hitSolid = &s;
            hitNormal = h.normal;
          }
        }
        double gu = 0, gv = 0, gt = 0;
        if (drawGround && groundUv(px, py, gu, gv, gt) && gt * dirDepth < best) {
          best = gt * dirDepth;
          kind = Ground;
        }
        Rgb colour = background;
        if (kind == Particle) {
          const std::size_t n = std::size_t(key & 0xffffffffu);
          Splat s;
          splat(cam, particles.positions[n], radiusOf(n), s);
          double nx = (px - s.sx) / s.r, ny = -(py - s.sy) / s.r;
          const double q = nx * nx + ny * ny;
          if (q > 1) {
            nx /= std::sqrt(q);
            ny /= std::sqrt(q);
          }
          const double nz = std::sqrt(std::max(0.0, 1.0 - nx * nx - ny * ny));
          colour = lighting.shade(particles.colours ? particles.colours[n] : settings.particleColour, {nx, ny, nz});
        } else if (kind == Triangle) {
          std::size_t mesh = 0, tri = 0;
          triangleOf(std::size_t(key & 0xffffffffu), mesh, tri);
          Vec3d p[3];
          corners(mesh, tri, p);
          double t = 0, u = 0, v = 0;
          rayTriangle(camera.position, dir, p[0], p[1], p[2], t, u, v);
          const TriangleMesh& m = *content.meshes[mesh].mesh;
          Vec3d nw = cross(p[1] - p[0], p[2] - p[0]);
          if (!m.normals.empty()) {
            const auto& f = m.triangles[tri];
            const Vec3d blend = (1 - u - v) * m.normals[f[0]] + u * m.normals[f[1]] + v * m.normals[f[2]];
            if (norm2(blend) > 0) nw = blend;
          }
          nw = normalised(nw);
          if (!isFinite(nw)) nw = -dir;
          if (dot(nw, dir) > 0) nw = -nw;  // seen from behind
          colour = lighting.shade(content.meshes[mesh].colour,
                                  {dot(nw, cam.right()), dot(nw, cam.upward()), -dot(nw, cam.forward())});
        } else if (kind == Shape) {
          Vec3d nw = hitSolid->prim->pose.vectorToWorld(hitNormal);
          if (dot(nw, dir) > 0) nw = -nw;  // seen from inside
          colour = lighting.shade(hitSolid->prim->colour,
                                  {dot(nw, cam.right()), dot(nw, cam.upward()), -dot(nw, cam.forward())});
        } else if (kind == Ground) {
          colour = settings.groundColour;
          if (spacing > 0) {
            double ux = 0, vx = 0, tx = 0, uy = 0, vy = 0, ty = 0;
            double line = 0;
            if (groundUv(px + 1, py, ux, vx, tx) && groundUv(px, py + 1, uy, vy, ty))
              line = std::max(gridLine(gu, ux - gu, uy - gu), gridLine(gv, vx - gv, vy - gv));
            colour = mix(colour, settings.gridColour, line);
          }
          // Fade into the background from fade / 4 to fade (smoothstep).
          const double f = std::clamp((gt / fade - 0.25) / 0.75, 0.0, 1.0);
          colour = mix(colour, background, f * f * (3 - 2 * f));
        }
        image.set(i, j, colour);
        if (kind != None) depthBuffer[at] = float(best);
      }
    }
  });
  local.resolveSeconds = seconds(clock);
  clock = std::chrono::steady_clock::now();

  // ---- 3. wireframes, serially, in the order given
  LineDrawer lines(cam, image, depthBuffer, settings.hiddenLineAlpha);
  for (const Primitive& p : primitives)
    if (p.style == Primitive::Style::Wireframe) drawWireframe(lines, p, p.pose.toLocal(camera.position));
  for (const Polyline& l : content.polylines) {
    const std::size_t n = l.points.size();
    for (std::size_t i = 0; i + 1 < n + (l.closed && n > 2 ? 1 : 0); ++i)
      lines.segment(l.points[i], l.points[(i + 1) % n], l.colours.empty() ? l.colour : l.colours[i]);
  }
  local.wireSeconds = seconds(clock);
  if (stats) *stats = local;
  return image;
}

}  // namespace lodestone::output
