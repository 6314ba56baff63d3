// The commands and options of `lodestone`. See command_args.h.
#include "command_args.h"

#include <iostream>

#include "lodestone/cli/command_line.h"
#include "lodestone/core/base/error.h"
#include "outputs.h"
#include "run_directory.h"

namespace lodestone::examples {

[[noreturn]] void usageError(const std::string& message) {
  throw InvalidArgument(message + " (see lodestone --help)");
}

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

}  // namespace lodestone::examples
