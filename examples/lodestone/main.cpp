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
#include "lodestone/vdb_io/point_file.h"
#endif
#include "lodestone/plugin/output/ply_writer.h"
#include "lodestone/plugin/output/png_writer.h"
#include "field_line_output.h"
#include "preview.h"
#include "lodestone/plugin/output/progress.h"
#include "farm_commands.h"
#include "outputs.h"
#include "plan_report.h"
#include "rank_job.h"
#include "run_directory.h"
#include "surface_command.h"
#include "lodestone/plugin/output/stats_json.h"

using namespace lodestone;
using namespace lodestone::examples;
using namespace lodestone::output;
using namespace lodestone::plugin;

namespace {

struct Args {
  std::string command, scene, out;
  int first = 0, last = 0;  // run --frames A:B, scene frame numbers
  bool framesGiven = false;  // run: --frames given (else all the scene's frames)
  SceneOptions options;
  int threads = 0;
  int ranks = 0;             // run: --ranks N (0: as launched)
  int frame = 0;            // export-fields: scene frame number
  bool frameGiven = false;  // export-fields: --frame given (else the initial state)
  std::string density, densityGrid = "n";  // export-fields: n (1/m^3) from a .vdb instead of the particles
  std::string particles;     // export-fields: the particles of a cache file instead of a simulated state
  bool png = true, ply = true;
  std::string outputs;        // run: --outputs LIST ("" = the scene's choice)
  SurfaceCommandArgs surface; // surface DIR
  int checkpointEvery = -1;  // -1: the scene's output.checkpoint_every
  bool resume = false, checkFinite = false;
  bool clean = false;         // run: delete another run's output in --out first
  int keepCheckpoints = 0;    // run: checkpoints kept (0 = all)
  double maxLost = 0.01;      // run: fraction of the particles that may be lost as non-finite
  long long maxSubsteps = 100000;  // run, export-fields: substeps per frame refused beyond
  bool markdown = false;      // nodes
  FarmArgs farm;              // wedge, wedge-summary, farm-post
  std::vector<std::string> args;  // the command line as given
};

// Exit codes (docs/cli.md).
constexpr int kExitError = 1;       // bad arguments, scene, directory or checkpoint; I/O failure
constexpr int kExitBlownUp = 3;     // more particles lost as non-finite than --max-lost allows
constexpr int kExitBrokenPipe = 141;  // standard output closed (128 + SIGPIPE)

[[noreturn]] void usageError(const std::string& message) {
  throw InvalidArgument(message + " (see lodestone --help)");
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
  const auto addMaxSubsteps = [&](CLI::App& c) {
    cli::addNumber(c, "--max-substeps", a.maxSubsteps,
                   "refuse a scene whose time step needs more substeps per frame than N (estimated from time.dt or "
                   "the first CFL step)")
        ->type_name("N")
        ->check(cli::wholeNumber(1, 1000000000000LL))
        ->default_str(cli::formatNumber(double(a.maxSubsteps)));
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
         "--frames",
         [&](const std::string& f) {
           readFrameRange(f, a.first, a.last);
           a.framesGiven = true;
         },
         "write frames A..B (scene frame numbers, within time.start_frame .. the scene's last frame; inclusive; "
         "earlier frames are still simulated); default all frames of the scene")
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
  cli::addNumber(run, "--ranks", a.ranks,
                 "split the simulation over N processes (starts mpirun -n N; or start lodestone under mpirun / "
                 "srun yourself; docs/distributed.md)")
      ->type_name("N")
      ->check(cli::wholeNumber(1, 4096));
  std::string outputNames;
  for (const OutputKind& k : outputKinds()) outputNames += concat(outputNames.empty() ? "" : ", ", k.name);
  run.add_option("--outputs", a.outputs,
                 concat("what to write per frame, comma-separated, of: ", outputNames,
                        "; default the scene's output settings (particles, png, and fields and points when "
                        "output.vdb / output.vdb_points ask)"))
      ->type_name("LIST")
      ->check(cli::rule("", [](const std::string& list) { return OutputSelection::check(list); }));
  run.add_flag_callback("--no-png", [&] { a.png = false; }, "skip previews (removes png from the outputs)");
  run.add_flag_callback("--no-ply", [&] { a.ply = false; }, "skip particle files (removes particles)");
  cli::addNumber(run, "--checkpoint-every", a.checkpointEvery,
                 "write DIR/checkpoint_NNNN.lsck every N frames (overrides the scene's output.checkpoint_every; "
                 "0 = none)")
      ->type_name("N")
      ->check(cli::wholeNumber(0, 1000000, "frames"));
  run.add_flag("--resume", a.resume,
               "continue from the last valid checkpoint in DIR; the frames it writes equal those of an "
               "uninterrupted run, bit for bit");
  run.add_flag("--clean", a.clean,
               "DIR holds another run's output (another scene, a changed scene file, another grid): delete the "
               "files that run wrote there and start over, instead of refusing");
  cli::addNumber(run, "--keep-checkpoints", a.keepCheckpoints,
                 "keep only the newest N checkpoint files, deleting older ones as new ones are written (0 = all)")
      ->type_name("N")
      ->check(cli::wholeNumber(0, 1000000))
      ->default_str(cli::formatNumber(a.keepCheckpoints));
  cli::addNumber(run, "--max-lost", a.maxLost,
                 "stop with exit code 3 when more than this fraction of the particles has been lost as non-finite "
                 "(the simulation blew up); 1 allows any loss")
      ->type_name("FRACTION")
      ->check(cli::numberIn(0, 1))
      ->default_str(cli::formatNumber(a.maxLost));
  addMaxSubsteps(run);
  run.add_flag("--check-finite", a.checkFinite,
               "stop with an error naming the quantity, substep and particle or node at the first NaN/Inf "
               "(one extra scan per substep)");
  run.footer(
      "Writes, in DIR:\n"
      "  frame_NNNN.ply      particles (x y z in m, vx vy vz in m/s, n_p, material, J)\n"
      "  frame_NNNN.png      a preview render (magnetic materials dark, magnets red; shaded from\n"
      "                      the surface mesh when --outputs has mesh)\n"
      "  contact_sheet.png   thumbnails of the previews this run rendered (up to 48)\n"
      "  field_lines_NNNN.ply/.obj  lines of B (--outputs field_lines): PLY edges with |B| in T, OBJ l lines\n"
      "  fields_NNNN.vdb     the grids listed in the scene's output.vdb (n, phi, H, M, B, force)\n"
      "  particles_NNNN.vdb  the particles as OpenVDB points (when output.vdb_points is true)\n"
      "  surface_NNNN.vdb    level sets surface and surface_<material> (--outputs surface)\n"
      "  mesh_NNNN.ply/.obj  the surface as a triangle mesh (--outputs mesh)\n"
      "  volume_NNNN.vdb     density (volume fraction), vel, magnetization (--outputs volume)\n"
      "  stats.json          per-frame time split by stage, field-solve reports, particle\n"
      "                      count and energies (rewritten after every frame)\n"
      "  lodestone_run.json  what wrote DIR: scene, content hash, grid, command, version,\n"
      "                      frames, status (a run of anything else into DIR is refused)\n"
      "  lodestone_run.lock  held while a run writes DIR (a second run is refused)\n"
      "\n"
      "Ctrl-C (or SIGTERM) stops after the current substep (a field solve in progress at its next\n"
      "Newton iteration), keeps every complete frame and says how to resume; a second one exits\n"
      "at once.\n"
      "Exit codes: 0 done; 1 error; 3 blown up (--max-lost); 130 Ctrl-C; 143 SIGTERM;\n"
      "141 standard output closed.");

  CLI::App& validate = *app.add_subcommand("validate", "check a scene file and print what it builds");
  addScene(validate);
  addResolution(validate);
  validate.footer(
      "Reads SCENE, builds everything it describes (grid, particles, materials, magnets,\n"
      "colliders, applied fields) without simulating, prints a summary (grid size and dx,\n"
      "particle count, each material's parameters, frames, time step and substeps per frame)\n"
      "and ends with \"SCENE: valid\". A bad scene is refused with a message naming the key\n"
      "and the value. Writes no file.\n"
      "Exit codes: 0 valid; 1 error.");

  CLI::App& plan = *app.add_subcommand(
      "plan", "print which stages would run, why, at what predicted error and cost (the effects planner), "
              "without running");
  addScene(plan);
  addResolution(plan);
  plan.footer(
      "Builds SCENE as validate does and prints, for each stage (gravity, colliders, fluid\n"
      "and elastic stress, the magnetic stages), whether lodestone run would run it and why.\n"
      "With the effects planner on (the scene's \"accuracy\" or \"planner\"), also the choice\n"
      "made for each magnetic stage, its predicted deviation from full physics against the\n"
      "accuracy budget and its estimated cost per field solve; off, every configured stage\n"
      "runs. Simulates nothing and writes no file (docs/planner.md).\n"
      "Exit codes: 0 done; 1 error.");

  CLI::App& exportFields = *app.add_subcommand(
      "export-fields", "field solve of the state at frame N, written as OpenVDB grids n, phi, H, M, B, force");
  addScene(exportFields);
  exportFields.add_option("--out", a.out, "the .vdb file to write")->required()->type_name("FILE.vdb");
  CLI::Option* frameOption =
      cli::addNumber(exportFields, "--frame", a.frame,
                     "the state at the end of scene frame N (time.start_frame - 1 .. the scene's last frame); "
                     "default the initial state, frame time.start_frame - 1")
          ->type_name("N")
          ->check(cli::wholeNumber(0));
  exportFields
      .add_option("--density", a.density,
                  "solve for the density grid of this file (n, 1/m^3) instead of the scene's particles")
      ->type_name("N.vdb");
  exportFields.add_option("--density-grid", a.densityGrid, "the grid of --density to read")
      ->type_name("G")
      ->capture_default_str();
  exportFields
      .add_option("--particles", a.particles,
                  "solve for the particles of this cache file (particles_NNNN.vdb of output.vdb_points) at its "
                  "frame and time instead of simulating; magnets at their keyframed pose then")
      ->type_name("P.vdb");
  addMaxSubsteps(exportFields);
  addResolution(exportFields);

  addFarmCommands(app, a.farm);
  CLI::App& surface = *app.add_subcommand(
      "surface", "surfaces, meshes and render volumes for the particle cache of a run directory");
  surface.add_option("DIR", a.surface.dir, "a lodestone run output directory with particles_NNNN.vdb")
      ->required()
      ->type_name("");
  surface.add_option("--outputs", a.surface.outputs, "of surface, mesh, volume, comma-separated")
      ->type_name("LIST")
      ->capture_default_str()
      ->check(cli::rule("", [](const std::string& list) { return OutputSelection::check(list); }));
  surface
      .add_option_function<std::string>(
          "--frames",
          [&](const std::string& f) { readFrameRange(f, a.surface.first, a.surface.last); },
          "only frames A..B (inclusive); default every frame of the cache")
      ->type_name("A:B")
      ->check(cli::rule("", [](const std::string& f) {
        int first = 0, last = 0;
        return readFrameRange(f, first, last);
      }));
  surface.add_option("--method", a.surface.method, "density or splat (default the scene's output.surface.method)")
      ->type_name("M")
      ->check(CLI::IsMember({"density", "splat"}));
  cli::addNumber(surface, "--voxel-size", a.surface.voxelSize,
                 "voxel size, m; 0 = the particle spacing (default the scene's output.surface.voxel_size)")
      ->type_name("M")
      ->check(cli::numberIn(0, 10));
  cli::addNumber(surface, "--threads", a.surface.threads, "worker threads (0 = all cores)")
      ->type_name("N")
      ->check(cli::wholeNumber(0, 1024));
  surface.footer(
      "Reads DIR/particles_NNNN.vdb (the particle cache: output.vdb_points, or run --outputs\n"
      "points) and writes, frames in parallel, surface_NNNN.vdb, mesh_NNNN.ply and .obj and\n"
      "volume_NNNN.vdb as lodestone run --outputs surface,mesh,volume does, with the run's scene's\n"
      "output.surface settings and material names; magnetization from fields_NNNN.vdb when there.\n"
      "Exit codes: 0 done; 1 error (a frame that failed is named).");

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
  a.frameGiven = frameOption->count() > 0;
  if (a.clean && a.resume) usageError("--clean and --resume exclude each other");
  if (!a.particles.empty() && (a.frameGiven || !a.density.empty()))
    usageError("--particles excludes --frame and --density (the file gives the state)");
  a.args.assign(argv, argv + argc);
  a.farm.args = a.args;
  return std::nullopt;
}
/// Substeps per frame the time step takes: time.dt's, or (CFL) the first
/// step's, which changes as the material moves.
std::string substepText(const Scene& scene, const MpmSolver& solver) {
  char text[256];
  const double n = substepsPerFrame(scene, solver);
  std::snprintf(text, sizeof text, "%s = %.3g s takes %.4g substeps per frame of %.4g s (%.4g for the %d frames)",
                scene.settings.fixedDt > 0 ? "time.dt" : "the first CFL step", solver.suggestedDt(), n,
                scene.frameDuration(), n * scene.frames, scene.frames);
  return text;
}

/// Refuses a time step that needs more than --max-substeps (or the scene's
/// time.max_substeps) substeps per frame.
void checkSubsteps(const Args& a, const Scene& scene, const MpmSolver& solver) {
  if (substepsPerFrame(scene, solver) > double(a.maxSubsteps))
    throw InvalidArgument(concat(a.scene, ": ", substepText(scene, solver), ", more than --max-substeps ",
                                 a.maxSubsteps, ": raise time.dt (or lower the scene's stiffness), or allow them with "
                                                "--max-substeps N"));
  const int limit = scene.settings.maxSubsteps;
  if (limit > 0 && substepsPerFrame(scene, solver) > double(limit))
    throw InvalidArgument(concat(a.scene, ": ", substepText(scene, solver), ", more than time.max_substeps ", limit,
                                 ": raise time.dt (or lower the scene's stiffness), or raise time.max_substeps"));
}

void printSceneSummary(const Scene& scene, const MpmSolver& solver) {
  const GridSpec& g = scene.settings.grid;
  std::printf("scene '%s' (%s)\n", scene.name.c_str(), scene.file.c_str());
  if (!scene.description.empty()) std::printf("  %s\n", scene.description.c_str());
  std::printf("  grid %d x %d x %d nodes, dx = %.4g m, origin (%.4g, %.4g, %.4g) m\n", g.dims.i, g.dims.j, g.dims.k,
              g.dx, g.origin.x, g.origin.y, g.origin.z);
  std::printf("  %zu particles, %zu materials, %zu magnets, %zu colliders, %zu applied fields\n",
              solver.totalParticles(), solver.materials().size(), solver.magnetCount(), solver.colliderCount(),
              scene.fields.size());
  for (std::size_t m = 0; m < scene.materials.size(); ++m)
    std::printf("  material '%s': %s\n", scene.materialNames[m].c_str(), scene.materials[m].describe().c_str());
  const double end = solver.time() + scene.frames * scene.frameDuration();
  for (std::size_t e = 0; e < solver.emitterCount(); ++e)
    std::printf("  emitter '%s' (%s): %s; up to %.0f particles by t = %.4g s\n", scene.emitters[e].name.c_str(),
                scene.materialNames[solver.emitter(e).materialIndex()].c_str(), solver.emitter(e).describe().c_str(),
                solver.emitter(e).particlesBy(end) - solver.emitter(e).particlesBy(solver.time()), end);
  std::printf("  %d frames at %.4g fps; %s; field solved %s\n", scene.frames, scene.fps,
              scene.settings.fixedDt > 0 ? concat("dt = ", scene.settings.fixedDt, " s").c_str()
                                         : concat("CFL ", scene.settings.cfl, ", dt <= ", scene.settings.dtMax, " s").c_str(),
              scene.settings.magneticSolveInterval == 0
                  ? (scene.settings.magneticSolveDistance > 0
                         ? concat("once per frame and whenever material or a magnet moved ",
                                  scene.settings.magneticSolveDistance, " cells")
                         : std::string("once per frame"))
                        .c_str()
                  : concat("every ", scene.settings.magneticSolveInterval, " substeps").c_str());
  std::printf("  frames %d..%d from the initial state, frame %d at t = %.6g s (frame f ends at t = f / fps)\n",
              scene.startFrame, scene.lastFrame(), scene.initialFrame(), scene.startTime());
  std::printf("  %s\n", substepText(scene, solver).c_str());
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
  putCount(f, "non_finite", std::int64_t(r.nonFinite));
  putCount(f, "emitted", std::int64_t(r.emitted.particles));
  putCount(f, "emission_blocked", std::int64_t(r.emitted.blocked + r.emitted.outside));
  nlohmann::json e;
  putQuantity(e, "kinetic", r.energies.kinetic, "J");
  putQuantity(e, "gravitational", r.energies.gravitational, "J");
  putQuantity(e, "elastic", r.energies.elastic, "J");
  f["energy"] = e;
  if (!r.bodies.empty()) {
    // The dynamic rigid bodies at the end of the frame and what acted on them.
    nlohmann::json bodies = nlohmann::json::array();
    for (const RigidBodyReport& b : r.bodies) {
      nlohmann::json j;
      j["collider"] = b.collider;
      if (b.magnet >= 0) j["magnet"] = b.magnet;
      putQuantity(j, "position", b.pose.position, "m");
      const Mat3d& R = b.pose.rotation;
      j["rotation"] = {{jsonNumber(R(0, 0)), jsonNumber(R(0, 1)), jsonNumber(R(0, 2))},
                       {jsonNumber(R(1, 0)), jsonNumber(R(1, 1)), jsonNumber(R(1, 2))},
                       {jsonNumber(R(2, 0)), jsonNumber(R(2, 1)), jsonNumber(R(2, 2))}};
      putQuantity(j, "velocity", b.velocity, "m/s");
      putQuantity(j, "angular_velocity", b.angularVelocity, "rad/s");
      putQuantity(j, "magnetic_force", b.magneticForce, "N");
      putQuantity(j, "magnetic_torque", b.magneticTorque, "N*m");
      putQuantity(j, "material_impulse", b.materialImpulse, "N*s");
      putQuantity(j, "contact_impulse", b.contactImpulse, "N*s");
      bodies.push_back(j);
    }
    f["rigid_bodies"] = bodies;
  }
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
    for (int j = lo.j; j < hi.j; ++j) {
      int first = 0, end = 0;  // every node outside the row's run is zero
      g.activeRun(j, k, first, end);
      for (int i = first; i < end; ++i) {
        const std::size_t n = s.index(i, j, k);
        if (!(g.nodes()[n].mass > 0)) continue;
        mass(i, j, k) = g.nodes()[n].mass;
        velocity(i, j, k) = g.velocity()[n];
      }
    }
}
#endif

/// The grids of the scene's output.vdb (sceneGrids) or the six field grids
/// n, phi, H, M, B and force (export-fields). `solver` (may be null)
/// supplies the MPM grid's mass and velocity when the scene's output.vdb
/// lists them.
void writeFields(const std::string& path, const Scene& scene, const MagneticForceStage& stage, int frame,
                 double time, const MpmSolver* solver, bool sceneGrids) {
#if LODESTONE_HAVE_VDB
  VdbWriteOptions o;
  const auto listed = [&](const char* g) {
    return sceneGrids && std::find(scene.output.vdbFields.begin(), scene.output.vdbFields.end(), g) !=
                             scene.output.vdbFields.end();
  };
  const auto has = [&](const char* g) { return !sceneGrids || scene.output.vdbFields.empty() || listed(g); };
  o.fields = {has("n"), has("phi"), has("H"), has("M"), has("B"), has("force")};
  o.fields.mass = listed("mass");
  o.fields.velocity = listed("velocity");
  o.displayAliases = sceneGrids && scene.output.vdbAliases;
  if (solver && solver->partition() && (o.fields.mass || o.fields.velocity)) {
    // Several processes: rank 0 holds only its window of the MPM grid.
    static bool said = false;
    if (!said)
      std::fprintf(stderr, "lodestone: %s: the MPM grids (mass, velocity) are not written on several processes\n",
                   path.c_str());
    said = true;
    o.fields.mass = o.fields.velocity = false;
  }
  DenseGrid<double> mass;
  DenseGrid<Vec3d> velocity;
  if (solver && !solver->partition() && (o.fields.mass || o.fields.velocity || o.displayAliases)) {
    mpmGridData(*solver, mass, velocity);
    o.mpm = {mass.view(), velocity.view()};
  }
  require(solver || !(o.fields.mass || o.fields.velocity), path, ": the mass and velocity grids need a simulated state");
  VdbFrameMetadata meta;
  meta.frame = frame;
  meta.time = time;
  writeFieldsVdb(path, stage, meta, o);
#else
  (void)scene, (void)stage, (void)frame, (void)time, (void)solver, (void)sceneGrids;
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

/// The law of the solver's magnetic materials (null when there is none).
const MpmMaterial* magneticLaw(const MpmSolver& solver) {
  for (const MpmMaterial& m : solver.materials())
    if (m.isMagnetic()) return &m;
  return nullptr;
}

/// One field solve of the solver's state through the stage's public entry
/// points, on the scene's magnetic grid: of the magnetic particles, or of the
/// density n (1/m^3) of `density` (a .vdb file, grid `densityGrid`) when
/// given. The solver must have a magnetic material.
std::unique_ptr<MagneticForceStage> solveFieldsNow(const Scene& scene, const MpmSolver& solver,
                                                   MagneticStageReport& report, const std::string& density = "",
                                                   const std::string& densityGrid = "n",
                                                   const std::vector<Vec3d>* cacheX = nullptr,
                                                   const std::vector<double>* cacheN = nullptr) {
  const MpmMaterial* law = magneticLaw(solver);
  if (!law)
    throw InvalidArgument(concat(scene.file, ": the scene has no magnetic material; there is no field to solve"));
  const GridSpec grid = scene.settings.magneticGrid ? *scene.settings.magneticGrid : scene.settings.grid;
  MagneticStageSettings settings = scene.settings.magnetic;
  settings.outOfGrid = OutOfGridPolicy::Skip;
  auto stage = std::make_unique<MagneticForceStage>(grid, law->magnetic, settings);
  if (!density.empty()) {
    // A host's own particle-to-grid transfer: n (1/m^3) on the field grid.
#if LODESTONE_HAVE_VDB
    const DenseGrid<double> n = readDensityVdb(density, grid, densityGrid);
    report = stage->runOnDensity(n.view(), solver.appliedField(), solver.time());
#else
    (void)densityGrid;
    throw Error(concat("cannot read ", density, ": this lodestone was built without OpenVDB"));
#endif
  } else if (cacheX) {
    report = stage->run({cacheX->data(), cacheN->data(), cacheX->size()}, solver.appliedField(), solver.time());
  } else {
    const MpmParticles& p = solver.particles();
    std::vector<Vec3d> x;
    std::vector<double> n;
    for (std::size_t i = 0; i < p.size(); ++i)
      if (solver.materials()[p.material[i]].isMagnetic()) {
        x.push_back(p.x[i]);
        n.push_back(p.count[i]);
      }
    report = stage->run({x.data(), n.data(), x.size()}, solver.appliedField(), solver.time());
  }
  return stage;
}

/// Seconds spent on each output (outputKinds() names).
using OutputCosts = std::vector<std::pair<std::string, double>>;

void addCost(OutputCosts& costs, const std::string& name, double seconds) {
  for (auto& [n, s] : costs)
    if (n == name) {
      s += seconds;
      return;
    }
  costs.emplace_back(name, seconds);
}

OutputCosts writeFrameFiles(const Args& a, const OutputSelection& outputs, const Scene& scene,
                            const MpmSolver& solver, int frame,
                            ContactSheetCollector& sheet) {
  const std::string number = frameNumber(frame);
  std::string name;
  const MpmParticles& p = solver.particles();
  OutputCosts costs;
  auto t0 = std::chrono::steady_clock::now();
  const auto lap = [&](const char* output) {
    const auto now = std::chrono::steady_clock::now();
    addCost(costs, output, std::chrono::duration<double>(now - t0).count());
    t0 = now;
  };
  if (outputs.has("particles")) {
    name = "frame_" + number + ".ply";
    PlyPointCloud cloud(p.x);
    cloud.addVec3("vx", "vy", "vz", p.v);
    cloud.addFloat("n_p", p.count);
    cloud.addFloat("J", p.J);
    std::vector<std::int32_t> mat(p.material.begin(), p.material.end());
    cloud.addInt("material", mat);
    cloud.addComment(concat("lodestone ", LODESTONE_VERSION_STRING, " scene ", scene.name, " frame ", frame,
                            " time ", solver.time(), " s; units m, m/s"));
    cloud.write((std::filesystem::path(a.out) / name).string());
    lap("particles");
  }
  if (outputs.has("points")) {
    name = "particles_" + number + ".vdb";
    writeParticles((std::filesystem::path(a.out) / name).string(), solver, frame);
    lap("points");
  }
  if (outputs.has("fields") && (solver.magneticStage() || magneticLaw(solver))) {
    name = "fields_" + number + ".vdb";
    const std::string path = (std::filesystem::path(a.out) / name).string();
    if (solver.magneticStage()) {
      writeFields(path, scene, *solver.magneticStage(), frame, solver.time(), &solver, true);
    } else {
      // Before the first substep (the initial frame): a field solve of this state.
      MagneticStageReport report;
      const std::unique_ptr<MagneticForceStage> stage = solveFieldsNow(scene, solver, report);
      writeFields(path, scene, *stage, frame, solver.time(), &solver, true);
    }
    lap("fields");
  }
  TriangleMesh surfaceMesh;  // filled when the mesh is written: the preview shades it
  if (outputs.rendersSurface()) {
    MagnetizationInput magnetization;
    if (solver.magneticStage()) magnetization.grid = solver.magneticStage()->magnetization();
    const RenderOutputCost c = writeRenderOutputs(renderOutputPaths(outputs, a.out, number), p,
                                                  scene.materialNames, scene.output.surface, frame, solver.time(),
                                                  magnetization, &surfaceMesh);
    if (outputs.has("surface")) addCost(costs, "surface", c.surface);
    if (outputs.has("mesh")) addCost(costs, "mesh", c.mesh);
    if (outputs.has("volume")) addCost(costs, "volume", c.volume);
    t0 = std::chrono::steady_clock::now();
  }
  std::vector<FieldLine> lines;
  if (outputs.has("field_lines")) {
    lines = solverFieldLines(scene, solver);
    writeFieldLineFiles(a.out, number, lines, scene, frame, solver.time());
    lap("field_lines");
  }
  if (outputs.has("png")) {
    name = "frame_" + number + ".png";
    const RgbImage img = surfaceMesh.triangles.empty() ? renderPreview(scene, solver, lines)
                                                       : renderMeshPreview(scene, solver, surfaceMesh, lines);
    writePng((std::filesystem::path(a.out) / name).string(), img.width, img.height, img.rgb.data());
    sheet.add(frame, img);
    lap("png");
  }
  return costs;
}

// Ctrl-C / SIGTERM: the first asks the run to stop after the current
// substep (the run then exits with 128 + the signal); the handler restores
// the default, so a second one exits at once.
volatile std::sig_atomic_t gStopSignal = 0;
extern "C" void onStopSignal(int sig) {
  gStopSignal = sig;
  std::signal(sig, SIG_DFL);
}

/// Standard output is gone (a closed pipe: `lodestone run ... | head`).
bool stdoutBroken() {
  std::cout.flush();
  return std::fflush(stdout) != 0 || std::ferror(stdout) != 0 || !std::cout.good();
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

// Restores the newest checkpoint in `dir` that reads back whole and belongs
// to this run: the same scene content and grid, a frame within --frames, and
// written by a run whose frames cover this one's start (a corrupted or
// foreign one is reported and the next older tried). Returns its frame.
int resumeFromCheckpoint(const std::string& dir, const CheckpointOrigin& run, MpmSolver& solver) {
  for (const int frame : checkpointFrames(dir)) {
    const std::filesystem::path path = std::filesystem::path(dir) / checkpointName(frame);
    try {
      if (frame > run.last)
        throw InvalidArgument(concat("frame ", frame, " lies beyond --frames ", run.first, ":", run.last));
      const std::vector<std::uint8_t> bytes = readBytes(path);
      const MpmCheckpointInfo head = readMpmCheckpointInfo(bytes.data(), bytes.size());
      const CheckpointOrigin origin = checkpointOrigin(head.tag);
      const std::string difference = origin.identity.differenceFrom(run.identity);
      if (!difference.empty()) throw InvalidArgument(concat("it belongs to another run: ", difference));
      if (origin.first > run.first && frame >= run.first)
        throw InvalidArgument(concat("its run wrote frames from ", origin.first, " on, this one writes from ",
                                     run.first, " (--frames ", run.first, ":", run.last, ")"));
      const MpmCheckpointInfo info = restoreMpmCheckpoint(solver, bytes.data(), bytes.size(), head.tag);
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

// The command that resumes this run: its own arguments (--dx and all) with
// --resume instead of --clean.
std::string resumeCommand(const Args& a) {
  std::vector<std::string> args{"lodestone"};
  for (std::size_t i = 1; i < a.args.size(); ++i)
    if (a.args[i] != "--clean") args.push_back(a.args[i]);
  if (!a.resume) args.push_back("--resume");
  return commandLine(args);
}

int run(const Args& a) {
  if (a.out.empty()) usageError("run needs --out DIR");
  if (a.ranks > 1 && !startedByMpiLauncher()) execUnderMpirun(a.ranks, a.args);
  // Under an MPI launcher every process runs this; rank 0 writes and prints.
  const RankJob job;
  if (a.ranks > 0 && a.ranks != job.ranks())
    usageError(concat("--ranks ", a.ranks, " but the MPI launcher started ", job.ranks(), " processes"));
  if (!job.writes() && !std::freopen("/dev/null", "w", stdout)) throw Error("cannot silence rank output");
  std::signal(SIGPIPE, SIG_IGN);  // a closed standard output is noticed and said (stdoutBroken)
  std::unique_ptr<tbb::global_control> threads;
  const int threadCount = a.threads > 0 ? a.threads : job.threadsPerRank();
  if (threadCount > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, std::size_t(threadCount));
  Scene scene = loadScene(a.scene, a.options);
  const double loadedBytes = residentBytes();  // the program, its libraries and the scene's files
  if (a.checkFinite) scene.settings.checkFinite = true;
  // The frames written, first..last, in scene frame numbers (time.start_frame on).
  const int initialFrame = scene.initialFrame();
  const std::string sceneRange = concat("the scene's frames are ", scene.startFrame, "..", scene.lastFrame());
  const int first = a.framesGiven ? a.first : scene.startFrame;
  const int last = a.framesGiven ? a.last : scene.lastFrame();
  if (first < scene.startFrame || first > scene.lastFrame())
    usageError(concat("--frames starts at ", first, " but ", sceneRange));
  if (last > scene.lastFrame()) usageError(concat("--frames ends at ", last, " but ", sceneRange));
  OutputSelection outputs =
      a.outputs.empty() ? OutputSelection::sceneDefault(scene.output) : OutputSelection::parse(a.outputs);
  if (!a.png) outputs.remove("png");
  if (!a.ply) outputs.remove("particles");
  // The fields files, the lines of B and the surface's magnetization read
  // one magnetic grid: the planner's patches (one grid per separate group
  // of material) stay off when they are written.
  const bool oneFieldGrid = outputs.has("fields") || outputs.has("field_lines") || outputs.rendersSurface();
  if (oneFieldGrid && scene.settings.planner.enabled && scene.settings.planner.patches == PlannerToggle::Auto) {
    scene.settings.planner.patches = PlannerToggle::Off;
    std::printf("planner: patches off (the fields, field_lines and surface outputs read one magnetic grid)\n");
  }
  // Several processes: each builds its part of the scene.
  auto solver = buildSolver(scene, job.partitionOf(scene.settings.grid));
  printSceneSummary(scene, *solver);
  if (const MpmPartition* split = solver->partition())
    std::printf("distributed: %s (figures below per process)\n", split->describe().c_str());
  printPlan(scene, *solver, stdout);
  const MemoryEstimate memory = printMemoryEstimate(scene, *solver, loadedBytes, outputs, stdout);
  requireFitsInMemory(concat("scene '", scene.name, "'"), memory);
  checkSubsteps(a, scene, *solver);
  std::string planShown;
  std::printf("writes per frame: %s\n", outputs.describe().c_str());
  OutputCosts outputCosts;  // summed over the frames written
  int framesWritten = 0;
  const auto addCosts = [&](const OutputCosts& c) {
    for (const auto& [n, s] : c) addCost(outputCosts, n, s);
    ++framesWritten;
  };
  const int checkpointEvery = a.checkpointEvery >= 0 ? a.checkpointEvery : scene.output.checkpointEvery;
  const CheckpointOrigin origin{runIdentity(scene), first, last};
  // Rank 0 keeps the directory; the other processes write nothing.
  const std::unique_ptr<const RunDirectory> directory =
      job.writes() ? std::make_unique<const RunDirectory>(a.out, origin.identity, a.clean) : nullptr;
  const std::string command = commandLine(a.args);
  const auto record = [&](int firstFrame, int lastFrame, const char* state, int done) {
    if (directory) directory->record(command, firstFrame, lastFrame, state, done);
  };
  const std::size_t initialParticles = solver->totalParticles();
  // The frame the solver is at: the initial one, or a checkpoint's.
  const int startFrame = a.resume ? resumeFromCheckpoint(a.out, origin, *solver) : initialFrame;
  if (startFrame == last) {
    std::printf("nothing to simulate: %s is at the last frame (%d) of --frames %d:%d; the run in %s is complete\n",
                checkpointName(startFrame).c_str(), last, first, last, a.out.c_str());
    record(first, last, "complete", last);
    return 0;
  }

  nlohmann::json stats;
  stats["scene"] = scene.name;
  stats["scene_file"] = scene.file;
  stats["lodestone_version"] = LODESTONE_VERSION_STRING;
  stats["grid"] = {{"dims", {scene.settings.grid.dims.i, scene.settings.grid.dims.j, scene.settings.grid.dims.k}},
                   {"dx_m", scene.settings.grid.dx}};
  stats["frames"] = nlohmann::json::array();
  // The estimate before the run and the peak resident memory so far
  // (rewritten with every frame).
  stats["memory"] = {{"estimated_peak_bytes", memory.total()},
                     {"estimated_mpm_grid_bytes", memory.mpmGrid},
                     {"estimated_field_solve_bytes", memory.fieldGrid},
                     {"estimated_particles_bytes", memory.particles},
                     {"estimated_frame_files_bytes", memory.outputs},
                     {"process_before_bytes", memory.process},
                     {"limit_bytes", memoryLimitBytes()},
                     {"peak_resident_bytes", peakResidentBytes()}};
  const std::filesystem::path statsPath = std::filesystem::path(a.out) / "stats.json";
  std::int64_t lost = 0;  // particles lost as non-finite since the initial frame
  if (startFrame > initialFrame && std::filesystem::exists(statsPath)) {
    // Keep the per-frame records up to the checkpoint.
    try {
      const std::vector<std::uint8_t> bytes = readBytes(statsPath);
      const nlohmann::json old = nlohmann::json::parse(bytes.begin(), bytes.end());
      for (const nlohmann::json& f : old.at("frames"))
        if (f.at("frame").get<int>() <= startFrame) {
          stats["frames"].push_back(f);
          lost += f.value("non_finite", std::int64_t(0));
        }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "lodestone: %s could not be read (%s); it restarts at frame %d\n",
                   statsPath.string().c_str(), e.what(), startFrame + 1);
    }
  }
  int lastCheckpoint = startFrame > initialFrame ? startFrame : initialFrame;  // initialFrame: none
  const auto howToResume = [&] {
    return lastCheckpoint > initialFrame ? concat("resume from ", checkpointName(lastCheckpoint), " (frame ", lastCheckpoint,
                                        ") with: ", resumeCommand(a))
                               : std::string("no checkpoint was written (use --checkpoint-every N or "
                                             "output.checkpoint_every); run again to start over");
  };
  const auto stopMessage = [&](int frame, double time, bool midFrame) {
    std::printf("\ninterrupted: stopped %s frame %d at t = %.6g s; frames up to %d are complete in %s; %s\n",
                midFrame ? "during" : "after", frame, time, midFrame ? frame - 1 : frame, a.out.c_str(),
                howToResume().c_str());
    record(first, last, "interrupted", midFrame ? frame - 1 : frame);
    return 128 + int(gStopSignal);
  };
  record(first, last, "running", startFrame);
  std::signal(SIGINT, onStopSignal);
  std::signal(SIGTERM, onStopSignal);
  // The decision to stop is the same on every process (a collective test).
  const MpmProgressCallback keepGoing = [&](const MpmProgress&) { return !job.anyRank(gStopSignal != 0); };
  // A field solve in progress stops at its next Newton iteration too; its
  // substep ends with the field reached and the frame is dropped.
  solver->setFieldSolveProgress([&](const NewtonIterationRecord&) { return !job.anyRank(gStopSignal != 0); });
  const auto t0 = std::chrono::steady_clock::now();
  ProgressOptions progressOptions{isTerminal(stdout)};
  progressOptions.firstFrame = initialFrame;
  ProgressPrinter progress(std::cout, last - initialFrame, progressOptions);
  ContactSheetCollector sheet(first == scene.startFrame ? initialFrame : first, last);
  // A frame's files: rank 0 gathers every particle and writes them.
  const auto writeFrame = [&](int f) {
    solver->gatherParticlesToRoot();
    return job.writes() ? writeFrameFiles(a, outputs, scene, *solver, f, sheet) : OutputCosts{};
  };
  int frame = startFrame;
  try {
    if (first == scene.startFrame && startFrame == initialFrame)
      addCosts(writeFrame(initialFrame));  // the initial state
    for (frame = startFrame + 1; frame <= last; ++frame) {
      const MpmFrameReport r = solver->advanceFrame(scene.frameDuration(), keepGoing);
      if (r.cancelled) {
        progress.finish();
        return stopMessage(frame, solver->time(), true);
      }
      const auto tio = std::chrono::steady_clock::now();
      OutputCosts frameCosts;
      if (frame >= first) {
        frameCosts = writeFrame(frame);
        addCosts(frameCosts);
      }
      const double io = std::chrono::duration<double>(std::chrono::steady_clock::now() - tio).count();
      stats["frames"].push_back(frameJson(frame, r, solver->particles().size(), io));
      nlohmann::json outputSeconds = nlohmann::json::object();
      for (const auto& [n, sec] : frameCosts) putQuantity(outputSeconds, n, sec, "s");
      stats["frames"].back()["outputs"] = outputSeconds;
      lost += std::int64_t(r.nonFinite);
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
      stats["memory"]["peak_resident_bytes"] = peakResidentBytes();
      if (job.writes()) writeJsonFile(statsPath.string(), stats);
      if (checkpointEvery > 0 && (frame - initialFrame) % checkpointEvery == 0) {
        solver->gatherParticlesToRoot();
        if (job.writes())
          writeFileAtomically((std::filesystem::path(a.out) / checkpointName(frame)).string(),
                              saveMpmCheckpoint(*solver, frame, checkpointTag(origin)));
        // A resumed solver starts its next field solve from phi = 0: so does this one.
        solver->resetMagneticWarmStart();
        lastCheckpoint = frame;
        if (directory) directory->pruneCheckpoints(frame, a.keepCheckpoints);
      }
      for (const MagneticStageReport& m : r.magneticReports)
        if (!m.converged()) progress.message(concat("frame ", frame, ": ", m.solve.message));
      for (const std::string& w : r.warnings) progress.message(concat("frame ", frame, ": ", w));
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      progress.update(frame - initialFrame, elapsed,
                      formatStageSplit({{"p2g", r.secondsP2G}, {"magnetic", r.secondsMagnetic},
                                        {"grid", r.secondsGridUpdate}, {"g2p", r.secondsG2P}, {"output", io}}));
      if (double(lost) > a.maxLost * double(initialParticles)) {
        progress.finish();
        std::fprintf(stderr,
                     "lodestone: the simulation blew up: %lld of its %zu particles (%.3g%%) were lost as non-finite "
                     "by frame %d (t = %.6g s), more than --max-lost %g allows; frames up to %d are in %s. A smaller "
                     "time.dt or time.cfl usually helps (--check-finite names the first NaN); --max-lost 1 lets the "
                     "run go on.\n",
                     static_cast<long long>(lost), initialParticles, 100.0 * double(lost) / double(initialParticles),
                     frame, solver->time(), a.maxLost, frame, a.out.c_str());
        record(first, last, "failed", frame);
        return kExitBlownUp;
      }
      if (frame < last && stdoutBroken()) {
        std::fprintf(stderr,
                     "lodestone: standard output was closed (broken pipe): stopped after frame %d at t = %.6g s; "
                     "frames up to %d are complete in %s; %s\n",
                     frame, solver->time(), frame, a.out.c_str(), howToResume().c_str());
        record(first, last, "interrupted", frame);
        return kExitBrokenPipe;
      }
      if (job.anyRank(gStopSignal != 0) && frame < last) {
        progress.finish();
        return stopMessage(frame, solver->time(), false);
      }
    }
  } catch (...) {
    record(first, last, "failed", frame - 1);
    throw;
  }
  progress.finish();
  if (job.writes()) sheet.write((std::filesystem::path(a.out) / "contact_sheet.png").string());
  record(first, last, "complete", last);
  if (lost > 0)
    std::printf("%lld of the %zu particles (%.3g%%) were lost as non-finite (within --max-lost %g)\n",
                static_cast<long long>(lost), initialParticles, 100.0 * double(lost) / double(initialParticles),
                a.maxLost);
  std::printf("wrote frames %d..%d to %s (stats.json has the per-frame details)\n", first, last, a.out.c_str());
  std::printf("peak memory %.3g GiB (estimated %.3g GiB)\n", peakResidentBytes() / double(1 << 30),
              memory.total() / double(1 << 30));
  if (framesWritten > 0) {
    std::string line;
    char cost[64];
    for (const auto& [n, s] : outputCosts) {
      std::snprintf(cost, sizeof cost, "%.3g s", s / framesWritten);
      line += concat(line.empty() ? "" : ", ", n, " ", cost);
    }
    std::printf("output cost per frame: %s\n", line.empty() ? "nothing written" : line.c_str());
  }
  if (stdoutBroken()) {
    std::fprintf(stderr, "lodestone: standard output was closed (broken pipe); the run completed: frames %d..%d are in %s\n",
                 first, last, a.out.c_str());
    return kExitBrokenPipe;
  }
  return 0;
}

#if LODESTONE_HAVE_VDB
/// The magnetic particles of a cache file (x, n) and its frame and time.
ParticleVdbData magneticParticles(const std::string& path, const MpmSolver& solver, std::vector<Vec3d>& x,
                                  std::vector<double>& n) {
  ParticleVdbData d = readParticlesVdb(path);
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (d.material[i] >= solver.materials().size())
      throw InvalidArgument(concat(path, ": particle ", d.id[i], " has material ", d.material[i], " but the scene has ",
                                   solver.materials().size(), " materials: is it a cache of this scene?"));
    if (solver.materials()[d.material[i]].isMagnetic()) {
      x.push_back(d.x[i]);
      n.push_back(d.count[i]);
    }
  }
  return d;
}
#endif

int exportFields(const Args& a) {
  if (a.out.empty()) usageError("export-fields needs --out FILE.vdb");
  const Scene scene = loadScene(a.scene, a.options);
  if (!a.particles.empty()) {
    // A frame of a particle cache: its particles at its time, no simulation.
#if LODESTONE_HAVE_VDB
    auto solver = buildSolver(scene);
    std::vector<Vec3d> x;
    std::vector<double> n;
    const ParticleVdbData d = magneticParticles(a.particles, *solver, x, n);
    solver->setTime(d.time);
    MagneticStageReport rep;
    const std::unique_ptr<MagneticForceStage> stage = solveFieldsNow(scene, *solver, rep, "", "n", &x, &n);
    std::printf("%s", rep.summary().c_str());
    writeFields(a.out, scene, *stage, int(d.frame), d.time, nullptr, false);
    std::printf("wrote %s (frame %d, t = %g s, %zu magnetic particles of %s)\n", a.out.c_str(), int(d.frame), d.time,
                x.size(), a.particles.c_str());
    return rep.converged() ? 0 : 1;
#else
    throw Error(concat("cannot read ", a.particles, ": this lodestone was built without OpenVDB"));
#endif
  }
  const int frame = a.frameGiven ? a.frame : scene.initialFrame();
  if (frame < scene.initialFrame() || frame > scene.lastFrame())
    usageError(concat("--frame ", frame, ": the scene has ", scene.frames, " frames (", scene.startFrame, "..",
                      scene.lastFrame(), ") after its initial state, frame ", scene.initialFrame(),
                      "; N must be in ", scene.initialFrame(), "..", scene.lastFrame()));
  auto solver = buildSolver(scene);
  if (frame > scene.initialFrame()) checkSubsteps(a, scene, *solver);
  for (int f = scene.initialFrame(); f < frame; ++f) solver->advanceFrame(scene.frameDuration());
  MagneticStageReport rep;
  const std::unique_ptr<MagneticForceStage> stage = solveFieldsNow(scene, *solver, rep, a.density, a.densityGrid);
  std::printf("%s", rep.summary().c_str());
  writeFields(a.out, scene, *stage, frame, solver->time(), solver.get(), false);
  std::printf("wrote %s (frame %d, t = %g s)\n", a.out.c_str(), frame, solver->time());
  return rep.converged() ? 0 : 1;
}

int plan(const Args& a) {
  const Scene scene = loadScene(a.scene, a.options);
  const double loadedBytes = residentBytes();
  auto solver = buildSolver(scene);
  printSceneSummary(scene, *solver);
  printPlan(scene, *solver, stdout);
  printMemoryEstimate(scene, *solver, loadedBytes, OutputSelection::sceneDefault(scene.output), stdout);
  return 0;
}

int validate(const Args& a) {
  const Scene scene = loadScene(a.scene, a.options);
  const double loadedBytes = residentBytes();
  auto solver = buildSolver(scene);
  printSceneSummary(scene, *solver);
  requireFitsInMemory(concat("scene '", scene.name, "'"),
                      printMemoryEstimate(scene, *solver, loadedBytes, OutputSelection::sceneDefault(scene.output), stdout));
  if (substepsPerFrame(scene, *solver) > double(a.maxSubsteps))
    std::printf("warning: more than %lld substeps per frame: lodestone run refuses it without --max-substeps\n",
                a.maxSubsteps);
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
    if (const std::optional<int> code = runFarmCommand(a.command, a.farm)) return *code;
    if (a.command == "surface") {
#if LODESTONE_HAVE_VDB
      return surfaceCommand(a.surface);
#else
      throw Error("lodestone surface needs OpenVDB: this lodestone was built without it");
#endif
    }
    usageError(concat("unknown command '", a.command, "'"));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone: %s\n", e.what());
    return 1;
  }
}
