// Sizes and times of the VDB files (lodestone::vdb_io), the figures of
// docs/vdb.md:
//   fields     a synthetic field set on N^3 nodes (2 scalar + 4 vector grids,
//              the vectors nonzero everywhere, the density a sparse ball):
//              conversion to VDB grids and the write, float and double;
//   solved     the six fields of an actual N^3 solve (a ball of linear
//              material, chi = 0.8, in a uniform field, open boundary):
//              the solve, then writeFieldsVdb (conversion and write);
//   particles  P particles written and read back, without and with F;
//   level set  an OpenVDB sphere of radius R voxels to a SampledSdf, the
//              emitter fill of it at ppc 8 (dx = R/10), and a torus mesh of
//              8R x 4R quads (tube radius R/2 voxels) through meshToLevelSet.
//
//   lodestone-bench-vdb-io [--nodes 128] [--solve-nodes 128]
//                          [--particles 100000] [--level-set-res 100]
//                          [--dir DIR] [--csv FILE]
// Files go to DIR (default: a fresh folder under the system temp directory,
// removed at the end).
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <string>

#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <tbb/info.h>

#include "lodestone/cli/command_line.h"
#include "lodestone/core/stage/density_raster.h"
#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/stopwatch.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/mpm/emitter.h"
#include "lodestone/core/mpm/particles.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/vdb_io/field_file.h"
#include "lodestone/vdb_io/grid_conversion.h"
#include "lodestone/vdb_io/level_set_file.h"
#include "lodestone/vdb_io/point_file.h"
#include "lodestone_test/sample_data.h"
#include "lodestone_test/scenes.h"

using namespace lodestone;
namespace cli = lodestone::cli;
namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;
double megabytes(const fs::path& f) { return double(fs::file_size(f)) / 1e6; }

/// One CSV row: case, what was measured, item count (nodes, particles,
/// triangles or voxels), seconds of the stages (negative: not applicable), MB.
struct Row {
  std::string kase, what;
  double items = 0, convertS = -1, writeS = -1, readS = -1, mb = -1;
};

class Table {
 public:
  explicit Table(const std::string& path) : csv_(path) {
    require(bool(csv_), "cannot write ", path);
    csv_ << "case,what,items,convert_s,write_s,read_s,megabytes,threads\n";
  }
  void add(const Row& r) {
    std::printf("%-10s %-58s %10.4g %9.4f %9.4f %9.4f %9.2f\n", r.kase.c_str(), r.what.c_str(), r.items, r.convertS,
                r.writeS, r.readS, r.mb);
    std::fflush(stdout);
    csv_ << r.kase << ",\"" << r.what << "\"," << r.items << ',' << r.convertS << ',' << r.writeS << ',' << r.readS << ','
         << r.mb << ',' << tbb::info::default_concurrency() << '\n';
  }

 private:
  std::ofstream csv_;
};

void fieldSet(Table& table, const fs::path& dir, int N) {
  const GridSpec g = test::cubeGrid(N, 0.5);
  const DenseGrid<double> n = rasterizeDensity(g, 1e24, test::ball({}, 0.2));
  DenseGrid<Vec3d> v(g);
  for (int k = 0; k < N; ++k)
    for (int j = 0; j < N; ++j)
      for (int i = 0; i < N; ++i) {
        const Vec3d x = g.nodePosition(i, j, k);
        v(i, j, k) = Vec3d{x.y, -x.x, 1.0} * 1e4;
      }
  for (const bool dbl : {false, true}) {
    const auto t0 = Clock::now();
    VdbConversionOptions o;
    o.transform = nodeCentredTransform(g);
    openvdb::GridPtrVec grids;
    if (dbl) {
      grids = {toVdbDoubleGrid(n.view(), "n", o), toVdbDoubleGrid(n.view(), "phi", o)};
      for (const char* name : {"H", "M", "B", "force"}) grids.push_back(toVdbVec3dGrid(v.view(), name, o));
    } else {
      grids = {toVdbFloatGrid(n.view(), "n", o), toVdbFloatGrid(n.view(), "phi", o)};
      for (const char* name : {"H", "M", "B", "force"}) grids.push_back(toVdbVec3fGrid(v.view(), name, o));
    }
    Row r{"fields", concat(N, "^3 synthetic, 2 scalar + 4 vector, ", dbl ? "double" : "float"), double(g.nodeCount())};
    r.convertS = secondsSince(t0);
    const fs::path file = dir / (dbl ? "set_double.vdb" : "set_float.vdb");
    const auto t1 = Clock::now();
    openvdb::io::File(file.string()).write(grids);
    r.writeS = secondsSince(t1);
    r.mb = megabytes(file);
    table.add(r);
  }
  // A sparse ball against a grid that varies everywhere (96^3, float).
  const GridSpec h = test::cubeGrid(96, 0.5);
  const DenseGrid<double> sparse = rasterizeDensity(h, 1.0, test::ball({0.1, -0.05, 0.2}, 0.03));
  DenseGrid<double> dense = sparse;
  for (std::size_t m = 0; m < dense.size(); ++m) dense[m] += 0.5 + 1e-3 * double(m % 97);
  for (const bool isDense : {false, true}) {
    const fs::path file = dir / (isDense ? "dense.vdb" : "sparse.vdb");
    const auto t0 = Clock::now();
    openvdb::io::File(file.string()).write({toVdbFloatGrid((isDense ? dense : sparse).view(), "n")});
    Row r{"fields", isDense ? "96^3 float, varying everywhere" : "96^3 float, sparse ball (r = 3 cells)",
          double(h.nodeCount())};
    r.writeS = secondsSince(t0);
    r.mb = megabytes(file);
    table.add(r);
  }
}

void solvedFields(Table& table, const fs::path& dir, int N) {
  const GridSpec g = test::cubeGrid(N, 0.1);
  const MagneticMaterial mat = linearMaterial(0.8, 1e24);
  MagneticForceStage stage(g, mat);
  const auto t0 = Clock::now();
  const MagneticStageReport rep =
      stage.runOnDensity(rasterizeDensity(g, 1e24, test::ball({}, 0.04), 2).view(), UniformField({0, 0, 1e4}), 0.0);
  require(rep.converged(), "the ", N, "^3 solve did not converge: ", rep.solve.message);
  Row solve{"solved", concat(N, "^3 solve, linear ball chi 0.8 (convert_s: the solve)"), double(g.nodeCount())};
  solve.convertS = secondsSince(t0);
  table.add(solve);
  for (const bool dbl : {false, true}) {
    VdbWriteOptions o;
    o.doublePrecision = dbl;
    const fs::path file = dir / (dbl ? "solve_double.vdb" : "solve_float.vdb");
    const auto t1 = Clock::now();
    writeFieldsVdb(file.string(), stage, {}, o);
    Row r{"solved", concat(N, "^3 writeFieldsVdb n phi H M B force, ", dbl ? "double" : "float"),
          double(g.nodeCount())};
    r.writeS = secondsSince(t1);
    r.mb = megabytes(file);
    table.add(r);
  }
}


void particles(Table& table, const fs::path& dir, std::size_t n) {
  const MpmParticles p = lodestone::test::randomParticles(n, 9);
  for (const bool withF : {false, true}) {
    PointFileOptions o;
    o.voxelSize = 0.005;
    o.deformationGradient = withF;
    const fs::path file = dir / (withF ? "with_F.vdb" : "plain.vdb");
    const auto t0 = Clock::now();
    writeParticlesVdb(file.string(), p, o);
    Row r{"particles", withF ? "voxel 5 mm, with F" : "voxel 5 mm, without F", double(n)};
    r.writeS = secondsSince(t0);
    const auto t1 = Clock::now();
    const ParticleVdbData back = readParticlesVdb(file.string());
    r.readS = secondsSince(t1);
    require(back.size() == n, "read ", back.size(), " particles of ", n);
    r.mb = megabytes(file);
    table.add(r);
  }
}


void levelSets(Table& table, int res) {
  const double R = 0.05, voxel = R / res;
  auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(float(R), openvdb::Vec3f(0.f), float(voxel));
  auto t0 = Clock::now();
  const auto sdf = std::make_shared<const SampledSdf>(toSampledSdf(*sphere, "sphere"));
  Row conv{"level set",
           concat("sphere R/h = ", res, " -> SampledSdf ", sdf->spec().dims.i, "^3 (items: active voxels)"),
           double(sphere->activeVoxelCount())};
  conv.convertS = secondsSince(t0);
  table.add(conv);
  MpmParticles p;
  EmitterSettings e;
  e.cellSize = R / 10;
  t0 = Clock::now();
  const EmitReport filled = emitParticles(p, EmitterShape::levelSetShape(Pose{}, sdf), neoHookeanSolid(1e5, 0.3, 1000),
                                          0, e);
  Row fill{"level set", "emitter fill of the sphere, dx = R/10, ppc 8 (items: particles)", double(filled.particles)};
  fill.convertS = secondsSince(t0);
  table.add(fill);
  const TriangleMesh mesh = lodestone::test::torusMesh({}, 0.04, 0.015, 8 * res, 4 * res);
  MeshLevelSetOptions o;
  o.voxelSize = 0.03 / res;
  t0 = Clock::now();
  const SampledSdf t = meshToSampledSdf(mesh, o, "torus");
  Row tor{"level set",
          concat("torus mesh -> level set -> SampledSdf ", t.spec().dims.i, "x", t.spec().dims.j, "x",
                 t.spec().dims.k, " (items: triangles)"),
          double(mesh.triangles.size())};
  tor.convertS = secondsSince(t0);
  table.add(tor);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    int nodes = 128, solveNodes = 128, res = 100;
    double particleCount = 1e5;
    std::string csvPath = "bench_vdb_io.csv", dirArg;
    CLI::App app("lodestone-bench-vdb-io: sizes and times of the VDB field, particle and level-set files",
                 "lodestone-bench-vdb-io");
    cli::helpLayout(app, 28);
    // 0 skips a case; otherwise the size must be in lo..hi.
    const auto zeroOr = [](long long lo, long long hi) {
      return cli::rule("0 or a whole number in " + std::to_string(lo) + ".." + std::to_string(hi),
                       [lo, hi](const std::string& text) -> std::string {
                         const std::optional<double> v = cli::toNumber(text);
                         if (!v) return "'" + text + "' is not a number";
                         if (*v != std::floor(*v) || !(*v == 0 || (*v >= double(lo) && *v <= double(hi))))
                           return "must be 0 or a whole number in " + std::to_string(lo) + ".." + std::to_string(hi) +
                                  ", got " + text;
                         return "";
                       });
    };
    cli::addNumber(app, "--nodes", nodes, "nodes per axis of the synthetic field set (0 skips it)")
        ->type_name("N")
        ->check(zeroOr(8, 1024))
        ->default_str(cli::formatNumber(nodes));
    cli::addNumber(app, "--solve-nodes", solveNodes, "nodes per axis of the solved field set (0 skips it)")
        ->type_name("N")
        ->check(zeroOr(8, 1024))
        ->default_str(cli::formatNumber(solveNodes));
    cli::addNumber(app, "--particles", particleCount, "particles written and read (0 skips them)")
        ->type_name("P")
        ->check(cli::numberIn(0, 1e9))
        ->default_str(cli::formatNumber(particleCount));
    cli::addNumber(app, "--level-set-res", res, "sphere radius in voxels (0 skips the level sets)")
        ->type_name("R")
        ->check(zeroOr(1, 1000))
        ->default_str(cli::formatNumber(res));
    app.add_option("--dir", dirArg, "where the files go (default: a temporary folder, removed at the end)")
        ->type_name("DIR");
    app.add_option("--csv", csvPath, "CSV output")->type_name("FILE")->default_str(csvPath);
    if (const std::optional<int> code = cli::parse(app, argc, argv)) return *code;
    const bool tempDir = dirArg.empty();
    const fs::path dir =
        tempDir ? fs::temp_directory_path() / ("lodestone_bench_vdb_" + std::to_string(::getpid())) : fs::path(dirArg);
    fs::create_directories(dir);
    initializeVdb();
    Table table(csvPath);
    std::printf("Lodestone VDB file benchmark (%d threads; times in s, sizes in MB; -1: not measured)\n",
                tbb::info::default_concurrency());
    std::printf("%-10s %-58s %10s %9s %9s %9s %9s\n", "case", "what", "items", "convert", "write", "read", "MB");
    if (nodes > 0) fieldSet(table, dir, nodes);
    if (solveNodes > 0) solvedFields(table, dir, solveNodes);
    if (particleCount > 0) particles(table, dir, std::size_t(particleCount));
    if (res > 0) levelSets(table, res);
    if (tempDir) fs::remove_all(dir);
    std::printf("CSV written to %s\n", csvPath.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone-bench-vdb-io: %s\n", e.what());
    return 1;
  }
}
