#pragma once
// Magnetic induction lines (the paper's Fig. 11): curves everywhere tangent
// to B, traced from seed points in both directions by integrating
// dx/ds = B(x) / |B(x)| over arc length s with the Dormand-Prince 5(4)
// embedded Runge-Kutta pair. A step is accepted when the difference of the
// two solutions (the local position error) is at most `tolerance` and B's
// direction turns by at most `maxTurn` over it, so the polyline resolves
// the line's curvature (the chord of a step of length h on a curve of
// curvature k deviates from the tangent by about h k / 2). A line ends when
//   - it closes: it crosses the plane through its seed normal to B there,
//     going the seed's way, within `closeDistance` of the seed (B is
//     divergence-free: lines through a magnet loop back through it); the
//     seed is then repeated as the last vertex;
//   - it leaves the domain box (the last vertex is on the box);
//   - it reaches `maxLength` or `maxVertices` in one direction;
//   - B vanishes (|B| == 0 or not finite), or the step shrinks below
//     `minStep` (a singularity, e.g. a point dipole's centre).
// Lines of a smooth field cannot cross; numerically traced ones of distinct
// seeds can only coincide (one seed lying on another's line). traceFieldLines
// therefore keeps a seed only when it lies farther than `separation` from
// every line kept before it, in seed order: the lines are deterministic and
// distinct. The field is any callable giving B (T) at a point (InductionField,
// a closed form in tests).
#include <cstddef>
#include <functional>
#include <vector>

#include "lodestone/core/base/vec3.h"
#include "lodestone/core/sources/magnet_source.h"

namespace lodestone {
inline namespace stage {

/// B (T) at a world point (m).
using InductionSampler = std::function<Vec3d(const Vec3d&)>;

struct FieldLineSettings {
  Vec3d domainMin, domainMax;  ///< m; lines stop where they leave this box (must be non-empty)
  double tolerance = 0;        ///< m, local position error per step; 0: 1e-7 x the box diagonal
  double maxStep = 0;          ///< m; 0: 1/100 of the box diagonal
  double minStep = 0;          ///< m; 0: 1e-9 x the box diagonal
  double maxTurn = 0.03;       ///< rad, turn of B's direction over one step
  double maxLength = 0;        ///< m, per direction; 0: 10 x the box diagonal
  int maxVertices = 5000;      ///< per direction
  double closeDistance = 0;    ///< m; 0: 1e-3 x the box diagonal
  double separation = 0;       ///< m; traceFieldLines drops seeds this close to a kept line (0: keeps all)

  /// Throws InvalidArgument naming the first bad value.
  void validate() const;
  /// A copy with the zero (automatic) values replaced by their defaults.
  FieldLineSettings resolved() const;
};

enum class FieldLineEnd { Closed, LeftDomain, LengthCap, VertexCap, NullField, Stalled };
/// "closed", "left the domain", "length cap", "vertex cap", "zero field", "stalled".
const char* fieldLineEndName(FieldLineEnd end);

struct FieldLine {
  std::vector<Vec3d> points;      ///< m, in the direction of B
  std::vector<double> magnitude;  ///< |B| (T) at each point
  Vec3d seed;                     ///< m
  bool closed = false;            ///< the last point repeats the first
  FieldLineEnd startEnd = FieldLineEnd::Closed;  ///< why the backward trace ended
  FieldLineEnd endEnd = FieldLineEnd::Closed;    ///< why the forward trace ended
  double length() const;                         ///< m, sum of the segments
};

/// One line through `seed`: traced along B; when it does not close, also
/// against B, the two joined at the seed. Throws InvalidArgument on bad
/// settings or a seed outside the domain box.
FieldLine traceFieldLine(const InductionSampler& B, const Vec3d& seed, const FieldLineSettings& settings);

/// Lines through the seeds (traced in parallel), keeping a seed only when it
/// lies farther than settings.separation from every line kept before it.
/// Seeds outside the domain box are skipped. Deterministic.
std::vector<FieldLine> traceFieldLines(const InductionSampler& B, const std::vector<Vec3d>& seeds,
                                       const FieldLineSettings& settings);

/// `count` of the candidates spread evenly: farthest-point sampling from
/// the first candidate (each next point the candidate farthest from those
/// taken). All candidates when there are no more than `count`.
std::vector<Vec3d> farthestPointSubset(const std::vector<Vec3d>& candidates, std::size_t count);

/// `count` points spread evenly over the surface of a sphere, cuboid or
/// cylinder magnet, `offset` (m, >= 0) outside it along the outward normal
/// (world frame, m). Throws InvalidArgument for another magnet shape.
std::vector<Vec3d> magnetSurfaceSeeds(const MagnetSource& magnet, std::size_t count, double offset);

/// `count` points spread evenly over the boundary of a cloud of material
/// points: the mean position of the points of each boundary cell (an
/// occupied cell of size `cell` (m) with an empty face neighbour), then a
/// farthest-point subset.
std::vector<Vec3d> pointCloudBoundarySeeds(const Vec3d* points, std::size_t n, double cell, std::size_t count);

/// The seeds of a scene's field lines: `perMagnet` on each magnet's surface
/// (magnetSurfaceSeeds, `cell` / 4 outside it) then `material` on the
/// boundary of the material points (pointCloudBoundarySeeds with `cell`, m).
std::vector<Vec3d> sceneFieldLineSeeds(const std::vector<const MagnetSource*>& magnets, const Vec3d* material,
                                       std::size_t materialCount, double cell, std::size_t perMagnet,
                                       std::size_t materialSeeds);

/// Shortest distance (m) between segments [a0, a1] and [b0, b1].
double segmentDistance(const Vec3d& a0, const Vec3d& a1, const Vec3d& b0, const Vec3d& b1);

}  // namespace stage
}  // namespace lodestone
