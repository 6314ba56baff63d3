#include "lodestone/core/mpm/emitter.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/sources/magnet_source.h"

namespace lodestone {
inline namespace mpm {

namespace {

/// SplitMix64 (Steele, Lea and Flood 2014): a tiny, fully specified generator,
/// so jittered emissions are identical on every platform and library.
struct SplitMix64 {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1) with 53 random bits.
  double uniform() { return double(next() >> 11) * (1.0 / 9007199254740992.0); }
};

/// Number of lattice cells fitted to a length 2a with target spacing h.
int fittedCells(double twoA, double h) {
  const double n = std::round(twoA / h);
  return n < 1 ? 1 : int(n);
}

}  // namespace

void EmitterShape::worldBounds(Vec3d& lo, Vec3d& hi) const {
  Vec3d blo, bhi;  // body frame
  switch (kind) {
    case EmitterShapeKind::Box:
      blo = -1.0 * halfSize;
      bhi = halfSize;
      break;
    case EmitterShapeKind::Sphere:
      blo = Vec3d{-radius, -radius, -radius};
      bhi = Vec3d{radius, radius, radius};
      break;
    case EmitterShapeKind::Cylinder:
      blo = Vec3d{-radius, -radius, -halfLength};
      bhi = Vec3d{radius, radius, halfLength};
      break;
    case EmitterShapeKind::LevelSet:
      levelSet->interiorBounds(blo, bhi);
      break;
  }
  const double inf = std::numeric_limits<double>::infinity();
  lo = Vec3d{inf, inf, inf};
  hi = -1.0 * lo;
  for (int c = 0; c < 8; ++c) {
    const Vec3d x = pose.toWorld({c & 1 ? bhi.x : blo.x, c & 2 ? bhi.y : blo.y, c & 4 ? bhi.z : blo.z});
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], x[a]);
      hi[a] = std::max(hi[a], x[a]);
    }
  }
}

EmitterShape EmitterShape::box(const Pose& pose, const Vec3d& halfSize) {
  EmitterShape s;
  s.kind = EmitterShapeKind::Box;
  s.pose = pose;
  s.halfSize = halfSize;
  s.validate();
  return s;
}

EmitterShape EmitterShape::sphere(const Pose& pose, double radius) {
  EmitterShape s;
  s.kind = EmitterShapeKind::Sphere;
  s.pose = pose;
  s.radius = radius;
  s.validate();
  return s;
}

EmitterShape EmitterShape::cylinder(const Pose& pose, double radius, double halfLength) {
  EmitterShape s;
  s.kind = EmitterShapeKind::Cylinder;
  s.pose = pose;
  s.radius = radius;
  s.halfLength = halfLength;
  s.validate();
  return s;
}

EmitterShape EmitterShape::levelSetShape(const Pose& pose, std::shared_ptr<const SampledSdf> sdf) {
  EmitterShape s;
  s.kind = EmitterShapeKind::LevelSet;
  s.pose = pose;
  s.levelSet = std::move(sdf);
  s.validate();
  return s;
}

double EmitterShape::volume() const {
  switch (kind) {
    case EmitterShapeKind::Box:
      return 8 * halfSize.x * halfSize.y * halfSize.z;
    case EmitterShapeKind::Sphere:
      return 4.0 / 3.0 * kPi * radius * radius * radius;
    case EmitterShapeKind::Cylinder:
      return 2 * kPi * radius * radius * halfLength;
    case EmitterShapeKind::LevelSet:
      return levelSet->volume();
  }
  return 0;
}

bool EmitterShape::containsBody(const Vec3d& xb) const {
  switch (kind) {
    case EmitterShapeKind::Box:
      return std::fabs(xb.x) <= halfSize.x && std::fabs(xb.y) <= halfSize.y && std::fabs(xb.z) <= halfSize.z;
    case EmitterShapeKind::Sphere:
      return norm2(xb) <= radius * radius;
    case EmitterShapeKind::Cylinder:
      return xb.x * xb.x + xb.y * xb.y <= radius * radius && std::fabs(xb.z) <= halfLength;
    case EmitterShapeKind::LevelSet:
      return levelSet->signedDistance(xb) <= 0;
  }
  return false;
}

void EmitterShape::validate() const {
  validatePose(pose, "emitter shape");
  switch (kind) {
    case EmitterShapeKind::Box:
      require(isFinite(halfSize) && halfSize.x > 0 && halfSize.y > 0 && halfSize.z > 0,
              "emitter box: half-sizes must be positive finite lengths in m, got (", halfSize.x, ", ", halfSize.y, ", ",
              halfSize.z, ")");
      return;
    case EmitterShapeKind::Sphere:
      require(std::isfinite(radius) && radius > 0, "emitter sphere: radius must be a positive finite length in m, got ",
              radius);
      return;
    case EmitterShapeKind::Cylinder:
      require(std::isfinite(radius) && radius > 0,
              "emitter cylinder: radius must be a positive finite length in m, got ", radius);
      require(std::isfinite(halfLength) && halfLength > 0,
              "emitter cylinder: half-length must be a positive finite length in m, got ", halfLength);
      return;
    case EmitterShapeKind::LevelSet:
      require(levelSet != nullptr, "emitter level set: no signed-distance grid");
      return;
  }
  throw InvalidArgument(concat("emitter shape: unknown kind ", int(kind)));
}

void EmitterSettings::validate() const {
  require(std::isfinite(cellSize) && cellSize > 0, "emitter: cell size dx must be a positive finite length in m, got ",
          cellSize);
  require(particlesPerCell >= 1 && particlesPerCell <= 1000, "emitter: particles per cell must be in 1..1000, got ",
          particlesPerCell);
  require(std::isfinite(jitter) && jitter >= 0 && jitter <= 1,
          "emitter: jitter must be in [0, 1] (fraction of the lattice spacing), got ", jitter);
  require(isFinite(velocity), "emitter: velocity must be finite (m/s), got (", velocity.x, ", ", velocity.y, ", ",
          velocity.z, ")");
  require(isFinite(angularVelocity), "emitter: angular velocity must be finite (rad/s), got (", angularVelocity.x, ", ",
          angularVelocity.y, ", ", angularVelocity.z, ")");
}

EmitterLattice emitterLattice(const EmitterShape& shape, const EmitterSettings& settings) {
  settings.validate();
  shape.validate();
  const double h = settings.cellSize / std::cbrt(double(settings.particlesPerCell));
  // Lattice: cell counts and spacings per axis, and the first cell centre.
  int n[3] = {1, 1, 1};
  double hs[3] = {h, h, h}, first[3] = {0, 0, 0};
  switch (shape.kind) {
    case EmitterShapeKind::Box:
      for (int a = 0; a < 3; ++a) {
        n[a] = fittedCells(2 * shape.halfSize[a], h);
        hs[a] = 2 * shape.halfSize[a] / n[a];
        first[a] = -shape.halfSize[a] + 0.5 * hs[a];
      }
      break;
    case EmitterShapeKind::Sphere:
    case EmitterShapeKind::Cylinder: {
      const int half = int(std::ceil(shape.radius / h));
      for (int a = 0; a < 2; ++a) {
        n[a] = 2 * half;
        hs[a] = h;
        first[a] = -half * h + 0.5 * h;
      }
      if (shape.kind == EmitterShapeKind::Sphere) {
        n[2] = 2 * half;
        hs[2] = h;
        first[2] = -half * h + 0.5 * h;
      } else {
        n[2] = fittedCells(2 * shape.halfLength, h);
        hs[2] = 2 * shape.halfLength / n[2];
        first[2] = -shape.halfLength + 0.5 * hs[2];
      }
      break;
    }
    case EmitterShapeKind::LevelSet: {
      Vec3d lo, hi;
      shape.levelSet->interiorBounds(lo, hi);
      for (int a = 0; a < 3; ++a) {
        n[a] = std::max(1, int(std::ceil((hi[a] - lo[a]) / h)));
        first[a] = lo[a] + 0.5 * h;
      }
      break;
    }
  }
  require(double(n[0]) * n[1] * n[2] <= 2e9, "emitter: ", n[0], " x ", n[1], " x ", n[2],
          " lattice cells is too many; use a larger cell size or fewer particles per cell");

  EmitterLattice lattice;
  lattice.spacing = {hs[0], hs[1], hs[2]};
  lattice.cells = {n[0], n[1], n[2]};
  lattice.pointVolume = hs[0] * hs[1] * hs[2];
  SplitMix64 rng{settings.seed};
  // Lattice cells are visited in blocks of c^3 (c = round(ppc^(1/3)), about
  // one grid cell), so the points of a cell are contiguous in memory and the
  // particle-to-grid transfer, which visits them cell by cell, reads them in
  // order.
  const int c = std::max(1, int(std::lround(std::cbrt(double(settings.particlesPerCell)))));
  for (int kb = 0; kb < n[2]; kb += c)
    for (int jb = 0; jb < n[1]; jb += c)
      for (int ib = 0; ib < n[0]; ib += c)
        for (int k = kb; k < std::min(kb + c, n[2]); ++k)
          for (int j = jb; j < std::min(jb + c, n[1]); ++j)
            for (int i = ib; i < std::min(ib + c, n[0]); ++i) {
              Vec3d xb{first[0] + i * hs[0], first[1] + j * hs[1], first[2] + k * hs[2]};
              if (!shape.containsBody(xb)) continue;
              if (settings.jitter > 0) {
                const double ox = rng.uniform() - 0.5, oy = rng.uniform() - 0.5, oz = rng.uniform() - 0.5;
                xb += settings.jitter * Vec3d{ox * hs[0], oy * hs[1], oz * hs[2]};
              }
              lattice.points.push_back(xb);
            }
  return lattice;
}

EmittedPoint emittedPoint(const MpmMaterial& material, double volume) {
  EmittedPoint e;
  e.volume = volume;
  e.mass = material.density * volume;
  e.count = material.isMagnetic() ? material.magnetic.numberDensity * volume : 0.0;
  require(e.mass > 0 && std::isfinite(e.mass), "emitter: particle mass rho V_p = ", e.mass,
          " kg is not positive and finite");
  return e;
}

EmitReport emitParticles(MpmParticles& particles, const EmitterShape& shape, const MpmMaterial& material,
                         std::uint32_t materialIndex, const EmitterSettings& settings,
                         const std::function<bool(const Vec3d&)>& keep) {
  material.validate();
  particles.checkSizes();
  const EmitterLattice lattice = emitterLattice(shape, settings);
  const EmittedPoint point = emittedPoint(material, lattice.pointVolume);

  EmitReport rep;
  rep.spacing = (lattice.spacing.x + lattice.spacing.y + lattice.spacing.z) / 3;
  const Vec3d& w = settings.angularVelocity;
  for (const Vec3d& xb : lattice.points) {
    const Vec3d x = shape.pose.toWorld(xb);
    rep.volume += point.volume;
    rep.mass += point.mass;
    rep.count += point.count;
    ++rep.particles;
    if (keep && !keep(x)) {
      ++particles.nextId;  // its id, taken where it is kept
      continue;
    }
    const Vec3d v = settings.velocity + cross(w, x - shape.pose.position);
    const std::size_t q = particles.add(x, v, point.mass, point.volume, point.count, materialIndex);
    // The affine matrix is the velocity gradient of the spin, [w]x, so the
    // first P2G carries the rigid rotation exactly (APIC).
    particles.C[q] = Mat3d::cross(w);
  }
  return rep;
}

}  // namespace mpm
}  // namespace lodestone
