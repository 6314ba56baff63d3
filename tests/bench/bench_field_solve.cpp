// Field-solve benchmark: the nonlinear (Langevin) solve of a sphere and a cube
// of the paper's material (dx = 7.8 mm, n0 = 3.6e17 per cell) on 64^3 and
// 128^3 grids at H0 = 1e4 and 1e5 A/m: first (a new stage from phi = 0,
// including its allocations), cold (phi = 0 on the used stage) and warm (from
// the previous frame's solution, with the applied field changed by 2%).
// Prints a table and writes CSV. Not a test: timings are machine-dependent.
//
// `lodestone-bench-field-solve --help` lists the options. --active-region M
// adds, per case and start, the same stage on the grid the MPM solver's
// planner solves on: the material's box plus the stencil's 3 cells, M free
// cells (effects_planner.h: 4 for a decision share of 0.5%, 8 for 0.1%) and
// the solver's 4 cells of slack, with the relative L2 differences of H over
// the material nodes and of the nodal force over the region from the full
// grid's solve of the same start.
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

#include "lodestone/core/base/error.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/planner/effects_planner.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/core/stage/density_raster.h"
#include "lodestone/core/stage/magnetic_stage.h"

using namespace lodestone;

namespace {

// A sphere (radius N/4 cells) or a cube (edge N/2 cells) centred in an N^3 grid.
struct Body {
  Vec3d centre;  // m
  double R = 0;  // radius or half edge, m
  bool cube = false;

  explicit Body(const GridSpec& g, bool isCube)
      : centre(g.origin + 0.5 * g.dx * Vec3d{double(g.dims.i - 1), double(g.dims.j - 1), double(g.dims.k - 1)}),
        R(0.25 * (g.dims.i - 1) * g.dx),
        cube(isCube) {}
  bool inside(const Vec3d& x) const {
    const Vec3d d = x - centre;
    return cube ? (std::fabs(d.x) < R && std::fabs(d.y) < R && std::fabs(d.z) < R) : norm2(d) < R * R;
  }
  // The body's density: n0 times the volume fraction of each node's dual cell.
  DenseGrid<double> density(const GridSpec& g, double n0) const {
    return rasterizeDensity(
        g, n0, [&](const Vec3d& x) { return inside(x); }, 4);
  }
};

// Relative L2 difference of a over b on the nodes of `sub` (a's grid) where
// `keep` holds; b lies on `whole`, which contains `sub`.
template <typename Keep>
double relativeDifference(GridView<const Vec3d> a, GridView<const Vec3d> b, const GridSpec& sub, const GridSpec& whole,
                          const Keep& keep) {
  const int oi = int(std::lround((sub.origin.x - whole.origin.x) / whole.dx));
  const int oj = int(std::lround((sub.origin.y - whole.origin.y) / whole.dx));
  const int ok = int(std::lround((sub.origin.z - whole.origin.z) / whole.dx));
  double num = 0, den = 0;
  for (int k = 0; k < sub.dims.k; ++k)
    for (int j = 0; j < sub.dims.j; ++j)
      for (int i = 0; i < sub.dims.i; ++i)
        if (keep(i, j, k)) {
          const Vec3d ref = b(oi + i, oj + j, ok + k);
          num += norm2(a(i, j, k) - ref);
          den += norm2(ref);
        }
  return den > 0 ? std::sqrt(num / den) : 0.0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::vector<double> sizes{64, 128}, fields{1e4, 1e5};
    std::string csvPath = "bench_field_solve.csv";
    MagneticStageSettings settings;
    bool history = false, linear = false;
    int activeMargin = 0;
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
    cli::addNumber(app, "--active-region", activeMargin,
                   "also solve on the planner's active region with M free cells (4..64; 0: not) and compare")
        ->type_name("M")
        ->check(cli::wholeNumber(0))
        ->default_str(cli::formatNumber(activeMargin));
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
    require(activeMargin == 0 || (activeMargin >= 4 && activeMargin <= 64), "--active-region: ", activeMargin,
            " is not 0 or in 4..64");
    settings.validate();

    const MagneticMaterial mat = linear ? linearized(paperMaterial()) : paperMaterial();
    std::ofstream csv(csvPath);
    require(bool(csv), "cannot write ", csvPath);
    csv << "body,nodes_per_axis,H0_A_per_m,start,newton_iterations,cg_iterations,line_search_cuts,relative_residual,"
           "status,material_cells,seconds_solve,seconds_stage,threads,tolerance,seconds_initial,seconds_wall,"
           "seconds_setup,seconds_cg,seconds_line_search,law,wall_prediction,seconds_wall_prediction,"
           "pre_smoothing,post_smoothing,seconds_transfer,seconds_applied_field,seconds_fields,seconds_force,"
           "grid,grid_nodes,H_difference,force_difference\n";
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
    // One stage run's row: printed, and written to the CSV.
    const auto report = [&](const char* body, int N, double H0, const char* start, const MagneticStageReport& r,
                            const char* grid, std::size_t gridNodes, double dH, double dF) {
      std::printf("%-6s %5d %8.0e %5s %7d %6d %5d %10.2e %9.3f %9.3f", body, N, H0, start, r.solve.newtonIterations,
                  r.solve.cgIterations, r.solve.lineSearchCuts, r.solve.relativeResidual, r.secondsSolve,
                  r.secondsTotal);
      if (dH >= 0) std::printf("  %s (%zu nodes): H differs by %.2e, force by %.2e", grid, gridNodes, dH, dF);
      std::printf("%s\n", r.converged() ? "" : "  NOT CONVERGED");
      if (history) {
        std::printf(
            "    stage: transfer %.3f s, applied field %.3f s, solve %.3f s, nodal H/M/B %.3f s, "
            "force %.3f s\n",
            r.secondsTransfer, r.secondsAppliedField, r.secondsSolve, r.secondsFields, r.secondsForce);
        for (const NewtonIterationRecord& h : r.solve.history)
          std::printf(
              "    newton %2d  residual %9.2e  eta %8.1e  cg %3d (%8.1e, wall %d)  step %5.3f%s  cuts %d"
              "  %.3f s  (wall %.3f, set-up %.3f, cg %.3f, wall prediction %.3f, line search %.3f)%s%s%s\n",
              h.iteration, h.relativeResidual, h.forcing, h.cgIterations, h.cgRelativeResidual, h.wallCgIterations,
              h.step, h.wallPredicted ? "+wall" : "", h.lineSearchCuts, h.seconds, h.secondsWall, h.secondsSetup,
              h.secondsCg, h.secondsWallPrediction, h.secondsLineSearch,
              h.jacobianRebuilt ? "  [deferred Jacobian built]" : "", h.chord ? "  [chord: the Jacobian before]" : "",
              h.jacobianDeferred ? "  [Jacobian deferred]" : "");
      }
      std::fflush(stdout);
      // Solve time by phase, summed over the Newton iterations.
      double wall = 0, setup = 0, cgs = 0, search = 0, predict = 0;
      for (const NewtonIterationRecord& h : r.solve.history) {
        wall += h.secondsWall;
        predict += h.secondsWallPrediction;
        setup += h.secondsSetup;
        cgs += h.secondsCg;
        search += h.secondsLineSearch;
      }
      csv << body << ',' << N << ',' << H0 << ',' << start << ',' << r.solve.newtonIterations << ','
          << r.solve.cgIterations << ',' << r.solve.lineSearchCuts << ',' << r.solve.relativeResidual << ','
          << toString(r.solve.status) << ',' << r.solve.materialCells << ',' << r.secondsSolve << ',' << r.secondsTotal
          << ',' << threads << ',' << settings.solve.tolerance << ',' << r.solve.secondsInitial << ',' << wall << ','
          << setup << ',' << cgs << ',' << search << ',' << (linear ? "linear" : "langevin") << ','
          << (predicted ? "on" : "off") << ',' << predict << ',' << settings.solve.multigrid.preSmoothing << ','
          << settings.solve.multigrid.postSmoothing << ',' << r.secondsTransfer << ',' << r.secondsAppliedField << ','
          << r.secondsFields << ',' << r.secondsForce << ',' << grid << ',' << gridNodes << ',';
      if (dH >= 0)
        csv << dH << ',' << dF;
      else
        csv << ',';
      csv << '\n';
    };
    for (double sN : sizes)
      for (int cube = 0; cube < 2; ++cube)
        for (double H0 : fields) {
          const int N = int(sN);
          GridSpec g;
          g.dx = 7.8e-3;
          g.dims = {N, N, N};
          const Body shape(g, cube != 0);
          const DenseGrid<double> n = shape.density(g, mat.numberDensity);
          MagneticForceStage stage(g, mat, settings);
          // The planner's active region (the solver's slack included) and
          // the density there: the full grid's, node for node.
          std::optional<MagneticForceStage> region;
          DenseGrid<double> rn;
          if (activeMargin > 0) {
            const Vec3d half{shape.R, shape.R, shape.R};
            const GridSpec rg =
                widenedRegion(activeRegionGrid(g, shape.centre - half, shape.centre + half, activeMargin), g,
                              kActiveRegionSlackCells);
            rn = shape.density(rg, mat.numberDensity);
            region.emplace(rg, mat, settings);
          }
          const char* body = cube ? "cube" : "sphere";
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
            report(body, N, H0, start, r, "full", g.nodeCount(), -1, -1);
            if (!region) continue;
            if (pass == 1) region->resetWarmStart();
            const MagneticStageReport rr = region->runOnDensity(rn.view(), src, 0.0);
            const GridSpec& rg = region->grid();
            const double dH = relativeDifference(region->field(), stage.field(), rg, g,
                                                 [&](int i, int j, int k) { return rn(i, j, k) > 0; });
            const double dF =
                relativeDifference(region->nodalForce(), stage.nodalForce(), rg, g, [](int, int, int) { return true; });
            const std::string label = "active " + std::to_string(rg.dims.i) + "x" + std::to_string(rg.dims.j) + "x" +
                                      std::to_string(rg.dims.k);
            report(body, N, H0, start, rr, label.c_str(), rg.nodeCount(), dH, dF);
          }
        }
    std::printf("CSV written to %s\n", csvPath.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone-bench-field-solve: %s\n", e.what());
    return 1;
  }
}
