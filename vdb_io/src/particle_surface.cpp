// Surfaces and render volumes from material points. See particle_surface.h.
#include "lodestone/vdb_io/particle_surface.h"

#include <algorithm>
#include <cmath>

#include <openvdb/tools/Composite.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetFilter.h>
#include <openvdb/tools/LevelSetMeasure.h>
#include <openvdb/tools/LevelSetRebuild.h>
#include <openvdb/tools/ParticlesToLevelSet.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/parallel_for.h>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/vdb_io/grid_conversion.h"

namespace lodestone {

SurfaceParticles surfaceParticles(const MpmParticles& p) {
  SurfaceParticles s;
  s.x = p.x;
  s.v = p.v;
  s.material = p.material;
  s.volume.resize(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) s.volume[i] = std::max(p.J[i], 0.0) * p.volume0[i];
  return s;
}

double particleSpacing(const SurfaceParticles& p) {
  double sum = 0;
  for (const double v : p.volume) sum += v;
  return p.size() ? std::cbrt(sum / double(p.size())) : 0.0;
}

const char* surfaceMethodName(SurfaceMethod method) {
  return method == SurfaceMethod::Splat ? "splat" : "density";
}

SurfaceMethod surfaceMethodFromName(const std::string& name) {
  if (name == "splat") return SurfaceMethod::Splat;
  if (name == "density") return SurfaceMethod::SmoothedDensity;
  throw InvalidArgument(concat("surface method '", name, "': expected splat or density"));
}

void SurfaceOptions::check(const std::string& who) const {
  require(std::isfinite(voxelSize) && voxelSize > 0, who, ": voxel size must be a positive length in m, got ",
          voxelSize);
  require(radiusScale >= 0.5 && radiusScale <= 4, who, ": radius scale must be in 0.5 .. 4, got ", radiusScale);
  require(kernelWidth >= 1 && kernelWidth <= 4, who, ": kernel width must be 1 .. 4 particle sizes, got ", kernelWidth);
  require(smoothing >= 0 && smoothing <= 4, who, ": smoothing must be 0 .. 4 voxels, got ", smoothing);
  require(closing >= 0 && closing <= 4, who, ": closing must be 0 .. 4 voxels, got ", closing);
  require(halfWidth >= 2 && halfWidth <= 8, who, ": narrow band half width must be 2 .. 8 voxels, got ", halfWidth);
}

namespace {

/// Quadratic B-spline, support |r| < 1.5.
double bspline2(double r) {
  r = std::abs(r);
  if (r < 0.5) return 0.75 - r * r;
  if (r < 1.5) return 0.5 * (1.5 - r) * (1.5 - r);
  return 0;
}

/// The particles ParticlesToLevelSet rasterizes: spheres of the particles'
/// volume, times `scale`.
struct SphereList {
  using PosType = openvdb::Vec3R;
  const SurfaceParticles* particles;
  const std::vector<std::size_t>* subset;
  double scale;
  std::size_t size() const { return subset ? subset->size() : particles->size(); }
  std::size_t at(std::size_t n) const { return subset ? (*subset)[n] : n; }
  void getPos(std::size_t n, openvdb::Vec3R& xyz) const {
    const Vec3d& x = particles->x[at(n)];
    xyz = openvdb::Vec3R(x.x, x.y, x.z);
  }
  void getPosRad(std::size_t n, openvdb::Vec3R& xyz, openvdb::Real& radius) const {
    getPos(n, xyz);
    radius = scale * std::cbrt(3.0 * particles->volume[at(n)] / (4.0 * kPi));
  }
};

void checkParticles(const SurfaceParticles& p) {
  require(p.v.size() == p.size() && p.volume.size() == p.size() && p.material.size() == p.size(),
          "surface particles: ", p.size(), " positions but ", p.v.size(), " velocities, ", p.volume.size(),
          " volumes and ", p.material.size(), " material indices");
}

}  // namespace

ParticleVolumeGrids particleVolumeGrids(const SurfaceParticles& p, double voxelSize, double kernelWidth,
                                        const std::vector<std::size_t>* subset) {
  initializeVdb();
  checkParticles(p);
  require(std::isfinite(voxelSize) && voxelSize > 0, "particle volume: voxel size must be positive, got ",
          voxelSize, " m");
  const std::size_t count = subset ? subset->size() : p.size();
  // Fixed chunks merged in order: the sums do not depend on the thread count.
  constexpr std::size_t kChunk = 8192;
  const std::size_t chunks = (count + kChunk - 1) / kChunk;
  std::vector<openvdb::FloatGrid::Ptr> fractions(chunks);
  std::vector<openvdb::Vec3fGrid::Ptr> momenta(chunks);
  const double inverseCell = 1.0 / (voxelSize * voxelSize * voxelSize);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
    auto fraction = openvdb::FloatGrid::create(0.0f);
    auto momentum = openvdb::Vec3fGrid::create(openvdb::Vec3f(0.0f));
    auto fa = fraction->getAccessor();
    auto ma = momentum->getAccessor();
    std::vector<double> w[3];
    for (std::size_t n = c * kChunk; n < std::min(count, (c + 1) * kChunk); ++n) {
      const std::size_t i = subset ? (*subset)[n] : n;
      const double volume = p.volume[i];
      if (!(volume > 0) || !isFinite(p.x[i])) continue;
      const double h = kernelWidth * std::cbrt(volume);
      int lo[3];
      double total = 1;
      for (int a = 0; a < 3; ++a) {
        const double centre = p.x[i][a] / voxelSize;
        lo[a] = int(std::ceil(centre - 1.5 * h / voxelSize));
        const int hi = int(std::floor(centre + 1.5 * h / voxelSize));
        w[a].clear();
        double sum = 0;
        for (int k = lo[a]; k <= hi; ++k) {
          w[a].push_back(bspline2((k - centre) * voxelSize / h));
          sum += w[a].back();
        }
        if (!(sum > 0)) {  // a kernel narrower than a voxel: all to the nearest voxel
          lo[a] = int(std::lround(centre));
          w[a].assign(1, 1.0);
          sum = 1;
        }
        total *= sum;
      }
      const double scale = volume * inverseCell / total;
      const openvdb::Vec3f v(float(p.v[i].x), float(p.v[i].y), float(p.v[i].z));
      for (std::size_t k = 0; k < w[2].size(); ++k)
        for (std::size_t j = 0; j < w[1].size(); ++j)
          for (std::size_t ii = 0; ii < w[0].size(); ++ii) {
            const float value = float(scale * w[0][ii] * w[1][j] * w[2][k]);
            if (value == 0.0f) continue;
            const openvdb::Coord ijk(lo[0] + int(ii), lo[1] + int(j), lo[2] + int(k));
            fa.setValue(ijk, fa.getValue(ijk) + value);
            ma.setValue(ijk, ma.getValue(ijk) + value * v);
          }
    }
    fractions[c] = fraction;
    momenta[c] = momentum;
  });
  ParticleVolumeGrids out;
  out.fraction = openvdb::FloatGrid::create(0.0f);
  out.momentum = openvdb::Vec3fGrid::create(openvdb::Vec3f(0.0f));
  for (std::size_t c = 0; c < chunks; ++c) {
    openvdb::tools::compSum(*out.fraction, *fractions[c]);
    openvdb::tools::compSum(*out.momentum, *momenta[c]);
  }
  const auto xf = openvdb::math::Transform::createLinearTransform(voxelSize);
  out.fraction->setTransform(xf);
  out.momentum->setTransform(xf);
  return out;
}

openvdb::FloatGrid::Ptr particleLevelSet(const SurfaceParticles& p, const SurfaceOptions& options,
                                         const std::string& name, const std::vector<std::size_t>* subset) {
  initializeVdb();
  checkParticles(p);
  options.check("surface '" + name + "'");
  if ((subset ? subset->size() : p.size()) == 0) return nullptr;
  const double dx = options.voxelSize;
  openvdb::FloatGrid::Ptr grid;
  if (options.method == SurfaceMethod::Splat) {
    grid = openvdb::createLevelSet<openvdb::FloatGrid>(dx, options.halfWidth);
    openvdb::tools::ParticlesToLevelSet<openvdb::FloatGrid> raster(*grid);
    raster.setRmin(1e-3);  // particles of a voxel or less are the common case here
    raster.rasterizeSpheres(SphereList{&p, subset, options.radiusScale});
    raster.finalize(true);
    openvdb::tools::LevelSetFilter<openvdb::FloatGrid> filter(*grid);
    if (options.closing > 0) filter.offset(float(-options.closing * dx));
    if (options.smoothing > 0) filter.gaussian(options.smoothing);
    if (options.closing > 0) filter.offset(float(options.closing * dx));
  } else {
    ParticleVolumeGrids volume = particleVolumeGrids(p, dx, options.kernelWidth, subset);
    openvdb::FloatGrid& fraction = *volume.fraction;
    // levelSetRebuild takes values below the iso value as inside.
    for (auto it = fraction.tree().beginValueOn(); it; ++it) it.setValue(-*it);
    grid = openvdb::tools::levelSetRebuild(fraction, -0.5f, float(options.halfWidth));
  }
  grid->setGridClass(openvdb::GRID_LEVEL_SET);
  grid->setName(name);
  grid->insertMeta("units", openvdb::StringMetadata("m"));
  grid->insertMeta("description",
                   openvdb::StringMetadata(concat(
                       "signed distance to the material's surface, negative inside (",
                       options.method == SurfaceMethod::Splat
                           ? concat("splat, radius scale ", options.radiusScale, ", closing ", options.closing,
                                    " voxels, smoothing ", options.smoothing, " voxels)")
                           : concat("density, kernel width ", options.kernelWidth, " particle sizes)"))));
  return grid;
}

TriangleMesh levelSetMesh(const openvdb::FloatGrid& levelSet, const ParticleVolumeGrids* volumes) {
  initializeVdb();
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(levelSet, points, triangles, quads, 0.0, 0.0);
  TriangleMesh mesh;
  mesh.vertices.reserve(points.size());
  for (const openvdb::Vec3s& q : points) mesh.vertices.push_back({double(q[0]), double(q[1]), double(q[2])});
  mesh.triangles.reserve(triangles.size() + 2 * quads.size());
  for (const openvdb::Vec3I& t : triangles) mesh.triangles.push_back({t[0], t[1], t[2]});
  for (const openvdb::Vec4I& q : quads) {
    mesh.triangles.push_back({q[0], q[1], q[2]});
    mesh.triangles.push_back({q[0], q[2], q[3]});
  }
  if (mesh.volume() < 0)  // outward, counter-clockwise faces
    for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
  // Normals: the level set's gradient (central differences over one voxel).
  const double h = 0.5 * levelSet.voxelSize()[0];
  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> phi(levelSet);
  mesh.normals.resize(mesh.vertices.size());
  tbb::parallel_for(std::size_t(0), mesh.vertices.size(), [&](std::size_t n) {
    const Vec3d& x = mesh.vertices[n];
    Vec3d g;
    for (int a = 0; a < 3; ++a) {
      openvdb::Vec3R plus(x.x, x.y, x.z), minus = plus;
      plus[a] += h;
      minus[a] -= h;
      g[a] = double(phi.wsSample(plus)) - double(phi.wsSample(minus));
    }
    const double length = std::sqrt(dot(g, g));
    mesh.normals[n] = length > 0 ? g / length : Vec3d{0, 0, 1};
  });
  if (volumes && volumes->fraction && volumes->momentum) {
    openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> fraction(*volumes->fraction);
    openvdb::tools::GridSampler<openvdb::Vec3fGrid, openvdb::tools::BoxSampler> momentum(*volumes->momentum);
    mesh.velocities.resize(mesh.vertices.size());
    tbb::parallel_for(std::size_t(0), mesh.vertices.size(), [&](std::size_t n) {
      const openvdb::Vec3R x(mesh.vertices[n].x, mesh.vertices[n].y, mesh.vertices[n].z);
      const double f = fraction.wsSample(x);
      const openvdb::Vec3f m = momentum.wsSample(x);
      mesh.velocities[n] = f > 1e-6 ? Vec3d{m[0] / f, m[1] / f, m[2] / f} : Vec3d{};
    });
  }
  return mesh;
}

double levelSetVolume(const openvdb::FloatGrid& levelSet) { return openvdb::tools::levelSetVolume(levelSet); }

SurfaceChange surfaceChange(const openvdb::FloatGrid& before, const openvdb::FloatGrid& after, const Vec3d& shift) {
  const double dx = before.voxelSize()[0];
  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(after);
  SurfaceChange out;
  double sum = 0;
  for (auto it = before.cbeginValueOn(); it; ++it) {
    if (!it.isVoxelValue() || std::abs(double(*it)) >= dx) continue;
    const openvdb::Vec3d x = before.transform().indexToWorld(it.getCoord());
    const double d = (double(sampler.wsSample(x + openvdb::Vec3d(shift.x, shift.y, shift.z))) - double(*it)) / dx;
    sum += d * d;
    out.max = std::max(out.max, std::abs(d));
    ++out.samples;
  }
  out.rms = out.samples ? std::sqrt(sum / double(out.samples)) : 0.0;
  return out;
}

}  // namespace lodestone
