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
// own onset. `--sources scene` keeps the scene's magnets and fields instead
// (one run; the desk toy, examples/scenes/desk_toy.json): every frame the
// onset is taken along the radius from the domain's vertical centre line,
// with the gravity the magnet's pull adds there (gravityNearMagnet), and the
// spikes are measured within --radius of that line. Writes per-frame figures to
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
#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/stopwatch.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/field/rosensweig_onset.h"
#include "lodestone/core/mpm/surface_peaks.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/plugin/scene.h"

using namespace lodestone;

namespace {

// The onset along the radius from the domain's vertical centre line at the
// surface's height z (m), in the applied field of `solver` now: at the
// centre, and the distance rc (m) within which the applied vertical field
// passes the onset field (where the magnet's pull, which raises the onset
// as g^(1/4), is taken into account).
struct LocalOnset {
  RosensweigOnset centre;
  double appliedH = 0;  ///< applied vertical field at the centre, A/m
  double gravity = 0;   ///< gravity with the magnet's pull at the centre, m/s^2
  double rc = 0;        ///< radius of the region above onset, m (0: none)
};

LocalOnset onsetAlongRadius(const MpmSolver& solver, const MpmMaterial& mat, double g, double z, double radius) {
  const Vec3d lo = solver.domainLower(), hi = solver.domainUpper();
  const Vec3d c{0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), z};
  const double dz = 0.25 * solver.grid().spec().dx, t = solver.time();
  const FieldSource& source = solver.appliedField();
  LocalOnset out;
  constexpr int kSamples = 64, kDirections = 8;
  for (int k = 0; k <= kSamples; ++k) {
    const double r = radius * k / kSamples;
    double ratio = 0;  // the mean over directions of the applied vertical field over its onset field
    for (int d = 0; d < kDirections; ++d) {
      const double a = 2 * kPi * d / kDirections;
      const Vec3d x = c + Vec3d{r * std::cos(a), r * std::sin(a), 0};
      const double H0 = std::max(0.0, source.field(x, t).z);
      const double dH = (source.field(x + Vec3d{0, 0, dz}, t).z - source.field(x - Vec3d{0, 0, dz}, t).z) / (2 * dz);
      const double gHere = gravityNearMagnet(mat.magnetic, mat.density, H0, dH, g);
      const RosensweigOnset o = rosensweigOnset(mat.magnetic, mat.density, mat.surfaceTension, gHere);
      ratio += H0 / o.appliedH / kDirections;
      if (k == 0 && d == 0) {
        out.centre = o;
        out.appliedH = H0;
        out.gravity = gHere;
      }
    }
    if (ratio < 1) break;
    out.rc = r;
  }
  return out;
}

struct Summary {
  double ratio = 0, appliedH = 0, finalRange = 0, maxRange = 0, finalRms = 0, spacing = 0, seconds = 0;
  double outermost = 0;  ///< the spike farthest from the centre line at the end, m (--sources scene)
  LocalOnset local;      ///< the onset at the end (--sources scene)
  double tallest = 0;    ///< highest spike tip above the mean surface, mean over the last quarter of the frames, m
  /// mean nearest spike distance over the wavelength, mean over the last quarter of the frames with spikes
  double lateSpacing = 0;
  int lateFrames = 0, lateSpacingFrames = 0;
  std::size_t peaks = 0;
  int solves = 0;
  bool converged = true;
};

}  // namespace

int main(int argc, char** argv) {
  try {
    std::string scenePath = std::string(LODESTONE_SCENES_DIR) + "/rosensweig.json";
    std::string csvPath = "bench_rosensweig.csv", tablePath = "bench_rosensweig.md", surfacePath;
    std::vector<double> ratios{0.8, 1.3};
    double ramp = 0.05, dx = 0;
    int frames = 0;
    std::string law = "scene", sources = "uniform";
    double radius = 0;
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
    app.add_option("--law", law,
                   "the liquid's magnetization law: scene (as in the scene) or linear (its linearisation)")
        ->check(CLI::IsMember({"scene", "linear"}))
        ->capture_default_str();
    app.add_option("--sources", sources,
                   "uniform (the scene's magnets and fields replaced by a uniform vertical field at each ratio) or "
                   "scene (its own, one run; the onset from the field along the radius)")
        ->check(CLI::IsMember({"uniform", "scene"}))
        ->capture_default_str();
    cli::addNumber(app, "--radius", radius,
                   "with --sources scene: measure within this distance of the domain's vertical centre line, m")
        ->type_name("M")
        ->default_str(cli::formatNumber(radius));
    app.add_option("--csv", csvPath, "per-frame CSV output")->type_name("FILE")->capture_default_str();
    app.add_option("--table", tablePath, "summary table (markdown)")->type_name("FILE")->capture_default_str();
    app.add_option("--surface", surfacePath,
                   "the last frame's surface of the last run (CSV: kind cell or spike, x, y, z in m) for plots")
        ->type_name("FILE");
    if (const std::optional<int> code = cli::parse(app, argc, argv)) return *code;
    for (double r : ratios) require(r >= 0 && r <= 100, "--ratios: ", r, " is not in 0..100");
    require(std::isfinite(ramp) && ramp >= 0, "--ramp: must be >= 0 s, got ", ramp);
    require(std::isfinite(dx) && dx >= 0, "--dx: must be >= 0 m, got ", dx);
    require(std::isfinite(radius) && radius >= 0, "--radius: must be >= 0 m, got ", radius);
    const bool sceneSources = sources == "scene";
    require(!sceneSources || radius > 0, "--sources scene needs --radius (the region to measure, m)");

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
    std::printf(
        "%s: rho = %g kg/m^3, sigma = %g N/m, %s\n  onset: M_c = %.1f A/m, H in the liquid %.1f A/m, applied "
        "H0_c = %.1f A/m, lambda_c = %.3f mm (%.1f cells)\n",
        base.name.c_str(), mat.density, mat.surfaceTension, mat.magnetic.describe().c_str(), onset.M, onset.H,
        onset.appliedH, 1e3 * onset.wavelength, onset.wavelength / h);

    if (sceneSources) ratios = {std::nan("")};
    if (!applied.empty() && !sceneSources) {
      ratios.clear();
      for (const double H : applied) {
        require(std::isfinite(H) && H >= 0, "--applied: ", H, " A/m is not a field >= 0");
        ratios.push_back(H / onset.appliedH);
      }
    }
    std::ofstream csv(csvPath);
    require(bool(csv), "cannot write ", csvPath);
    csv << "law,ratio,applied_H_A_per_m,frame,time_s,range_m,range_cells,rms_cells,peaks,mean_nearest_m,"
           "mean_nearest_over_lambda,tallest_cells,centre_applied_H_A_per_m,centre_gravity_m_per_s2,"
           "centre_lambda_m,centre_onset_H0_A_per_m,onset_radius_m,outermost_spike_m\n";
    std::vector<Summary> rows;
    for (const double ratio : ratios) {
      plugin::Scene scene = base;
      if (!sceneSources) {
        FieldSourceSet fields;
        fields.add(UniformField({0, 0, ratio * onset.appliedH}, ramp > 0 ? TimeProfile::ramp(0, ramp) : TimeProfile()));
        scene.fields = std::move(fields);
      }
      auto solver = plugin::buildSolver(scene);
      const Vec3d lo = solver->domainLower(), hi = solver->domainUpper();
      const double cx = 0.5 * (lo.x + hi.x), cy = 0.5 * (lo.y + hi.y);
      // The surface's height (m) at which the onset is taken: the layer's top
      // over the centre line at the start, then the measured mean surface.
      double surfaceZ = lo.z;
      for (std::size_t i = 0; i < solver->particles().size(); ++i) {
        const Vec3d& x = solver->particles().x[i];
        if (solver->particles().material[i] == liquid && std::hypot(x.x - cx, x.y - cy) < 2 * h)
          surfaceZ = std::max(surfaceZ, x.z);
      }
      Summary s;
      s.ratio = ratio;
      s.appliedH = ratio * onset.appliedH;
      const SteadyClock::time_point t0 = SteadyClock::now();
      for (int f = scene.startFrame; f <= scene.lastFrame(); ++f) {
        const MpmFrameReport r = solver->advanceFrame(scene.frameDuration());
        for (const auto& solve : r.magneticReports) s.converged = s.converged && solve.converged();
        s.solves += int(r.magneticReports.size());
        // The surface away from the walls by half a wavelength (within
        // --radius less half a wavelength of the centre line).
        LocalOnset local;  // uniform: the same everywhere
        local.centre = onset;
        local.appliedH = s.appliedH;
        local.gravity = g;
        local.rc = std::nan("");
        double lambda = onset.wavelength, x0 = lo.x + 0.5 * lambda, x1 = hi.x - 0.5 * lambda;
        double y0 = lo.y + 0.5 * lambda, y1 = hi.y - 0.5 * lambda, keep = radius;
        std::vector<Vec3d> surface;
        const MpmParticles& p = solver->particles();
        if (sceneSources) {
          local = onsetAlongRadius(*solver, mat, g, surfaceZ, radius);
          lambda = local.centre.wavelength;
          keep = radius - 0.5 * lambda;
          require(keep > 2 * lambda, "--radius ", radius, " m leaves less than two wavelengths (", lambda,
                  " m) to measure");
          x0 = cx - keep, x1 = cx + keep, y0 = cy - keep, y1 = cy + keep;
        }
        for (std::size_t i = 0; i < p.size(); ++i)
          if (p.material[i] == liquid && (!sceneSources || std::hypot(p.x[i].x - cx, p.x[i].y - cy) < keep))
            surface.push_back(p.x[i]);
        const SurfaceHeightField field = surfaceHeight(surface, x0, y0, x1, y1, h);
        // Spikes: peaks rising at least half a cell and 1.5 rms heights above
        // the lowest surface within 0.4 lambda_c (ripples between spikes are
        // not spikes).
        std::vector<SurfacePeak> peaks = findSurfacePeaks(field, 0.4 * lambda, std::max(0.5 * h, 1.5 * field.rms()));
        // A disc's edge cuts the search around its outer cells: those are no
        // peaks (the surface rising toward the wall beyond would be higher).
        if (sceneSources)
          peaks.erase(std::remove_if(peaks.begin(), peaks.end(),
                                     [&](const SurfacePeak& pk) {
                                       return std::hypot(pk.tip.x - cx, pk.tip.y - cy) > keep - 0.4 * lambda;
                                     }),
                      peaks.end());
        s.outermost = 0;
        for (const SurfacePeak& pk : peaks)
          s.outermost = std::max(s.outermost, std::hypot(pk.tip.x - cx, pk.tip.y - cy));
        s.local = local;
        const double spacing = meanNearestPeakDistance(field, peaks, 0);
        double tip = field.mean();
        for (const SurfacePeak& pk : peaks) tip = std::max(tip, pk.tip.z);
        if (4 * (f - scene.startFrame) >= 3 * (scene.lastFrame() - scene.startFrame + 1)) {
          s.tallest += tip - field.mean();
          ++s.lateFrames;
          if (!std::isnan(spacing)) {
            s.lateSpacing += spacing / lambda;
            ++s.lateSpacingFrames;
          }
        }
        surfaceZ = field.mean();
        if (!surfacePath.empty() && f == scene.lastFrame()) {
          std::ofstream out(surfacePath);
          require(bool(out), "cannot write ", surfacePath);
          out << "kind,x_m,y_m,z_m\n";
          for (int j = 0; j < field.ny; ++j)
            for (int i = 0; i < field.nx; ++i)
              if (!std::isnan(field.at(i, j)))
                out << "cell," << field.x0 + (i + 0.5) * h << ',' << field.y0 + (j + 0.5) * h << ',' << field.at(i, j)
                    << '\n';
          for (const SurfacePeak& pk : peaks) out << "spike," << pk.tip.x << ',' << pk.tip.y << ',' << pk.tip.z << '\n';
        }
        s.finalRange = field.range();
        s.finalRms = field.rms();
        s.maxRange = std::max(s.maxRange, s.finalRange);
        s.peaks = peaks.size();
        s.spacing = spacing;
        csv << law << ',' << (sceneSources ? local.appliedH / local.centre.appliedH : ratio) << ',' << local.appliedH
            << ',' << f << ',' << solver->time() << ',' << s.finalRange << ',' << s.finalRange / h << ','
            << s.finalRms / h << ',' << peaks.size() << ',' << spacing << ',' << spacing / lambda << ','
            << (tip - field.mean()) / h << ',' << local.appliedH << ',' << local.gravity << ','
            << local.centre.wavelength << ',' << local.centre.appliedH << ',' << local.rc << ',' << s.outermost << '\n';
        if (sceneSources)
          std::printf(
              "  frame %d (t = %.3f s): centre H0 %.0f A/m = %.2f H0_c (g %.2f m/s^2, lambda %.2f mm), above "
              "onset within %.1f mm; range %.2f cells, rms %.3f cells, %zu peaks (outermost %.1f mm), mean "
              "nearest %.2f lambda\n",
              f, solver->time(), local.appliedH, local.appliedH / local.centre.appliedH, local.gravity, 1e3 * lambda,
              1e3 * local.rc, s.finalRange / h, s.finalRms / h, peaks.size(), 1e3 * s.outermost, spacing / lambda);
        else
          std::printf(
              "  %.2f H0_c, frame %d (t = %.3f s): range %.2f cells, rms %.3f cells, %zu peaks, mean nearest "
              "%.2f lambda_c\n",
              ratio, f, solver->time(), s.finalRange / h, s.finalRms / h, peaks.size(), spacing / lambda);
        std::fflush(stdout);
      }
      s.seconds = secondsSince(t0);
      s.tallest = s.lateFrames > 0 ? s.tallest / s.lateFrames : 0;
      s.lateSpacing = s.lateSpacingFrames > 0 ? s.lateSpacing / s.lateSpacingFrames : std::nan("");
      if (sceneSources) {
        s.appliedH = s.local.appliedH;
        s.ratio = s.local.appliedH / s.local.centre.appliedH;
      }
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
                    law.c_str(), s.ratio, s.appliedH, s.finalRms / h, s.finalRange / h, s.maxRange / h, s.tallest / h,
                    s.peaks,
                    std::isnan(s.lateSpacing) ? "-" : cli::formatNumber(std::round(100 * s.lateSpacing) / 100).c_str(),
                    s.solves, s.converged ? "yes" : "no", s.seconds);
      table << line;
    }
    if (sceneSources) {
      const Summary& s = rows.front();
      table << "\n| at the end, centre | applied H0 (A/m) | gravity with the pull (m/s^2) | onset H0_c (A/m) | "
               "lambda (mm) | above onset within (mm) | outermost spike (mm) |\n|---|---|---|---|---|---|---|\n";
      char line[512];
      std::snprintf(line, sizeof line, "| %s | %.0f | %.2f | %.0f | %.2f | %.1f | %.1f |\n", base.name.c_str(),
                    s.local.appliedH, s.local.gravity, s.local.centre.appliedH, 1e3 * s.local.centre.wavelength,
                    1e3 * s.local.rc, 1e3 * s.outermost);
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
