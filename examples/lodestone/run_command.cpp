// `lodestone run`. See run_command.h.
#include "run_command.h"

#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <tbb/global_control.h>

#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/checkpoint.h"
#include "lodestone/plugin/output/atomic_file.h"
#include "lodestone/plugin/output/ply_writer.h"
#include "lodestone/plugin/output/png_writer.h"
#include "lodestone/plugin/output/progress.h"
#include "lodestone/plugin/output/stats_json.h"
#include "lodestone/plugin/scene.h"
#if LODESTONE_HAVE_VDB
#include "lodestone/vdb_io/point_file.h"
#endif
#include "field_export.h"
#include "field_line_output.h"
#include "outputs.h"
#include "plan_report.h"
#include "preview.h"
#include "rank_job.h"
#include "run_directory.h"
#include "scene_summary.h"

namespace lodestone::examples {

using namespace lodestone::output;
using namespace lodestone::plugin;

namespace {

nlohmann::json frameJson(int frame, const MpmFrameReport& r, std::size_t particles, double ioSeconds) {
  nlohmann::json f;
  f["frame"] = frame;
  putQuantity(f, "time", r.time, "s");
  f["substeps"] = r.substeps;
  putQuantity(f, "dt_min", r.minDt, "s");
  putQuantity(f, "dt_max", r.maxDt, "s");
  nlohmann::json stages;
  putQuantity(stages, "p2g", r.secondsP2G, "s");
  putQuantity(stages, "p2g_binning", r.secondsBinning, "s");  // part of p2g
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

}  // namespace

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

}  // namespace lodestone::examples
