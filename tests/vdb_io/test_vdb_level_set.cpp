// lodestone::vdb_io level sets and meshes: VDB level sets and OBJ meshes as
// SampledSdf (against closed-form distances and volumes), level-set emitters
// and colliders, strict readers; the density grid as field-solve input; the
// display aliases and MPM grids of field files.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/LevelSetUtil.h>

#include "lodestone/core/stage/density_raster.h"
#include "lodestone/core/base/constants.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/mpm/emitter.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/vdb_io/field_file.h"
#include "lodestone/vdb_io/grid_conversion.h"
#include "lodestone/vdb_io/level_set_file.h"
#include "lodestone_test/sample_data.h"
#include "lodestone_test/scenes.h"
#if LODESTONE_TEST_SCENE
#include "lodestone/plugin/scene.h"
#endif

namespace lodestone {
namespace {

namespace fs = std::filesystem;

fs::path tempDir() {
  const fs::path d = fs::path(::testing::TempDir()) /
                     ("lodestone_ls_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  fs::create_directories(d);
  return d;
}

double seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void expectMessageNames(const std::function<void()>& f, const std::vector<std::string>& parts) {
  try {
    f();
    ADD_FAILURE() << "no exception; expected one naming " << parts.front();
  } catch (const InvalidArgument& e) {
    const std::string msg = e.what();
    for (const std::string& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
  }
}

void writeGrid(const fs::path& file, openvdb::GridBase::Ptr grid) { openvdb::io::File(file.string()).write({grid}); }


std::string toObj(const TriangleMesh& m) {
  std::string s = "# torus\no torus\n";
  char line[128];
  for (const Vec3d& v : m.vertices) {
    std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", v.x, v.y, v.z);
    s += line;
  }
  for (const auto& t : m.triangles) {
    std::snprintf(line, sizeof line, "f %u/%u %u/%u %u/%u\n", t[0] + 1, t[0] + 1, t[1] + 1, t[1] + 1, t[2] + 1,
                  t[2] + 1);
    s += line;
  }
  return s;
}

void writeText(const fs::path& file, const std::string& text) { std::ofstream(file, std::ios::binary) << text; }

/// Emits at ppc 8 and returns the report; prints the fill rate.
EmitReport fill(const EmitterShape& shape, double dx, const char* what) {
  MpmParticles p;
  EmitterSettings e;
  e.cellSize = dx;
  const auto t0 = std::chrono::steady_clock::now();
  const EmitReport r = emitParticles(p, shape, neoHookeanSolid(1e5, 0.3, 1000), 0, e);
  const double t = seconds(t0);
  std::printf("%s: %zu particles in %.4f s (%.3g particles/s), volume %.6g m^3\n", what, r.particles, t,
              double(r.particles) / t, r.volume);
  return r;
}

}  // namespace

TEST(VdbLevelSet, SphereFromOpenVdbMatchesTheClosedForm) {
  // openvdb::tools::createLevelSetSphere: exact distances in a 3-voxel band.
  const double R = 0.05, voxel = 0.0025;
  const Vec3d c{0.1, -0.2, 0.3};
  auto grid = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(float(R), openvdb::Vec3f(0.1f, -0.2f, 0.3f),
                                                                       float(voxel), 3.0f);
  grid->setName("surface");
  const fs::path file = tempDir() / "sphere.vdb";
  writeGrid(file, grid);
  const auto t0 = std::chrono::steady_clock::now();
  const SampledSdf sdf = readLevelSetVdb(file.string(), "surface");
  std::printf("sphere level set R/h = %.0f: SDF -> core grid (%d x %d x %d) in %.4f s\n", R / voxel, sdf.spec().dims.i,
              sdf.spec().dims.j, sdf.spec().dims.k, seconds(t0));
  EXPECT_NE(sdf.description().find("sphere.vdb"), std::string::npos);
  EXPECT_NEAR(sdf.spec().dx, voxel, 1e-7 * voxel);  // the voxel size went through float
  // Within the band the trilinear distance errs by 3 h^2 / (8 r) plus float
  // rounding; the sign is right everywhere (inside tiles are -background).
  for (const double r : {0.3 * R, 0.9 * R, 0.97 * R, R, 1.03 * R, 1.1 * R, 2.0 * R}) {
    for (const Vec3d& d : {Vec3d{1, 0, 0}, Vec3d{0, -1, 0}, Vec3d{1, 2, -2} / 3.0}) {
      const Vec3d x = c + r * d;
      const double phi = sdf.signedDistance(x), exact = r - R;
      if (std::fabs(exact) < 2 * voxel) {
        EXPECT_NEAR(phi, exact, 3 * voxel * voxel / (8 * 0.9 * R) + 1e-6) << r;
        EXPECT_LT(norm(sdf.normal(x) - d), 0.1) << r;
      }
      EXPECT_EQ(phi < 0, exact < 0) << r;
    }
  }
  const double exactV = 4.0 / 3.0 * kPi * R * R * R;
  EXPECT_NEAR(sdf.volume(), exactV, 0.01 * exactV);
  // Emitter: the particles' volumes match the sphere (staircase error at
  // h = dx/2 = R/10, as for the analytic sphere emitter).
  const auto shared = std::make_shared<const SampledSdf>(sdf);
  const EmitReport r = fill(EmitterShape::levelSetShape(Pose{}, shared), 0.01, "sphere level-set fill");
  EXPECT_NEAR(r.volume, exactV, 0.05 * exactV);
  const EmitReport fine = fill(EmitterShape::levelSetShape(Pose{}, shared), 0.005, "sphere level-set fill, dx/2");
  EXPECT_NEAR(fine.volume, exactV, 0.03 * exactV);
}

TEST(VdbLevelSet, TorusMeshFillsItsVolume) {
  // A torus mesh (R = 4 cm, r = 1.5 cm): the mesh's own volume (divergence
  // theorem) is the reference; meshToLevelSet at 1.5 mm voxels, then the
  // SDF's volume and the emitted particles' volume must match it.
  const TriangleMesh mesh = lodestone::test::torusMesh({0.01, 0.02, 0.03}, 0.04, 0.015, 64, 32);
  const double V = mesh.volume();
  EXPECT_NEAR(V, 2 * kPi * kPi * 0.04 * 0.015 * 0.015, 0.02 * V);  // polygon vs smooth torus
  const fs::path obj = tempDir() / "torus.obj";
  writeText(obj, toObj(mesh));
  const TriangleMesh back = readObj(obj.string());
  ASSERT_EQ(back.triangles.size(), mesh.triangles.size());
  EXPECT_NEAR(back.volume(), V, 1e-6 * V);
  const auto t0 = std::chrono::steady_clock::now();
  const SampledSdf sdf = levelSetFromObj(obj.string(), 0.0015);
  std::printf("torus mesh (%zu triangles) -> level set at 1.5 mm -> core grid (%d x %d x %d): %.4f s\n",
              mesh.triangles.size(), sdf.spec().dims.i, sdf.spec().dims.j, sdf.spec().dims.k, seconds(t0));
  EXPECT_NEAR(sdf.volume(), V, 0.02 * V);
  // One voxel inside the outer equator (a mesh vertex): -1 voxel, to a
  // fraction of a voxel; the core circle is deeper than the 3-voxel band, so
  // it reads -background; the hole is outside.
  EXPECT_NEAR(sdf.signedDistance({0.01 + 0.055 - 0.0015, 0.02, 0.03}), -0.0015, 0.3 * 0.0015);
  EXPECT_NEAR(sdf.signedDistance({0.01 + 0.04, 0.02, 0.03}), -3 * 0.0015, 1e-6);
  EXPECT_GT(sdf.signedDistance({0.01, 0.02, 0.03}), 0);
  const auto shared = std::make_shared<const SampledSdf>(sdf);
  const Pose pose = Pose::fromAxisAngle({1, 1, 1}, {0, 1, 0}, 0.5);
  const EmitReport r = fill(EmitterShape::levelSetShape(pose, shared), 0.005, "torus mesh fill");
  EXPECT_NEAR(r.volume, V, 0.05 * V);
  // Writing the mesh's level set and reading it back gives the same SDF.
  const fs::path vdb = tempDir() / "torus.vdb";
  MeshLevelSetOptions o;
  o.voxelSize = 0.0015;
  writeMeshLevelSetVdb(vdb.string(), mesh, o, "torus");
  const SampledSdf again = readLevelSetVdb(vdb.string(), "torus");
  EXPECT_NEAR(again.volume(), sdf.volume(), 1e-3 * V);
}

TEST(VdbLevelSet, BadLevelSetsThrowNamingFileAndGrid) {
  const fs::path dir = tempDir();
  const auto sphere = [] {
    return openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(0.1f, openvdb::Vec3f(0.f), 0.01f, 3.0f);
  };
  // Fog volume (grid class).
  {
    auto g = sphere();
    openvdb::tools::sdfToFogVolume(*g);
    g->setName("fog");
    writeGrid(dir / "fog.vdb", g);
    expectMessageNames([&] { readLevelSetVdb((dir / "fog.vdb").string(), "fog"); }, {"fog.vdb", "'fog'", "class"});
  }
  // Double grid (type).
  {
    auto g = openvdb::DoubleGrid::create(0.03);
    g->setGridClass(openvdb::GRID_LEVEL_SET);
    g->tree().setValue(openvdb::Coord(0, 0, 0), -0.01);
    g->setName("dbl");
    writeGrid(dir / "dbl.vdb", g);
    expectMessageNames([&] { readLevelSetVdb((dir / "dbl.vdb").string(), "dbl"); }, {"dbl.vdb", "'dbl'", "FloatGrid"});
  }
  // Rotated and non-uniformly scaled transforms.
  {
    auto g = sphere();
    g->setName("rot");
    g->transform().postRotate(0.3, openvdb::math::Z_AXIS);
    writeGrid(dir / "rot.vdb", g);
    expectMessageNames([&] { readLevelSetVdb((dir / "rot.vdb").string(), "rot"); }, {"rot.vdb", "'rot'", "transform"});
    auto s = sphere();
    s->setName("stretched");
    auto xf = openvdb::math::Transform::createLinearTransform(0.01);
    xf->postScale(openvdb::Vec3d(1, 2, 1));
    s->setTransform(xf);
    writeGrid(dir / "stretched.vdb", s);
    expectMessageNames([&] { readLevelSetVdb((dir / "stretched.vdb").string(), "stretched"); },
                       {"stretched.vdb", "'stretched'", "transform"});
  }
  // Missing grid, missing file, empty level set.
  {
    auto g = sphere();
    g->setName("surface");
    writeGrid(dir / "ok.vdb", g);
    expectMessageNames([&] { readLevelSetVdb((dir / "ok.vdb").string(), "nope"); }, {"ok.vdb", "'nope'"});
    expectMessageNames([&] { readLevelSetVdb((dir / "absent.vdb").string(), "surface"); }, {"absent.vdb", "surface"});
    auto e = openvdb::FloatGrid::create(0.03f);
    e->setGridClass(openvdb::GRID_LEVEL_SET);
    e->setName("empty");
    writeGrid(dir / "empty.vdb", e);
    expectMessageNames([&] { readLevelSetVdb((dir / "empty.vdb").string(), "empty"); }, {"empty.vdb", "'empty'"});
  }
  // The good one reads.
  EXPECT_NO_THROW(readLevelSetVdb((dir / "ok.vdb").string()));
}

TEST(VdbLevelSet, ObjReaderTriangulatesAndRejectsBadInput) {
  // A unit cube of quads (outward, counter-clockwise), with comments,
  // normals, texture coordinates and a negative (relative) index.
  const std::string cube =
      "# cube\nmtllib x.mtl\no cube\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
      "vn 0 0 1\nvt 0 0\ns off\nusemtl m\n"
      "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2/1 3/1 7/1 6/1\nf 3//1 4//1 8//1 7//1\nf 4 1 5 -1 # back to v8\n";
  const TriangleMesh m = parseObj(cube, "cube.obj");
  EXPECT_EQ(m.vertices.size(), 8u);
  EXPECT_EQ(m.triangles.size(), 12u);
  EXPECT_NEAR(m.volume(), 1.0, 1e-15);
  expectMessageNames([] { parseObj("v 0 0 0\nv 1 0 0\nv 0 1 x\nf 1 2 3\n", "bad.obj"); }, {"bad.obj:3", "'x'"});
  expectMessageNames([] { parseObj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "two.obj"); }, {"two.obj:4", "3 vertices"});
  expectMessageNames([] { parseObj("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 9\n", "range.obj"); },
                     {"range.obj:5", "index 9"});
  expectMessageNames([] { parseObj("v 0 0 0\nf 1 -4 1\n", "rel.obj"); }, {"rel.obj:2", "-4"});
  expectMessageNames([] { parseObj("v 0 0 0\nf 1 0 1\n", "zero.obj"); }, {"zero.obj:2"});
  expectMessageNames([] { parseObj("v 0 0\n", "short.obj"); }, {"short.obj:1"});
  expectMessageNames([] { parseObj("v 0 0 0\n", "nofaces.obj"); }, {"nofaces.obj", "no faces"});
  expectMessageNames([] { readObj("/nonexistent/dir/mesh.obj"); }, {"/nonexistent/dir/mesh.obj"});
  // A device (endless) or a directory is refused before it is read.
  expectMessageNames([] { readObj("/dev/zero"); }, {"/dev/zero", "not a regular file"});
  expectMessageNames([] { readObj("/tmp"); }, {"/tmp", "not a regular file"});
  // Bad voxel size names the mesh.
  MeshLevelSetOptions o;
  o.voxelSize = -1;
  expectMessageNames([&] { meshToSampledSdf(m, o, "OBJ file 'cube.obj'"); }, {"cube.obj", "voxel size"});
}

namespace {

/// A block dropped on a slab collider (top at z = 0.06 m), as in the core
/// collider test; returns the centre-of-mass height after 0.6 s.
double blockOnSlab(const ColliderShape& slab, const Pose& pose) {
  MpmSettings s;
  s.grid.dx = 0.01;
  s.grid.origin = {0, 0, 0};
  s.grid.dims = {21, 21, 21};
  MpmSolver solver(s);
  solver.addCollider(MpmCollider(slab, ColliderMotion::fixed(pose), BoundaryCondition{BoundaryMode::Separate, 0.0}));
  const std::uint32_t m = solver.addMaterial(neoHookeanSolid(1e5, 0.3, 1000));
  solver.emit(EmitterShape::box(Pose::at({0.1, 0.1, 0.12}), {0.03, 0.03, 0.02}), m, {});
  while (solver.time() < 0.6 - 1e-12) solver.advanceFrame(1.0 / 50);
  return solver.particles().centreOfMass().z;
}

}  // namespace

TEST(VdbLevelSet, VdbBoxColliderStopsAFallingBlockLikeTheAnalyticBox) {
  // openvdb::tools::createLevelSetBox of the slab [-0.15, 0.15]^2 x [-0.03, 0.03]
  // placed at (0.1, 0.1, 0.03): rest height as with the analytic box.
  const openvdb::BBoxd box(openvdb::Vec3d(-0.15, -0.15, -0.03), openvdb::Vec3d(0.15, 0.15, 0.03));
  const auto xf = openvdb::math::Transform::createLinearTransform(0.005);
  auto grid = openvdb::tools::createLevelSetBox<openvdb::FloatGrid>(box, *xf, 3.0);
  grid->setName("slab");
  const fs::path file = tempDir() / "slab.vdb";
  writeGrid(file, grid);
  const auto sdf = std::make_shared<const SampledSdf>(readLevelSetVdb(file.string(), "slab"));
  const Pose pose = Pose::at({0.1, 0.1, 0.03});
  const double za = blockOnSlab(ColliderShape::box({0.15, 0.15, 0.03}), pose);
  const double zl = blockOnSlab(ColliderShape::levelSetShape(sdf), pose);
  std::printf("block on slab: rest height analytic %.5f m, VDB level set %.5f m\n", za, zl);
  EXPECT_NEAR(zl, za, 0.001);
  EXPECT_GT(zl, 0.08);
}

// ------------------------------------------------------------ density input

TEST(VdbDensityInput, ParticlePathFieldIsReproducedFromItsDensityFile) {
  // The particle path (run: transfer + solve) writes n; a host feeding that n
  // to runOnDensity gets the same fields: bit for bit from a double file, to
  // float rounding (relative 1e-6 of the peak, solver tolerance aside) from a
  // float file.
  const GridSpec g = test::cubeGrid(17, 0.1);
  const MagneticMaterial mat = linearMaterial(0.8, 1e24);
  std::vector<Vec3d> x;
  std::vector<double> n;
  for (int k = -4; k <= 4; ++k)
    for (int j = -4; j <= 4; ++j)
      for (int i = -4; i <= 4; ++i) {
        const Vec3d p = 0.006 * Vec3d{double(i), double(j), double(k)} + Vec3d{0.001, -0.002, 0.0005};
        if (norm(p) < 0.024) {
          x.push_back(p);
          n.push_back(1e24 * 0.006 * 0.006 * 0.006);
        }
      }
  const UniformField H0({0, 2e4, 1e4});
  MagneticForceStage particles(g, mat);
  const MagneticStageReport r0 = particles.run({x.data(), n.data(), x.size()}, H0, 0.0);
  ASSERT_TRUE(r0.converged());
  const fs::path dir = tempDir();
  for (const bool dbl : {true, false}) {
    VdbWriteOptions o;
    o.doublePrecision = dbl;
    const fs::path file = dir / (dbl ? "n_double.vdb" : "n_float.vdb");
    writeFieldsVdb(file.string(), particles, {}, o);
    const DenseGrid<double> nIn = readDensityVdb(file.string(), g);
    MagneticForceStage host(g, mat);
    const MagneticStageReport r1 = host.runOnDensity(nIn.view(), H0, 0.0);
    ASSERT_TRUE(r1.converged());
    double peakH = 0, peakF = 0, errH = 0, errF = 0;
    for (std::size_t i = 0; i < g.nodeCount(); ++i) {
      peakH = std::max(peakH, norm(particles.field()[i]));
      peakF = std::max(peakF, norm(particles.forceDensity()[i]));
      errH = std::max(errH, norm(host.field()[i] - particles.field()[i]));
      errF = std::max(errF, norm(host.forceDensity()[i] - particles.forceDensity()[i]));
    }
    std::printf("density input (%s file): max |dH| / |H|max = %.3g, max |dt| / |t|max = %.3g\n",
                dbl ? "double" : "float", errH / peakH, errF / peakF);
    if (dbl) {
      EXPECT_EQ(errH, 0.0);
      EXPECT_EQ(errF, 0.0);
    } else {
      EXPECT_LE(errH, 1e-5 * peakH);
      EXPECT_LE(errF, 1e-4 * peakF);
    }
  }
  // Negative densities are refused, naming file, grid and node.
  DenseGrid<double> bad(g, 0.0);
  bad(3, 4, 5) = -1;
  auto grid = toVdbFloatGrid(bad.view(), "n");
  writeGrid(dir / "negative.vdb", grid);
  expectMessageNames([&] { readDensityVdb((dir / "negative.vdb").string(), g); }, {"negative.vdb", "'n'", "(3, 4, 5)"});
}

// ------------------------------------------------------------ aliases, MPM grids

TEST(VdbFieldFile, DisplayAliasesAndMpmGrids) {
  const GridSpec g = test::cubeGrid(9, 0.1);
  const MagneticMaterial mat = linearMaterial(0.5, 1e24);
  MagneticForceStage stage(g, mat);
  stage.runOnDensity(rasterizeDensity(g, 1e24, test::ball({}, 0.05)).view(), UniformField({0, 0, 1e4}), 0.0);
  // An MPM grid of another spacing and origin.
  GridSpec mg;
  mg.dx = 0.02;
  mg.origin = {-0.05, -0.05, 0.0};
  mg.dims = {6, 5, 4};
  DenseGrid<double> mass(mg, 0.0);
  DenseGrid<Vec3d> vel(mg);
  for (std::size_t i = 0; i < mass.size(); ++i) {
    mass[i] = i % 3 ? 1e-3 * double(i) : 0.0;
    vel[i] = Vec3d{0.1 * double(i), -1.0, 2.0};
  }
  VdbWriteOptions o;
  o.doublePrecision = true;
  o.displayAliases = true;
  o.fields.mass = true;
  o.fields.velocity = true;
  o.mpm = {mass.view(), vel.view()};
  const fs::path file = tempDir() / "aliases.vdb";
  writeFieldsVdb(file.string(), stage, {}, o);
  const DenseGrid<double> density = readScalarField(file.string(), "density", g);
  for (std::size_t i = 0; i < g.nodeCount(); ++i) ASSERT_EQ(density[i], stage.density()[i]);
  const DenseGrid<double> m2 = readScalarField(file.string(), "mass", mg);
  const DenseGrid<Vec3d> v2 = readVec3Field(file.string(), "velocity", mg);
  const DenseGrid<Vec3d> v3 = readVec3Field(file.string(), "vel", mg);
  for (std::size_t i = 0; i < mass.size(); ++i) {
    ASSERT_EQ(m2[i], mass[i]);
    ASSERT_EQ(v2[i], vel[i]);
    ASSERT_EQ(v3[i], vel[i]);
  }
  openvdb::io::File f(file.string());
  f.open();
  EXPECT_EQ(f.readGrid("vel")->getVectorType(), openvdb::VEC_CONTRAVARIANT_RELATIVE);
  EXPECT_EQ(f.readGrid("density")->getGridClass(), openvdb::GRID_FOG_VOLUME);
  EXPECT_TRUE(transformMatches(f.readGrid("vel")->constTransform(), mg));
  f.close();
  // Standard tools see the display names: pyopenvdb (Debian's python3-openvdb,
  // for /usr/bin/python3) lists them with their vector type. It cannot load
  // Vec3d grids, so the check reads a float file.
  o.doublePrecision = false;
  const fs::path floatFile = tempDir() / "aliases_float.vdb";
  writeFieldsVdb(floatFile.string(), stage, {}, o);
  for (const char* python : {"python3", "/usr/bin/python3"}) {
    if (std::system((std::string(python) + " -c 'import pyopenvdb' > /dev/null 2>&1").c_str()) != 0) continue;
    const fs::path script = tempDir() / "names.py", out = tempDir() / "names.out";
    std::ofstream(script) << "import sys, pyopenvdb as vdb\n"
                             "grids, meta = vdb.readAll(sys.argv[1])\n"
                             "print(' '.join(sorted(g.name for g in grids)))\n"
                             "print([g.vectorType for g in grids if g.name == 'vel'][0])\n";
    const int rc = std::system(
        (std::string(python) + " '" + script.string() + "' '" + floatFile.string() + "' > '" + out.string() + "' 2>&1")
            .c_str());
    std::ifstream in(out);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(rc, 0) << text;
    EXPECT_NE(text.find("B H M density force mass n phi vel velocity"), std::string::npos) << text;
    EXPECT_NE(text.find("contravariant relative"), std::string::npos) << text;
    break;
  }
  // Asking for MPM grids without giving them names the file.
  VdbWriteOptions missing;
  missing.fields.mass = true;
  expectMessageNames([&] { writeFieldsVdb((tempDir() / "m.vdb").string(), stage, {}, missing); }, {"m.vdb", "mass"});
}

#if LODESTONE_TEST_SCENE
TEST(VdbLevelSet, SceneShapesFromFiles) {
  const fs::path dir = tempDir();
  auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(0.03f, openvdb::Vec3f(0.f), 0.0025f, 3.0f);
  sphere->setName("ball");
  writeGrid(dir / "ball.vdb", sphere);
  writeText(dir / "torus.obj", toObj(lodestone::test::torusMesh({}, 0.04, 0.015, 32, 16)));
  const std::string text = R"({
    "name": "files",
    "domain": {"min": [0, 0, 0], "max": [0.2, 0.2, 0.2], "dx": 0.01},
    "time": {"frames": 1},
    "materials": [{"name": "gel", "model": "solid", "density": 1000, "youngs_modulus": 1e5}],
    "bodies": [
      {"material": "gel", "shape": "level_set", "file": "ball.vdb", "grid": "ball", "center": [0.1, 0.1, 0.15]},
      {"material": "gel", "shape": "mesh", "file": "torus.obj", "voxel_size": 0.002, "center": [0.1, 0.1, 0.05]}
    ],
    "colliders": [
      {"shape": "level_set", "file": "ball.vdb", "grid": "ball", "center": [0.1, 0.1, 0.1], "boundary": "slip"}
    ]
  })";
  // Without readers installed the scene uses the node library's (vdb_io's).
  plugin::SceneOptions options;
  const std::string source = (dir / "scene.json").string();
  const plugin::Scene scene = plugin::parseScene(text, source, options);
  ASSERT_EQ(scene.bodies.size(), 2u);
  EXPECT_EQ(scene.bodies[0].shape.kind, EmitterShapeKind::LevelSet);
  EXPECT_NEAR(scene.bodies[0].shape.volume(), 4.0 / 3.0 * kPi * 0.03 * 0.03 * 0.03, 0.01 * 1.2e-4);
  EXPECT_NEAR(scene.bodies[1].shape.levelSet->spec().dx, 0.002, 1e-12);
  ASSERT_EQ(scene.colliders.size(), 1u);
  EXPECT_EQ(scene.colliders[0].shape().kind, ColliderShapeKind::LevelSet);
  EXPECT_NEAR(scene.colliders[0].signedDistance({0.1, 0.1, 0.1}, 0.0), -0.0075, 1e-6);  // -background (3 voxels)
  const auto solver = plugin::buildSolver(scene);
  EXPECT_GT(solver->particles().size(), 100u);
  // Errors name the scene entry and the file.
  std::string wrongGrid = text;
  wrongGrid.replace(wrongGrid.find("\"grid\": \"ball\""), 14, "\"grid\": \"cube\"");
  expectMessageNames([&] { plugin::parseScene(wrongGrid, source, options); }, {"bodies[0]", "ball.vdb", "'cube'"});
  // A host's own readers, when installed, are used instead (here: counted).
  int levelSets = 0, meshes = 0;
  options.loaders.levelSet = [&](const std::string& p, const std::string& grid) {
    ++levelSets;
    return std::make_shared<const SampledSdf>(readLevelSetVdb(p, grid));
  };
  options.loaders.mesh = [&](const std::string& p, double voxel) {
    ++meshes;
    return std::make_shared<const SampledSdf>(levelSetFromObj(p, voxel));
  };
  const plugin::Scene hosted = plugin::parseScene(text, source, options);
  EXPECT_EQ(levelSets, 2);
  EXPECT_EQ(meshes, 1);
  EXPECT_EQ(hosted.bodies[0].shape.volume(), scene.bodies[0].shape.volume());
}
#endif

}  // namespace lodestone
