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
#include "render_detail.h"

namespace lodestone::output {

using render_detail::checkPrimitive;
using render_detail::drawWireframe;
using render_detail::Hit;
using render_detail::intersect;
using render_detail::kInf;
using render_detail::LineDrawer;
using render_detail::mix;
using render_detail::normalised;
using render_detail::toByte;

namespace {

constexpr std::uint64_t kEmpty = ~std::uint64_t(0);

double seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
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

}  // namespace

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
