// lodestone: the command-line host. Runs scene files with the reference
// MLS-MPM and the magnetic-force stage, writes per-frame particles (PLY),
// previews (PNG) and stats.json.
//
//   lodestone run scene.json --out DIR [--frames a:b] [--full] [--dx m] [--threads n]
//   lodestone validate scene.json [--full] [--dx m]
//   lodestone --help | --version
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "lodestone/core/error.h"
#if LODESTONE_HAVE_VDB
#include "lodestone/vdb_io/field_file.h"
#include "lodestone/vdb_io/point_file.h"
#endif
#include "ply_writer.h"
#include "png_writer.h"
#include "preview.h"
#include "progress.h"
#include "scene.h"
#include "stats_json.h"

using namespace lodestone;
using namespace lodestone::examples;

namespace {

const char* kUsage =
    "lodestone " LODESTONE_VERSION_STRING ": nonlinear magnetism for material point method simulation\n"
    "\n"
    "Usage:\n"
    "  lodestone run SCENE.json --out DIR [options]   simulate a scene, write frames and stats.json\n"
    "  lodestone validate SCENE.json [options]        check a scene file and print what it builds\n"
    "  lodestone export-fields SCENE.json --out FILE.vdb [--frame N]\n"
    "                                                 field solve of the state at frame N (default 0),\n"
    "                                                 written as OpenVDB grids n, phi, H, M, B, force\n"
    "  lodestone --help | --version\n"
    "\n"
    "Run `lodestone run --help` for the options. Scene files are documented in docs/scenes.md.\n";

const char* kRunUsage =
    "lodestone run SCENE.json --out DIR [options]\n"
    "\n"
    "Simulates the scene's frames and writes, in DIR:\n"
    "  frame_NNNN.ply   particles (x y z in m, vx vy vz in m/s, n_p, material, J)\n"
    "  frame_NNNN.png   a preview render (magnetic materials dark, magnets red)\n"
    "  fields_NNNN.vdb  the grids listed in the scene's output.vdb (n, phi, H, M, B, force)\n"
    "  particles_NNNN.vdb  the particles as OpenVDB points (when output.vdb_points is true)\n"
    "  stats.json       per-frame time split by stage, field-solve reports, particle\n"
    "                   count and energies (rewritten after every frame)\n"
    "\n"
    "Options:\n"
    "  --out DIR        output directory (created; required)\n"
    "  --frames A:B     write frames A..B (1-based, inclusive; earlier frames are still\n"
    "                   simulated); default all frames of the scene\n"
    "  --full           paper resolution: use the scene's domain.full_dx\n"
    "  --dx M           override the grid spacing, m (> 0)\n"
    "  --threads N      worker threads (0 = all cores; default 0)\n"
    "  --no-png         skip previews;  --no-ply  skip particle files\n";

struct Args {
  std::string command, scene, out;
  int first = 1, last = -1;
  SceneOptions options;
  int threads = 0;
  int frame = 0;  // export-fields
  bool png = true, ply = true;
};

[[noreturn]] void usageError(const std::string& message) {
  throw InvalidArgument(message + " (see lodestone --help)");
}

double parseNumber(const std::string& option, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v)) usageError(concat(option, ": '", text, "' is not a number"));
  return v;
}

Args parseArgs(int argc, char** argv) {
  Args a;
  if (argc < 2) usageError("no command given");
  a.command = argv[1];
  for (int i = 2; i < argc; ++i) {
    const std::string s = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) usageError(concat(s, " needs a value"));
      return argv[++i];
    };
    if (s == "--help" || s == "-h") {
      std::cout << (a.command == "run" ? kRunUsage : kUsage);
      std::exit(0);
    } else if (s == "--out") {
      a.out = value();
    } else if (s == "--frames") {
      const std::string f = value();
      const auto colon = f.find(':');
      if (colon == std::string::npos) usageError(concat("--frames: expected A:B, got '", f, "'"));
      a.first = int(parseNumber("--frames", f.substr(0, colon)));
      a.last = int(parseNumber("--frames", f.substr(colon + 1)));
      if (a.first < 1 || a.last < a.first) usageError(concat("--frames: need 1 <= A <= B, got ", f));
    } else if (s == "--frame") {
      a.frame = int(parseNumber("--frame", value()));
      if (a.frame < 0) usageError(concat("--frame: must be >= 0, got ", a.frame));
    } else if (s == "--full") {
      a.options.full = true;
    } else if (s == "--dx") {
      a.options.dx = parseNumber("--dx", value());
      if (!(a.options.dx > 0)) usageError(concat("--dx: must be > 0 m, got ", a.options.dx));
    } else if (s == "--threads") {
      a.threads = int(parseNumber("--threads", value()));
      if (a.threads < 0 || a.threads > 1024) usageError(concat("--threads: must be 0..1024, got ", a.threads));
    } else if (s == "--no-png") {
      a.png = false;
    } else if (s == "--no-ply") {
      a.ply = false;
    } else if (!s.empty() && s[0] == '-') {
      usageError(concat("unknown option '", s, "'"));
    } else if (a.scene.empty()) {
      a.scene = s;
    } else {
      usageError(concat("unexpected argument '", s, "'"));
    }
  }
  if (a.scene.empty()) usageError(concat("'", a.command, "' needs a scene file"));
  return a;
}

void printSceneSummary(const Scene& scene, const MpmSolver& solver) {
  const GridSpec& g = scene.settings.grid;
  std::printf("scene '%s' (%s)\n", scene.name.c_str(), scene.file.c_str());
  if (!scene.description.empty()) std::printf("  %s\n", scene.description.c_str());
  std::printf("  grid %d x %d x %d nodes, dx = %.4g m, origin (%.4g, %.4g, %.4g) m\n", g.dims.i, g.dims.j, g.dims.k,
              g.dx, g.origin.x, g.origin.y, g.origin.z);
  std::printf("  %zu particles, %zu materials, %zu magnets, %zu colliders, %zu applied fields\n",
              solver.particles().size(), solver.materials().size(), solver.magnetCount(), solver.colliderCount(),
              scene.fields.size());
  for (std::size_t m = 0; m < scene.materials.size(); ++m)
    std::printf("  material '%s': %s\n", scene.materialNames[m].c_str(), scene.materials[m].describe().c_str());
  std::printf("  %d frames at %.4g fps; %s; field solved %s\n", scene.frames, scene.fps,
              scene.settings.fixedDt > 0 ? concat("dt = ", scene.settings.fixedDt, " s").c_str()
                                         : concat("CFL ", scene.settings.cfl, ", dt <= ", scene.settings.dtMax, " s").c_str(),
              scene.settings.magneticSolveInterval == 0
                  ? "once per frame"
                  : concat("every ", scene.settings.magneticSolveInterval, " substeps").c_str());
}

nlohmann::json frameJson(int frame, const MpmFrameReport& r, std::size_t particles, double ioSeconds) {
  nlohmann::json f;
  f["frame"] = frame;
  putQuantity(f, "time", r.time, "s");
  f["substeps"] = r.substeps;
  putQuantity(f, "dt_min", r.minDt, "s");
  putQuantity(f, "dt_max", r.maxDt, "s");
  nlohmann::json stages;
  putQuantity(stages, "p2g", r.secondsP2G, "s");
  putQuantity(stages, "magnetic", r.secondsMagnetic, "s");
  putQuantity(stages, "grid_update", r.secondsGridUpdate, "s");
  putQuantity(stages, "g2p", r.secondsG2P, "s");
  putQuantity(stages, "output", ioSeconds, "s");
  putQuantity(stages, "total", r.secondsTotal + ioSeconds, "s");
  f["stages"] = stages;
  nlohmann::json solves = nlohmann::json::array();
  for (const MagneticStageReport& m : r.magneticReports) {
    nlohmann::json s;
    s["status"] = toString(m.solve.status);
    s["newton_iterations"] = m.solve.newtonIterations;
    s["cg_iterations"] = m.solve.cgIterations;
    s["relative_residual"] = jsonNumber(m.solve.relativeResidual);
    putQuantity(s, "solve", m.secondsSolve, "s");
    putQuantity(s, "stage", m.secondsTotal, "s");
    putQuantity(s, "total_force", m.totalForce, "N");
    s["warnings"] = m.warnings;
    solves.push_back(s);
  }
  f["field_solves"] = solves;
  putCount(f, "particles", std::int64_t(particles));
  putCount(f, "clamped", std::int64_t(r.clamped));
  putCount(f, "removed", std::int64_t(r.removed));
  nlohmann::json e;
  putQuantity(e, "kinetic", r.energies.kinetic, "J");
  putQuantity(e, "gravitational", r.energies.gravitational, "J");
  putQuantity(e, "elastic", r.energies.elastic, "J");
  f["energy"] = e;
  f["warnings"] = r.warnings;
  return f;
}

void writeFields(const std::string& path, const Scene& scene, const MagneticForceStage& stage, int frame,
                 double time) {
#if LODESTONE_HAVE_VDB
  VdbWriteOptions o;
  const auto has = [&](const char* g) {
    return scene.output.vdbFields.empty() ||
           std::find(scene.output.vdbFields.begin(), scene.output.vdbFields.end(), g) != scene.output.vdbFields.end();
  };
  o.fields = {has("n"), has("phi"), has("H"), has("M"), has("B"), has("force")};
  VdbFrameMetadata meta;
  meta.frame = frame;
  meta.time = time;
  writeFieldsVdb(path, stage, meta, o);
#else
  (void)scene, (void)stage, (void)frame, (void)time;
  throw Error(concat("cannot write ", path, ": this lodestone was built without OpenVDB"));
#endif
}

void writeParticles(const std::string& path, const MpmSolver& solver, int frame) {
#if LODESTONE_HAVE_VDB
  PointFileOptions o;
  o.voxelSize = solver.settings().grid.dx;
  o.frame = frame;
  o.time = solver.time();
  writeParticlesVdb(path, solver.particles(), o);
#else
  (void)solver, (void)frame;
  throw Error(concat("cannot write ", path, ": this lodestone was built without OpenVDB"));
#endif
}

void writeFrameFiles(const Args& a, const Scene& scene, const MpmSolver& solver, int frame) {
  char name[64];
  const MpmParticles& p = solver.particles();
  if (a.ply && scene.output.ply) {
    std::snprintf(name, sizeof name, "frame_%04d.ply", frame);
    PlyPointCloud cloud(p.x);
    cloud.addVec3("vx", "vy", "vz", p.v);
    cloud.addFloat("n_p", p.count);
    cloud.addFloat("J", p.J);
    std::vector<std::int32_t> mat(p.material.begin(), p.material.end());
    cloud.addInt("material", mat);
    cloud.addComment(concat("lodestone ", LODESTONE_VERSION_STRING, " scene ", scene.name, " frame ", frame,
                            " time ", solver.time(), " s; units m, m/s"));
    cloud.write((std::filesystem::path(a.out) / name).string());
  }
  if (!scene.output.vdbFields.empty() && solver.magneticStage()) {
    std::snprintf(name, sizeof name, "fields_%04d.vdb", frame);
    writeFields((std::filesystem::path(a.out) / name).string(), scene, *solver.magneticStage(), frame, solver.time());
  }
  if (scene.output.vdbPoints) {
    std::snprintf(name, sizeof name, "particles_%04d.vdb", frame);
    writeParticles((std::filesystem::path(a.out) / name).string(), solver, frame);
  }
  if (a.png && scene.output.png) {
    std::snprintf(name, sizeof name, "frame_%04d.png", frame);
    const RgbImage img = renderPreview(scene, solver);
    writePng((std::filesystem::path(a.out) / name).string(), img.width, img.height, img.rgb.data());
  }
}

int run(const Args& a) {
  if (a.out.empty()) usageError("run needs --out DIR");
  std::unique_ptr<tbb::global_control> threads;
  if (a.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, std::size_t(a.threads));
  const Scene scene = loadScene(a.scene, a.options);
  auto solver = buildSolver(scene);
  printSceneSummary(scene, *solver);
  std::filesystem::create_directories(a.out);
  const int last = a.last < 0 ? scene.frames : std::min(a.last, scene.frames);
  if (a.first > scene.frames) usageError(concat("--frames starts at ", a.first, " but the scene has ", scene.frames));

  nlohmann::json stats;
  stats["scene"] = scene.name;
  stats["scene_file"] = scene.file;
  stats["lodestone_version"] = LODESTONE_VERSION_STRING;
  stats["grid"] = {{"dims", {scene.settings.grid.dims.i, scene.settings.grid.dims.j, scene.settings.grid.dims.k}},
                   {"dx_m", scene.settings.grid.dx}};
  stats["frames"] = nlohmann::json::array();
  const auto t0 = std::chrono::steady_clock::now();
  ProgressPrinter progress(std::cout, last, ProgressOptions{isTerminal(stdout)});
  if (a.first == 1) writeFrameFiles(a, scene, *solver, 0);  // the initial state
  for (int frame = 1; frame <= last; ++frame) {
    const MpmFrameReport r = solver->advanceFrame(scene.frameDuration());
    const auto tio = std::chrono::steady_clock::now();
    if (frame >= a.first) writeFrameFiles(a, scene, *solver, frame);
    const double io = std::chrono::duration<double>(std::chrono::steady_clock::now() - tio).count();
    stats["frames"].push_back(frameJson(frame, r, solver->particles().size(), io));
    writeJsonFile((std::filesystem::path(a.out) / "stats.json").string(), stats);
    for (const MagneticStageReport& m : r.magneticReports)
      if (!m.converged()) progress.message(concat("frame ", frame, ": ", m.solve.message));
    for (const std::string& w : r.warnings) progress.message(concat("frame ", frame, ": ", w));
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    progress.update(frame, elapsed,
                    formatStageSplit({{"p2g", r.secondsP2G}, {"magnetic", r.secondsMagnetic},
                                      {"grid", r.secondsGridUpdate}, {"g2p", r.secondsG2P}, {"output", io}}));
  }
  progress.finish();
  std::printf("wrote frames %d..%d to %s (stats.json has the per-frame details)\n", a.first, last, a.out.c_str());
  return 0;
}

int exportFields(const Args& a) {
  if (a.out.empty()) usageError("export-fields needs --out FILE.vdb");
  const Scene scene = loadScene(a.scene, a.options);
  auto solver = buildSolver(scene);
  for (int f = 0; f < a.frame && f < scene.frames; ++f) solver->advanceFrame(scene.frameDuration());
  // One field solve of this state, through the stage's public entry point.
  const MpmParticles& p = solver->particles();
  std::vector<std::uint32_t> magnetic;
  const MpmMaterial* law = nullptr;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (solver->materials()[p.material[i]].isMagnetic()) magnetic.push_back(std::uint32_t(i));
  for (const MpmMaterial& m : solver->materials())
    if (m.isMagnetic()) law = &m;
  if (!law) throw InvalidArgument(concat(a.scene, ": the scene has no magnetic material; there is no field to export"));
  std::vector<Vec3d> x;
  std::vector<double> n;
  for (std::uint32_t i : magnetic) {
    x.push_back(p.x[i]);
    n.push_back(p.count[i]);
  }
  const GridSpec grid = scene.settings.magneticGrid ? *scene.settings.magneticGrid : scene.settings.grid;
  MagneticStageSettings settings = scene.settings.magnetic;
  settings.outOfGrid = OutOfGridPolicy::Skip;
  MagneticForceStage stage(grid, law->magnetic, settings);
  const MagneticStageReport rep = stage.run({x.data(), n.data(), x.size()}, solver->appliedField(), solver->time());
  std::printf("%s", rep.summary().c_str());
  writeFields(a.out, scene, stage, a.frame, solver->time());
  std::printf("wrote %s (frame %d, t = %g s)\n", a.out.c_str(), a.frame, solver->time());
  return rep.converged() ? 0 : 1;
}

int validate(const Args& a) {
  const Scene scene = loadScene(a.scene, a.options);
  auto solver = buildSolver(scene);
  printSceneSummary(scene, *solver);
  std::printf("%s: valid\n", a.scene.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc >= 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
      std::cout << kUsage;
      return 0;
    }
    if (argc >= 2 && std::string(argv[1]) == "--version") {
      std::cout << "lodestone " << LODESTONE_VERSION_STRING << "\n";
      return 0;
    }
    const Args a = parseArgs(argc, argv);
    if (a.command == "run") return run(a);
    if (a.command == "validate") return validate(a);
    if (a.command == "export-fields") return exportFields(a);
    usageError(concat("unknown command '", a.command, "'"));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone: %s\n", e.what());
    return 1;
  }
}
