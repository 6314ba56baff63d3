// Mesh previews: a sphere mesh is the disc of the exact projected radius,
// images are deterministic across thread counts, automatic framing keeps the
// material's bounding box in view, field lines are drawn in their colours,
// and contact sheets place their thumbnails.
#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <cmath>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/plugin/output/contact_sheet.h"
#include "lodestone/plugin/output/mesh_render.h"
#include "lodestone_test/sphere_mesh.h"

using namespace lodestone;
using namespace lodestone::output;

namespace {

TriangleMesh sphereMesh(const Vec3d& c, double r, int rings = 96, int segments = 192) {
  return test::latLongSphere(c, r, rings, segments);
}

MeshRenderSettings flatSettings() {
  MeshRenderSettings s;
  s.render.ground = false;
  s.render.backgroundTop = s.render.backgroundBottom = {0, 0, 0};
  s.render.ambient = 1.0;  // flat: every mesh pixel has the mesh colour
  s.render.specular = 0.0;
  s.meshColour = {200, 100, 50};
  return s;
}

bool same(Rgb a, Rgb b) { return a.r == b.r && a.g == b.g && a.b == b.b; }

}  // namespace

TEST(MeshRender, SphereMeshIsADiscOfTheProjectedRadius) {
  const double R = 0.02, d = 0.15;
  const TriangleMesh sphere = sphereMesh({0, 0, 0}, R);
  Camera cam;
  cam.position = {0, -d, 0};
  cam.lookAt = {0, 0, 0};
  cam.width = 320;
  cam.height = 240;
  const MeshRenderSettings s = flatSettings();
  RenderStats stats;
  const RgbImage img = renderMesh(cam, sphere, {}, {}, s, &stats);
  double area = 0, cx = 0, cy = 0;
  for (int j = 0; j < img.height; ++j)
    for (int i = 0; i < img.width; ++i)
      if (same(img.get(i, j), s.meshColour)) {
        area += 1;
        cx += i + 0.5;
        cy += j + 0.5;
      }
  const CameraProjection proj(cam);
  const double expected = proj.sphereRadiusPixels(R, d);
  const double radius = std::sqrt(area / kPi);
  std::printf("sphere mesh: disc radius %.3f px, exact silhouette %.3f px, %zu triangles drawn\n", radius, expected,
              stats.trianglesDrawn);
  EXPECT_GT(expected, 40.0);
  EXPECT_NEAR(radius, expected, 0.005 * expected);
  EXPECT_NEAR(cx / area, 160.0, 0.05);
  EXPECT_NEAR(cy / area, 120.0, 0.05);
  EXPECT_GT(stats.trianglesDrawn, 5000u);  // of 36864, most smaller than a pixel
}

TEST(MeshRender, ShadingFollowsTheNormalsAndIsDeterministic) {
  const TriangleMesh sphere = sphereMesh({0.01, 0.0, 0.02}, 0.015, 48, 96);
  Camera cam;
  cam.position = {0.05, -0.12, 0.08};
  cam.lookAt = {0.01, 0, 0.02};
  MeshRenderSettings s;
  std::vector<Primitive> shapes{Primitive::box(Pose::at({0.05, 0, 0.02}), {0.01, 0.01, 0.01}, {196, 52, 46})};
  const RgbImage a = renderMesh(cam, sphere, shapes, {}, s);
  RgbImage b;
  tbb::task_arena one(1);
  one.execute([&] { b = renderMesh(cam, sphere, shapes, {}, s); });
  EXPECT_EQ(a.rgb, b.rgb);
  // Lit from the upper left: the sphere's upper-left limb is brighter than its lower right.
  const CameraProjection proj(cam);
  double px = 0, py = 0, z = 0;
  ASSERT_TRUE(proj.project({0.01, 0, 0.02}, px, py, z));
  const double r = proj.sphereRadiusPixels(0.015, z);
  const Rgb ul = a.get(int(px - 0.5 * r), int(py - 0.5 * r)), lr = a.get(int(px + 0.5 * r), int(py + 0.5 * r));
  EXPECT_GT(ul.r + ul.g + ul.b, lr.r + lr.g + lr.b + 60);
}

TEST(MeshRender, AutomaticFramingKeepsTheMaterialInView) {
  // An elongated, off-centre material.
  TriangleMesh m = sphereMesh({0.3, -0.1, 0.05}, 0.02, 16, 32);
  for (Vec3d& v : m.vertices) v.x = 0.3 + 4.0 * (v.x - 0.3);
  const Bounds3 box = boundsOf(m);
  for (const Vec3d& view : {Vec3d{0.55, 1.0, -0.45}, Vec3d{0, 1, 0}, Vec3d{1, 0.2, -0.8}}) {
    const Camera cam = frameCamera(box, view, {0, 0, 1}, 35, 640, 360, 1.02);
    const CameraProjection proj(cam);
    double minX = 1e9, maxX = -1e9, minY = 1e9, maxY = -1e9;
    for (int c = 0; c < 8; ++c) {
      const Vec3d p{c & 1 ? box.max.x : box.min.x, c & 2 ? box.max.y : box.min.y, c & 4 ? box.max.z : box.min.z};
      double px = 0, py = 0, z = 0;
      ASSERT_TRUE(proj.project(p, px, py, z));
      minX = std::min(minX, px), maxX = std::max(maxX, px), minY = std::min(minY, py), maxY = std::max(maxY, py);
    }
    EXPECT_GE(minX, 0.0);
    EXPECT_LE(maxX, 640.0);
    EXPECT_GE(minY, 0.0);
    EXPECT_LE(maxY, 360.0);
    // and fills a good part of it (the box's bounding sphere fits the view).
    EXPECT_GT(std::max((maxX - minX) / 640.0, (maxY - minY) / 360.0), 0.4);
  }
}

TEST(MeshRender, FieldLinesAreDrawnInTheirColours) {
  FieldLine weak, strong;
  for (int i = 0; i <= 20; ++i) {
    weak.points.push_back({-0.05 + 0.005 * i, 0.0, 0.01});
    weak.magnitude.push_back(0.001);
    strong.points.push_back({-0.05 + 0.005 * i, 0.0, -0.01});
    strong.magnitude.push_back(0.1);
  }
  const std::vector<Polyline> lines = fieldLinePolylines({weak, strong});
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_TRUE(same(lines[0].colours[0], mapColour(Colormap::Inferno, 0.0)));
  EXPECT_TRUE(same(lines[1].colours[0], mapColour(Colormap::Inferno, 1.0)));
  Camera cam;
  cam.position = {0, -0.2, 0};
  cam.lookAt = {0, 0, 0};
  const TriangleMesh empty;
  const RgbImage img = renderMesh(cam, empty, {}, {weak, strong}, flatSettings());
  const CameraProjection proj(cam);
  double px = 0, py = 0, z = 0;
  ASSERT_TRUE(proj.project({0.0, 0.0, -0.01}, px, py, z));
  bool found = false;
  for (int dj = -1; dj <= 1; ++dj) found |= same(img.get(int(px), int(py) + dj), lines[1].colours[0]);
  EXPECT_TRUE(found);
}

TEST(ContactSheet, ThumbnailsAverageAndLandInTheirCells) {
  RgbImage a(8, 4, {0, 0, 0});
  for (int y = 0; y < 4; ++y) a.set(0, y, {255, 255, 255});
  const RgbImage t = thumbnail(a, 4);  // 2 x 2 source pixels per thumbnail pixel
  ASSERT_EQ(t.width, 4);
  ASSERT_EQ(t.height, 2);
  EXPECT_EQ(t.get(0, 0).r, 128);  // half white
  EXPECT_EQ(t.get(1, 0).r, 0);
  std::vector<RgbImage> thumbs;
  for (int n = 0; n < 5; ++n) thumbs.emplace_back(10, 6, Rgb{std::uint8_t(10 * n), 0, 0});
  const RgbImage sheet = contactSheet(thumbs, 3, 2, {1, 2, 3});
  EXPECT_EQ(sheet.width, 2 + 3 * 12);
  EXPECT_EQ(sheet.height, 2 + 2 * 8);
  EXPECT_EQ(sheet.get(2 + 12 * 1, 2).r, 10);      // the second thumbnail
  EXPECT_EQ(sheet.get(2 + 12 * 1, 2 + 8).r, 40);  // the fifth, second row
  EXPECT_EQ(sheet.get(2 + 12 * 2, 2 + 8).b, 3);   // an empty cell: background
  EXPECT_EQ(contactSheetStride(10, 48), 1);
  EXPECT_EQ(contactSheetStride(100, 48), 3);
  thumbs.emplace_back(9, 6);
  EXPECT_THROW(contactSheet(thumbs, 3), InvalidArgument);
}
