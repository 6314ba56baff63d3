// lodestone: the command-line host. Runs scene files with the reference
// MLS-MPM and the magnetic-force stage, writes per-frame particles (PLY),
// previews (PNG) and stats.json. Its commands and options are declared in
// parseArgs(); `lodestone --help` and `lodestone COMMAND --help` print them.
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <tbb/global_control.h>

#include "lodestone/cli/command_line.h"

#include "lodestone/plugin/output/atomic_file.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/checkpoint.h"
#include "lodestone/plugin/node_registry.h"
#include "lodestone/plugin/scene.h"
#if LODESTONE_HAVE_VDB
#include "lodestone/vdb_io/field_file.h"
#include "lodestone/vdb_io/level_set_file.h"
#include "lodestone/vdb_io/point_file.h"
#endif
#include "lodestone/plugin/output/ply_writer.h"
#include "lodestone/plugin/output/png_writer.h"
#include "preview.h"
#include "lodestone/plugin/output/progress.h"
#include "plan_report.h"
#include "lodestone/plugin/output/stats_json.h"

using namespace lodestone;
using namespace lodestone::examples;
using namespace lodestone::output;
using namespace lodestone::plugin;

namespace {

struct Args {
  std::string command, scene, out;
  int first = 1, last = -1;
  SceneOptions options;
  int threads = 0;
  int frame = 0;  // export-fields
  std::string density, densityGrid = "n";  // export-fields: n (1/m^3) from a .vdb instead of the particles
  bool png = true, ply = true;
  int checkpointEvery = -1;  // -1: the scene's output.checkpoint_every
  bool resume = false, checkFinite = false;
  bool markdown = false;  // nodes
};

[[noreturn]] void usageError(const std::string& message) {
  throw InvalidArgument(message + " (see lodestone --help)");
}

/// Readers for the scene's "level_set" and "mesh" shapes (none without OpenVDB).
void installShapeLoaders(SceneOptions& options) {
#if LODESTONE_HAVE_VDB
  options.loaders.levelSet = [](const std::string& path, const std::string& grid) {
    return std::make_shared<const SampledSdf>(readLevelSetVdb(path, grid));
  };
  options.loaders.mesh = [](const std::string& path, double voxelSize) {
    return std::make_shared<const SampledSdf>(levelSetFromObj(path, voxelSize));
  };
#else
  (void)options;
#endif
}

// "A:B", 1 <= A <= B, into first and last; returns the error ("" when good).
std::string readFrameRange(const std::string& text, int& first, int& last) {
  const auto colon = text.find(':');
  if (colon == std::string::npos) return concat("expected A:B, got '", text, "'");
  for (const std::string& part : {text.substr(0, colon), text.substr(colon + 1)}) {
    const std::optional<double> v = cli::toNumber(part);
    if (!v) return concat("'", part, "' is not a number");
    if (*v != std::floor(*v) || std::fabs(*v) > 1e9) return concat("'", part, "' is not a whole number of frames");
  }
  first = int(*cli::toNumber(text.substr(0, colon)));
  last = int(*cli::toNumber(text.substr(colon + 1)));
  if (first < 1 || last < first) return concat("need 1 <= A <= B, got ", text);
  return "";
}

/// The commands and their options, declared once: the help text is generated
/// from these declarations. Fills `a`; returns the code to exit with after
/// --help, --version or a bad argument (message on stderr), nullopt to go on.
std::optional<int> parseArgs(int argc, char** argv, Args& a) {
  CLI::App app("lodestone " LODESTONE_VERSION_STRING ": nonlinear magnetism for material point method simulation",
               "lodestone");
  cli::helpLayout(app);
  app.set_version_flag("--version", "lodestone " LODESTONE_VERSION_STRING, "print the version and exit");
  app.require_subcommand(0, 1);

  const auto addScene = [&](CLI::App& c) {
    c.add_option("SCENE", a.scene, "scene file (JSON, docs/scenes.md)")->required()->type_name("");
  };
  const auto addResolution = [&](CLI::App& c) {
    c.add_flag("--full", a.options.full, "paper resolution: use the scene's domain.full_dx");
    cli::addNumber(c, "--dx", a.options.dx, "override the grid spacing, m")
        ->type_name("M")
        ->check(cli::numberAbove(0, "m"));
  };

  CLI::App& run = *app.add_subcommand("run", "simulate a scene, write frames and stats.json");
  addScene(run);
  run.add_option("--out", a.out, "output directory (created)")->required()->type_name("DIR");
  run.add_option_function<std::string>(
         "--frames", [&](const std::string& f) { readFrameRange(f, a.first, a.last); },
         "write frames A..B (1-based, inclusive; earlier frames are still simulated); default all frames of the scene")
      ->type_name("A:B")
      ->check(cli::rule("", [](const std::string& f) {
        int first = 0, last = 0;
        return readFrameRange(f, first, last);
      }));
  addResolution(run);
  cli::addNumber(run, "--threads", a.threads, "worker threads (0 = all cores)")
      ->type_name("N")
      ->check(cli::wholeNumber(0, 1024))
      ->default_str(cli::formatNumber(a.threads));
  run.add_flag_callback("--no-png", [&] { a.png = false; }, "skip previews");
  run.add_flag_callback("--no-ply", [&] { a.ply = false; }, "skip particle files");
  cli::addNumber(run, "--checkpoint-every", a.checkpointEvery,
                 "write DIR/checkpoint_NNNN.lsck every N frames (overrides the scene's output.checkpoint_every; "
                 "0 = none)")
      ->type_name("N")
      ->check(cli::wholeNumber(0, 1000000, "frames"));
  run.add_flag("--resume", a.resume,
               "continue from the last valid checkpoint in DIR; the frames it writes equal those of an "
               "uninterrupted run, bit for bit");
  run.add_flag("--check-finite", a.checkFinite,
               "stop with an error naming the quantity, substep and particle or node at the first NaN/Inf "
               "(one extra scan per substep)");
  run.footer(
      "Writes, in DIR:\n"
      "  frame_NNNN.ply      particles (x y z in m, vx vy vz in m/s, n_p, material, J)\n"
      "  frame_NNNN.png      a preview render (magnetic materials dark, magnets red)\n"
      "  fields_NNNN.vdb     the grids listed in the scene's output.vdb (n, phi, H, M, B, force)\n"
      "  particles_NNNN.vdb  the particles as OpenVDB points (when output.vdb_points is true)\n"
      "  stats.json          per-frame time split by stage, field-solve reports, particle\n"
      "                      count and energies (rewritten after every frame)\n"
      "\n"
      "Ctrl-C stops after the current substep, keeps every complete frame and says how\n"
      "to resume; a second Ctrl-C exits at once.");

  CLI::App& validate = *app.add_subcommand("validate", "check a scene file and print what it builds");
  addScene(validate);
  addResolution(validate);

  CLI::App& plan = *app.add_subcommand(
      "plan", "print which stages would run, why, at what predicted error and cost (the effects planner), "
              "without running");
  addScene(plan);
  addResolution(plan);

  CLI::App& exportFields = *app.add_subcommand(
      "export-fields", "field solve of the state at frame N, written as OpenVDB grids n, phi, H, M, B, force");
  addScene(exportFields);
  exportFields.add_option("--out", a.out, "the .vdb file to write")->required()->type_name("FILE.vdb");
  cli::addNumber(exportFields, "--frame", a.frame, "the state after N frames of the scene")
      ->type_name("N")
      ->check(cli::wholeNumber(0))
      ->default_str(cli::formatNumber(a.frame));
  exportFields
      .add_option("--density", a.density,
                  "solve for the density grid of this file (n, 1/m^3) instead of the scene's particles")
      ->type_name("N.vdb");
  exportFields.add_option("--density-grid", a.densityGrid, "the grid of --density to read")
      ->type_name("G")
      ->capture_default_str();
  addResolution(exportFields);

  CLI::App& nodes = *app.add_subcommand("nodes", "list the node library");
  nodes.add_flag("--markdown", a.markdown, "as Markdown (docs/nodes.md is this output)");

  // After the subcommands, which would take it over.
  app.footer("Run `lodestone COMMAND --help` for a command's options. Scene files are documented in docs/scenes.md.");
  if (const std::optional<int> code = cli::parse(app, argc, argv)) return code;
  if (app.get_subcommands().empty()) {
    std::cerr << "lodestone: no command given (see lodestone --help)\n";
    return 1;
  }
  a.command = app.get_subcommands().front()->get_name();
  installShapeLoaders(a.options);
  return std::nullopt;
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
    putQuantity(s, "transfer", m.secondsTransfer, "s");
    putQuantity(s, "applied_field", m.secondsAppliedField, "s");
    s["applied_field_reused"] = m.appliedFieldReused;
    putQuantity(s, "nodal_fields", m.secondsFields, "s");
    putQuantity(s, "force", m.secondsForce, "s");
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

#if LODESTONE_HAVE_VDB
/// The MPM grid's node mass (kg) and velocity (m/s) after the last substep;
/// zero outside the box the last transfer touched (all zero before the first).
void mpmGridData(const MpmSolver& solver, DenseGrid<double>& mass, DenseGrid<Vec3d>& velocity) {
  const MpmGrid& g = solver.grid();
  const GridSpec& s = g.spec();
  mass.reset(s, 0.0);
  velocity.reset(s, Vec3d{});
  if (g.nodes().size() != s.nodeCount() || g.velocity().size() != s.nodeCount()) return;
  const Index3 lo = g.activeLo(), hi = g.activeHi();
  for (int k = lo.k; k < hi.k; ++k)
    for (int j = lo.j; j < hi.j; ++j)
      for (int i = lo.i; i < hi.i; ++i) {
        const std::size_t n = s.index(i, j, k);
        if (!(g.nodes()[n].mass > 0)) continue;
        mass(i, j, k) = g.nodes()[n].mass;
        velocity(i, j, k) = g.velocity()[n];
      }
}
#endif

/// `solver` (may be null) supplies the MPM grid's mass and velocity when the
/// scene's output.vdb lists them.
void writeFields(const std::string& path, const Scene& scene, const MagneticForceStage& stage, int frame,
                 double time, const MpmSolver* solver = nullptr) {
#if LODESTONE_HAVE_VDB
  VdbWriteOptions o;
  const auto listed = [&](const char* g) {
    return std::find(scene.output.vdbFields.begin(), scene.output.vdbFields.end(), g) != scene.output.vdbFields.end();
  };
  const auto has = [&](const char* g) { return scene.output.vdbFields.empty() || listed(g); };
  o.fields = {has("n"), has("phi"), has("H"), has("M"), has("B"), has("force")};
  o.fields.mass = listed("mass");
  o.fields.velocity = listed("velocity");
  o.displayAliases = scene.output.vdbAliases;
  DenseGrid<double> mass;
  DenseGrid<Vec3d> velocity;
  if (solver && (o.fields.mass || o.fields.velocity || o.displayAliases)) {
    mpmGridData(*solver, mass, velocity);
    o.mpm = {mass.view(), velocity.view()};
  }
  require(solver || !(o.fields.mass || o.fields.velocity), path, ": the mass and velocity grids need a simulated state");
  VdbFrameMetadata meta;
  meta.frame = frame;
  meta.time = time;
  writeFieldsVdb(path, stage, meta, o);
#else
  (void)scene, (void)stage, (void)frame, (void)time, (void)solver;
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
    writeFields((std::filesystem::path(a.out) / name).string(), scene, *solver.magneticStage(), frame, solver.time(),
                &solver);
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

// Ctrl-C / SIGTERM: the first asks the run to stop after the current
// substep; the handler then restores the default, so a second one exits.
volatile std::sig_atomic_t gStopRequested = 0;
extern "C" void onStopSignal(int sig) {
  gStopRequested = 1;
  std::signal(sig, SIG_DFL);
}

std::string checkpointName(int frame) {
  char name[64];
  std::snprintf(name, sizeof name, "checkpoint_%04d.lsck", frame);
  return name;
}

// What a checkpoint must match: the scene and the options that change the
// simulation (grid spacing, --full).
std::string checkpointTag(const Scene& scene) {
  const GridSpec& g = scene.settings.grid;
  char buf[256];
  std::snprintf(buf, sizeof buf, " grid %dx%dx%d dx %.17g m", g.dims.i, g.dims.j, g.dims.k, g.dx);
  return scene.name + buf;
}

std::vector<std::uint8_t> readBytes(const std::filesystem::path& path) {
  std::FILE* f = std::fopen(path.string().c_str(), "rb");
  if (!f) throw Error(concat("cannot open '", path.string(), "'"));
  std::vector<std::uint8_t> bytes;
  std::uint8_t buf[1 << 16];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) bytes.insert(bytes.end(), buf, buf + n);
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) throw Error(concat("cannot read '", path.string(), "'"));
  return bytes;
}

// Restores the newest checkpoint in `dir` that reads back whole (a corrupted
// or foreign one is reported and the next older tried); returns its frame.
int resumeFromCheckpoint(const std::string& dir, const Scene& scene, MpmSolver& solver) {
  std::vector<std::pair<int, std::filesystem::path>> found;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    int frame = -1;
    char tail[8] = {};
    if (std::sscanf(name.c_str(), "checkpoint_%d.%7s", &frame, tail) == 2 && std::string(tail) == "lsck" &&
        frame >= 0 && name == checkpointName(frame))
      found.emplace_back(frame, e.path());
  }
  if (ec) throw Error(concat("--resume: cannot list '", dir, "' (", ec.message(), ")"));
  std::sort(found.rbegin(), found.rend());
  for (const auto& [frame, path] : found) {
    try {
      const std::vector<std::uint8_t> bytes = readBytes(path);
      const MpmCheckpointInfo info = restoreMpmCheckpoint(solver, bytes.data(), bytes.size(), checkpointTag(scene));
      if (info.frame != frame) throw InvalidArgument(concat("it holds frame ", info.frame));
      std::printf("resuming from %s: frame %d, t = %.6g s, %zu particles\n", path.string().c_str(), frame, info.time,
                  info.particles);
      return frame;
    } catch (const Error& e) {
      std::fprintf(stderr, "lodestone: skipping %s: %s\n", path.string().c_str(), e.what());
    }
  }
  throw Error(concat("--resume: no usable checkpoint_NNNN.lsck in '", dir,
                     "' (write them with output.checkpoint_every or --checkpoint-every N)"));
}

int run(const Args& a) {
  if (a.out.empty()) usageError("run needs --out DIR");
  std::unique_ptr<tbb::global_control> threads;
  if (a.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, std::size_t(a.threads));
  Scene scene = loadScene(a.scene, a.options);
  if (a.checkFinite) scene.settings.checkFinite = true;
  auto solver = buildSolver(scene);
  printSceneSummary(scene, *solver);
  printPlan(scene, *solver, stdout);
  std::string planShown;
  std::filesystem::create_directories(a.out);
  const int last = a.last < 0 ? scene.frames : std::min(a.last, scene.frames);
  if (a.first > scene.frames) usageError(concat("--frames starts at ", a.first, " but the scene has ", scene.frames));
  const int checkpointEvery = a.checkpointEvery >= 0 ? a.checkpointEvery : scene.output.checkpointEvery;
  const int startFrame = a.resume ? resumeFromCheckpoint(a.out, scene, *solver) : 0;

  nlohmann::json stats;
  stats["scene"] = scene.name;
  stats["scene_file"] = scene.file;
  stats["lodestone_version"] = LODESTONE_VERSION_STRING;
  stats["grid"] = {{"dims", {scene.settings.grid.dims.i, scene.settings.grid.dims.j, scene.settings.grid.dims.k}},
                   {"dx_m", scene.settings.grid.dx}};
  stats["frames"] = nlohmann::json::array();
  const std::filesystem::path statsPath = std::filesystem::path(a.out) / "stats.json";
  if (startFrame > 0 && std::filesystem::exists(statsPath)) {
    // Keep the per-frame records up to the checkpoint.
    try {
      const std::vector<std::uint8_t> bytes = readBytes(statsPath);
      const nlohmann::json old = nlohmann::json::parse(bytes.begin(), bytes.end());
      for (const nlohmann::json& f : old.at("frames"))
        if (f.at("frame").get<int>() <= startFrame) stats["frames"].push_back(f);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "lodestone: %s could not be read (%s); it restarts at frame %d\n",
                   statsPath.string().c_str(), e.what(), startFrame + 1);
    }
  }
  int lastCheckpoint = startFrame > 0 ? startFrame : -1;
  const auto stopMessage = [&](int frame, double time, bool midFrame) {
    std::string how = lastCheckpoint >= 0
                          ? concat("resume from ", checkpointName(lastCheckpoint), " (frame ", lastCheckpoint,
                                   ") with: lodestone run ", a.scene, " --out ", a.out, " --resume")
                          : std::string("no checkpoint was written (use --checkpoint-every N or "
                                        "output.checkpoint_every); run again to start over");
    std::printf("\ninterrupted: stopped %s frame %d at t = %.6g s; frames up to %d are complete in %s; %s\n",
                midFrame ? "during" : "after", frame, time, midFrame ? frame - 1 : frame, a.out.c_str(), how.c_str());
  };
  std::signal(SIGINT, onStopSignal);
  std::signal(SIGTERM, onStopSignal);
  const MpmProgressCallback keepGoing = [](const MpmProgress&) { return gStopRequested == 0; };
  const auto t0 = std::chrono::steady_clock::now();
  ProgressPrinter progress(std::cout, last, ProgressOptions{isTerminal(stdout)});
  if (a.first == 1 && startFrame == 0) writeFrameFiles(a, scene, *solver, 0);  // the initial state
  for (int frame = startFrame + 1; frame <= last; ++frame) {
    const MpmFrameReport r = solver->advanceFrame(scene.frameDuration(), keepGoing);
    if (r.cancelled) {
      progress.finish();
      stopMessage(frame, solver->time(), true);
      return 130;
    }
    const auto tio = std::chrono::steady_clock::now();
    if (frame >= a.first) writeFrameFiles(a, scene, *solver, frame);
    const double io = std::chrono::duration<double>(std::chrono::steady_clock::now() - tio).count();
    stats["frames"].push_back(frameJson(frame, r, solver->particles().size(), io));
    if (scene.settings.planner.enabled) {
      // Every decision in stats.json; a line when one changes.
      const MagneticPlan& plan = solver->lastMagneticPlan();
      stats["frames"].back()["planner"] = {{"decisions", decisionsJson(plan.decisions)},
                                           {"predicted_error", plan.predictedError},
                                           {"field_solves_reused", r.magneticReused}};
      const std::string sig = planSignature(plan);
      if (!plan.decisions.empty() && sig != planShown) {
        if (!planShown.empty()) progress.message(concat("frame ", frame, ": plan changed\n", plan.summary()));
        planShown = sig;
      }
    }
    writeJsonFile(statsPath.string(), stats);
    if (checkpointEvery > 0 && frame % checkpointEvery == 0) {
      writeFileAtomically((std::filesystem::path(a.out) / checkpointName(frame)).string(),
                          saveMpmCheckpoint(*solver, frame, checkpointTag(scene)));
      // A resumed solver starts its next field solve from phi = 0: so does this one.
      solver->resetMagneticWarmStart();
      lastCheckpoint = frame;
    }
    for (const MagneticStageReport& m : r.magneticReports)
      if (!m.converged()) progress.message(concat("frame ", frame, ": ", m.solve.message));
    for (const std::string& w : r.warnings) progress.message(concat("frame ", frame, ": ", w));
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    progress.update(frame, elapsed,
                    formatStageSplit({{"p2g", r.secondsP2G}, {"magnetic", r.secondsMagnetic},
                                      {"grid", r.secondsGridUpdate}, {"g2p", r.secondsG2P}, {"output", io}}));
    if (gStopRequested != 0 && frame < last) {
      progress.finish();
      stopMessage(frame, solver->time(), false);
      return 130;
    }
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
  // One field solve of this state, through the stage's public entry points.
  const MpmParticles& p = solver->particles();
  const MpmMaterial* law = nullptr;
  for (const MpmMaterial& m : solver->materials())
    if (m.isMagnetic()) law = &m;
  if (!law) throw InvalidArgument(concat(a.scene, ": the scene has no magnetic material; there is no field to export"));
  const GridSpec grid = scene.settings.magneticGrid ? *scene.settings.magneticGrid : scene.settings.grid;
  MagneticStageSettings settings = scene.settings.magnetic;
  settings.outOfGrid = OutOfGridPolicy::Skip;
  MagneticForceStage stage(grid, law->magnetic, settings);
  MagneticStageReport rep;
  if (!a.density.empty()) {
    // A host's own particle-to-grid transfer: n (1/m^3) on the field grid.
#if LODESTONE_HAVE_VDB
    const DenseGrid<double> n = readDensityVdb(a.density, grid, a.densityGrid);
    rep = stage.runOnDensity(n.view(), solver->appliedField(), solver->time());
#else
    throw Error(concat("cannot read ", a.density, ": this lodestone was built without OpenVDB"));
#endif
  } else {
    std::vector<Vec3d> x;
    std::vector<double> n;
    for (std::size_t i = 0; i < p.size(); ++i)
      if (solver->materials()[p.material[i]].isMagnetic()) {
        x.push_back(p.x[i]);
        n.push_back(p.count[i]);
      }
    rep = stage.run({x.data(), n.data(), x.size()}, solver->appliedField(), solver->time());
  }
  std::printf("%s", rep.summary().c_str());
  writeFields(a.out, scene, stage, a.frame, solver->time(), solver.get());
  std::printf("wrote %s (frame %d, t = %g s)\n", a.out.c_str(), a.frame, solver->time());
  return rep.converged() ? 0 : 1;
}

int plan(const Args& a) {
  const Scene scene = loadScene(a.scene, a.options);
  auto solver = buildSolver(scene);
  printSceneSummary(scene, *solver);
  printPlan(scene, *solver, stdout);
  return 0;
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
    Args a;
    if (const std::optional<int> code = parseArgs(argc, argv, a)) return *code;
    if (a.command == "nodes") {
      // The node library, generated from the node declarations.
      std::cout << (a.markdown ? plugin::nodesMarkdown() : plugin::nodesText());
      return 0;
    }
    if (a.command == "run") return run(a);
    if (a.command == "validate") return validate(a);
    if (a.command == "plan") return plan(a);
    if (a.command == "export-fields") return exportFields(a);
    usageError(concat("unknown command '", a.command, "'"));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone: %s\n", e.what());
    return 1;
  }
}
