#include "preview.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "lodestone/core/sources/cuboid_magnet.h"
#include "lodestone/core/sources/cylinder_magnet.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone/plugin/output/contact_sheet.h"
#include "lodestone/plugin/output/mesh_render.h"
#include "lodestone/plugin/output/png_writer.h"
#include "lodestone/plugin/output/particle_render.h"

namespace lodestone::examples {

using namespace lodestone::output;

namespace {
const Rgb kMagneticColours[] = {{38, 40, 52}, {70, 48, 80}, {30, 60, 70}};
const Rgb kPlainColours[] = {{90, 150, 210}, {220, 160, 70}, {110, 180, 120}, {200, 110, 140}};

Primitive magnetPrimitive(const MagnetSource& m) {
  const Rgb red{196, 52, 46};
  if (const auto* s = dynamic_cast<const SphereMagnet*>(&m)) return Primitive::sphere(m.pose(), s->radius(), red);
  if (const auto* c = dynamic_cast<const CylinderMagnet*>(&m))
    return Primitive::cylinder(m.pose(), c->radius(), c->halfLength(), red);
  const auto& b = dynamic_cast<const CuboidMagnet&>(m);
  return Primitive::box(m.pose(), b.halfSize(), red);
}
/// Points on the surface of a level-set collider (world frame, m), about
/// `spacing` apart: the nodes of its signed distance within half a voxel of
/// the surface, every stride-th along each axis, moved onto phi = 0.
void levelSetSurfacePoints(const MpmCollider& c, const Pose& pose, double spacing, std::vector<Vec3d>& out) {
  const SampledSdf& sdf = *c.shape().levelSet;
  const GridSpec& g = sdf.spec();
  const int stride = std::max(1, int(std::lround(spacing / g.dx)));
  for (int k = 0; k < g.dims.k; k += stride)
    for (int j = 0; j < g.dims.j; j += stride)
      for (int i = 0; i < g.dims.i; i += stride) {
        const Vec3d xb = g.nodePosition(i, j, k);
        const double phi = sdf.signedDistance(xb);
        if (std::fabs(phi) > 0.5 * stride * g.dx) continue;
        out.push_back(pose.toWorld(xb - phi * sdf.normal(xb)));
      }
}
/// The magnets (solid), colliders and the domain (wireframes).
std::vector<Primitive> scenePrimitives(const plugin::Scene& scene, const MpmSolver& solver) {
  const GridSpec& g = scene.settings.grid;
  std::vector<Primitive> shapes;
  for (std::size_t i = 0; i < solver.magnetCount(); ++i) shapes.push_back(magnetPrimitive(solver.magnet(i)));
  for (std::size_t i = 0; i < solver.colliderCount(); ++i) {
    const MpmCollider& c = solver.collider(i);
    const ColliderShape& s = c.shape();
    const Pose pose = c.motion().poseAt(solver.time());
    const Rgb grey{225, 225, 225};
    if (s.kind == ColliderShapeKind::Box)
      shapes.push_back(Primitive::box(pose, s.halfSize, grey, Primitive::Style::Wireframe));
    else if (s.kind == ColliderShapeKind::Sphere)
      shapes.push_back(Primitive::sphere(pose, s.radius, grey, Primitive::Style::Wireframe));
    else if (s.kind == ColliderShapeKind::Cylinder)
      shapes.push_back(Primitive::cylinder(pose, s.radius, s.halfLength, grey, Primitive::Style::Wireframe));
  }
  const Vec3d lo = g.origin, hi = g.maxCorner();
  shapes.push_back(Primitive::box(Pose::at(0.5 * (lo + hi)), 0.5 * (hi - lo), Rgb{160, 165, 175},
                                  Primitive::Style::Wireframe));
  return shapes;
}

/// The scene's camera, or one framing `box` when it asks for an automatic one.
Camera previewCamera(const plugin::Scene& scene, const Bounds3& box) {
  Camera cam;
  if (scene.output.autoCamera) {
    cam = frameCamera(box, {0.55, 1.0, -0.45}, {0, 0, 1}, scene.output.fovDegrees, scene.output.width,
                      scene.output.height, 1.02);
  } else {
    cam.position = scene.output.cameraPosition;
    cam.lookAt = scene.output.cameraLookAt;
    cam.verticalFovDegrees = scene.output.fovDegrees;
    cam.width = scene.output.width;
    cam.height = scene.output.height;
  }
  return cam;
}

RenderSettings previewSettings(const GridSpec& g) {
  RenderSettings rs;
  rs.groundHeight = g.origin.z;
  rs.gridSpacing = 8 * g.dx;
  return rs;
}
}  // namespace

RgbImage renderPreview(const plugin::Scene& scene, const MpmSolver& solver, const std::vector<FieldLine>& fieldLines) {
  const MpmParticles& p = solver.particles();
  const GridSpec& g = scene.settings.grid;
  std::vector<Rgb> colours(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    const std::uint32_t m = p.material[i];
    colours[i] = solver.materials()[m].isMagnetic() ? kMagneticColours[m % 3] : kPlainColours[m % 4];
  }
  // Level-set and mesh colliders are drawn as points on their surface.
  std::vector<Vec3d> points(p.x);
  const Rgb surface{200, 200, 196};
  for (std::size_t i = 0; i < solver.colliderCount(); ++i) {
    const MpmCollider& c = solver.collider(i);
    if (c.shape().kind == ColliderShapeKind::LevelSet)
      levelSetSurfacePoints(c, c.motion().poseAt(solver.time()), 0.5 * g.dx, points);
  }
  colours.resize(points.size(), surface);
  Bounds3 box;
  box.add(g.origin);
  box.add(g.maxCorner());
  SceneContent content;
  content.primitives = scenePrimitives(scene, solver);
  content.polylines = fieldLinePolylines(fieldLines);
  content.particles.positions = points.data();
  content.particles.count = points.size();
  content.particles.colours = colours.data();
  // Sphere impostors about the particle spacing (dx / ppc^(1/3) for 8 ppc).
  content.particles.radius = 0.5 * g.dx * 0.62;
  return renderScene(previewCamera(scene, box), content, previewSettings(g));
}

RgbImage renderMeshPreview(const plugin::Scene& scene, const MpmSolver& solver, const TriangleMesh& surface,
                           const std::vector<FieldLine>& fieldLines) {
  const GridSpec& g = scene.settings.grid;
  Bounds3 box = boundsOf(surface);
  if (box.empty()) {  // no material: the domain
    box.add(g.origin);
    box.add(g.maxCorner());
  }
  MeshRenderSettings s;
  s.render = previewSettings(g);
  s.meshColour = kMagneticColours[0];
  return renderMesh(previewCamera(scene, box), surface, scenePrimitives(scene, solver), fieldLines, s);
}

namespace {
constexpr int kSheetThumbnails = 48, kSheetColumns = 8, kThumbnailWidth = 160;
}

ContactSheetCollector::ContactSheetCollector(int first, int last)
    : first_(first), stride_(contactSheetStride(std::max(1, last - first + 1), kSheetThumbnails)) {}

void ContactSheetCollector::add(int frame, const RgbImage& preview) {
  if ((frame - first_) % stride_ != 0 || frame < first_) return;
  thumbnails_.push_back(thumbnail(preview, std::min(kThumbnailWidth, preview.width)));
}

void ContactSheetCollector::write(const std::string& path) const {
  if (thumbnails_.empty()) return;
  const RgbImage sheet = contactSheet(thumbnails_, kSheetColumns);
  writePng(path, sheet.width, sheet.height, sheet.rgb.data());
}

}  // namespace lodestone::examples
