#include "lodestone/core/stage/field_lines.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>

#include <tbb/parallel_for.h>

#include "lodestone/core/base/error.h"
#include "lodestone/core/sources/cuboid_magnet.h"
#include "lodestone/core/sources/cylinder_magnet.h"
#include "lodestone/core/sources/sphere_magnet.h"

namespace lodestone {
inline namespace stage {

namespace {

double diagonal(const FieldLineSettings& s) { return norm(s.domainMax - s.domainMin); }

bool inside(const FieldLineSettings& s, const Vec3d& x) {
  return x.x >= s.domainMin.x && x.y >= s.domainMin.y && x.z >= s.domainMin.z && x.x <= s.domainMax.x &&
         x.y <= s.domainMax.y && x.z <= s.domainMax.z;
}

constexpr double kKinkSteps = 1000;  // in minStep: steps this short cross a kink

bool usable(const Vec3d& b) { return isFinite(b) && norm2(b) > 0.0; }

struct HalfLine {
  std::vector<Vec3d> points;
  std::vector<double> magnitude;
  FieldLineEnd end = FieldLineEnd::LeftDomain;
};

// Dormand-Prince 5(4) tableau.
constexpr double kA[7][6] = {{0, 0, 0, 0, 0, 0},
                             {1.0 / 5, 0, 0, 0, 0, 0},
                             {3.0 / 40, 9.0 / 40, 0, 0, 0, 0},
                             {44.0 / 45, -56.0 / 15, 32.0 / 9, 0, 0, 0},
                             {19372.0 / 6561, -25360.0 / 2187, 64448.0 / 6561, -212.0 / 729, 0, 0},
                             {9017.0 / 3168, -355.0 / 33, 46732.0 / 5247, 49.0 / 176, -5103.0 / 18656, 0},
                             {35.0 / 384, 0, 500.0 / 1113, 125.0 / 192, -2187.0 / 6784, 11.0 / 84}};
// Fifth-order weights minus the embedded fourth-order ones.
constexpr double kE[7] = {35.0 / 384 - 5179.0 / 57600,  0.0, 500.0 / 1113 - 7571.0 / 16695, 125.0 / 192 - 393.0 / 640,
                          -2187.0 / 6784 + 92097.0 / 339200, 11.0 / 84 - 187.0 / 2100, -1.0 / 40};

/// The fifth-order end point of one step of length h from x (k0: the unit
/// direction at x); non-finite where B vanishes on the way.
Vec3d rkStep(const InductionSampler& B, const Vec3d& x, const Vec3d& k0, double h, double sign) {
  Vec3d k[7];
  k[0] = k0;
  for (int st = 1; st < 6; ++st) {
    Vec3d y = x;
    for (int r = 0; r < st; ++r) y += (h * kA[st][r]) * k[r];
    const Vec3d b = B(y);
    if (!usable(b)) {
      const double nan = std::numeric_limits<double>::quiet_NaN();
      return {nan, nan, nan};
    }
    k[st] = (sign / norm(b)) * b;
  }
  Vec3d y = x;
  for (int r = 0; r < 6; ++r) y += (h * kA[6][r]) * k[r];
  return y;
}

/// The step length in [0, h] at which the end point of rkStep from x
/// leaves `before` (true at 0, false at h), bisected 40 times: `lo` (last
/// end point `before`) and `hi`; returns the end point at `lo` (x when none).
template <typename Before>
Vec3d bisectStep(const InductionSampler& B, const Vec3d& x, const Vec3d& k0, double h, double sign,
                 const Before& before, double& lo, double& hi) {
  lo = 0, hi = h;
  Vec3d at = x;
  for (int it = 0; it < 40; ++it) {
    const double hm = 0.5 * (lo + hi);
    const Vec3d y = rkStep(B, x, k0, hm, sign);
    if (!isFinite(y)) break;
    if (before(y)) {
      lo = hm;
      at = y;
    } else {
      hi = hm;
    }
  }
  return at;
}

/// Traces from the seed along sign * B. `closable`: watch for the line
/// returning to the seed (the forward half only).
HalfLine traceHalf(const InductionSampler& B, const Vec3d& seed, double sign, bool closable,
                   const FieldLineSettings& s) {
  HalfLine out;
  Vec3d b0 = B(seed);
  out.points.push_back(seed);
  out.magnitude.push_back(norm(b0));
  if (!usable(b0)) {
    out.end = FieldLineEnd::NullField;
    return out;
  }
  const Vec3d t0 = (sign / norm(b0)) * b0;
  Vec3d x = seed, k[7];
  k[0] = t0;
  double h = std::max(0.1 * s.maxStep, s.minStep);
  double length = 0, dPrev = 0;
  for (;;) {
    if (int(out.points.size()) > s.maxVertices) {
      out.end = FieldLineEnd::VertexCap;
      return out;
    }
    if (length >= s.maxLength) {
      out.end = FieldLineEnd::LengthCap;
      return out;
    }
    // One attempted step of length h.
    bool bad = false;
    Vec3d bNew;
    for (int st = 1; st < 7 && !bad; ++st) {
      Vec3d y = x;
      for (int r = 0; r < st; ++r) y += (h * kA[st][r]) * k[r];
      const Vec3d b = B(y);
      if (!usable(b)) {
        bad = true;
        break;
      }
      k[st] = (sign / norm(b)) * b;
      if (st == 6) bNew = b;
    }
    double err = 0, turn = 0;
    Vec3d xNew = x;
    if (!bad) {
      Vec3d e;
      for (int r = 0; r < 7; ++r) e += (h * kE[r]) * k[r];
      err = norm(e);
      for (int r = 0; r < 6; ++r) xNew += (h * kA[6][r]) * k[r];
      turn = std::acos(std::clamp(dot(k[0], k[6]), -1.0, 1.0));
    }
    // The turn limit yields to very short steps: B's direction has a kink
    // where a line crosses a magnet's face (B's tangential part jumps with M).
    const bool turnLimited = turn > s.maxTurn && h > kKinkSteps * s.minStep;
    if (bad || err > s.tolerance || turnLimited) {
      double factor = 0.5;
      if (!bad) {
        if (err > s.tolerance) factor = std::min(factor * 1.8, 0.9 * std::pow(s.tolerance / err, 0.2));
        if (turnLimited) factor = std::min(factor * 1.8, 0.9 * s.maxTurn / turn);
        factor = std::clamp(factor, 0.1, 0.9);
      }
      h *= factor;
      if (h < s.minStep) {
        out.end = bad ? FieldLineEnd::NullField : FieldLineEnd::Stalled;
        return out;
      }
      continue;
    }
    // Accepted.
    if (!inside(s, xNew)) {
      // The last vertex on the box and on the curve: bisect the step length
      // for the Runge-Kutta end point on the box.
      double lo = 0, hi = h;
      Vec3d xe = bisectStep(B, x, k[0], h, sign, [&](const Vec3d& y) { return inside(s, y); }, lo, hi);
      // Onto the face it reached (moves it by at most h 2^-40).
      const Vec3d beyond = rkStep(B, x, k[0], hi, sign);
      if (isFinite(beyond))
        for (int c = 0; c < 3; ++c)
          if (beyond[c] > s.domainMax[c] || beyond[c] < s.domainMin[c])
            xe[c] = std::clamp(beyond[c], s.domainMin[c], s.domainMax[c]);
      out.points.push_back(xe);
      out.magnitude.push_back(norm(B(xe)));
      out.end = FieldLineEnd::LeftDomain;
      return out;
    }
    if (closable) {
      const double d = dot(xNew - seed, t0);
      if (dPrev < 0 && d >= 0) {
        const Vec3d guess = x + (dPrev / (dPrev - d)) * (xNew - x);
        if (norm(guess - seed) <= s.closeDistance) {
          // The crossing on the curve: bisect the step length for the
          // Runge-Kutta end point on the seed's plane.
          double lo = 0, hi = h;
          const Vec3d c = bisectStep(
              B, x, k[0], h, sign, [&](const Vec3d& y) { return dot(y - seed, t0) < 0; }, lo, hi);
          // The loop misses the seed by the error accumulated along it:
          // spread that miss over the line in proportion to arc length (a
          // turn of |miss| / length), so that it ends on its seed.
          const Vec3d miss = seed - c;
          const double total = length + norm(c - x);
          double arc = 0;
          for (std::size_t i = 1; i < out.points.size(); ++i) {
            arc += norm(out.points[i] - out.points[i - 1]);
            out.points[i] += (arc / total) * miss;
          }
          // A vertex just before the seed would make a chord much shorter
          // than its neighbour: drop it.
          if (out.points.size() > 2 &&
              norm(out.points.back() - seed) < 0.25 * norm(out.points.back() - out.points[out.points.size() - 2])) {
            out.points.pop_back();
            out.magnitude.pop_back();
          }
          out.points.push_back(seed);
          out.magnitude.push_back(out.magnitude.front());
          out.end = FieldLineEnd::Closed;
          return out;
        }
      }
      dPrev = d;
    }
    length += norm(xNew - x);
    x = xNew;
    out.points.push_back(x);
    out.magnitude.push_back(norm(bNew));
    k[0] = k[6];
    double grow = 5.0;
    if (err > 0) grow = std::min(grow, 0.9 * std::pow(s.tolerance / err, 0.2));
    if (turn > 0) grow = std::min(grow, std::max(0.9 * s.maxTurn / turn, 0.2));
    h = std::min(s.maxStep, h * std::max(grow, 0.2));
  }
}

double pointSegmentDistance(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
  const Vec3d ab = b - a;
  const double l2 = norm2(ab);
  const double t = l2 > 0 ? std::clamp(dot(p - a, ab) / l2, 0.0, 1.0) : 0.0;
  return norm(p - (a + t * ab));
}

double distanceToLine(const Vec3d& p, const FieldLine& line) {
  double best = std::numeric_limits<double>::infinity();
  if (line.points.size() == 1) return norm(p - line.points[0]);
  for (std::size_t i = 0; i + 1 < line.points.size(); ++i)
    best = std::min(best, pointSegmentDistance(p, line.points[i], line.points[i + 1]));
  return best;
}

}  // namespace

void FieldLineSettings::validate() const {
  require(isFinite(domainMin) && isFinite(domainMax), "field lines: the domain box must be finite");
  require(domainMin.x < domainMax.x && domainMin.y < domainMax.y && domainMin.z < domainMax.z,
          "field lines: the domain box must be non-empty, got min (", domainMin.x, ", ", domainMin.y, ", ",
          domainMin.z, ") max (", domainMax.x, ", ", domainMax.y, ", ", domainMax.z, ") m");
  require(std::isfinite(tolerance) && tolerance >= 0, "field lines: tolerance must be >= 0 m, got ", tolerance);
  require(std::isfinite(maxStep) && maxStep >= 0, "field lines: maxStep must be >= 0 m, got ", maxStep);
  require(std::isfinite(minStep) && minStep >= 0, "field lines: minStep must be >= 0 m, got ", minStep);
  require(std::isfinite(maxTurn) && maxTurn > 0 && maxTurn < 1.6, "field lines: maxTurn must be in (0, 1.6) rad, got ",
          maxTurn);
  require(std::isfinite(maxLength) && maxLength >= 0, "field lines: maxLength must be >= 0 m, got ", maxLength);
  require(maxVertices >= 2, "field lines: maxVertices must be >= 2, got ", maxVertices);
  require(std::isfinite(closeDistance) && closeDistance >= 0, "field lines: closeDistance must be >= 0 m, got ",
          closeDistance);
  require(std::isfinite(separation) && separation >= 0, "field lines: separation must be >= 0 m, got ", separation);
}

FieldLineSettings FieldLineSettings::resolved() const {
  validate();
  FieldLineSettings s = *this;
  const double d = diagonal(s);
  if (s.tolerance == 0) s.tolerance = 1e-7 * d;
  if (s.maxStep == 0) s.maxStep = d / 100;
  if (s.minStep == 0) s.minStep = 1e-9 * d;
  if (s.maxLength == 0) s.maxLength = 10 * d;
  if (s.closeDistance == 0) s.closeDistance = 1e-3 * d;
  require(s.minStep < s.maxStep, "field lines: minStep (", s.minStep, " m) must be below maxStep (", s.maxStep, " m)");
  return s;
}

const char* fieldLineEndName(FieldLineEnd end) {
  switch (end) {
    case FieldLineEnd::Closed: return "closed";
    case FieldLineEnd::LeftDomain: return "left the domain";
    case FieldLineEnd::LengthCap: return "length cap";
    case FieldLineEnd::VertexCap: return "vertex cap";
    case FieldLineEnd::NullField: return "zero field";
    case FieldLineEnd::Stalled: return "stalled";
  }
  return "?";
}

double FieldLine::length() const {
  double l = 0;
  for (std::size_t i = 0; i + 1 < points.size(); ++i) l += norm(points[i + 1] - points[i]);
  return l;
}

FieldLine traceFieldLine(const InductionSampler& B, const Vec3d& seed, const FieldLineSettings& settings) {
  const FieldLineSettings s = settings.resolved();
  require(isFinite(seed) && inside(s, seed), "field lines: seed (", seed.x, ", ", seed.y, ", ", seed.z,
          ") m lies outside the domain box");
  FieldLine line;
  line.seed = seed;
  HalfLine forward = traceHalf(B, seed, 1.0, true, s);
  line.endEnd = forward.end;
  if (forward.end == FieldLineEnd::Closed) {
    line.closed = true;
    line.startEnd = FieldLineEnd::Closed;
    line.points = std::move(forward.points);
    line.magnitude = std::move(forward.magnitude);
    return line;
  }
  HalfLine backward = traceHalf(B, seed, -1.0, false, s);
  line.startEnd = backward.end;
  line.points.assign(backward.points.rbegin(), backward.points.rend());
  line.magnitude.assign(backward.magnitude.rbegin(), backward.magnitude.rend());
  line.points.insert(line.points.end(), forward.points.begin() + 1, forward.points.end());
  line.magnitude.insert(line.magnitude.end(), forward.magnitude.begin() + 1, forward.magnitude.end());
  return line;
}

std::vector<FieldLine> traceFieldLines(const InductionSampler& B, const std::vector<Vec3d>& seeds,
                                       const FieldLineSettings& settings) {
  const FieldLineSettings s = settings.resolved();
  std::vector<Vec3d> valid;
  for (const Vec3d& p : seeds)
    if (isFinite(p) && inside(s, p)) valid.push_back(p);
  std::vector<FieldLine> traced(valid.size());
  tbb::parallel_for(std::size_t(0), valid.size(), [&](std::size_t i) { traced[i] = traceFieldLine(B, valid[i], s); });
  std::vector<FieldLine> kept;
  for (FieldLine& line : traced) {
    bool near = false;
    if (s.separation > 0)
      for (const FieldLine& k : kept)
        if (distanceToLine(line.seed, k) < s.separation) {
          near = true;
          break;
        }
    if (!near) kept.push_back(std::move(line));
  }
  return kept;
}

std::vector<Vec3d> farthestPointSubset(const std::vector<Vec3d>& candidates, std::size_t count) {
  if (candidates.size() <= count) return candidates;
  std::vector<Vec3d> out;
  if (count == 0) return out;
  std::vector<double> dist(candidates.size(), std::numeric_limits<double>::infinity());
  std::size_t next = 0;
  for (std::size_t n = 0; n < count; ++n) {
    out.push_back(candidates[next]);
    std::size_t far = 0;
    double farD = -1;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      dist[i] = std::min(dist[i], norm2(candidates[i] - candidates[next]));
      if (dist[i] > farD) {
        farD = dist[i];
        far = i;
      }
    }
    next = far;
  }
  return out;
}

std::vector<Vec3d> magnetSurfaceSeeds(const MagnetSource& magnet, std::size_t count, double offset) {
  require(std::isfinite(offset) && offset >= 0, "field-line seeds: offset must be >= 0 m, got ", offset);
  Vec3d half;
  if (const auto* sp = dynamic_cast<const SphereMagnet*>(&magnet)) {
    half = {sp->radius(), sp->radius(), sp->radius()};
  } else if (const auto* cy = dynamic_cast<const CylinderMagnet*>(&magnet)) {
    half = {cy->radius(), cy->radius(), cy->halfLength()};
  } else if (const auto* cu = dynamic_cast<const CuboidMagnet*>(&magnet)) {
    half = cu->halfSize();
  } else {
    throw InvalidArgument("field-line seeds: only sphere, cuboid and cylinder magnets can be seeded");
  }
  // Interior points of a body-frame lattice moved onto the nearest surface
  // point, then spread evenly.
  constexpr int kN = 24;
  std::vector<Vec3d> candidates;
  for (int k = 0; k < kN; ++k)
    for (int j = 0; j < kN; ++j)
      for (int i = 0; i < kN; ++i) {
        const Vec3d xb{half.x * (2 * (i + 0.5) / kN - 1), half.y * (2 * (j + 0.5) / kN - 1),
                       half.z * (2 * (k + 0.5) / kN - 1)};
        if (!magnet.containsBody(xb)) continue;
        Vec3d n;
        const double depth = magnet.surfaceDepth(xb, n);
        candidates.push_back(magnet.pose().toWorld(xb + (depth + offset) * n));
      }
  return farthestPointSubset(candidates, count);
}

std::vector<Vec3d> pointCloudBoundarySeeds(const Vec3d* points, std::size_t n, double cell, std::size_t count) {
  require(std::isfinite(cell) && cell > 0, "field-line seeds: cell must be a positive length in m, got ", cell);
  struct Acc {
    Vec3d sum;
    std::size_t n = 0;
    std::size_t first = 0;  // order of appearance, for a deterministic result
  };
  const auto key = [](std::int64_t i, std::int64_t j, std::int64_t k) {
    return std::uint64_t((i & 0x1FFFFF) | ((j & 0x1FFFFF) << 21) | ((k & 0x1FFFFF) << 42));
  };
  std::unordered_map<std::uint64_t, Acc> cells;
  std::vector<std::array<std::int64_t, 3>> order;
  for (std::size_t p = 0; p < n; ++p) {
    if (!isFinite(points[p])) continue;
    const std::int64_t i = std::int64_t(std::floor(points[p].x / cell)), j = std::int64_t(std::floor(points[p].y / cell)),
                       k = std::int64_t(std::floor(points[p].z / cell));
    Acc& a = cells[key(i, j, k)];
    if (a.n == 0) {
      a.first = order.size();
      order.push_back({i, j, k});
    }
    a.sum += points[p];
    ++a.n;
  }
  std::vector<Vec3d> candidates;
  const int offsets[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const auto& c : order) {
    bool boundary = false;
    for (const auto& o : offsets)
      if (!cells.count(key(c[0] + o[0], c[1] + o[1], c[2] + o[2]))) boundary = true;
    if (!boundary) continue;
    const Acc& a = cells.at(key(c[0], c[1], c[2]));
    candidates.push_back(a.sum / double(a.n));
  }
  return farthestPointSubset(candidates, count);
}

std::vector<Vec3d> sceneFieldLineSeeds(const std::vector<const MagnetSource*>& magnets, const Vec3d* material,
                                       std::size_t materialCount, double cell, std::size_t perMagnet,
                                       std::size_t materialSeeds) {
  require(std::isfinite(cell) && cell > 0, "field-line seeds: cell must be a positive length in m, got ", cell);
  std::vector<Vec3d> seeds;
  for (const MagnetSource* m : magnets) {
    require(m != nullptr, "field-line seeds: null magnet");
    const std::vector<Vec3d> s = magnetSurfaceSeeds(*m, perMagnet, 0.25 * cell);
    seeds.insert(seeds.end(), s.begin(), s.end());
  }
  if (materialCount > 0 && materialSeeds > 0) {
    const std::vector<Vec3d> s = pointCloudBoundarySeeds(material, materialCount, cell, materialSeeds);
    seeds.insert(seeds.end(), s.begin(), s.end());
  }
  return seeds;
}

double segmentDistance(const Vec3d& p1, const Vec3d& q1, const Vec3d& p2, const Vec3d& q2) {
  // Closest points of two segments (Ericson, Real-Time Collision Detection, 5.1.9).
  const Vec3d d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = norm2(d1), e = norm2(d2), f = dot(d2, r);
  double s = 0, t = 0;
  if (a <= 0 && e <= 0) return norm(r);
  if (a <= 0) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = dot(d1, r);
    if (e <= 0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = dot(d1, d2), denom = a * e - b * b;
      s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return norm((p1 + s * d1) - (p2 + t * d2));
}

}  // namespace stage
}  // namespace lodestone
