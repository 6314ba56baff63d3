// Surfaces, meshes and render volumes from particles (particle_surface.h,
// render_frame.h, mesh_files.h): a ball of particles against the sphere it
// fills, a resting pool against a plane, the frame-to-frame change of both
// methods, the volume fraction against the particles' volume, and the mesh
// files read back.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <openvdb/openvdb.h>

#include "lodestone/core/base/constants.h"
#include "lodestone/plugin/output/mesh_files.h"
#include "lodestone/vdb_io/grid_conversion.h"
#include "lodestone/vdb_io/level_set_file.h"
#include "lodestone/vdb_io/particle_surface.h"
#include "lodestone/vdb_io/render_frame.h"

using namespace lodestone;

namespace {

constexpr double kSpacing = 0.005;  // particle spacing, m (dx / 2 of an MPM grid at 1 cm, ppc 8)

/// Particles on a cubic lattice of spacing s, each of volume s^3, at the
/// lattice points where `inside` holds; each position moved by `shift` and
/// by a uniform random jitter of +-jitter * s per axis.
template <typename Inside>
SurfaceParticles lattice(int n, Inside inside, const Vec3d& shift = {}, double jitter = 0, unsigned seed = 1,
                         Vec3d velocity = {}) {
  SurfaceParticles p;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  for (int k = -n; k <= n; ++k)
    for (int j = -n; j <= n; ++j)
      for (int i = -n; i <= n; ++i) {
        const Vec3d x{i * kSpacing, j * kSpacing, k * kSpacing};
        if (!inside(x)) continue;
        p.x.push_back(x + shift + Vec3d{u(rng), u(rng), u(rng)} * kSpacing);
        p.v.push_back(velocity);
        p.volume.push_back(kSpacing * kSpacing * kSpacing);
        p.material.push_back(0);
      }
  return p;
}

SurfaceParticles ball(double radius, const Vec3d& shift = {}, double jitter = 0, unsigned seed = 1) {
  return lattice(int(radius / kSpacing) + 2, [&](const Vec3d& x) { return dot(x, x) <= radius * radius; }, shift,
                 jitter, seed);
}

/// A pool 40 x 40 x 8 spacings (top layer at z = 0).
SurfaceParticles pool(double jitter = 0, unsigned seed = 1) {
  return lattice(20, [](const Vec3d& x) { return x.z <= 1e-9 && x.z >= -8 * kSpacing - 1e-9; }, {}, jitter, seed);
}

double totalVolume(const SurfaceParticles& p) {
  double v = 0;
  for (const double q : p.volume) v += q;
  return v;
}

SurfaceOptions optionsFor(SurfaceMethod method) {
  SurfaceOptions o;
  o.voxelSize = kSpacing;
  o.method = method;
  return o;
}

/// The grids of a .vdb file (listed by name).
openvdb::GridPtrVecPtr fileGrids(const std::string& path) {
  openvdb::io::File file(path);
  file.open();
  openvdb::GridPtrVecPtr grids = file.getGrids();
  file.close();
  return grids;
}

const SurfaceMethod kMethods[] = {SurfaceMethod::Splat, SurfaceMethod::SmoothedDensity};

}  // namespace

// The ball's particles fill a volume N s^3: the sphere of that volume. The
// zero crossing (the mesh's vertices) lies within half a voxel of it and the
// enclosed volume within 3%, for both methods.
TEST(ParticleSurface, BallGivesItsSphere) {
  const SurfaceParticles p = ball(12 * kSpacing);
  const double volume = totalVolume(p);
  const double radius = std::cbrt(3 * volume / (4 * kPi));
  for (const SurfaceMethod method : kMethods) {
    SCOPED_TRACE(surfaceMethodName(method));
    const auto grid = particleLevelSet(p, optionsFor(method), "surface");
    ASSERT_TRUE(grid);
    EXPECT_EQ(grid->getGridClass(), openvdb::GRID_LEVEL_SET);
    const TriangleMesh mesh = levelSetMesh(*grid);
    ASSERT_GT(mesh.vertices.size(), 100u);
    double worst = 0;
    for (const Vec3d& v : mesh.vertices) worst = std::max(worst, std::abs(std::sqrt(dot(v, v)) - radius));
    std::printf("%s: sphere R = %.2f voxels, worst zero-crossing error %.3f voxel, volume error %.2f%% (level set), "
                "%.2f%% (mesh)\n",
                surfaceMethodName(method), radius / kSpacing, worst / kSpacing,
                100 * (levelSetVolume(*grid) / volume - 1), 100 * (mesh.volume() / volume - 1));
    EXPECT_LT(worst, 0.5 * kSpacing);
    EXPECT_NEAR(levelSetVolume(*grid), volume, 0.03 * volume);
    EXPECT_NEAR(mesh.volume(), volume, 0.03 * volume);
  }
}

// A resting pool (particles jittered by 2% of their spacing, as settled
// material is): the top surface is flat within a quarter voxel, at the
// top layer plus half a spacing.
TEST(ParticleSurface, RestingPoolIsFlat) {
  const SurfaceParticles p = pool(0.02);
  for (const SurfaceMethod method : kMethods) {
    SCOPED_TRACE(surfaceMethodName(method));
    const auto grid = particleLevelSet(p, optionsFor(method), "surface");
    const TriangleMesh mesh = levelSetMesh(*grid);
    double lo = 1e9, hi = -1e9;
    std::size_t count = 0;
    for (std::size_t n = 0; n < mesh.vertices.size(); ++n) {
      const Vec3d& v = mesh.vertices[n];
      // The top, away from the pool's sides by 4 voxels.
      if (v.z < -2 * kSpacing || std::abs(v.x) > 16 * kSpacing || std::abs(v.y) > 16 * kSpacing) continue;
      lo = std::min(lo, v.z);
      hi = std::max(hi, v.z);
      ++count;
    }
    ASSERT_GT(count, 500u);
    std::printf("%s: pool top z in [%.3f, %.3f] voxels (expected 0.5), spread %.3f voxel\n",
                surfaceMethodName(method), lo / kSpacing, hi / kSpacing, (hi - lo) / kSpacing);
    EXPECT_LT(hi - lo, 0.5 * kSpacing);  // within +-0.25 voxel of the middle
    EXPECT_NEAR(0.5 * (hi + lo), 0.5 * kSpacing, 0.25 * kSpacing);
  }
}

// Temporal coherence. At rest: two frames of the pool whose particles jitter
// independently by 2% of their spacing. Translating: a ball moved by 0.13
// voxel between frames, compared after undoing the motion. The change of
// the surface near its zero crossing, in voxels, is bounded for both
// methods; for the moving ball the smoothed density changes less than the
// splat (at rest both change by less than 0.01 voxel).
TEST(ParticleSurface, TemporalCoherence) {
  struct Case {
    const char* name;
    SurfaceParticles a, b;
    Vec3d shift;
  };
  const Vec3d motion{0.13 * kSpacing, 0.07 * kSpacing, 0.0};
  Case cases[] = {{"pool at rest", pool(0.02, 1), pool(0.02, 2), {}},
                  {"translating ball", ball(10 * kSpacing), ball(10 * kSpacing, motion), motion}};
  for (Case& c : cases) {
    double rms[2] = {0, 0};
    for (int m = 0; m < 2; ++m) {
      const SurfaceOptions o = optionsFor(kMethods[m]);
      const auto a = particleLevelSet(c.a, o, "surface");
      const auto b = particleLevelSet(c.b, o, "surface");
      const SurfaceChange change = surfaceChange(*a, *b, c.shift);
      std::printf("%s, %s: frame-to-frame change rms %.4f voxel, max %.4f voxel (%zu samples)\n", c.name,
                  surfaceMethodName(kMethods[m]), change.rms, change.max, change.samples);
      ASSERT_GT(change.samples, 100u);
      rms[m] = change.rms;
    }
    EXPECT_LT(rms[0], 0.05) << c.name << ": splat";
    EXPECT_LT(rms[1], 0.025) << c.name << ": smoothed density";
    if (c.shift.x != 0) {
      EXPECT_LT(rms[1], 0.75 * rms[0]) << c.name << ": moving material flickers less";
    }
  }
}

// The volume file's `density` is the volume fraction: in [0, 1], 1 inside
// the material, integrating to the particles' volume within 2%; `vel` is the
// particles' velocity; `density` is the file's first grid.
TEST(ParticleSurface, VolumeFractionIntegratesToTheMaterialVolume) {
  SurfaceParticles p = ball(10 * kSpacing);
  for (Vec3d& v : p.v) v = {0.25, -0.5, 1.0};
  const double volume = totalVolume(p);
  SurfaceOptions o = optionsFor(SurfaceMethod::SmoothedDensity);
  RenderFrame frame(p, o, {"ferrofluid"});
  const std::string path = (std::filesystem::temp_directory_path() / "lodestone_volume_test.vdb").string();
  frame.writeVolumeVdb(path, {});
  const openvdb::GridPtrVecPtr grids = fileGrids(path);
  ASSERT_GE(grids->size(), 2u);
  EXPECT_EQ((*grids)[0]->getName(), "density");
  const auto density = openvdb::GridBase::grid<openvdb::FloatGrid>((*grids)[0]);
  ASSERT_TRUE(density);
  double sum = 0, lo = 1e9, hi = -1e9;
  for (auto it = density->cbeginValueOn(); it; ++it) {
    sum += double(*it) * double(it.getVoxelCount());
    lo = std::min(lo, double(*it));
    hi = std::max(hi, double(*it));
  }
  sum *= kSpacing * kSpacing * kSpacing;
  std::printf("density in [%.4f, %.4f], integral / particle volume - 1 = %.3g\n", lo, hi, sum / volume - 1);
  EXPECT_GE(lo, 0.0);
  EXPECT_LE(hi, 1.0);
  EXPECT_NEAR(density->tree().getValue(openvdb::Coord(0, 0, 0)), 1.0, 0.01);
  EXPECT_NEAR(sum, volume, 0.02 * volume);
  const auto vel = readVdbVec3Grid(path, "vel");
  const auto v = openvdb::GridBase::grid<openvdb::Vec3fGrid>(vel)->tree().getValue(openvdb::Coord(0, 0, 0));
  EXPECT_NEAR(v[0], 0.25, 1e-5);
  EXPECT_NEAR(v[1], -0.5, 1e-5);
  EXPECT_NEAR(v[2], 1.0, 1e-5);
  std::filesystem::remove(path);
}

// Two materials: the surface file holds `surface` then one level set per material.
TEST(ParticleSurface, SurfaceFileHasUnionAndMaterials) {
  SurfaceParticles p = ball(6 * kSpacing);
  for (std::size_t i = 0; i < p.size(); ++i) p.material[i] = p.x[i].x > 0 ? 1 : 0;
  RenderFrame frame(p, optionsFor(SurfaceMethod::SmoothedDensity), {"oil", "iron"});
  const std::string path = (std::filesystem::temp_directory_path() / "lodestone_surface_test.vdb").string();
  frame.writeSurfaceVdb(path, {});
  const openvdb::GridPtrVecPtr grids = fileGrids(path);
  // (getGrids lists them by name.)
  ASSERT_EQ(grids->size(), 3u);
  EXPECT_EQ((*grids)[0]->getName(), "surface");
  EXPECT_EQ((*grids)[1]->getName(), "surface_iron");
  EXPECT_EQ((*grids)[2]->getName(), "surface_oil");
  for (const auto& g : *grids) EXPECT_EQ(g->getGridClass(), openvdb::GRID_LEVEL_SET);
  // The union reads back as a level set enclosing the particles' volume.
  const SampledSdf sdf = readLevelSetVdb(path, "surface");
  EXPECT_LT(sdf.signedDistance({0, 0, 0}), 0);
  std::filesystem::remove(path);
}

// Mesh files: the PLY's header and counts, the OBJ through parseObj, unit
// normals, velocities of the particles, and the mesh's volume near the level
// set's.
TEST(ParticleSurface, MeshFilesReadBack) {
  SurfaceParticles p = ball(8 * kSpacing);
  for (Vec3d& v : p.v) v = {0.0, 0.0, -2.0};
  RenderFrame frame(p, optionsFor(SurfaceMethod::SmoothedDensity), {});
  const TriangleMesh& mesh = frame.mesh();
  ASSERT_EQ(mesh.normals.size(), mesh.vertices.size());
  ASSERT_EQ(mesh.velocities.size(), mesh.vertices.size());
  for (std::size_t n = 0; n < mesh.vertices.size(); ++n) {
    EXPECT_NEAR(std::sqrt(dot(mesh.normals[n], mesh.normals[n])), 1.0, 1e-9);
    // Outward: along the position for a ball.
    EXPECT_GT(dot(mesh.normals[n], mesh.vertices[n]), 0.9 * std::sqrt(dot(mesh.vertices[n], mesh.vertices[n])));
    EXPECT_NEAR(mesh.velocities[n].z, -2.0, 1e-5);
  }
  // The mesh's chords cut the curved surface (R = 8 voxels): 2.6% less volume.
  EXPECT_NEAR(mesh.volume(), frame.surfaceVolume(), 0.04 * frame.surfaceVolume());
  EXPECT_LT(mesh.volume(), frame.surfaceVolume());

  const std::vector<std::uint8_t> ply = output::meshPly(mesh).encode();
  const std::string text(ply.begin(), ply.end());
  const std::size_t end = text.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  const std::string header = text.substr(0, end);
  EXPECT_NE(header.find("element vertex " + std::to_string(mesh.vertices.size()) + "\n"), std::string::npos);
  EXPECT_NE(header.find("element face " + std::to_string(mesh.triangles.size()) + "\n"), std::string::npos);
  EXPECT_NE(header.find("property float nx\n"), std::string::npos);
  EXPECT_NE(header.find("property float vz\n"), std::string::npos);
  // 9 floats per vertex, 13 bytes per face.
  EXPECT_EQ(ply.size(), end + 11 + 36 * mesh.vertices.size() + 13 * mesh.triangles.size());
  std::uint8_t count = 0;
  std::int32_t last[3];
  const std::size_t lastFace = ply.size() - 13;
  std::memcpy(&count, ply.data() + lastFace, 1);
  std::memcpy(last, ply.data() + lastFace + 1, 12);
  EXPECT_EQ(count, 3);
  for (int a = 0; a < 3; ++a) EXPECT_EQ(std::uint32_t(last[a]), mesh.triangles.back()[a]);

  const TriangleMesh back = parseObj(output::meshObj(mesh, "test"), "mesh.obj");
  ASSERT_EQ(back.vertices.size(), mesh.vertices.size());
  ASSERT_EQ(back.triangles.size(), mesh.triangles.size());
  EXPECT_NEAR(back.volume(), mesh.volume(), 1e-6 * mesh.volume());
}
