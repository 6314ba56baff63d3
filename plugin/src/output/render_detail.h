#pragma once
// What the preview renderer's parts share (particle_render.cpp,
// render_camera.cpp, render_primitives.cpp): small colour and vector helpers,
// the ray casting of the primitives and their line drawings.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "lodestone/plugin/output/particle_render.h"

namespace lodestone::output::render_detail {

constexpr double kInf = std::numeric_limits<double>::infinity();

inline Vec3d normalised(const Vec3d& v) { return v / norm(v); }

inline std::uint8_t toByte(double v) { return std::uint8_t(std::lround(std::clamp(v, 0.0, 255.0))); }

inline Rgb mix(Rgb a, Rgb b, double t) {
  return {toByte(a.r + (b.r - a.r) * t), toByte(a.g + (b.g - a.g) * t), toByte(a.b + (b.b - a.b) * t)};
}

/// A ray's nearest hit on a primitive.
struct Hit {
  double t = kInf;  // along the unit ray, m
  Vec3d normal;     // body frame, unit
};

/// The nearest hit (t > 0) of the ray oLocal + t dLocal (unit), in the
/// primitive's body frame.
Hit intersect(const Primitive& prim, const Vec3d& oLocal, const Vec3d& dLocal);

/// Throws InvalidArgument naming primitive k when its pose or size is not
/// finite or its size not positive.
void checkPrimitive(const Primitive& p, std::size_t k);

/// Draws line segments over an image whose depth buffer is given: visible
/// parts in full colour, hidden ones blended in at hiddenAlpha.
class LineDrawer {
 public:
  LineDrawer(const CameraProjection& cam, RgbImage& image, const std::vector<float>& depth, double hiddenAlpha);
  void segment(const Vec3d& aWorld, const Vec3d& bWorld, Rgb colour);
  void polyline(const std::vector<Vec3d>& points, Rgb colour, bool closed);

 private:
  void plot(int i, int j, double z, Rgb colour);

  const CameraProjection& cam_;
  RgbImage& image_;
  const std::vector<float>& depth_;
  double hiddenAlpha_;
  double near_ = 0;
  std::vector<std::uint8_t> mask_;  // 1: hidden edge drawn, 2: visible edge drawn
};

/// The primitive's edges (box), great circles and silhouette (sphere), or
/// end circles and silhouette generators (cylinder), seen from cameraLocal
/// (the camera's position in the body frame).
void drawWireframe(LineDrawer& lines, const Primitive& p, const Vec3d& cameraLocal);

}  // namespace lodestone::output::render_detail
