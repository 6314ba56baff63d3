// Field-solve benchmark: the nonlinear (Langevin) solve of a sphere and a cube
// of the paper's material (dx = 7.8 mm, n0 = 3.6e17 per cell) on 64^3 and
// 128^3 grids at H0 = 1e4 and 1e5 A/m: first (a new stage from phi = 0,
// including its allocations), cold (phi = 0 on the used stage) and warm (from
// the previous frame's solution, with the applied field changed by 2%).
// Prints a table and writes CSV. Not a test: timings are machine-dependent.
//
// `lodestone-bench-field-solve --help` lists the options. --crop M adds, per case, a cold solve on the material's bounding box plus
// M free cells (what the effects planner's active region does) and the
// relative L2 difference of H over the material nodes from the full grid.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <tbb/info.h>

#include "lodestone/cli/command_line.h"

#include "lodestone/core/stage/density_raster.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/sources/uniform_field.h"

using namespace lodestone;

namespace {

// Density of a sphere (radius N/4 cells) or a cube (edge N/2 cells) centred
// in an N^3 grid: n0 times the volume fraction of each node's dual cell.
DenseGrid<double> body(const GridSpec& g, bool cube, double n0) {
  const Vec3d c = g.origin + 0.5 * g.dx * Vec3d{double(g.dims.i - 1), double(g.dims.j - 1), double(g.dims.k - 1)};
  const double R = 0.25 * (g.dims.i - 1) * g.dx;
  return rasterizeDensity(
      g, n0,
      [&](const Vec3d& x) {
        const Vec3d d = x - c;
        return cube ? (std::fabs(d.x) < R && std::fabs(d.y) < R && std::fabs(d.z) < R) : norm2(d) < R * R;
      },
      4);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::vector<double> sizes{64, 128}, fields{1e4, 1e5};
    std::string csvPath = "bench_field_solve.csv";
    MagneticStageSettings settings;
    bool history = false, linear = false;
    int crop = 0;
    std::string law = "langevin";
    std::string preconditioner = settings.solve.preconditioner == PreconditionerKind::Jacobi ? "jacobi" : "multigrid";
    std::string wallPrediction = settings.solve.predictWall ? "on" : "off";
    std::vector<double> smoothing{double(settings.solve.multigrid.preSmoothing),
                                  double(settings.solve.multigrid.postSmoothing)};
    CLI::App app("lodestone-bench-field-solve: times the nonlinear field solve", "lodestone-bench-field-solve");
    cli::helpLayout(app, 32);
    cli::addNumberList(app, "--sizes", sizes, "grid nodes per axis (each 16..512)");
    cli::addNumberList(app, "--fields", fields, "applied field H0, A/m");
    app.add_option("--preconditioner", preconditioner, "CG preconditioner")
        ->type_name("P")
        ->check(cli::oneOf({"multigrid", "jacobi"}))
        ->capture_default_str();
    cli::addNumber(app, "--tolerance", settings.solve.tolerance, "relative Newton residual")
        ->type_name("X")
        ->check(cli::number())
        ->default_str(cli::formatNumber(settings.solve.tolerance));
    app.add_option("--csv", csvPath, "CSV output")->type_name("FILE")->capture_default_str();
    app.add_flag("--history", history, "print every Newton iteration");
    app.add_option("--law", law, "magnetization law (linear: the paper's chi0 = 0.91 linearization)")
        ->type_name("L")
        ->check(cli::oneOf({"langevin", "linear"}))
        ->capture_default_str();
    cli::addNumber(app, "--crop", crop, "also solve on the material box plus M cells and compare H (0: not)")
        ->type_name("M")
        ->check(cli::wholeNumber(0))
        ->default_str(cli::formatNumber(crop));
    app.add_option("--wall-prediction", wallPrediction, "move the open wall with each Newton step")
        ->type_name("on|off")
        ->check(cli::oneOf({"on", "off"}))
        ->capture_default_str();
    cli::addNumber(app, "--wall-tolerance", settings.solve.wallPredictionTolerance,
                   "relative CG tolerance of the wall-response solve")
        ->type_name("X")
        ->check(cli::number())
        ->default_str(cli::formatNumber(settings.solve.wallPredictionTolerance));
    cli::addNumberList(app, "--smoothing", smoothing, "multigrid damped-Jacobi sweeps per level, PRE,POST")
        ->type_name("PRE,POST");
    if (const std::optional<int> code = cli::parse(app, argc, argv)) return *code;
    linear = law == "linear";
    settings.solve.preconditioner =
        preconditioner == "jacobi" ? PreconditionerKind::Jacobi : PreconditionerKind::Multigrid;
    settings.solve.predictWall = wallPrediction == "on";
    require(smoothing.size() == 2 && smoothing[0] == std::floor(smoothing[0]) && smoothing[1] == std::floor(smoothing[1]),
            "--smoothing: expected PRE,POST sweep counts, e.g. 2,2");
    settings.solve.multigrid.preSmoothing = int(smoothing[0]);
    settings.solve.multigrid.postSmoothing = int(smoothing[1]);
    for (double s : sizes) require(s >= 16 && s <= 512 && s == std::floor(s), "--sizes: ", s, " is not in 16..512");
    settings.validate();

    const MagneticMaterial mat = linear ? linearized(paperMaterial()) : paperMaterial();
    std::ofstream csv(csvPath);
    require(bool(csv), "cannot write ", csvPath);
    csv << "body,nodes_per_axis,H0_A_per_m,start,newton_iterations,cg_iterations,line_search_cuts,relative_residual,"
           "status,material_cells,seconds_solve,seconds_stage,threads,tolerance,seconds_initial,seconds_wall,"
           "seconds_setup,seconds_cg,seconds_line_search,law,wall_prediction,seconds_wall_prediction,"
           "pre_smoothing,post_smoothing,seconds_transfer,seconds_applied_field,seconds_fields,seconds_force\n";
    const int threads = tbb::info::default_concurrency();
    // The solver predicts the open wall with multigrid only.
    const bool predicted =
        settings.solve.predictWall && settings.solve.preconditioner == PreconditionerKind::Multigrid;
    std::printf("Lodestone field-solve benchmark (%d threads, %s law, preconditioner %s, tolerance %.0e, wall "
                "prediction %s, smoothing %d,%d)\n",
                threads, linear ? "linear" : "Langevin", toString(settings.solve.preconditioner),
                settings.solve.tolerance, predicted ? "on" : "off", settings.solve.multigrid.preSmoothing,
                settings.solve.multigrid.postSmoothing);
    std::printf("%-6s %5s %8s %5s %7s %6s %5s %10s %9s %9s\n", "body", "N", "H0", "start", "newton", "cg", "cuts",
                "residual", "solve s", "stage s");
    for (double sN : sizes)
      for (int cube = 0; cube < 2; ++cube)
        for (double H0 : fields) {
          const int N = int(sN);
          GridSpec g;
          g.dx = 7.8e-3;
          g.dims = {N, N, N};
          const DenseGrid<double> n = body(g, cube != 0, mat.numberDensity);
          MagneticForceStage stage(g, mat, settings);
          // Pass 0 "first": a new stage from phi = 0 (its first run also
          // allocates and first touches all storage); pass 1 "cold": the same
          // solve again from phi = 0 on the used stage; pass 2 "warm": from
          // the previous solution with H0 changed by 2%.
          for (int pass = 0; pass < 3; ++pass) {
            const bool warm = pass == 2;
            const char* start = pass == 0 ? "first" : (pass == 1 ? "cold" : "warm");
            if (pass == 1) stage.resetWarmStart();
            const UniformField src({0, 0, H0 * (warm ? 1.02 : 1.0)});
            const MagneticStageReport r = stage.runOnDensity(n.view(), src, 0.0);
            const char* body = cube ? "cube" : "sphere";
            std::printf("%-6s %5d %8.0e %5s %7d %6d %5d %10.2e %9.3f %9.3f%s\n", body, N, H0, start,
                        r.solve.newtonIterations, r.solve.cgIterations, r.solve.lineSearchCuts,
                        r.solve.relativeResidual, r.secondsSolve, r.secondsTotal,
                        r.converged() ? "" : "  NOT CONVERGED");
            if (history) {
              std::printf("    stage: transfer %.3f s, applied field %.3f s, solve %.3f s, nodal H/M/B %.3f s, "
                          "force %.3f s\n",
                          r.secondsTransfer, r.secondsAppliedField, r.secondsSolve, r.secondsFields, r.secondsForce);
              for (const NewtonIterationRecord& h : r.solve.history)
                std::printf("    newton %2d  residual %9.2e  eta %8.1e  cg %3d (%8.1e, wall %d)  step %5.3f%s  cuts %d"
                            "  %.3f s  (wall %.3f, set-up %.3f, cg %.3f, wall prediction %.3f, line search %.3f)%s%s\n",
                            h.iteration, h.relativeResidual, h.forcing, h.cgIterations, h.cgRelativeResidual,
                            h.wallCgIterations, h.step, h.wallPredicted ? "+wall" : "", h.lineSearchCuts, h.seconds,
                            h.secondsWall, h.secondsSetup, h.secondsCg, h.secondsWallPrediction, h.secondsLineSearch,
                            h.jacobianRebuilt ? "  [deferred Jacobian built]" : "",
                            h.jacobianDeferred ? "  [Jacobian deferred]" : "");
            }
            std::fflush(stdout);
            if (crop > 0 && pass == 0) {
              // The material's box plus `crop` free cells, cold.
              int lo[3] = {N, N, N}, hi[3] = {0, 0, 0};
              for (int k = 0; k < N; ++k)
                for (int j = 0; j < N; ++j)
                  for (int i = 0; i < N; ++i)
                    if (n(i, j, k) > 0) {
                      const int c[3] = {i, j, k};
                      for (int a = 0; a < 3; ++a) {
                        lo[a] = std::min(lo[a], c[a]);
                        hi[a] = std::max(hi[a], c[a]);
                      }
                    }
              for (int a = 0; a < 3; ++a) {
                lo[a] = std::max(0, lo[a] - crop);
                hi[a] = std::min(N - 1, hi[a] + crop);
              }
              GridSpec cg = g;
              cg.origin = g.nodePosition(lo[0], lo[1], lo[2]);
              cg.dims = {hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1};
              DenseGrid<double> cn(cg, 0.0);
              for (int k = 0; k < cg.dims.k; ++k)
                for (int j = 0; j < cg.dims.j; ++j)
                  for (int i = 0; i < cg.dims.i; ++i) cn(i, j, k) = n(lo[0] + i, lo[1] + j, lo[2] + k);
              MagneticForceStage cropped(cg, mat, settings);
              const MagneticStageReport rc = cropped.runOnDensity(cn.view(), src, 0.0);
              double num = 0, den = 0;
              for (int k = 0; k < cg.dims.k; ++k)
                for (int j = 0; j < cg.dims.j; ++j)
                  for (int i = 0; i < cg.dims.i; ++i)
                    if (cn(i, j, k) > 0) {
                      const Vec3d Hf = stage.field()[g.index(lo[0] + i, lo[1] + j, lo[2] + k)];
                      num += norm2(cropped.field()[cg.index(i, j, k)] - Hf);
                      den += norm2(Hf);
                    }
              std::printf("  cropped to %dx%dx%d (+%d cells): newton %d, cg %d, solve %.3f s, stage %.3f s; H differs "
                          "by %.2e (relative L2 over the material)\n",
                          cg.dims.i, cg.dims.j, cg.dims.k, crop, rc.solve.newtonIterations, rc.solve.cgIterations,
                          rc.secondsSolve, rc.secondsTotal, std::sqrt(num / den));
            }
            csv << body << ',' << N << ',' << H0 << ',' << start << ',' << r.solve.newtonIterations
                << ',' << r.solve.cgIterations << ',' << r.solve.lineSearchCuts << ',' << r.solve.relativeResidual
                << ',' << toString(r.solve.status) << ',' << r.solve.materialCells << ',' << r.secondsSolve << ','
                << r.secondsTotal << ',' << threads << ',' << settings.solve.tolerance << ',' << r.solve.secondsInitial;
            {
              // Solve time by phase, summed over the Newton iterations.
              double wall = 0, setup = 0, cgs = 0, search = 0, predict = 0;
              for (const NewtonIterationRecord& h : r.solve.history) {
                wall += h.secondsWall;
                predict += h.secondsWallPrediction;
                setup += h.secondsSetup;
                cgs += h.secondsCg;
                search += h.secondsLineSearch;
              }
              csv << ',' << wall << ',' << setup << ',' << cgs << ',' << search << ',' << (linear ? "linear" : "langevin")
                  << ',' << (predicted ? "on" : "off") << ',' << predict << ',' << settings.solve.multigrid.preSmoothing
                  << ',' << settings.solve.multigrid.postSmoothing << ',' << r.secondsTransfer << ','
                  << r.secondsAppliedField << ',' << r.secondsFields << ',' << r.secondsForce << '\n';
            }
          }
        }
    std::printf("CSV written to %s\n", csvPath.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone-bench-field-solve: %s\n", e.what());
    return 1;
  }
}
