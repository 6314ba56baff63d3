// Effects-planner benchmark: every example scene run twice from the same
// start, with every stage on (planner off) and with the planner (the scene's
// accuracy preset as budget, or --budget), at the scene's default grid for a
// few frames. Prints wall times, the speedup and the measured deviation of
// the planned run from the full one, and writes CSV. Not a test: timings are
// machine-dependent; the ratios come from one run.
//
// `lodestone-bench-planner --help` lists the options.
//
// Deviation: the largest distance over frames between the centres of mass of
// each material in the two runs, relative to how far that centre moved in
// the full run (at least one cell, so a body at rest is not divided by zero).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "lodestone/cli/command_line.h"
#include "lodestone/core/base/error.h"
#include "lodestone/plugin/scene.h"

using namespace lodestone;
using namespace lodestone::plugin;

namespace {

struct Run {
  double seconds = 0;
  int solves = 0, reused = 0;
  std::vector<std::vector<Vec3d>> com;  // [frame][material]
  std::string plan;
};

std::vector<Vec3d> centres(const MpmSolver& s, std::size_t materials) {
  std::vector<Vec3d> c(materials);
  std::vector<double> m(materials, 0.0);
  const MpmParticles& p = s.particles();
  for (std::size_t q = 0; q < p.size(); ++q) {
    c[p.material[q]] += p.mass[q] * p.x[q];
    m[p.material[q]] += p.mass[q];
  }
  for (std::size_t k = 0; k < materials; ++k) c[k] = m[k] > 0 ? c[k] / m[k] : Vec3d{};
  return c;
}

Run simulate(const Scene& scene, int frames) {
  Run r;
  auto solver = buildSolver(scene);
  const std::size_t materials = scene.materials.size();
  r.com.push_back(centres(*solver, materials));
  const auto t0 = std::chrono::steady_clock::now();
  for (int f = 0; f < frames; ++f) {
    const MpmFrameReport fr = solver->advanceFrame(scene.frameDuration());
    r.solves += int(fr.magneticReports.size());
    r.reused += fr.magneticReused;
    r.com.push_back(centres(*solver, materials));
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (const StageDecision& d : solver->lastMagneticPlan().decisions)
    if (d.stage != "field reuse") r.plan += (r.plan.empty() ? "" : "; ") + d.stage + ": " + d.choice;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    int frames = 4;
    double budget = 0;  // 0: the scene's preset, else 0.05
    std::string csvPath = "bench_planner.csv";
    PlannerToggle region = PlannerToggle::Auto;
    std::vector<std::string> scenes;
    std::string regionName = "auto";
    CLI::App app("lodestone-bench-planner: every example scene with all stages on and with the effects planner",
                 "lodestone-bench-planner");
    cli::helpLayout(app, 24);
    app.add_option("SCENE.json", scenes, "scenes to run (default: every scene in examples/scenes)")->type_name("");
    cli::addNumber(app, "--frames", frames, "frames per run (fewer when the scene has fewer)")
        ->type_name("N")
        ->check(cli::wholeNumber(1, 1000))
        ->default_str(cli::formatNumber(frames));
    cli::addNumber(app, "--budget", budget, "the planner's accuracy budget (0: the scene's preset)")
        ->type_name("B")
        ->check(cli::number())
        ->default_str(cli::formatNumber(budget));
    app.add_option("--region", regionName, "the planner's active region")
        ->type_name("R")
        ->check(cli::oneOf({"auto", "on", "off"}))
        ->capture_default_str();
    app.add_option("--csv", csvPath, "CSV output")->type_name("FILE")->capture_default_str();
    if (const std::optional<int> code = cli::parse(app, argc, argv)) return *code;
    region = parsePlannerToggle(regionName);
    if (scenes.empty()) {
      for (const auto& e : std::filesystem::directory_iterator(LODESTONE_SCENES_DIR))
        if (e.path().extension() == ".json") scenes.push_back(e.path().string());
      std::sort(scenes.begin(), scenes.end());
    }
    std::ofstream csv(csvPath);
    require(bool(csv), "cannot write ", csvPath);
    csv << "scene,frames,budget,seconds_full,seconds_planned,speedup,solves_full,solves_planned,reused,deviation,"
           "decisions\n";
    std::printf("%-22s %6s %8s %8s %7s %9s %9s %10s  %s\n", "scene", "budget", "full s", "plan s", "speedup",
                "solves", "reused", "deviation", "decisions");
    for (const std::string& path : scenes) {
      Scene full = loadScene(path);
      full.frames = std::min(full.frames, frames);
      full.settings.planner.enabled = false;
      Scene planned = loadScene(path);  // scenes own their magnets: load twice
      planned.frames = full.frames;
      planned.settings.planner.enabled = true;
      planned.settings.planner.activeRegion = region;
      if (budget > 0) planned.settings.planner.budget = budget;
      else if (!planned.accuracy) planned.settings.planner.budget = 0.05;
      const Run a = simulate(full, full.frames), b = simulate(planned, full.frames);
      double dev = 0;
      for (std::size_t k = 0; k < full.materials.size(); ++k) {
        double moved = full.settings.grid.dx, diff = 0;
        for (std::size_t f = 0; f < a.com.size(); ++f) {
          moved = std::max(moved, norm(a.com[f][k] - a.com[0][k]));
          diff = std::max(diff, norm(a.com[f][k] - b.com[f][k]));
        }
        dev = std::max(dev, diff / moved);
      }
      const std::string name = std::filesystem::path(path).stem().string();
      std::printf("%-22s %5.1f%% %8.2f %8.2f %6.2fx %4d/%-4d %9d %9.2e  %s\n", name.c_str(),
                  100 * planned.settings.planner.budget, a.seconds, b.seconds, a.seconds / b.seconds, b.solves,
                  a.solves, b.reused, dev, b.plan.c_str());
      std::fflush(stdout);
      csv << name << ',' << full.frames << ',' << planned.settings.planner.budget << ',' << a.seconds << ','
          << b.seconds << ',' << a.seconds / b.seconds << ',' << a.solves << ',' << b.solves << ',' << b.reused << ','
          << dev << ",\"" << b.plan << "\"\n";
    }
    std::printf("CSV written to %s\n", csvPath.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone-bench-planner: %s\n", e.what());
    return 1;
  }
}
