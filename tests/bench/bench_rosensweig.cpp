// The Rosensweig instability measured: a flat layer of magnetizable liquid
// with surface tension in a vertical uniform field, at several multiples of
// the onset field H0_c (field/rosensweig_onset.h, docs/physics.md "Spikes"):
// the surface's peak-to-trough height, the spikes (mpm/surface_peaks.h) and
// their mean nearest distance against the capillary wavelength lambda_c.
//
// The scene (default examples/scenes/rosensweig.json) gives the layer, the
// liquid (its first material with surface tension), the grid and the time
// line; its applied fields are replaced by one uniform vertical field of
// ratio * H0_c (or the --applied fields, A/m), switched on over --ramp
// seconds; `--law linear` replaces the
// liquid's law by its linearisation (the same chi0, no saturation) and its
// own onset. Writes per-frame figures to
// --csv and a summary table (markdown) to --table; prints both. Not a test:
// it runs minutes per ratio.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "lodestone/cli/command_line.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/stopwatch.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/field/rosensweig_onset.h"
#include "lodestone/core/mpm/surface_peaks.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/plugin/scene.h"

using namespace lodestone;

namespace {

struct Summary {
  double ratio = 0, appliedH = 0, finalRange = 0, maxRange = 0, finalRms = 0, spacing = 0, seconds = 0;
  double tallest = 0;     ///< highest spike tip above the mean surface, mean over the last quarter of the frames, m
  double lateSpacing = 0; ///< mean nearest spike distance, mean over the last quarter of the frames with spikes, m
  int lateFrames = 0, lateSpacingFrames = 0;
  std::size_t peaks = 0;
  int solves = 0;
  bool converged = true;
};

}  // namespace

int main(int argc, char** argv) {
  try {
    std::string scenePath = std::string(LODESTONE_SCENES_DIR) + "/rosensweig.json";
    std::string csvPath = "bench_rosensweig.csv", tablePath = "bench_rosensweig.md";
    std::vector<double> ratios{0.8, 1.3};
    double ramp = 0.05, dx = 0;
    int frames = 0;
    std::string law = "scene";
    CLI::App app("lodestone-bench-rosensweig: spikes of a magnetizable layer against the Rosensweig onset",
                 "lodestone-bench-rosensweig");
    cli::helpLayout(app, 28);
    app.add_option("--scene", scenePath, "the layer's scene")->type_name("FILE")->capture_default_str();
    cli::addNumberList(app, "--ratios", ratios, "applied fields as multiples of the onset field H0_c (each 0..100)");
    std::vector<double> applied;
    cli::addNumberList(app, "--applied", applied,
                       "applied fields in A/m instead of --ratios (the same fields for either --law)");
    cli::addNumber(app, "--ramp", ramp, "time over which the field is switched on, s")
        ->type_name("S")
        ->default_str(cli::formatNumber(ramp));
    cli::addNumber(app, "--dx", dx, "override the scene's grid spacing, m (0: the scene's)")
        ->type_name("M")
        ->default_str(cli::formatNumber(dx));
    cli::addNumber(app, "--frames", frames, "frames to run (0: the scene's)")
        ->type_name("N")
        ->check(cli::wholeNumber(0, 100000))
        ->default_str(cli::formatNumber(frames));
    app.add_option("--law", law, "the liquid's magnetization law: scene (as in the scene) or linear (its linearisation)")
        ->check(CLI::IsMember({"scene", "linear"}))
        ->capture_default_str();
    app.add_option("--csv", csvPath, "per-frame CSV output")->type_name("FILE")->capture_default_str();
    app.add_option("--table", tablePath, "summary table (markdown)")->type_name("FILE")->capture_default_str();
    if (const std::optional<int> code = cli::parse(app, argc, argv)) return *code;
    for (double r : ratios) require(r >= 0 && r <= 100, "--ratios: ", r, " is not in 0..100");
    require(std::isfinite(ramp) && ramp >= 0, "--ramp: must be >= 0 s, got ", ramp);
    require(std::isfinite(dx) && dx >= 0, "--dx: must be >= 0 m, got ", dx);

    plugin::SceneOptions so;
    so.dx = dx;
    plugin::Scene base = plugin::loadScene(scenePath, so);
    if (frames > 0) base.frames = frames;
    std::size_t liquid = base.materials.size();
    for (std::size_t m = 0; m < base.materials.size(); ++m)
      if (base.materials[m].surfaceTension > 0 && base.materials[m].isMagnetic()) {
        liquid = m;
        break;
      }
    require(liquid < base.materials.size(), scenePath, ": no magnetic material with surface tension");
    if (law == "linear") base.materials[liquid].magnetic = linearized(base.materials[liquid].magnetic);
    const MpmMaterial& mat = base.materials[liquid];
    const double g = norm(base.settings.gravity);
    const RosensweigOnset onset = rosensweigOnset(mat.magnetic, mat.density, mat.surfaceTension, g);
    const double h = base.settings.grid.dx;
    std::printf("%s: rho = %g kg/m^3, sigma = %g N/m, %s\n  onset: M_c = %.1f A/m, H in the liquid %.1f A/m, applied "
                "H0_c = %.1f A/m, lambda_c = %.3f mm (%.1f cells)\n",
                base.name.c_str(), mat.density, mat.surfaceTension, mat.magnetic.describe().c_str(), onset.M, onset.H,
                onset.appliedH, 1e3 * onset.wavelength, onset.wavelength / h);

    if (!applied.empty()) {
      ratios.clear();
      for (const double H : applied) {
        require(std::isfinite(H) && H >= 0, "--applied: ", H, " A/m is not a field >= 0");
        ratios.push_back(H / onset.appliedH);
      }
    }
    std::ofstream csv(csvPath);
    require(bool(csv), "cannot write ", csvPath);
    csv << "law,ratio,applied_H_A_per_m,frame,time_s,range_m,range_cells,rms_cells,peaks,mean_nearest_m,"
           "mean_nearest_over_lambda,tallest_cells\n";
    std::vector<Summary> rows;
    for (const double ratio : ratios) {
      plugin::Scene scene = base;
      FieldSourceSet fields;
      fields.add(UniformField({0, 0, ratio * onset.appliedH}, ramp > 0 ? TimeProfile::ramp(0, ramp) : TimeProfile()));
      scene.fields = std::move(fields);
      auto solver = plugin::buildSolver(scene);
      // The surface away from the walls by half a wavelength.
      const double margin = 0.5 * onset.wavelength;
      const Vec3d lo = solver->domainLower(), hi = solver->domainUpper();
      Summary s;
      s.ratio = ratio;
      s.appliedH = ratio * onset.appliedH;
      const SteadyClock::time_point t0 = SteadyClock::now();
      for (int f = scene.startFrame; f <= scene.lastFrame(); ++f) {
        const MpmFrameReport r = solver->advanceFrame(scene.frameDuration());
        for (const auto& solve : r.magneticReports) s.converged = s.converged && solve.converged();
        s.solves += int(r.magneticReports.size());
        std::vector<Vec3d> surface;
        const MpmParticles& p = solver->particles();
        for (std::size_t i = 0; i < p.size(); ++i)
          if (p.material[i] == liquid) surface.push_back(p.x[i]);
        const SurfaceHeightField field =
            surfaceHeight(surface, lo.x + margin, lo.y + margin, hi.x - margin, hi.y - margin, h);
        // Spikes: peaks rising at least half a cell and 1.5 rms heights above
        // the lowest surface within 0.4 lambda_c (ripples between spikes are
        // not spikes).
        const std::vector<SurfacePeak> peaks =
            findSurfacePeaks(field, 0.4 * onset.wavelength, std::max(0.5 * h, 1.5 * field.rms()));
        const double spacing = meanNearestPeakDistance(field, peaks, 0);
        double tip = field.mean();
        for (const SurfacePeak& pk : peaks) tip = std::max(tip, pk.tip.z);
        if (4 * (f - scene.startFrame) >= 3 * (scene.lastFrame() - scene.startFrame + 1)) {
          s.tallest += tip - field.mean();
          ++s.lateFrames;
          if (!std::isnan(spacing)) {
            s.lateSpacing += spacing;
            ++s.lateSpacingFrames;
          }
        }
        s.finalRange = field.range();
        s.finalRms = field.rms();
        s.maxRange = std::max(s.maxRange, s.finalRange);
        s.peaks = peaks.size();
        s.spacing = spacing;
        csv << law << ',' << ratio << ',' << s.appliedH << ',' << f << ',' << solver->time() << ',' << s.finalRange << ','
            << s.finalRange / h << ',' << s.finalRms / h << ',' << peaks.size() << ',' << spacing << ','
            << spacing / onset.wavelength << ',' << (tip - field.mean()) / h << '\n';
        std::printf("  %.2f H0_c, frame %d (t = %.3f s): range %.2f cells, rms %.3f cells, %zu peaks, mean nearest %.2f "
                    "lambda_c\n",
                    ratio, f, solver->time(), s.finalRange / h, s.finalRms / h, peaks.size(), spacing / onset.wavelength);
        std::fflush(stdout);
      }
      s.seconds = secondsSince(t0);
      s.tallest = s.lateFrames > 0 ? s.tallest / s.lateFrames : 0;
      s.lateSpacing = s.lateSpacingFrames > 0 ? s.lateSpacing / s.lateSpacingFrames : std::nan("");
      rows.push_back(s);
    }
    std::ofstream table(tablePath);
    require(bool(table), "cannot write ", tablePath);
    table << "| law | H0 / H0_c | H0 (A/m) | rms height at the end (cells) | peak-to-trough at the end (cells) | "
             "largest (cells) | tallest spike, last quarter (cells) | spikes | mean nearest / lambda_c, last quarter | "
             "field solves | all converged | run time (s) |\n"
             "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Summary& s : rows) {
      char line[512];
      std::snprintf(line, sizeof line, "| %s | %.2f | %.0f | %.3f | %.2f | %.2f | %.2f | %zu | %s | %d | %s | %.0f |\n",
                    law.c_str(), s.ratio, s.appliedH, s.finalRms / h, s.finalRange / h, s.maxRange / h,
                    s.tallest / h, s.peaks,
                    std::isnan(s.lateSpacing) ? "-"
                                              : cli::formatNumber(std::round(100 * s.lateSpacing / onset.wavelength) / 100).c_str(),
                    s.solves, s.converged ? "yes" : "no", s.seconds);
      table << line;
    }
    table.close();
    std::printf("\nsummary (%s):\n", tablePath.c_str());
    std::ifstream back(tablePath);
    for (std::string line; std::getline(back, line);) std::printf("%s\n", line.c_str());
    std::printf("CSV written to %s\n", csvPath.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone-bench-rosensweig: %s\n", e.what());
    return 1;
  }
}
