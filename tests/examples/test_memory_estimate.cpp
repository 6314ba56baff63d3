// The memory estimate of `lodestone run` (plugin/memory_estimate.h) against
// the peak resident memory the run measures, both from its stats.json: within
// 20% for scenes where one part dominates in turn (the MPM grid, the field
// solve, the particles, magnetic particles, the surface outputs), so a wrong
// figure for that part shows. The command's path comes from LODESTONE_CLI,
// the example scenes from LODESTONE_SCENES_DIR.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <nlohmann/json.hpp>

#include "lodestone_test/scratch_dir.h"

namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) { return lodestone::test::scratchDir("memory", name); }

nlohmann::json readJson(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

/// The cube scene without magnetism or with, its body of half-size `half` (m)
/// and the grid at `dx` (m), written into `dir`.
fs::path cubeScene(const fs::path& dir, double dx, double half, bool magnetic) {
  nlohmann::json s = readJson(fs::path(LODESTONE_SCENES_DIR) / "cube_langevin.json");
  s["domain"]["dx"] = dx;
  s["bodies"][0]["half_size"] = {half, half, 0.6 * half};
  s["bodies"][0]["center"] = {0, 0, 0.4 + 0.6 * half};
  if (!magnetic) {
    s["materials"][0].erase("magnetic");
    s["magnets"] = nlohmann::json::array();
    s.erase("magnetic");
  }
  const fs::path path = dir / "scene.json";
  std::ofstream(path) << s.dump(1);
  return path;
}

struct Memory {
  double estimated = 0, peak = 0, mpmGrid = 0, fieldSolve = 0, particles = 0;
};

/// What the run in `dir` printed.
std::string logOf(const fs::path& dir) {
  std::ifstream in(dir / "log.txt");
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// Runs frame 1 of `scene` with `args` into `dir`; the memory of its stats.json.
Memory run(const fs::path& scene, const fs::path& dir, const std::string& args) {
  const std::string command = std::string(LODESTONE_CLI) + " run '" + scene.string() + "' --out '" +
                              (dir / "out").string() + "' --frames 1:1 --threads 2 " + args + " > '" +
                              (dir / "log.txt").string() + "' 2>&1";
  const int status = std::system(command.c_str());
  if (status != 0) {
    ADD_FAILURE() << command << " exited with status " << status << ":\n" << logOf(dir);
  }
  const nlohmann::json stats = readJson(dir / "out" / "stats.json");
  // The binning is a part of P2G, reported on its own.
  const nlohmann::json& stages = stats.at("frames").back().at("stages");
  EXPECT_GT(stages.at("p2g_binning_s").get<double>(), 0.0);
  EXPECT_LT(stages.at("p2g_binning_s").get<double>(), stages.at("p2g_s").get<double>());
  const nlohmann::json& m = stats.at("memory");
  Memory r;
  r.estimated = m.at("estimated_peak_bytes").get<double>();
  r.peak = m.at("peak_resident_bytes").get<double>();
  r.mpmGrid = m.at("estimated_mpm_grid_bytes").get<double>();
  r.fieldSolve = m.at("estimated_field_solve_bytes").get<double>();
  r.particles = m.at("estimated_particles_bytes").get<double>();
  // The parts stats.json lists add up to its total.
  EXPECT_DOUBLE_EQ(r.mpmGrid + r.fieldSolve + r.particles + m.at("estimated_frame_files_bytes").get<double>() +
                       m.at("process_before_bytes").get<double>(),
                   r.estimated);
  return r;
}

/// `scene` (its first body) with a copy of that body named "far": the
/// first centred at `a`, the copy at `b` (m), written to dir/scene.json and
/// run with `args`.
Memory runApart(const fs::path& dir, nlohmann::json scene, const std::array<double, 3>& a,
                const std::array<double, 3>& b, const std::string& args) {
  scene["bodies"][0]["center"] = a;
  nlohmann::json far = scene["bodies"][0];
  far["name"] = "far";
  far["center"] = b;
  scene["bodies"].push_back(far);
  std::ofstream(dir / "scene.json") << scene.dump(1);
  return run(dir / "scene.json", dir, args);
}

/// The estimate within 20% of the peak, and `part` (bytes) at least
/// `share` of it, so that the part's own figure is what is checked.
void expectClose(const Memory& m, double part, double share) {
  std::printf("estimated %.1f MB, peak %.1f MB (ratio %.3f), the part checked %.0f%% of the estimate\n",
              m.estimated / 1e6, m.peak / 1e6, m.peak / m.estimated, 100 * part / m.estimated);
  EXPECT_GT(m.peak, 0);
  EXPECT_NEAR(m.estimated / m.peak, 1.0, 0.2) << "estimated " << m.estimated / 1e6 << " MB, peak " << m.peak / 1e6
                                              << " MB";
  EXPECT_GE(part, share * m.estimated) << "the case does not exercise its part";
}

/// One case of the cube scene: its body of half-size `half` (m) at `dx` (m),
/// magnetic or not, run with `args`; the estimate's part `part` of it must
/// be at least `share` of the total and the estimate within 20%.
Memory cubeCase(const std::string& name, double dx, double half, bool magnetic, const std::string& args,
                double Memory::*part, double share) {
  const fs::path dir = scratch(name);
  const Memory m = run(cubeScene(dir, dx, half, magnetic), dir, args);
  expectClose(m, m.*part, share);
  return m;
}

TEST(MemoryEstimate, TwoSmallBodiesFarApartCostTheirOwnRowsNotTheBoxBetween) {
  // Two 6 cm cubes at opposite corners of the 129^3 grid (2.1M nodes at
  // dx = 7.8 mm): the box the material reaches is most of the grid (134 MB
  // at 64 B a node), but the MPM grid holds memory only for each x-row's
  // run of nodes that stencils reach (mpm/grid.h): the cubes' own rows.
  const fs::path dir = scratch("mpm_grid");
  cubeScene(dir, 0.0078, 0.03, false);
  const Memory m =
      runApart(dir, readJson(dir / "scene.json"), {-0.42, -0.42, 0.06}, {0.42, 0.42, 0.92}, "--no-png --no-ply");
  expectClose(m, m.mpmGrid, 0.0);
  EXPECT_GT(m.mpmGrid, 0);
  EXPECT_LT(m.mpmGrid, 0.02 * 129.0 * 129.0 * 129.0 * 64) << "the estimate counts the box between the bodies";
  EXPECT_LT(m.peak, 100e6) << "the grid held the box between the bodies";
  EXPECT_EQ(m.fieldSolve, 0) << "nothing magnetic: no field solve";
}

TEST(MemoryEstimate, ASmallBodyInALargeBoxCostsItsOwnBox) {
  // One 6 cm cube in a 257^3 grid (17M nodes, 1.1 GB if the grid were held
  // whole): the grid holds the cube's box, the estimate says so.
  const Memory m = cubeCase("small_body", 0.0039, 0.03, false, "--no-png --no-ply", &Memory::particles, 0.0);
  EXPECT_LT(m.mpmGrid, 0.01 * 257.0 * 257.0 * 257.0 * 64) << "the estimate counts the whole grid";
  EXPECT_LT(m.peak, 150e6);
}

TEST(MemoryEstimate, FieldSolveOfASmallBodyInALargeGrid) {
  // The field solve's 105^3 grid (1.16M nodes) dominates.
  cubeCase("field", 0.0104, 0.03, true, "--no-ply", &Memory::fieldSolve, 0.6);
}

TEST(MemoryEstimate, ManyParticles) {
  // 0.5M particles of a non-magnetic solid on a 65^3 grid.
  cubeCase("particles", 0.0156, 0.36, false, "--no-png --no-ply", &Memory::particles, 0.6);
}

TEST(MemoryEstimate, ManyMagneticParticles) {
  // The same particles, magnetic: the stage's per-particle data on top, and
  // the field solve's data per material cell (77,500 cells, 18% of the estimate).
  cubeCase("magnetic_particles", 0.0156, 0.36, true, "--no-png --no-ply", &Memory::particles, 0.4);
}

TEST(MemoryEstimate, SurfaceOutputs) {
  // A ferrofluid layer (1.4e5 particles) meshed and written as render volumes.
  const fs::path dir = scratch("surface");
  const Memory m =
      run(fs::path(LODESTONE_SCENES_DIR) / "ferrofluid_3d.json", dir, "--full --outputs surface,mesh,volume");
  expectClose(m, m.estimated - m.mpmGrid - m.fieldSolve - m.particles, 0.25);
}

}  // namespace

TEST(MemoryEstimate, TwoMagneticBodiesFarApartCostTheirPatches) {
  // Two 6 cm magnetic cubes at opposite corners of the 129^3 grid, each
  // above a magnet of its own, with the effects planner: the field solve
  // runs on a patch around each (planner.patches), not on the box between
  // them (most of the grid, 0.77 GB at 356 B a node). The estimate counts
  // the patches; were the whole grid solved, the peak would be 8x it.
  const fs::path dir = scratch("patches");
  cubeScene(dir, 0.0078, 0.03, true);
  nlohmann::json s = readJson(dir / "scene.json");
  s["planner"] = nlohmann::json::object();
  s["bodies"][0]["center"] = {-0.4, -0.4, 0.3};
  nlohmann::json second = s["bodies"][0];
  second["name"] = "far";
  second["center"] = {0.4, 0.4, 0.8};
  s["bodies"].push_back(second);
  nlohmann::json magnet = s["magnets"][0];
  magnet["radius"] = 0.04;
  magnet["half_length"] = 0.02;
  magnet["center"] = {-0.4, -0.4, 0.22};
  s["magnets"][0] = magnet;
  magnet["center"] = {0.4, 0.4, 0.72};
  s["magnets"].push_back(magnet);
  std::ofstream(dir / "scene.json") << s.dump(1);
  const Memory m = run(dir / "scene.json", dir, "--no-png --no-ply");
  const std::string log = logOf(dir);
  EXPECT_NE(log.find("patches: on (2 patches)"), std::string::npos) << log;
  EXPECT_GT(m.fieldSolve, 0);
  EXPECT_LT(m.fieldSolve, 0.1 * 129.0 * 129.0 * 129.0 * 356) << "the estimate counts the box between the bodies";
  expectClose(m, m.fieldSolve, 0.0);
}

namespace {

/// A box of material, one point a cell, no magnetism or gravity, in a
/// 257^3 grid over a 2 m box: half-size `half` (cells), its z axis along
/// `axis`. Returns the scene file.
fs::path slabScene(const fs::path& dir, const std::array<double, 3>& half, const std::array<double, 3>& axis) {
  nlohmann::json s = readJson(fs::path(LODESTONE_SCENES_DIR) / "cube_langevin.json");
  const double dx = 2.0 / 256;
  s["domain"] = {{"min", {0, 0, 0}}, {"max", {2, 2, 2}}, {"dx", dx}};
  s["materials"][0].erase("magnetic");
  s["magnets"] = nlohmann::json::array();
  s.erase("magnetic");
  s["gravity"] = {0, 0, 0};
  s["bodies"][0]["center"] = {1.0, 1.0, 1.0};
  s["bodies"][0]["half_size"] = {half[0] * dx, half[1] * dx, half[2] * dx};
  s["bodies"][0]["axis"] = {axis[0], axis[1], axis[2]};
  s["bodies"][0]["particles_per_cell"] = 1;
  std::ofstream(dir / "scene.json") << s.dump(1);
  return dir / "scene.json";
}

}  // namespace

TEST(MemoryEstimate, ASheetSlantedAcrossXCostsItsRuns) {
  // A sheet 2 cells thick, 250 x 250 cells across, one point a cell, in a
  // 257^3 grid, its normal at 45 degrees between x and z: each x-row's run
  // is about 5 nodes of a box about 180 nodes wide along x. The runs are
  // packed (mpm/grid.h), so the grid costs its runs' 56 B a node, the bins'
  // offsets and the rows' bookkeeping, where a page a row of each node array
  // would be 0.4 GB. Estimated within 20% (mpmHeldBytes), and no note.
  const fs::path dir = scratch("sheet");
  const Memory m = run(slabScene(dir, {90, 125, 1}, {1, 0, 1}), dir, "--no-png --no-ply");
  expectClose(m, m.mpmGrid, 0.1);
  EXPECT_LT(m.mpmGrid, 60e6) << "the sheet's runs took a page each";
  const std::string log = logOf(dir);
  EXPECT_EQ(log.find("note: the MPM grid"), std::string::npos) << log;
}

TEST(MemoryEstimate, TwoSmallBodiesFarApartSayWhatTheirRowsCost) {
  // Two cubes 12 cells wide at opposite corners of an 8 m box (1025^3
  // nodes): the grid keeps 40 B for each of the about 1000^2 x-rows of the
  // box around both (about 40 MB), where the cubes' own runs take 2 MB.
  // Estimated within 20%, and the CLI says why the grid costs that.
  const fs::path dir = scratch("apart");
  nlohmann::json s = readJson(slabScene(dir, {6, 6, 6}, {0, 0, 1}));
  s["domain"] = {{"min", {0, 0, 0}}, {"max", {8, 8, 8}}, {"dx", 8.0 / 1024}};
  const Memory m = runApart(dir, s, {0.2, 0.2, 0.2}, {7.8, 7.8, 7.8}, "--no-png --no-ply");
  expectClose(m, m.mpmGrid, 0.2);
  const std::string log = logOf(dir);
  EXPECT_NE(log.find("note: the MPM grid takes"), std::string::npos) << log;
  EXPECT_NE(log.find("bodies far apart along y or z"), std::string::npos) << log;
}

TEST(MemoryEstimate, APlateThinAlongXCostsItsBox) {
  // A plate 2 cells thick along x, 250 x 250 cells across, one point a cell,
  // in a 257^3 grid: its x-rows' runs of 5 nodes are packed (about 20 MB;
  // a page a row of each array in rows as wide as the grid would be
  // 0.5 GB). Estimated within 20%, and no note.
  const fs::path dir = scratch("plate");
  const Memory m = run(slabScene(dir, {1, 125, 125}, {0, 0, 1}), dir, "--no-png --no-ply");
  expectClose(m, m.mpmGrid, 0.1);
  EXPECT_LT(m.mpmGrid, 60e6) << "the plate's rows took a page each";
  const std::string log = logOf(dir);
  EXPECT_EQ(log.find("note: the MPM grid"), std::string::npos) << log;
}
