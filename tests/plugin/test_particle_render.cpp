// The preview renderer against closed forms of the pinhole camera: the disc
// of a sphere on the optical axis (radius F R / sqrt(D^2 - R^2), F = (H/2) /
// tan(fov/2)), rectangles of boxes seen face on, a cylinder's outline;
// occlusion, off-screen particles, image orientation, determinism across
// thread counts, wireframes (visible and hidden), the ground plane and the
// framing helper. Flat lighting (ambient 1, no highlight) on a black
// background makes every covered pixel exactly the object's colour.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/output/particle_render.h"

using namespace lodestone;
using namespace lodestone::output;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr Rgb kBlack{0, 0, 0};
constexpr Rgb kRed{220, 40, 30};
constexpr Rgb kBlue{30, 60, 230};
constexpr Rgb kYellow{255, 255, 0};

bool same(Rgb a, Rgb b) { return a.r == b.r && a.g == b.g && a.b == b.b; }

RenderSettings flat() {
  RenderSettings s;
  s.ground = false;
  s.backgroundTop = s.backgroundBottom = kBlack;
  s.ambient = 1.0;
  s.specular = 0.0;
  return s;
}

// 200 x 160 pixels, 60 degrees vertical, on the -y axis looking at the origin, z up.
Camera axisCamera(double distance = 1.0) {
  Camera c;
  c.position = {0.0, -distance, 0.0};
  c.lookAt = {0.0, 0.0, 0.0};
  c.up = {0.0, 0.0, 1.0};
  c.verticalFovDegrees = 60;
  c.width = 200;
  c.height = 160;
  return c;
}

double focal(const Camera& c) { return 0.5 * c.height / std::tan(0.5 * c.verticalFovDegrees * kPi / 180.0); }

RgbImage render(const std::vector<Vec3d>& x, double radius, const std::vector<Rgb>& colours,
                const std::vector<Primitive>& prims = {}, const RenderSettings& settings = flat(),
                const Camera& camera = axisCamera()) {
  ParticleView view;
  view.positions = x.data();
  view.count = x.size();
  view.colours = colours.empty() ? nullptr : colours.data();
  view.radius = radius;
  return renderScene(camera, view, prims, settings);
}

// Compares the covered pixels (not background) with `inside(px, py)` at the
// pixel centres, skipping pixels within `slack` of the boundary as measured by
// `margin(px, py)` (> 0 inside). Returns the number of covered pixels.
template <typename Margin>
int expectMask(const RgbImage& img, Rgb background, const Margin& margin, double slack = 1e-6) {
  int covered = 0, mismatches = 0;
  for (int j = 0; j < img.height; ++j)
    for (int i = 0; i < img.width; ++i) {
      const bool got = !same(img.get(i, j), background);
      covered += got;
      const double m = margin(i + 0.5, j + 0.5);
      if (std::abs(m) < slack) continue;
      if (got != (m > 0) && ++mismatches <= 5) {
        ADD_FAILURE() << "pixel (" << i << ", " << j << "): covered " << got << ", expected " << (m > 0) << " (margin "
                      << m << ")";
      }
    }
  EXPECT_EQ(mismatches, 0);
  return covered;
}

}  // namespace

TEST(ParticleRender, SphereOnAxisIsTheClosedFormDisc) {
  const Camera cam = axisCamera(1.0);
  const double R = 0.3, F = focal(cam);
  const double r = F * R / std::sqrt(1.0 - R * R);  // 43.58 px
  const RgbImage img = render({{0, 0, 0}}, R, {kRed});
  // Every covered pixel has the particle colour (flat lighting).
  for (int j = 0; j < img.height; ++j)
    for (int i = 0; i < img.width; ++i) EXPECT_TRUE(same(img.get(i, j), kBlack) || same(img.get(i, j), kRed));
  const int covered = expectMask(
      img, kBlack, [&](double px, double py) { return r - std::hypot(px - 0.5 * cam.width, py - 0.5 * cam.height); });
  EXPECT_NEAR(covered, kPi * r * r, 2 * kPi * r);
  // The test tells the exact silhouette from the naive F R / D (41.57 px):
  // about 530 pixel centres lie between the two circles.
  EXPECT_GT(covered - kPi * (F * R) * (F * R), 300);

  // A ray-cast sphere primitive has the same silhouette.
  const RgbImage prim = render({}, R, {}, {Primitive::sphere(Pose::at({0, 0, 0}), R, kBlue)});
  expectMask(prim, kBlack,
             [&](double px, double py) { return r - std::hypot(px - 0.5 * cam.width, py - 0.5 * cam.height); });
}

TEST(ParticleRender, NearerParticleWinsWhateverTheOrder) {
  // Near: depth 0.7, R 0.1 -> 20.0 px. Far: depth 1.5, R 0.4 -> 38.3 px.
  // Different radii: the per-particle radius array.
  const std::vector<Vec3d> x = {{0, -0.3, 0}, {0, 0.5, 0}};
  const std::vector<double> radii = {0.1, 0.4};
  const std::vector<Rgb> colours = {kRed, kBlue};
  ParticleView view{x.data(), 2, colours.data(), 0.0, radii.data()};
  const RgbImage a = renderScene(axisCamera(), view, {}, flat());
  EXPECT_TRUE(same(a.get(100, 80), kRed));
  EXPECT_TRUE(same(a.get(100 + 15, 80), kRed));
  EXPECT_TRUE(same(a.get(100 + 30, 80), kBlue));
  EXPECT_TRUE(same(a.get(100, 80 - 30), kBlue));
  EXPECT_TRUE(same(a.get(100 + 45, 80), kBlack));

  const std::vector<Vec3d> xr = {x[1], x[0]};
  const std::vector<double> radiiR = {radii[1], radii[0]};
  const std::vector<Rgb> coloursR = {kBlue, kRed};
  ParticleView reversed{xr.data(), 2, coloursR.data(), 0.0, radiiR.data()};
  EXPECT_EQ(renderScene(axisCamera(), reversed, {}, flat()).rgb, a.rgb);

  // A solid box between the camera and the far particle hides it; one behind it does not.
  const Primitive front = Primitive::box(Pose::at({0, 0.1, 0}), {0.02, 0.02, 0.5}, kYellow);
  const Primitive back = Primitive::box(Pose::at({0, 2.5, 0}), {3.0, 0.1, 3.0}, kYellow);
  const RgbImage b = renderScene(axisCamera(), view, {front, back}, flat());
  EXPECT_TRUE(same(b.get(100, 80), kRed));          // near particle still in front
  EXPECT_TRUE(same(b.get(100, 80 - 30), kYellow));  // thin box over the far particle
  EXPECT_TRUE(same(b.get(100 + 30, 80), kBlue));    // far particle over the back wall
  EXPECT_TRUE(same(b.get(100 + 45, 80), kYellow));  // back wall
}

TEST(ParticleRender, OffScreenParticlesChangeNothing) {
  const RgbImage base = render({{0, 0, 0}}, 0.05, {kRed, kRed, kRed, kRed, kRed, kRed});
  const double nan = std::nan("");
  const std::vector<Vec3d> x = {{0, 0, 0},     {5, 0, 0},  // projects 700 px right of the image
                                {0, 0, -4},                // below
                                {0, -3, 0},                // behind the camera
                                {0, -1.02, 0},             // contains the camera
                                {nan, 0, 0}};              // not finite: skipped
  EXPECT_EQ(render(x, 0.05, {kRed, kBlue, kBlue, kBlue, kBlue, kBlue}).rgb, base.rgb);
}

TEST(ParticleRender, OrientationMatchesThePinholeModel) {
  const Camera cam = axisCamera();
  const double F = focal(cam);
  auto centroid = [&](const Vec3d& p, double& cx, double& cy) {
    const RgbImage img = render({p}, 0.03, {kRed});
    double sx = 0, sy = 0, n = 0;
    for (int j = 0; j < img.height; ++j)
      for (int i = 0; i < img.width; ++i)
        if (same(img.get(i, j), kRed)) {
          sx += i + 0.5;
          sy += j + 0.5;
          n += 1;
        }
    ASSERT_GT(n, 0);
    cx = sx / n;
    cy = sy / n;
  };
  double cx = 0, cy = 0;
  centroid({0.3, 0, 0}, cx, cy);  // +x (camera right) appears right of the centre
  EXPECT_NEAR(cx, 100 + F * 0.3, 0.5);
  EXPECT_NEAR(cy, 80, 0.5);
  centroid({0, 0, 0.3}, cx, cy);  // +z (up) appears above the centre (smaller row)
  EXPECT_NEAR(cx, 100, 0.5);
  EXPECT_NEAR(cy, 80 - F * 0.3, 0.5);
  centroid({-0.2, 0.5, -0.1}, cx, cy);  // general point: F x / z
  EXPECT_NEAR(cx, 100 - F * 0.2 / 1.5, 0.5);
  EXPECT_NEAR(cy, 80 + F * 0.1 / 1.5, 0.5);

  // The headlight comes from the upper left: that side of a sphere is brighter.
  RenderSettings lit = flat();
  lit.ambient = 0.2;
  const RgbImage img = render({{0, 0, 0}}, 0.3, {kRed}, {}, lit);
  EXPECT_GT(img.get(100 - 20, 80 - 20).r, img.get(100 + 20, 80 + 20).r + 50);
}

TEST(ParticleRender, DeterministicAcrossThreadCounts) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<Vec3d> x(50000);
  std::vector<Rgb> colours(x.size());
  for (std::size_t n = 0; n < x.size(); ++n) {
    x[n] = {u(rng), u(rng), u(rng)};
    colours[n] = {std::uint8_t(rng() & 255), std::uint8_t(rng() & 255), std::uint8_t(rng() & 255)};
  }
  // Duplicated positions with other colours: equal depths go to the lower index.
  for (std::size_t n = 0; n < 1000; ++n) {
    const Vec3d p = x[n];
    x.push_back(p);
    colours.push_back(kYellow);
  }
  RenderSettings settings;  // default ground and grid; flat lighting, so that yellow stays exact
  settings.groundHeight = -0.35;
  settings.ambient = 1.0;
  settings.specular = 0.0;
  const std::vector<Primitive> prims = {
      Primitive::cylinder(Pose::fromAxisAngle({0, 0, -0.3}, {1, 0, 0}, 0.3), 0.1, 0.04, kRed),
      Primitive::box(Pose::at({0.2, 0, 0}), {0.1, 0.1, 0.1}, kBlue, Primitive::Style::Wireframe)};
  RgbImage serial, parallel;
  tbb::task_arena one(1);
  one.execute([&] { serial = render(x, 0.004, colours, prims, settings); });
  tbb::task_arena all;  // every core
  all.execute([&] { parallel = render(x, 0.004, colours, prims, settings); });
  EXPECT_EQ(serial.rgb, parallel.rgb);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(render(x, 0.004, colours, prims, settings).rgb, serial.rgb);
  // No yellow: every duplicate loses to its original.
  int yellow = 0;
  for (int j = 0; j < serial.height; ++j)
    for (int i = 0; i < serial.width; ++i) yellow += same(serial.get(i, j), kYellow);
  EXPECT_EQ(yellow, 0);
}

TEST(ParticleRender, BoxAndCylinderOutlines) {
  const Camera cam = axisCamera();
  const double F = focal(cam);
  // Box seen face on: the front face (depth 0.9) bounds the outline.
  const Vec3d h{0.2, 0.1, 0.15};
  const RgbImage box = render({}, 0.1, {}, {Primitive::box(Pose::at({0, 0, 0}), h, kRed)});
  const double hx = F * h.x / (1 - h.y), hy = F * h.z / (1 - h.y);
  const int covered = expectMask(
      box, kBlack, [&](double px, double py) { return std::min(hx - std::abs(px - 100), hy - std::abs(py - 80)); });
  EXPECT_GT(covered, 2000);

  // Cylinder along z: the centre row spans the tangent lines, +-F R / sqrt(D^2 - R^2);
  // the centre column the near rim of the caps, +-F L / (D - R).
  const double R = 0.2, L = 0.25;
  const RgbImage cyl = render({}, 0.1, {}, {Primitive::cylinder(Pose::at({0, 0, 0}), R, L, kRed)});
  const double halfWidth = F * R / std::sqrt(1 - R * R), halfHeight = F * L / (1 - R);
  for (int i = 0; i < cam.width; ++i) {
    const double m = halfWidth - std::abs(i + 0.5 - 100);
    if (std::abs(m) > 1e-6) {
      EXPECT_EQ(!same(cyl.get(i, 80), kBlack), m > 0) << "column " << i;
    }
  }
  for (int j = 0; j < cam.height; ++j) {
    const double m = halfHeight - std::abs(j + 0.5 - 80);
    if (std::abs(m) > 1e-6) {
      EXPECT_EQ(!same(cyl.get(100, j), kBlack), m > 0) << "row " << j;
    }
  }
  // Rotated a quarter turn about x, the cylinder shows its round cap: a disc of radius F R / (D - L).
  const RgbImage cap =
      render({}, 0.1, {}, {Primitive::cylinder(Pose::fromAxisAngle({0, 0, 0}, {1, 0, 0}, kPi / 2), R, L, kRed)});
  expectMask(cap, kBlack, [&](double px, double py) { return F * R / (1 - L) - std::hypot(px - 100, py - 80); });
}

TEST(ParticleRender, WireframesVisibleAndHidden) {
  const Camera cam = axisCamera();
  const double F = focal(cam);
  const Vec3d h{0.2, 0.1, 0.15};
  const Primitive wire = Primitive::box(Pose::at({0, 0, 0}), h, kYellow, Primitive::Style::Wireframe);
  const int frontTop = int(std::floor(80 - F * h.z / (1 - h.y)));  // row of the front top edge
  const int backTop = int(std::floor(80 - F * h.z / (1 + h.y)));   // row of the back top edge
  ASSERT_NE(frontTop, backTop);

  const RgbImage open = render({}, 0.1, {}, {wire});
  EXPECT_TRUE(same(open.get(100, frontTop), kYellow));
  EXPECT_TRUE(same(open.get(100, backTop), kYellow));
  EXPECT_TRUE(same(open.get(100, 80), kBlack));  // no faces
  int lit = 0;
  for (std::uint8_t v : open.rgb) lit += v != 0;
  EXPECT_LT(lit, 3 * 2000);  // lines only

  // A particle in front hides both edges: they are blended faintly over it.
  const RgbImage hidden = render({{0, -0.5, 0}}, 0.2, {kBlue}, {wire});
  for (int row : {frontTop, backTop}) {
    const Rgb c = hidden.get(100, row);
    EXPECT_FALSE(same(c, kBlue));
    EXPECT_FALSE(same(c, kYellow));
    EXPECT_GT(c.r, kBlue.r);
    EXPECT_LT(c.b, kBlue.b);
  }
}

TEST(ParticleRender, GroundPlaneAndBackground) {
  Camera cam = axisCamera();
  cam.position = {0, -1, 0.3};
  RenderSettings s = flat();
  s.backgroundTop = {10, 20, 30};
  s.backgroundBottom = {90, 100, 110};
  s.ground = false;
  const RgbImage sky = render({}, 0.05, {}, {}, s, cam);
  EXPECT_TRUE(same(sky.get(0, 0), Rgb{10, 20, 30}) || sky.get(0, 0).r < 12);
  EXPECT_GT(sky.get(0, cam.height - 1).r, 85);  // gradient towards the bottom colour

  s.ground = true;
  s.groundHeight = -0.1;
  s.gridSpacing = 0.05;
  const std::vector<Vec3d> below = {{0, 0, -0.5}};  // on screen, under the ground
  const RgbImage ground = render(below, 0.05, {kRed}, {}, s, cam);
  EXPECT_EQ(ground.get(0, 0).r, sky.get(0, 0).r);  // sky above the horizon
  EXPECT_FALSE(same(ground.get(100, cam.height - 1), sky.get(100, cam.height - 1)));
  EXPECT_EQ(ground.rgb, render({}, 0.05, {}, {}, s, cam).rgb);  // the particle is hidden by the ground
  // Grid lines: the bottom rows hold both the ground and the grid colour.
  int groundPixels = 0, gridPixels = 0;
  for (int i = 0; i < cam.width; ++i) {
    groundPixels += same(ground.get(i, cam.height - 1), s.groundColour);
    gridPixels += ground.get(i, cam.height - 1).r + 30 < s.groundColour.r;  // on or near a line
  }
  EXPECT_GT(groundPixels, 50);
  EXPECT_GT(gridPixels, 2);

  // From below the ground, no ground is drawn.
  s.groundHeight = 0.5;
  EXPECT_EQ(render({}, 0.05, {}, {}, s, cam).rgb, sky.rgb);
}

TEST(ParticleRender, FrameCameraFitsTheBox) {
  Bounds3 box;
  box.add({-0.1, -0.05, 0.0});
  box.add({0.1, 0.05, 0.2});
  const Camera cam = frameCamera(box, {1, 1, -0.5}, {0, 0, 1}, 40, 640, 480, 1.05);
  const CameraProjection proj(cam);
  double minX = 1e9, maxX = -1e9, minY = 1e9, maxY = -1e9;
  for (int c = 0; c < 8; ++c) {
    const Vec3d p{(c & 1) ? box.max.x : box.min.x, (c & 2) ? box.max.y : box.min.y, (c & 4) ? box.max.z : box.min.z};
    double px = 0, py = 0, z = 0;
    ASSERT_TRUE(proj.project(p, px, py, z));
    minX = std::min(minX, px);
    maxX = std::max(maxX, px);
    minY = std::min(minY, py);
    maxY = std::max(maxY, py);
  }
  EXPECT_GE(minX, 0);
  EXPECT_LE(maxX, 640);
  EXPECT_GE(minY, 0);
  EXPECT_LE(maxY, 480);
  EXPECT_GT(maxY - minY, 0.4 * 480);  // and not lost in the distance
  // The look-at point is the box centre, at the image centre.
  double px = 0, py = 0, z = 0;
  ASSERT_TRUE(proj.project({0, 0, 0.1}, px, py, z));
  EXPECT_NEAR(px, 320, 1e-9);
  EXPECT_NEAR(py, 240, 1e-9);

  std::vector<Vec3d> x = {{1, 2, 3}, {-1, 0, 5}};
  const Bounds3 b = boundsOf(ParticleView{x.data(), 2, nullptr, 0.5, nullptr});
  EXPECT_EQ(b.min.x, -1.5);
  EXPECT_EQ(b.max.z, 5.5);
  EXPECT_THROW(frameCamera(Bounds3{}, {1, 0, 0}), InvalidArgument);
  EXPECT_THROW(frameCamera(box, {0, 0, -1}, {0, 0, 1}), InvalidArgument);  // up parallel to the view
}

TEST(ParticleRender, RejectsBadArguments) {
  Camera cam = axisCamera();
  const std::vector<Vec3d> x = {{0, 0, 0}};
  EXPECT_THROW(render(x, 0.0, {}), InvalidArgument);
  EXPECT_THROW(render(x, std::nan(""), {}), InvalidArgument);
  cam.up = {0, 3, 0};
  EXPECT_THROW(render(x, 0.1, {}, {}, flat(), cam), InvalidArgument);
  cam = axisCamera();
  cam.verticalFovDegrees = 180;
  EXPECT_THROW(render(x, 0.1, {}, {}, flat(), cam), InvalidArgument);
  cam = axisCamera();
  cam.lookAt = cam.position;
  EXPECT_THROW(render(x, 0.1, {}, {}, flat(), cam), InvalidArgument);
  EXPECT_THROW(render({}, 0.1, {}, {Primitive::sphere(Pose::at({0, 0, 0}), -1.0, kRed)}), InvalidArgument);
  EXPECT_THROW(render({}, 0.1, {}, {Primitive::box(Pose::at({0, 0, 0}), {1, 0, 1}, kRed)}), InvalidArgument);
  ParticleView missing;
  missing.count = 3;
  missing.radius = 0.1;
  EXPECT_THROW(renderScene(axisCamera(), missing, {}), InvalidArgument);
}
