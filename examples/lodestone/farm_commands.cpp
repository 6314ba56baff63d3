#include "farm_commands.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <sstream>

#include "lodestone/cli/command_line.h"
#include "lodestone/core/base/error.h"
#include "lodestone/plugin/output/atomic_file.h"
#include "lodestone/plugin/output/png_reader.h"
#include "lodestone/plugin/output/png_writer.h"
#include "lodestone/plugin/output/stats_json.h"
#include "lodestone/plugin/scene.h"
#include "farm_jobs.h"
#include "run_directory.h"
#include "wedge.h"

namespace fs = std::filesystem;

namespace lodestone::examples {
namespace {

constexpr const char* kWedgeManifest = "wedges.json";
constexpr const char* kWedgeCsv = "wedges.csv";
constexpr int kThumbWidth = 240;  // pixels of a contact-sheet tile
constexpr int kTileGap = 4;       // pixels between tiles

std::string readText(const fs::path& path) {
  if (fs::is_directory(path)) throw InvalidArgument(concat("'", path.string(), "' is a directory, not a file"));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InvalidArgument(concat("cannot open '", path.string(), "'"));
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

nlohmann::json readJson(const fs::path& path) {
  const std::string text = readText(path);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw InvalidArgument(concat("'", path.string(), "' is not JSON: ", e.what()));
  }
}

std::string valueText(const nlohmann::json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); }

// The shell line of one task that continues from its own checkpoints: with
// --resume when `out` holds a checkpoint (a requeued or re-run task), else
// from the start. `extra`: shell text appended to the command as it is.
std::string resumingLine(const std::vector<std::string>& run, const std::string& out, const std::string& extra) {
  const std::string cmd = commandLine(run) + extra;
  return concat("if ls ", commandLine({out}), "/checkpoint_*.lsck >/dev/null 2>&1; then exec ", cmd,
                " --resume; else exec ", cmd, "; fi");
}

// Runs task lines locally (a pool of `parallel` shells) or as a Slurm array.
// Returns the exit code.
int dispatch(const FarmArgs& a, const std::string& jobName, const fs::path& dir, const std::vector<std::string>& lines,
             const std::vector<std::string>& names) {
  const fs::path logs = dir / "logs";
  fs::create_directories(logs);
  if (a.slurm) {
    ArrayJob job{jobName, logs.string(), lines, a.partition, a.sbatchArgs};
    const fs::path script = dir / (jobName + ".sbatch");
    if (a.dryRun) {
      output::writeFileAtomically(script.string(), arrayScript(job));
      std::printf("dry run: wrote %s (submit with: sbatch %s)\n", script.string().c_str(), script.string().c_str());
      return 0;
    }
    const SubmittedArray sub = submitArray(job, script.string(), a.wait);
    output::writeFileAtomically((dir / (jobName + ".jobid")).string(), sub.id + "\n");
    std::printf("submitted Slurm job array %s (%zu tasks, script %s, logs %s/%s_N.log)\n", sub.id.c_str(),
                lines.size(), script.string().c_str(), logs.string().c_str(), jobName.c_str());
    if (sub.status != 0)
      std::fprintf(stderr, "lodestone: a task of job array %s failed (sbatch --wait status %d); see %s\n",
                   sub.id.c_str(), sub.status, logs.string().c_str());
    return sub.status == 0 ? 0 : 1;
  }
  if (a.dryRun) {
    for (std::size_t i = 0; i < lines.size(); ++i) std::printf("%zu %s: %s\n", i, names[i].c_str(), lines[i].c_str());
    return 0;
  }
  std::vector<FarmJob> jobs;
  for (std::size_t i = 0; i < lines.size(); ++i)
    jobs.push_back({{"/bin/sh", "-c", lines[i]}, (logs / concat(jobName, "_", i, ".log")).string()});
  std::size_t finished = 0;
  const std::vector<int> status = runPool(jobs, std::max(1, a.local), [&](std::size_t i, int s) {
    ++finished;
    std::printf("[%zu/%zu] %s: %s\n", finished, jobs.size(), names[i].c_str(),
                s == 0 ? "done" : concat("failed with status ", s, " (", jobs[i].log, ")").c_str());
    std::fflush(stdout);
  });
  return std::all_of(status.begin(), status.end(), [](int s) { return s == 0; }) ? 0 : 1;
}

// ---------------------------------------------------------------------------
// wedge-summary

// Area-average downscale of `image` to `width` x `height`.
output::RgbImage downscale(const output::RgbImage& image, int width, int height) {
  output::RgbImage out(width, height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const int x0 = x * image.width / width, x1 = std::max(x0 + 1, (x + 1) * image.width / width);
      const int y0 = y * image.height / height, y1 = std::max(y0 + 1, (y + 1) * image.height / height);
      double sum[3] = {0, 0, 0};
      for (int yy = y0; yy < y1; ++yy)
        for (int xx = x0; xx < x1; ++xx)
          for (int c = 0; c < 3; ++c) sum[c] += image.rgb[3 * (std::size_t(yy) * std::size_t(image.width) + std::size_t(xx)) + std::size_t(c)];
      const double n = double((x1 - x0) * (y1 - y0));
      out.set(x, y, {std::uint8_t(std::lround(sum[0] / n)), std::uint8_t(std::lround(sum[1] / n)),
                     std::uint8_t(std::lround(sum[2] / n))});
    }
  return out;
}

struct WedgeStats {
  std::string status = "not started";
  int frames = 0, lastFrame = -1;
  long long substeps = 0, particles = 0;
  double seconds = 0, kinetic = NAN;
  int maxNewton = 0;
  std::string preview;  // the last frame's PNG ("" when none)
};

WedgeStats wedgeStats(const fs::path& out) {
  WedgeStats s;
  if (fs::exists(out / RunDirectory::kManifest))
    s.status = readJson(out / RunDirectory::kManifest).value("status", std::string("unknown"));
  if (fs::exists(out / "stats.json")) {
    const nlohmann::json stats = readJson(out / "stats.json");
    for (const nlohmann::json& f : stats.at("frames")) {
      ++s.frames;
      s.lastFrame = f.value("frame", -1);
      s.substeps += f.value("substeps", 0LL);
      s.particles = f.value("particles", 0LL);
      if (f.contains("stages") && f["stages"].contains("total_s") && f["stages"]["total_s"].is_number())
        s.seconds += f["stages"]["total_s"].get<double>();
      if (f.contains("energy") && f["energy"].contains("kinetic_J") && f["energy"]["kinetic_J"].is_number())
        s.kinetic = f["energy"]["kinetic_J"].get<double>();
      for (const nlohmann::json& solve : f.value("field_solves", nlohmann::json::array()))
        s.maxNewton = std::max(s.maxNewton, solve.value("newton_iterations", 0));
    }
  }
  const std::vector<int> pngs = frameFiles(out.string(), "frame_", "png");
  if (!pngs.empty()) s.preview = (out / ("frame_" + frameNumber(pngs.back()) + ".png")).string();
  return s;
}

int wedgeSummary(const fs::path& dir) {
  const nlohmann::json manifest = readJson(dir / kWedgeManifest);
  const nlohmann::json& wedges = manifest.at("wedges");
  const int n = int(wedges.size());
  const int columns = std::max(1, int(std::ceil(std::sqrt(double(n)))));
  const int rows = (n + columns - 1) / columns;
  std::vector<WedgeStats> stats;
  int thumbHeight = 0;
  std::vector<output::RgbImage> thumbs(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    stats.push_back(wedgeStats(dir / wedges[std::size_t(i)].at("out").get<std::string>()));
    if (stats.back().preview.empty()) continue;
    const output::RgbImage image = output::readPng(stats.back().preview);
    if (thumbHeight == 0) thumbHeight = std::max(1, int(std::lround(double(kThumbWidth) * image.height / image.width)));
    thumbs[std::size_t(i)] = downscale(image, kThumbWidth, thumbHeight);
  }
  // The table: CSV and Markdown.
  std::ostringstream csv, md;
  csv << "index,name,row,column";
  md << "| index | name | row | column |";
  std::vector<std::string> keys;
  for (const nlohmann::json& ax : manifest.at("axes")) keys.push_back(ax.at("key").get<std::string>());
  for (const std::string& k : keys) {
    csv << "," << k;
    md << " " << k << " |";
  }
  const char* columnsText =
      "status,frames,last_frame,substeps,particles,max_newton_iterations,final_kinetic_energy_J,compute_time_s";
  csv << "," << columnsText << "\n";
  md << " status | frames | last frame | substeps | particles | max Newton iterations | final kinetic energy (J) | "
        "compute time (s) |\n|";
  for (std::size_t c = 0; c < 4 + keys.size() + 8; ++c) md << " --- |";
  md << "\n";
  for (int i = 0; i < n; ++i) {
    const nlohmann::json& w = wedges[std::size_t(i)];
    const WedgeStats& s = stats[std::size_t(i)];
    const std::string name = w.at("name").get<std::string>();
    csv << i << "," << name << "," << i / columns << "," << i % columns;
    md << "| " << i << " | " << name << " | " << i / columns << " | " << i % columns << " |";
    for (const std::string& k : keys) {
      std::string v = valueText(w.at("values").at(k));
      if (v.find(',') != std::string::npos) v = "\"" + v + "\"";
      csv << "," << v;
      md << " " << valueText(w.at("values").at(k)) << " |";
    }
    const std::string kinetic = std::isfinite(s.kinetic) ? concat(s.kinetic) : "";
    csv << "," << s.status << "," << s.frames << "," << s.lastFrame << "," << s.substeps << "," << s.particles << ","
        << s.maxNewton << "," << kinetic << "," << s.seconds << "\n";
    md << " " << s.status << " | " << s.frames << " | " << s.lastFrame << " | " << s.substeps << " | " << s.particles
       << " | " << s.maxNewton << " | " << kinetic << " | " << s.seconds << " |\n";
  }
  output::writeFileAtomically((dir / "summary.csv").string(), csv.str());
  output::writeFileAtomically(
      (dir / "summary.md").string(),
      concat("# Wedges of ", manifest.value("source_scene", std::string("?")), "\n\n",
             "contact_sheet.png: the last frame's preview of each wedge, in index order, left to right then top to "
             "bottom (", columns, " per row; row and column below, from 0); a grey tile: no preview.\n\n",
             md.str()));
  std::printf("wrote %s/summary.csv and summary.md (%d wedges)\n", dir.string().c_str(), n);
  if (thumbHeight == 0) {
    std::printf("no wedge has a preview (frame_NNNN.png) yet: no contact sheet\n");
    return 0;
  }
  const output::Rgb background{24, 24, 24}, missing{128, 128, 128};
  output::RgbImage sheet(columns * kThumbWidth + (columns + 1) * kTileGap, rows * thumbHeight + (rows + 1) * kTileGap,
                         background);
  for (int i = 0; i < n; ++i) {
    const int x0 = kTileGap + (i % columns) * (kThumbWidth + kTileGap);
    const int y0 = kTileGap + (i / columns) * (thumbHeight + kTileGap);
    const output::RgbImage& t = thumbs[std::size_t(i)];
    for (int y = 0; y < thumbHeight; ++y)
      for (int x = 0; x < kThumbWidth; ++x)
        sheet.set(x0 + x, y0 + y, t.width == kThumbWidth && t.height == thumbHeight ? t.get(x, y) : missing);
  }
  output::writePng((dir / "contact_sheet.png").string(), sheet.width, sheet.height, sheet.rgb.data());
  std::printf("wrote %s/contact_sheet.png (%d x %d tiles of %d x %d pixels)\n", dir.string().c_str(), columns, rows,
              kThumbWidth, thumbHeight);
  return 0;
}

// ---------------------------------------------------------------------------
// wedge

int wedge(FarmArgs& a) {
  if (a.slurm == (a.local > 0) && !a.dryRun) throw InvalidArgument("wedge: give one of --local N and --slurm");
  const fs::path dir = fs::absolute(a.dir);
  const nlohmann::json source = readJson(a.scene);
  if (!source.is_object()) throw InvalidArgument(concat(a.scene, ": a scene is a JSON object"));
  std::vector<WedgeAxis> axes;
  for (const std::string& v : a.vary) axes.push_back(parseVary(v));
  const std::vector<Wedge> wedges = expandWedges(source, axes);
  // Every wedge is checked as `lodestone validate` checks a scene, from the
  // file it will be run from, before anything is written or submitted.
  std::vector<std::string> texts;
  for (const Wedge& w : wedges) {
    const fs::path path = dir / wedgeSceneFile(w);
    std::string values;
    for (const auto& [k, v] : w.values) values += (values.empty() ? "" : ", ") + k + " = " + valueText(v);
    texts.push_back(w.scene.dump(2) + "\n");
    try {
      const plugin::Scene scene = plugin::parseScene(texts.back(), path.string());
      plugin::buildSolver(scene);
      if (a.framesGiven && (a.first < scene.startFrame || a.last > scene.lastFrame()))
        throw InvalidArgument(concat("--frames ", a.first, ":", a.last, " but the scene's frames are ",
                                     scene.startFrame, "..", scene.lastFrame()));
    } catch (const Error& e) {
      throw InvalidArgument(concat("wedge ", w.name, " (", values, "): ", e.what()));
    }
  }
  std::printf("%zu wedges of %s, all valid\n", wedges.size(), a.scene.c_str());
  fs::create_directories(dir);
  nlohmann::json manifest = wedgeManifest(fs::absolute(a.scene).string(), axes, wedges);
  manifest["command"] = commandLine(a.args);
  manifest["lodestone_version"] = LODESTONE_VERSION_STRING;
  manifest["checkpoint_every"] = a.checkpointEvery;
  if (a.framesGiven) manifest["frames"] = {a.first, a.last};
  std::vector<std::string> lines, names;
  const std::string exe = selfExecutable();
  for (std::size_t i = 0; i < wedges.size(); ++i) {
    const Wedge& w = wedges[i];
    fs::create_directories(dir / w.name);
    output::writeFileAtomically((dir / wedgeSceneFile(w)).string(), texts[i]);
    const std::string out = (dir / wedgeOutDir(w)).string();
    std::vector<std::string> run{exe, "run", (dir / wedgeSceneFile(w)).string(), "--out", out, "--checkpoint-every",
                                 concat(a.checkpointEvery)};
    if (a.framesGiven) run.insert(run.end(), {"--frames", concat(a.first, ":", a.last)});
    std::string extra;
    if (a.threads > 0)
      run.insert(run.end(), {"--threads", concat(a.threads)});
    else if (a.slurm)
      extra = " --threads \"${SLURM_CPUS_PER_TASK:-1}\"";  // the task's CPUs (sbatch --cpus-per-task)
    lines.push_back(resumingLine(run, out, extra));
    names.push_back(w.name);
  }
  output::writeFileAtomically((dir / kWedgeManifest).string(), manifest.dump(2) + "\n");
  output::writeFileAtomically((dir / kWedgeCsv).string(), wedgeManifestCsv(manifest));
  std::printf("wrote %s/%s and %s\n", dir.string().c_str(), kWedgeManifest, kWedgeCsv);
  int code = dispatch(a, "wedge", dir, lines, names);
  if (a.dryRun) return code;
  if (a.slurm && !a.wait) {
    std::printf("when the array has finished: lodestone wedge-summary %s\n", dir.string().c_str());
    return code;
  }
  wedgeSummary(dir);
  // A wedge that failed shows in the table's status column too.
  for (const nlohmann::json& w : manifest["wedges"])
    if (wedgeStats(dir / w.at("out").get<std::string>()).status != "complete") {
      std::fprintf(stderr, "lodestone: wedge %s did not complete (see %s/logs)\n",
                   w.at("name").get<std::string>().c_str(), dir.string().c_str());
      code = 1;
    }
  return code;
}

// ---------------------------------------------------------------------------
// farm-post

/// What a post-processing task needs of the run directory.
struct PostContext {
  std::string exe;    // this lodestone
  fs::path dir;       // the run directory
  std::string scene;  // its scene file
  double dx = 0;      // its grid spacing, m
  fs::path out;       // DIR/post/TASK
};

/// A per-frame task: the files it reads (PREFIXNNNN.EXT in the run
/// directory), the file it writes per frame in DIR/post/TASK, and the
/// command that makes that file. Another per-frame command is one more
/// entry of postTasks().
struct PostTask {
  std::string name, description;
  std::string inputPrefix, inputExt;    // per frame input in DIR
  std::string outputPrefix, outputExt;  // per frame output in DIR/post/TASK
  std::function<std::vector<std::string>(const PostContext&, int frame)> command;
};

const std::vector<PostTask>& postTasks() {
  static const std::vector<PostTask> tasks = {
      {"export-fields",
       "the field solve of each frame's particles (particles_NNNN.vdb: output.vdb_points) as OpenVDB grids n, phi, "
       "H, M, B, force",
       "particles_", "vdb", "fields_", "vdb",
       [](const PostContext& c, int frame) {
         return std::vector<std::string>{c.exe,
                                         "export-fields",
                                         c.scene,
                                         "--particles",
                                         (c.dir / ("particles_" + frameNumber(frame) + ".vdb")).string(),
                                         "--dx",
                                         concat(c.dx),
                                         "--out",
                                         (c.out / ("fields_" + frameNumber(frame) + ".vdb")).string()};
       }},
  };
  return tasks;
}

const PostTask& postTask(const std::string& name) {
  std::string names;
  for (const PostTask& t : postTasks()) {
    if (t.name == name) return t;
    names += (names.empty() ? "" : ", ") + t.name;
  }
  throw InvalidArgument(concat("--task '", name, "' is not a post-processing task (", names, ")"));
}

int farmPost(FarmArgs& a) {
  const PostTask& task = postTask(a.task);
  const fs::path dir = fs::absolute(a.dir);
  const nlohmann::json manifest = readJson(dir / RunDirectory::kManifest);
  const RunIdentity identity = RunIdentity::fromJson(manifest.at("identity"));
  PostContext c;
  c.exe = selfExecutable();
  c.dir = dir;
  c.scene = a.postScene.empty() ? identity.sceneFile : a.postScene;
  if (!fs::exists(c.scene))
    throw InvalidArgument(concat("the scene of ", dir.string(), " ('", c.scene,
                                 "' as its run was given it) is not found from here: give it with --scene FILE"));
  c.scene = fs::absolute(c.scene).string();
  // The run's grid: the same dx (given as 17 digits).
  char dx[32];
  std::snprintf(dx, sizeof dx, "%.17g", identity.dx);
  c.dx = std::stod(dx);
  c.out = dir / "post" / task.name;
  std::vector<int> frames;
  for (const int f : frameFiles(dir.string(), task.inputPrefix, task.inputExt))
    if (!a.framesGiven || (f >= a.first && f <= a.last)) frames.push_back(f);
  if (frames.empty())
    throw InvalidArgument(concat(dir.string(), " has no ", task.inputPrefix, "NNNN.", task.inputExt, " files",
                                 a.framesGiven ? concat(" in frames ", a.first, ":", a.last) : std::string(),
                                 " for --task ", task.name, " (", task.description, ")"));
  fs::create_directories(c.out);
  if (a.here) {
    // One range, in this process: frames whose output exists are kept (a
    // requeued task continues where it stopped; outputs are written atomically).
    int failed = 0;
    for (const int f : frames) {
      const fs::path target = c.out / (task.outputPrefix + frameNumber(f) + "." + task.outputExt);
      if (fs::exists(target)) {
        std::printf("frame %d: %s exists\n", f, target.string().c_str());
        continue;
      }
      const std::vector<std::string> cmd = task.command(c, f);
      std::printf("frame %d: %s\n", f, commandLine(cmd).c_str());
      std::fflush(stdout);
      const int s = runPool({{cmd, ""}}, 1).front();
      if (s != 0) {
        std::fprintf(stderr, "lodestone: frame %d failed with status %d\n", f, s);
        ++failed;
      }
    }
    return failed == 0 ? 0 : 1;
  }
  if (a.slurm == (a.local > 0) && !a.dryRun) throw InvalidArgument("farm-post: give one of --local N and --slurm");
  std::vector<std::string> lines, names;
  for (std::size_t i = 0; i < frames.size(); i += std::size_t(a.framesPerTask)) {
    const int lo = frames[i], hi = frames[std::min(frames.size(), i + std::size_t(a.framesPerTask)) - 1];
    std::vector<std::string> cmd{c.exe, "farm-post", dir.string(), "--task", task.name, "--scene", c.scene,
                                 "--frames", concat(lo, ":", hi), "--here"};
    lines.push_back("exec " + commandLine(cmd));
    names.push_back(concat("frames ", lo, "-", hi));
  }
  std::printf("%s: %zu frames in %zu tasks of up to %d frames, writing %s\n", task.name.c_str(), frames.size(),
              lines.size(), a.framesPerTask, c.out.string().c_str());
  return dispatch(a, "post-" + task.name, dir / "post", lines, names);
}

void addRunnerOptions(CLI::App& c, FarmArgs& a) {
  cli::addNumber(c, "--local", a.local, "run here, N processes at a time")
      ->type_name("N")
      ->check(cli::wholeNumber(1, 1024));
  c.add_flag("--slurm", a.slurm, "submit one Slurm job array (sbatch --array, one task each)");
  c.add_option("--partition", a.partition, "the Slurm partition (default: the cluster's)")->type_name("P");
  c.add_option("--sbatch-args", a.sbatchArgs,
               "more sbatch options, one argument each (--sbatch-args=--account=fx --sbatch-args=--time=2:00:00)")
      ->type_name("ARG")
      ->allow_extra_args(false);
  c.add_flag("--wait", a.wait, "with --slurm: wait until every task has ended (sbatch --wait), then summarise");
  c.add_flag("--dry-run", a.dryRun,
             "write the files (and the batch script), print what would run, run and submit nothing");
}

// --frames A:B, lowest <= A <= B.
void addFrames(CLI::App& c, FarmArgs& a, const std::string& help, int lowest) {
  c.add_option_function<std::string>(
       "--frames",
       [&a, lowest](const std::string& f) {
         readFrameRange(f, a.first, a.last, lowest);
         a.framesGiven = true;
       },
       help)
      ->type_name("A:B")
      ->check(cli::rule("", [lowest](const std::string& f) {
        int first = 0, last = 0;
        return readFrameRange(f, first, last, lowest);
      }));
}

}  // namespace

void addFarmCommands(CLI::App& app, FarmArgs& a) {
  CLI::App& w = *app.add_subcommand("wedge", "run variants of a scene (a value of each --vary per variant), locally or "
                                             "as a Slurm job array, and summarise them");
  w.add_option("SCENE", a.scene, "scene file (JSON, docs/scenes.md)")->required()->type_name("");
  w.add_option("--vary", a.vary,
               "a JSON path into the scene and its values: magnets[0].magnetization=1e5,2e5 or "
               "materials.ferrofluid.viscosity=1,5 (repeatable; the wedges are every combination)")
      ->required()
      ->type_name("KEY=V1,V2,...")
      ->allow_extra_args(false);
  w.add_option("--out", a.dir, "wedge directory (created)")->required()->type_name("DIR");
  addFrames(w, a, "write frames A..B of each wedge (as lodestone run --frames)", 1);
  cli::addNumber(w, "--checkpoint-every", a.checkpointEvery,
                 "checkpoint each wedge every N frames, so that a requeued or re-run task continues (0 = none)")
      ->type_name("N")
      ->check(cli::wholeNumber(0, 1000000, "frames"))
      ->default_str(cli::formatNumber(a.checkpointEvery));
  cli::addNumber(w, "--threads", a.threads,
                 "worker threads of each run (0: all cores with --local, the task's CPUs with --slurm)")
      ->type_name("N")
      ->check(cli::wholeNumber(0, 1024))
      ->default_str(cli::formatNumber(a.threads));
  addRunnerOptions(w, a);
  w.footer(
      "Writes, in DIR:\n"
      "  wedges.json, wedges.csv  the manifest: each wedge's index, name, values, scene, output\n"
      "  NAME/scene.json          the wedge's scene (NAME: wIII_KEY-VALUE_..., I the index)\n"
      "  NAME/out/                its lodestone run output\n"
      "  logs/wedge_I.log         each task's output\n"
      "  wedge.sbatch, wedge.jobid  with --slurm: the batch script and the array's job id\n"
      "  summary.csv, summary.md, contact_sheet.png  when all have run (or: lodestone wedge-summary DIR)\n"
      "Every wedge is validated (as lodestone validate) before anything is written or submitted.\n"
      "Exit codes: 0 done (or submitted); 1 error, or a wedge failed.");

  CLI::App& s = *app.add_subcommand("wedge-summary", "contact sheet and table of a wedge directory's runs");
  s.add_option("DIR", a.dir, "the --out of lodestone wedge")->required()->type_name("");
  s.footer("Writes DIR/summary.csv, DIR/summary.md and DIR/contact_sheet.png (docs/farm.md).\n"
           "Exit codes: 0 done; 1 error.");

  CLI::App& p = *app.add_subcommand(
      "farm-post", "per-frame post-processing of a run directory, over frame ranges, locally or as a Slurm array");
  p.add_option("DIR", a.dir, "the --out of lodestone run")->required()->type_name("");
  std::string tasks;
  for (const PostTask& t : postTasks()) tasks += "  " + t.name + ": " + t.description + "\n";
  p.add_option("--task", a.task, "what to compute for each frame")->type_name("T")->capture_default_str();
  cli::addNumber(p, "--frames-per-task", a.framesPerTask, "frames per process or array task")
      ->type_name("K")
      ->check(cli::wholeNumber(1, 1000000, "frames"))
      ->default_str(cli::formatNumber(a.framesPerTask));
  addFrames(p, a, "only frames A..B (default: every frame with an input file; frame 0 is the initial state)", 0);
  p.add_option("--scene", a.postScene, "the run's scene file (default: as recorded in DIR/lodestone_run.json)")
      ->type_name("FILE");
  p.add_flag("--here", a.here, "run the frames in this process, one after the other (what each task runs)");
  addRunnerOptions(p, a);
  p.footer("Tasks (outputs in DIR/post/TASK/; a frame whose output exists is skipped):\n" + tasks +
           "Exit codes: 0 done (or submitted); 1 error, or a frame failed.");
}

std::optional<int> runFarmCommand(const std::string& command, FarmArgs& a) {
  if (command == "wedge") return wedge(a);
  if (command == "wedge-summary") return wedgeSummary(fs::absolute(a.dir));
  if (command == "farm-post") return farmPost(a);
  return std::nullopt;
}

}  // namespace lodestone::examples
