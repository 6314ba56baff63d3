#pragma once
// A small software renderer for previews of MPM runs: particles as shaded
// sphere impostors, triangle meshes (a material's surface) shaded with their
// vertex normals, polylines (field lines) drawn like wireframes, magnets and colliders as ray-cast boxes, spheres and
// cylinders (solid) or as line drawings (wireframe), over a ground plane with
// a grid and a background gradient, seen by a perspective (pinhole) camera.
// No text, no anti-aliasing, no shadows: enough to see what a scene does.
//
// Camera model. forward f = normalise(lookAt - position), right
// r = normalise(f x up), upward u = r x f. A point p at camera coordinates
// (x, y, z) = ((p - position).r, (p - position).u, (p - position).f), z > 0,
// lands at the continuous image position
//   px = width / 2 + F x / z,   py = height / 2 - F y / z,
//   F = (height / 2) / tan(verticalFov / 2)   (focal length in pixels),
// pixel (i, j) (column i, row j from the top) covering [i, i+1) x [j, j+1).
// So +right appears right of the image centre and +up above it.
//
// Particles. A sphere of radius R whose centre is at depth z is drawn as the
// disc of radius F R / sqrt(z^2 - R^2) around the projection of its centre
// (its exact silhouette on the optical axis; off axis the true silhouette is
// a slightly larger ellipse). A pixel is covered when its centre lies in the
// disc; the pixel holding the projected centre is always covered, so
// particles smaller than a pixel do not vanish. The depth of a fragment is the
// sphere's surface depth there, z - R sqrt(1 - d^2), d the distance from the
// centre relative to the disc radius; shading is Lambert plus a small specular
// highlight from a light fixed to the camera (upper left, in front).
//
// Meshes. A pixel is covered by a triangle when the ray through its centre
// hits it (Moller-Trumbore); the fragment's depth is the hit's, its normal
// the barycentric blend of the vertex normals (the face normal when the mesh
// has none), turned towards the viewer.
//
// Visibility and determinism. Particles and triangles are rasterised in parallel (TBB)
// into a visibility buffer of 64-bit keys (float depth bits << 32 | particle
// index) with an atomic minimum, so the nearest fragment wins and equal depths
// go to the lower index (particles first, then triangles): the image does not depend on the thread count or the
// scheduling. A per-pixel pass then compares that fragment with the
// ray-cast solid primitives and the ground, and shades the nearest. Wireframe
// primitives and polylines are drawn last, serially: full colour where in front of the
// depth buffer, faintly where hidden.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "lodestone/plugin/output/colormap.h"
#include "lodestone/core/base/pose.h"
#include "lodestone/core/base/triangle_mesh.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone::output {

struct Camera {
  Vec3d position{0.0, -1.0, 0.5};  ///< m
  Vec3d lookAt{0.0, 0.0, 0.0};     ///< m
  Vec3d up{0.0, 0.0, 1.0};         ///< any length; must not be parallel to the view direction
  double verticalFovDegrees = 40;  ///< in (0, 180)
  int width = 640, height = 480;   ///< pixels, 1..16384
};

/// A validated camera with its basis (see the file comment). Throws
/// lodestone::InvalidArgument naming the bad field.
class CameraProjection {
 public:
  explicit CameraProjection(const Camera& camera);

  const Camera& camera() const { return camera_; }
  const Vec3d& forward() const { return forward_; }
  const Vec3d& right() const { return right_; }
  const Vec3d& upward() const { return up_; }
  double focalPixels() const { return focal_; }  ///< F

  /// (x right, y up, z depth along forward) of a world point, m.
  Vec3d toCamera(const Vec3d& world) const;
  /// Image position (px, py) and depth z of a world point; false when z <= 0.
  bool project(const Vec3d& world, double& px, double& py, double& depth) const;
  /// Unit world direction of the ray through image position (px, py).
  Vec3d rayDirection(double px, double py) const;
  /// Disc radius in pixels of a sphere of radius R at depth z (> R): F R / sqrt(z^2 - R^2).
  double sphereRadiusPixels(double radius, double depth) const;

 private:
  Camera camera_;
  Vec3d forward_, right_, up_;
  double focal_ = 0;
};

/// Axis-aligned bounds (m); empty() until something is added.
struct Bounds3 {
  Vec3d min{1.0, 1.0, 1.0}, max{-1.0, -1.0, -1.0};
  bool empty() const { return min.x > max.x; }
  void add(const Vec3d& p, double radius = 0.0);
};

/// A camera looking along `viewDirection` (from the camera towards the box)
/// at the centre of the box, far enough for the box's bounding sphere, times
/// `margin` (>= 1), to fit the vertical and the horizontal field of view. A
/// box of zero size is treated as a 1 mm sphere. Throws on an empty box, a
/// zero or non-finite direction, `up` parallel to it, or bad fov/size.
Camera frameCamera(const Bounds3& box, const Vec3d& viewDirection, const Vec3d& up = {0.0, 0.0, 1.0},
                   double verticalFovDegrees = 40, int width = 640, int height = 480, double margin = 1.1);

/// A magnet or collider to draw. Shapes are centred on the pose origin: a box
/// of half-sizes (m) along the body axes, a sphere, or a cylinder of radius R
/// and half-length L along the body z axis (the conventions of
/// CuboidMagnet, SphereMagnet and CylinderMagnet).
struct Primitive {
  enum class Shape { Box, Sphere, Cylinder };
  enum class Style { Solid, Wireframe };

  Shape shape = Shape::Box;
  Pose pose;
  Vec3d halfSize{0.5, 0.5, 0.5};  ///< Box, m
  double radius = 0.5;            ///< Sphere, Cylinder, m
  double halfLength = 0.5;        ///< Cylinder, m
  Rgb colour{200, 60, 50};
  Style style = Style::Solid;

  static Primitive box(const Pose& pose, const Vec3d& halfSize, Rgb colour, Style style = Style::Solid);
  static Primitive sphere(const Pose& pose, double radius, Rgb colour, Style style = Style::Solid);
  static Primitive cylinder(const Pose& pose, double radius, double halfLength, Rgb colour, Style style = Style::Solid);
};

/// The particles to draw (arrays owned by the caller).
struct ParticleView {
  const Vec3d* positions = nullptr;  ///< m
  std::size_t count = 0;             ///< < 2^32
  const Rgb* colours = nullptr;      ///< per particle, or null: RenderSettings::particleColour
  double radius = 0.0;               ///< m, used when radii is null
  const double* radii = nullptr;     ///< per particle (m), or null
};

/// Bounds of the particle spheres (radius included); empty when count == 0.
Bounds3 boundsOf(const ParticleView& particles);
/// Bounds of a mesh's vertices; empty when it has none.
Bounds3 boundsOf(const TriangleMesh& mesh);

/// A triangle mesh to draw (owned by the caller), in one colour.
struct MeshView {
  const TriangleMesh* mesh = nullptr;
  Rgb colour{70, 130, 200};
};

/// A polyline to draw over the shaded image, like a wireframe edge: full
/// colour where in front, faint where hidden. `colours`: one per point (a
/// segment takes its first point's) or empty for `colour`.
struct Polyline {
  std::vector<Vec3d> points;  ///< m
  std::vector<Rgb> colours;
  Rgb colour{240, 200, 60};
  bool closed = false;  ///< also join the last point to the first
};

/// Everything renderScene draws.
struct SceneContent {
  ParticleView particles;
  std::vector<MeshView> meshes;
  std::vector<Primitive> primitives;
  std::vector<Polyline> polylines;
};

struct RenderSettings {
  Rgb backgroundTop{58, 63, 74};
  Rgb backgroundBottom{150, 156, 168};
  Rgb particleColour{70, 130, 200};

  /// Ground plane {x : x.groundNormal = groundHeight}, drawn where the camera
  /// is on its normal side, with grid lines every gridSpacing (m, 0: none)
  /// that fade out where they would be denser than a few pixels, and the
  /// plane fading into the background between a quarter of and the whole
  /// groundFadeDistance (m, 0: 30 times the camera's distance to its look-at
  /// point) from the camera.
  bool ground = true;
  Vec3d groundNormal{0.0, 0.0, 1.0};
  double groundHeight = 0.0;  ///< m
  double gridSpacing = 0.01;  ///< m
  double groundFadeDistance = 0.0;
  Rgb groundColour{196, 196, 190};
  Rgb gridColour{120, 120, 116};

  double ambient = 0.3;          ///< in [0, 1]: light on surfaces facing away
  double specular = 0.25;        ///< in [0, 1]: highlight strength
  double hiddenLineAlpha = 0.3;  ///< in [0, 1]: opacity of hidden wireframe edges
};

/// Where the time went (s) and what was drawn.
struct RenderStats {
  std::size_t particlesDrawn = 0;  ///< particles with at least one pixel on screen
  std::size_t fragments = 0;       ///< particle and triangle pixels tested
  std::size_t trianglesDrawn = 0;  ///< triangles with at least one pixel on screen
  double rasterSeconds = 0, resolveSeconds = 0, wireSeconds = 0;
};

/// Renders the scene. Throws lodestone::InvalidArgument on a bad camera,
/// settings, primitive (non-positive size, non-finite pose), particle
/// radius (not finite and > 0) or null arrays; particles with non-finite
/// positions, behind the camera or off screen are skipped.
RgbImage renderScene(const Camera& camera, const ParticleView& particles, const std::vector<Primitive>& primitives,
                     const RenderSettings& settings = {}, RenderStats* stats = nullptr);
/// The same with meshes and polylines; also throws on a mesh that is null,
/// has a vertex index out of range, non-finite vertices or a normal count
/// other than zero or its vertex count, and on a polyline whose colour
/// count is neither zero nor its point count. At most 2^32 - 2 particles
/// and triangles together.
RgbImage renderScene(const Camera& camera, const SceneContent& content, const RenderSettings& settings = {},
                     RenderStats* stats = nullptr);

}  // namespace lodestone::output
