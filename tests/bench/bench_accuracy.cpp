// Accuracy against time: what each setting of the magnetic solve costs and
// how close it comes to a closed form or a refined reference.
//
//   field     a sphere of the paper's material (radius a = 5 cm, box of
//             half-width 2a, N nodes per axis) in a uniform field H0 along z:
//             RMS error of the nodal H over r < a/2 against the closed-form
//             interior field (H_in + M(H_in)/3 = H0, solved to 1e-14), over
//             resolution, Newton tolerance, preconditioner and law;
//   laws      the error of assuming the linear law (chi = chi0) for the
//             Langevin material, closed forms, H0 = 1e3 ... 1e6 A/m, plus
//             solved spheres of both laws;
//   force     two spheres (a = 2 cm, centres 3a apart along z) in 1e6 A/m:
//             force on one against the dipole force of the closed-form
//             moments, over cells per radius, tolerance and preconditioner;
//   dynamics  the induced-attraction scene (examples/scenes): deviation of the
//             gap between the two cubes' centres of mass from a reference run
//             (field solved every substep, tolerance 1e-10), over field-solve
//             frequency and tolerance;
//   table2    one frame (cold, then warm) of the paper's 128^3 cube scenes,
//             Langevin and linear, at full resolution.
// Writes DIR/accuracy_{field,laws,force,dynamics,table2,presets}.csv
// (`--help` lists the options). The figures are drawn by docs/accuracy_plots.py. Not a test: timings depend on
// the machine and are never asserted.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include "lodestone/cli/command_line.h"
#include "lodestone/core/stage/density_raster.h"
#include "lodestone/core/base/stopwatch.h"

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/field/langevin.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/plugin/scene.h"

using namespace lodestone;

namespace {

using Clock = std::chrono::steady_clock;

/// A number as printf's %g writes it (short, for labels).
std::string shortNumber(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", x);
  return b;
}

// ---------------------------------------------------------------- closed forms

/// M(H) (A/m) of the bulk material at field magnitude H (A/m).
double bulkMagnetization(const MagneticMaterial& mat, double H) {
  if (mat.law.kind == LawKind::Linear) return mat.lowFieldSusceptibility() * H;
  return mat.saturation() * langevin(mat.law.k2 * H);
}

/// Interior field (A/m) of a sphere in a uniform applied field H0 (A/m): the
/// root of g(H) = H + M(H)/3 - H0, which is increasing in H, by bisection on
/// [0, H0] followed by Newton steps (relative accuracy ~1e-15).
double sphereInteriorField(const MagneticMaterial& mat, double H0) {
  if (mat.law.kind == LawKind::Linear) return 3 * H0 / (3 + mat.lowFieldSusceptibility());
  const auto g = [&](double H) { return H + bulkMagnetization(mat, H) / 3 - H0; };
  double lo = 0, hi = H0;
  for (int it = 0; it < 80; ++it) {
    const double m = 0.5 * (lo + hi);
    (g(m) > 0 ? hi : lo) = m;
  }
  double H = 0.5 * (lo + hi);
  for (int it = 0; it < 4; ++it) {
    const double h = 1e-6 * H;
    const double d = (g(H + h) - g(H - h)) / (2 * h);
    H -= g(H) / d;
  }
  return H;
}

// ------------------------------------------------------------ rasterization

/// n0 times the volume fraction of each node's dual cell inside the union of
/// balls (centres in m, radius in m), 8^3 samples a cell where the cell
/// straddles a surface.
DenseGrid<double> rasterizeBalls(const GridSpec& g, double n0, const std::vector<Vec3d>& centres, double radius) {
  return rasterizeDensityFromDistance(
      g, n0,
      [&](const Vec3d& p) {
        double phi = std::numeric_limits<double>::infinity();
        for (const Vec3d& c : centres) phi = std::min(phi, norm(p - c) - radius);
        return phi;
      },
      8);
}

// ------------------------------------------------------------------ settings

struct SolveChoice {
  PreconditionerKind preconditioner = PreconditionerKind::Multigrid;
  double tolerance = 1e-8;
  bool singlePrecision = true;  // multigrid levels in float (the default) or double
};

MagneticStageSettings stageSettings(const SolveChoice& c) {
  MagneticStageSettings s;
  s.solve.preconditioner = c.preconditioner;
  s.solve.tolerance = c.tolerance;
  s.solve.multigrid.singlePrecision = c.singlePrecision;
  s.solve.maxNewtonIterations = 60;
  s.solve.maxCgIterations = 20000;
  return s;
}

const char* lawName(const MagneticMaterial& m) { return m.law.kind == LawKind::Linear ? "linear" : "langevin"; }

// ---------------------------------------------------------------- field study

constexpr double kSphereRadius = 0.05;  // m

struct SphereRun {
  double hMean = 0;     // mean H_z over r < a/2, A/m
  double errRms = 0;    // RMS |H - H_exact e_z| / H_exact over r < a/2, H_exact of the run's own law
  double errMean = 0;   // |hMean - H_exact| / H_exact
  double errTruth = 0;  // RMS error against the Langevin material's closed form
  double errDemag = 0;  // |hMean - H_exact| / (H0 - H_exact): error of the field the material makes
  MagneticStageReport report;
  double seconds = 0;  // stage wall time (applied field, solve, nodal fields, force), s
};

SphereRun solveSphere(const MagneticMaterial& law, const MagneticMaterial& truth, double H0, int N,
                      const SolveChoice& choice) {
  GridSpec g;
  g.dx = 4 * kSphereRadius / (N - 1);
  g.origin = {-2 * kSphereRadius, -2 * kSphereRadius, -2 * kSphereRadius};
  g.dims = {N, N, N};
  const DenseGrid<double> n = rasterizeBalls(g, law.numberDensity, {Vec3d{}}, kSphereRadius);
  MagneticForceStage stage(g, law, stageSettings(choice));
  SphereRun r;
  const auto t0 = Clock::now();
  r.report = stage.runOnDensity(n.view(), UniformField({0, 0, H0}), 0.0);
  r.seconds = secondsSince(t0);
  const double exact = sphereInteriorField(law, H0), exactTruth = sphereInteriorField(truth, H0);
  double sum = 0, sq = 0, sqTruth = 0;
  long count = 0;
  for (int k = 0; k < N; ++k)
    for (int j = 0; j < N; ++j)
      for (int i = 0; i < N; ++i)
        if (norm(g.nodePosition(i, j, k)) < 0.5 * kSphereRadius) {
          const Vec3d H = stage.field()(i, j, k);
          sum += H.z;
          sq += norm2(H - Vec3d{0, 0, exact});
          sqTruth += norm2(H - Vec3d{0, 0, exactTruth});
          ++count;
        }
  r.hMean = sum / count;
  r.errRms = std::sqrt(sq / count) / exact;
  r.errMean = std::fabs(r.hMean - exact) / exact;
  r.errDemag = std::fabs(r.hMean - exact) / (H0 - exact);
  r.errTruth = std::sqrt(sqTruth / count) / exactTruth;
  return r;
}

// One row of any study, for the presets.
struct Candidate {
  std::string study, resolution, tolerance, preconditioner, law, frequency;
  double error = 0, seconds = 0;
  double cellsPerRadius = 0;  // resolution as a number (0 when the study has one resolution)
};

/// Within the bound, and so are all finer runs of the same setting: the
/// cheapest such run is a resolution that stays within the bound when refined
/// (a lucky coarse run on a non-monotone convergence curve does not count).
bool staysWithin(const Candidate& c, const std::vector<Candidate>& all, double bound) {
  if (c.error > bound) return false;
  for (const Candidate& f : all)
    if (f.study == c.study && f.tolerance == c.tolerance && f.preconditioner == c.preconditioner && f.law == c.law &&
        f.frequency == c.frequency && f.cellsPerRadius > c.cellsPerRadius && f.error > bound)
      return false;
  return true;
}

struct Options {
  std::string outDir = "docs/data";
  std::string scenesDir = LODESTONE_SCENES_DIR;
  std::set<std::string> studies{"field", "precision", "laws", "force", "dynamics", "table2"};
  bool quick = false;
  std::vector<double> sizes{17, 33, 65, 129, 257};
  std::vector<double> tolerances{1e-2, 1e-4, 1e-6, 1e-8, 1e-10};
  int jacobiMaxNodes = 129;     // Jacobi-PCG sweeps up to this many nodes per axis
  int fullSweepMaxNodes = 129;  // above it, only multigrid at 1e-4 and 1e-8 (Langevin)
  std::vector<double> forceCells{3, 4, 6, 8, 12, 16};
  double dynamicsDx = 0.013;  // m
  int dynamicsFrames = 25;
};

std::ofstream openCsv(const Options& o, const char* name) {
  const std::string path = o.outDir + "/" + name;
  std::ofstream f(path);
  require(bool(f), "cannot write ", path);
  f.precision(10);
  return f;
}

void fieldStudy(const Options& o, std::vector<Candidate>& cands) {
  const double H0 = 1e5;
  const MagneticMaterial lang = paperMaterial(), lin = linearized(lang);
  std::ofstream csv = openCsv(o, "accuracy_field.csv");
  csv << "law,preconditioner,tolerance,nodes_per_axis,cells_per_radius,dx_m,H0_A_per_m,H_exact_A_per_m,H_mean_A_per_m,"
         "error_rms,error_mean,error_demag,error_vs_langevin,newton_iterations,cg_iterations,relative_residual,status,"
         "seconds_solve,seconds_stage\n";
  std::printf("\n== field: sphere (a = %.2f m) in H0 = %.0e A/m, RMS error of H over r < a/2\n", kSphereRadius, H0);
  std::printf("%-8s %-9s %7s %5s %6s %10s %10s %10s %6s %6s %9s %9s\n", "law", "precond", "tol", "N", "a/dx", "err rms",
              "err mean", "err Lang.", "newton", "cg", "solve s", "stage s");
  for (double sN : o.sizes) {
    const int N = int(sN);
    for (const MagneticMaterial* law : {&lang, &lin})
      for (PreconditionerKind pk : {PreconditionerKind::Multigrid, PreconditionerKind::Jacobi})
        for (double tol : o.tolerances) {
          if (pk == PreconditionerKind::Jacobi && N > o.jacobiMaxNodes) continue;
          if (N > o.fullSweepMaxNodes &&
              (law != &lang || pk != PreconditionerKind::Multigrid || (tol != 1e-4 && tol != 1e-8)))
            continue;
          const SphereRun r = solveSphere(*law, lang, H0, N, {pk, tol});
          const double cpr = (N - 1) / 4.0;
          std::printf("%-8s %-9s %7.0e %5d %6.1f %10.3e %10.3e %10.3e %6d %6d %9.3f %9.3f%s\n", lawName(*law),
                      toString(pk), tol, N, cpr, r.errRms, r.errMean, r.errTruth, r.report.solve.newtonIterations,
                      r.report.solve.cgIterations, r.report.secondsSolve, r.seconds,
                      r.report.converged() ? "" : "  NOT CONVERGED");
          std::fflush(stdout);
          csv << lawName(*law) << ',' << toString(pk) << ',' << tol << ',' << N << ',' << cpr << ','
              << 4 * kSphereRadius / (N - 1) << ',' << H0 << ',' << sphereInteriorField(*law, H0) << ',' << r.hMean
              << ',' << r.errRms << ',' << r.errMean << ',' << r.errDemag << ',' << r.errTruth << ','
              << r.report.solve.newtonIterations << ',' << r.report.solve.cgIterations << ','
              << r.report.solve.relativeResidual << ',' << toString(r.report.solve.status) << ','
              << r.report.secondsSolve << ',' << r.seconds << '\n';
          if (r.report.converged() || r.report.solve.status == SolveStatus::IterationCap)
            cands.push_back({"field", concat(shortNumber(cpr), " cells/radius"), shortNumber(tol), toString(pk),
                             lawName(*law), "per solve", r.errTruth, r.seconds, cpr});
        }
  }
}

// Float against double storage of the multigrid preconditioner, same grid,
// same tolerance, solved twice in a row each (the second time is reported).
void precisionStudy(const Options& o) {
  const MagneticMaterial lang = paperMaterial();
  const double H0 = 1e5;
  std::ofstream csv = openCsv(o, "accuracy_precision.csv");
  csv << "multigrid_storage,tolerance,nodes_per_axis,cells_per_radius,error_rms,newton_iterations,cg_iterations,"
         "seconds_solve,seconds_stage\n";
  std::printf("\n== precision: multigrid levels in float or double (sphere, H0 = %.0e A/m)\n", H0);
  std::printf("%-7s %7s %5s %10s %6s %6s %9s %9s\n", "storage", "tol", "N", "err rms", "newton", "cg", "solve s",
              "stage s");
  for (double sN : o.sizes) {
    const int N = int(sN);
    if (N > 129) continue;
    for (double tol : {1e-4, 1e-8})
      for (bool single : {true, false}) {
        SolveChoice c{PreconditionerKind::Multigrid, tol, single};
        solveSphere(lang, lang, H0, N, c);  // warm the caches and allocator
        const SphereRun r = solveSphere(lang, lang, H0, N, c);
        std::printf("%-7s %7.0e %5d %10.3e %6d %6d %9.3f %9.3f\n", single ? "float" : "double", tol, N, r.errRms,
                    r.report.solve.newtonIterations, r.report.solve.cgIterations, r.report.secondsSolve, r.seconds);
        std::fflush(stdout);
        csv << (single ? "float" : "double") << ',' << tol << ',' << N << ',' << (N - 1) / 4.0 << ',' << r.errRms
            << ',' << r.report.solve.newtonIterations << ',' << r.report.solve.cgIterations << ','
            << r.report.secondsSolve << ',' << r.seconds << '\n';
      }
  }
}

void lawStudy(const Options& o) {
  const MagneticMaterial lang = paperMaterial(), lin = linearized(lang);
  std::ofstream csv = openCsv(o, "accuracy_laws.csv");
  csv << "kind,H0_A_per_m,H_in_langevin_A_per_m,H_in_linear_A_per_m,M_langevin_A_per_m,M_linear_A_per_m,"
         "error_H_linear,error_M_linear,error_force_linear,nodes_per_axis,error_rms_langevin_solve,"
         "error_rms_linear_solve_vs_langevin,seconds_langevin,seconds_linear\n";
  std::printf(
      "\n== laws: the linear law (chi0 = %.3f) for the Langevin material (Ms = %.4g A/m), sphere closed forms\n",
      lang.lowFieldSusceptibility(), lang.saturation());
  std::printf("%9s %11s %11s %10s %10s %10s\n", "H0", "H_in Lang", "H_in lin", "err H", "err M", "err F~M^2");
  double worst = 0;  // largest |H_in + M(H_in)/3 - H0| / H0 of the closed forms
  for (int e = 0; e <= 30; ++e) {
    const double H0 = std::pow(10.0, 3 + e / 10.0);
    const double hl = sphereInteriorField(lang, H0), hn = sphereInteriorField(lin, H0);
    const double ml = bulkMagnetization(lang, hl), mn = bulkMagnetization(lin, hn);
    worst = std::max({worst, std::fabs(hl + ml / 3 - H0) / H0, std::fabs(hn + mn / 3 - H0) / H0});
    const double eF = std::fabs(mn * mn / (ml * ml) - 1);
    if (e % 5 == 0)
      std::printf("%9.2e %11.5g %11.5g %10.3e %10.3e %10.3e\n", H0, hl, hn, std::fabs(hn - hl) / hl,
                  std::fabs(mn - ml) / ml, eF);
    csv << "closed_form," << H0 << ',' << hl << ',' << hn << ',' << ml << ',' << mn << ',' << std::fabs(hn - hl) / hl
        << ',' << std::fabs(mn - ml) / ml << ',' << eF << ",,,,,\n";
  }
  std::printf("closed forms: largest relative residual |H_in + M(H_in)/3 - H0| / H0 = %.1e\n", worst);
  require(worst < 1e-14, "the sphere's closed form did not converge (relative residual ", worst, ")");
  const int N = o.quick ? 33 : 65;
  std::printf("solved spheres, N = %d, multigrid, tolerance 1e-8:\n%9s %12s %12s %9s %9s\n", N, "H0", "err Lang.",
              "err lin/Lang", "Lang. s", "lin s");
  for (double H0 : {1e3, 1e4, 1e5, 1e6}) {
    const SphereRun a = solveSphere(lang, lang, H0, N, {});
    const SphereRun b = solveSphere(lin, lang, H0, N, {});
    std::printf("%9.0e %12.3e %12.3e %9.3f %9.3f\n", H0, a.errRms, b.errTruth, a.seconds, b.seconds);
    csv << "solved," << H0 << ",,,,,,,," << N << ',' << a.errRms << ',' << b.errTruth << ',' << a.seconds << ','
        << b.seconds << '\n';
  }
}

// ---------------------------------------------------------------- force study

struct PairRun {
  double force = 0, expected = 0, error = 0;
  MagneticStageReport report;
  double seconds = 0;
  Index3 dims;
};

// As tests/core/test_magnetic_force.cpp: spheres of radius a = 2 cm, centres
// 3a apart along z, H0 = 1e6 A/m (deep saturation: nearly uniform M, whose
// mutual force is the dipole force 3 mu0 m^2 / (2 pi d^4)).
PairRun spherePair(double cellsPerRadius, const SolveChoice& choice) {
  const double a = 0.02, d = 3 * a, H0 = 1e6, margin = 2 * a;
  const MagneticMaterial mat = paperMaterial();
  GridSpec g;
  g.dx = a / cellsPerRadius;
  const Vec3d lo{-a - margin, -a - margin, -a - margin - d / 2}, hi{a + margin, a + margin, a + margin + d / 2};
  g.origin = lo;
  g.dims = {int(std::ceil((hi.x - lo.x) / g.dx)) + 1, int(std::ceil((hi.y - lo.y) / g.dx)) + 1,
            int(std::ceil((hi.z - lo.z) / g.dx)) + 1};
  const DenseGrid<double> n = rasterizeBalls(g, mat.numberDensity, {Vec3d{0, 0, -d / 2}, Vec3d{0, 0, d / 2}}, a);
  MagneticForceStage stage(g, mat, stageSettings(choice));
  PairRun r;
  r.dims = g.dims;
  const auto t0 = Clock::now();
  r.report = stage.runOnDensity(n.view(), UniformField({0, 0, H0}), 0.0);
  r.seconds = secondsSince(t0);
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i)
        if (g.nodePosition(i, j, k).z > 0) r.force += stage.nodalForce()(i, j, k).z;
  const double Hin = sphereInteriorField(mat, H0);
  const double m = bulkMagnetization(mat, Hin) * 4.0 / 3.0 * kPi * a * a * a;
  r.expected = -3 * kMu0 * m * m / (2 * kPi * std::pow(d, 4));
  r.error = std::fabs(r.force - r.expected) / std::fabs(r.expected);
  return r;
}

void forceStudy(const Options& o, std::vector<Candidate>& cands) {
  std::ofstream csv = openCsv(o, "accuracy_force.csv");
  csv << "preconditioner,tolerance,cells_per_radius,dx_m,nodes,force_N,dipole_force_N,error,newton_iterations,"
         "cg_iterations,status,seconds_solve,seconds_stage\n";
  std::printf("\n== force: coaxial sphere pair (a = 2 cm, d = 3a) in 1e6 A/m against the dipole force\n");
  std::printf("%-9s %7s %6s %9s %12s %12s %9s %6s %6s %9s\n", "precond", "tol", "a/dx", "nodes", "F (N)", "dipole (N)",
              "error", "newton", "cg", "stage s");
  std::vector<std::pair<double, SolveChoice>> runs;
  for (double c : o.forceCells) runs.push_back({c, SolveChoice{}});
  const double mid = o.quick ? 4 : 8;
  for (double tol : o.tolerances)
    if (tol != 1e-8) runs.push_back({mid, SolveChoice{PreconditionerKind::Multigrid, tol}});
  for (double c : o.forceCells)
    if (c <= (o.quick ? 4 : 12)) runs.push_back({c, SolveChoice{PreconditionerKind::Jacobi, 1e-8}});
  for (double tol : {1e-2, 1e-4}) {
    for (double c : o.forceCells)
      if (c != mid && c >= 6) runs.push_back({c, SolveChoice{PreconditionerKind::Multigrid, tol}});
  }
  for (const auto& [cells, choice] : runs) {
    const PairRun r = spherePair(cells, choice);
    const std::size_t nodes = std::size_t(r.dims.i) * r.dims.j * r.dims.k;
    std::printf("%-9s %7.0e %6.1f %9zu %12.5e %12.5e %9.3e %6d %6d %9.3f%s\n", toString(choice.preconditioner),
                choice.tolerance, cells, nodes, r.force, r.expected, r.error, r.report.solve.newtonIterations,
                r.report.solve.cgIterations, r.seconds, r.report.converged() ? "" : "  NOT CONVERGED");
    std::fflush(stdout);
    csv << toString(choice.preconditioner) << ',' << choice.tolerance << ',' << cells << ',' << 0.02 / cells << ','
        << nodes << ',' << r.force << ',' << r.expected << ',' << r.error << ',' << r.report.solve.newtonIterations
        << ',' << r.report.solve.cgIterations << ',' << toString(r.report.solve.status) << ',' << r.report.secondsSolve
        << ',' << r.seconds << '\n';
    cands.push_back({"force", concat(shortNumber(cells), " cells/radius"), shortNumber(choice.tolerance),
                     toString(choice.preconditioner), "langevin", "per solve", r.error, r.seconds, cells});
  }
}

// ------------------------------------------------------------- dynamics study

struct Trajectory {
  std::vector<Vec3d> left, right;  // centre of mass per frame (frame 0 = start), m
  double seconds = 0, secondsMagnetic = 0;
  int solves = 0, newton = 0, cg = 0;
  bool allConverged = true;
};

Trajectory runAttraction(const Options& o, int interval, double tol, int frames) {
  plugin::SceneOptions so;
  so.dx = o.dynamicsDx;
  plugin::Scene scene = plugin::loadScene(o.scenesDir + "/induced_attraction.json", so);
  scene.settings.magneticSolveInterval = interval;
  scene.settings.magnetic.solve.tolerance = tol;
  scene.settings.magnetic.solve.maxNewtonIterations = 60;
  scene.settings.reorderInterval = 20;
  auto solver = plugin::buildSolver(scene);
  // Left and right cube by position at the start (persistent ids).
  std::set<std::uint64_t> leftIds;
  Trajectory t;
  const auto com = [&](Trajectory& tr) {
    const MpmParticles& p = static_cast<const MpmSolver&>(*solver).particles();
    Vec3d sl{}, sr{};
    double ml = 0, mr = 0;
    for (std::size_t q = 0; q < p.size(); ++q)
      if (leftIds.count(p.id[q])) {
        sl += p.mass[q] * p.x[q];
        ml += p.mass[q];
      } else {
        sr += p.mass[q] * p.x[q];
        mr += p.mass[q];
      }
    tr.left.push_back(sl / ml);
    tr.right.push_back(sr / mr);
  };
  {
    const MpmParticles& p = static_cast<const MpmSolver&>(*solver).particles();
    for (std::size_t q = 0; q < p.size(); ++q)
      if (p.x[q].x < 0) leftIds.insert(p.id[q]);
  }
  com(t);
  for (int f = 0; f < frames; ++f) {
    const MpmFrameReport r = solver->advanceFrame(scene.frameDuration());
    t.seconds += r.secondsTotal;
    t.secondsMagnetic += r.secondsMagnetic;
    for (const MagneticStageReport& m : r.magneticReports) {
      ++t.solves;
      t.newton += m.solve.newtonIterations;
      t.cg += m.solve.cgIterations;
      t.allConverged = t.allConverged && m.converged();
    }
    com(t);
  }
  return t;
}

/// The gap between the cubes per frame of one cheap run (field solved once
/// per frame): how many frames the attraction needs to show.
void dynamicsProbe(const Options& o) {
  const Trajectory t = runAttraction(o, 0, 1e-6, o.dynamicsFrames);
  std::printf("\n== dynamics probe (dx = %.4g m, field once per frame): gap between the cubes' centres\n",
              o.dynamicsDx);
  for (std::size_t f = 0; f < t.left.size(); ++f)
    std::printf("frame %3zu  t = %.4f s  gap %.6f m  left z %.6f m\n", f, f / 500.0, t.right[f].x - t.left[f].x,
                t.left[f].z);
  std::printf("%.2f s in all\n", t.seconds);
}

void dynamicsStudy(const Options& o, std::vector<Candidate>& cands) {
  const int frames = o.quick ? 3 : o.dynamicsFrames;
  std::ofstream csv = openCsv(o, "accuracy_dynamics.csv");
  std::ofstream traj = openCsv(o, "accuracy_dynamics_trajectories.csv");
  csv << "solve_every_substeps,tolerance,dx_m,frames,field_solves,newton_iterations,cg_iterations,converged,"
         "gap_error,gap_error_m,com_error_m,gap_change_reference_m,seconds_total,seconds_magnetic\n";
  traj << "solve_every_substeps,tolerance,frame,time_s,left_x_m,left_y_m,left_z_m,right_x_m,right_y_m,right_z_m\n";
  std::printf("\n== dynamics: induced attraction (dx = %.4g m, %d frames of 40 substeps), gap between the cubes\n",
              o.dynamicsDx, frames);
  std::printf("%6s %7s %7s %7s %8s %11s %11s %11s %9s %9s\n", "every", "tol", "solves", "newton", "cg", "gap err",
              "gap err m", "com err m", "total s", "magn. s");
  const Trajectory ref = runAttraction(o, 1, 1e-10, frames);
  std::vector<std::pair<int, double>> runs{{1, 1e-10}};
  // Solving every substep costs 40 solves a frame: its sweep stops at 1e-6.
  for (int every : {1, 5, 0})
    for (double tol : {1e-2, 1e-4, 1e-6, 1e-8})
      if (every != 1 || tol >= 1e-6) runs.push_back({every, tol});
  runs.push_back({5, 1e-3});  // the preview preset's tolerance
  const double gap0 = ref.right[0].x - ref.left[0].x;
  double gapChange = 0;
  for (std::size_t f = 0; f < ref.left.size(); ++f)
    gapChange = std::max(gapChange, std::fabs(ref.right[f].x - ref.left[f].x - gap0));
  const double frameTime = 1.0 / 500.0;
  for (const auto& [every, tol] : runs) {
    const Trajectory t = (every == 1 && tol == 1e-10) ? ref : runAttraction(o, every, tol, frames);
    double gapErr = 0, comErr = 0;
    for (std::size_t f = 0; f < t.left.size(); ++f) {
      gapErr = std::max(gapErr, std::fabs((t.right[f].x - t.left[f].x) - (ref.right[f].x - ref.left[f].x)));
      comErr = std::max({comErr, norm(t.left[f] - ref.left[f]), norm(t.right[f] - ref.right[f])});
      traj << every << ',' << tol << ',' << f << ',' << f * frameTime << ',' << t.left[f].x << ',' << t.left[f].y << ','
           << t.left[f].z << ',' << t.right[f].x << ',' << t.right[f].y << ',' << t.right[f].z << '\n';
    }
    const double rel = gapChange > 0 ? gapErr / gapChange : 0;
    std::printf("%6s %7.0e %7d %7d %8d %11.3e %11.3e %11.3e %9.2f %9.2f%s\n",
                every == 0 ? "frame" : concat(every).c_str(), tol, t.solves, t.newton, t.cg, rel, gapErr, comErr,
                t.seconds, t.secondsMagnetic, t.allConverged ? "" : "  (some solves not converged)");
    std::fflush(stdout);
    csv << every << ',' << tol << ',' << o.dynamicsDx << ',' << frames << ',' << t.solves << ',' << t.newton << ','
        << t.cg << ',' << (t.allConverged ? 1 : 0) << ',' << rel << ',' << gapErr << ',' << comErr << ',' << gapChange
        << ',' << t.seconds << ',' << t.secondsMagnetic << '\n';
    if (!(every == 1 && tol == 1e-10))
      cands.push_back({"dynamics", concat("dx ", shortNumber(o.dynamicsDx), " m"), shortNumber(tol), "multigrid",
                       "langevin", every == 0 ? "once per frame" : concat("every ", every, " substeps"), rel,
                       t.seconds});
  }
  std::printf("reference (every substep, 1e-10): gap %.4f m -> largest change %.3e m over %d frames, %.1f s\n", gap0,
              gapChange, frames, ref.seconds);
}

// --------------------------------------------------------------- Table 2 scale

void table2Study(const Options& o) {
  std::ofstream csv = openCsv(o, "accuracy_table2.csv");
  csv << "scene,full_resolution,mpm_nodes,magnetic_nodes,particles,frame,seconds_frame,seconds_magnetic,seconds_solve,"
         "newton_iterations,cg_iterations,seconds_mpm,paper_seconds_frame\n";
  std::printf("\n== Table 2 scale: one frame of the cube scenes%s\n",
              o.quick ? " (quick: scene resolution)" : " (--full)");
  std::printf("%-14s %6s %9s %9s %9s %7s %5s %9s %9s\n", "scene", "frame", "frame s", "magn. s", "solve s", "newton",
              "cg", "MPM s", "paper s");
  for (const char* name : {"cube_langevin", "cube_linear"}) {
    plugin::SceneOptions so;
    so.full = !o.quick;
    const plugin::Scene scene = plugin::loadScene(o.scenesDir + "/" + name + ".json", so);
    auto solver = plugin::buildSolver(scene);
    const double paper = std::string(name) == "cube_langevin" ? 48.6 : 45.3;
    for (int f = 1; f <= 2; ++f) {
      const MpmFrameReport r = solver->advanceFrame(scene.frameDuration());
      double solve = 0;
      int newton = 0, cg = 0;
      for (const MagneticStageReport& m : r.magneticReports) {
        solve += m.secondsSolve;
        newton += m.solve.newtonIterations;
        cg += m.solve.cgIterations;
      }
      const GridSpec& mg = solver->magneticStage() ? solver->magneticStage()->grid() : scene.settings.grid;
      const double mpm = r.secondsP2G + r.secondsGridUpdate + r.secondsG2P;
      std::printf("%-14s %6d %9.2f %9.2f %9.2f %7d %5d %9.2f %9.1f\n", name, f, r.secondsTotal, r.secondsMagnetic,
                  solve, newton, cg, mpm, paper);
      std::fflush(stdout);
      csv << name << ',' << (o.quick ? 0 : 1) << ',' << scene.settings.grid.nodeCount() << ',' << mg.nodeCount() << ','
          << solver->particles().size() << ',' << f << ',' << r.secondsTotal << ',' << r.secondsMagnetic << ',' << solve
          << ',' << newton << ',' << cg << ',' << mpm << ',' << paper << '\n';
    }
  }
}

// -------------------------------------------------------------------- presets

void writePresets(const Options& o, const std::vector<Candidate>& cands) {
  std::ofstream csv = openCsv(o, "accuracy_presets.csv");
  csv << "preset,study,bound,resolution,tolerance,preconditioner,law,solve_frequency,measured_error,seconds\n";
  std::printf("\n== presets: the cheapest setting within each bound\n");
  const std::vector<std::pair<const char*, double>> bounds{{"final", 0.01}, {"preview", 0.05}, {"draft", 0.10}};
  for (const char* study : {"field", "force", "dynamics"})
    for (const auto& [name, bound] : bounds) {
      const Candidate* best = nullptr;
      for (const Candidate& c : cands)
        if (c.study == study && staysWithin(c, cands, bound) && (!best || c.seconds < best->seconds)) best = &c;
      if (!best) {
        bool any = false;
        for (const Candidate& c : cands) any = any || c.study == study;
        if (any) {
          std::printf("%-8s %-9s %4.0f%%  none of the measured settings\n", name, study, bound * 100);
          csv << name << ',' << study << ',' << bound << ",none,,,,,,\n";
        }
        continue;
      }
      std::printf("%-8s %-9s %4.0f%%  %-18s tol %-6s %-9s %-8s %-18s error %.3e  %.3f s\n", name, study, bound * 100,
                  best->resolution.c_str(), best->tolerance.c_str(), best->preconditioner.c_str(), best->law.c_str(),
                  best->frequency.c_str(), best->error, best->seconds);
      csv << name << ',' << study << ',' << bound << ',' << best->resolution << ',' << best->tolerance << ','
          << best->preconditioner << ',' << best->law << ',' << best->frequency << ',' << best->error << ','
          << best->seconds << '\n';
    }
}

}  // namespace

int main(int argc, char** argv) {
  try {
    Options o;
    bool sizesGiven = false, probe = false;
    CLI::App app("lodestone-bench-accuracy: error against wall time of the magnetic solve", "lodestone-bench-accuracy");
    cli::helpLayout(app, 28);
    std::string allStudies;
    for (const std::string& study : o.studies) allStudies += (allStudies.empty() ? "" : ",") + study;
    app.add_option_function<std::string>(
           "--studies",
           [&](const std::string& list) {
             o.studies.clear();
             std::stringstream items(list);
             for (std::string item; std::getline(items, item, ',');) o.studies.insert(item);
           },
           "comma-separated, of field, precision, laws, force, dynamics, table2")
        ->type_name("LIST")
        ->default_str(allStudies)
        ->check(cli::rule("", [known = o.studies](const std::string& list) -> std::string {
          std::stringstream items(list);
          for (std::string item; std::getline(items, item, ',');)
            if (!known.count(item))
              return concat("unknown study '", item, "' (expected field, precision, laws, force, dynamics, table2)");
          return "";
        }));
    app.add_flag("--quick", o.quick, "small sizes (development check, a minute)");
    cli::addNumberList(app, "--sizes", o.sizes, "sphere grid nodes per axis (each 9..513)")
        ->each([&](const std::string&) { sizesGiven = true; });
    cli::addNumber(app, "--dynamics-dx", o.dynamicsDx, "grid spacing of the dynamics scene, m, in (0, 0.05)")
        ->type_name("X")
        ->check(cli::number())
        ->default_str(cli::formatNumber(o.dynamicsDx));
    cli::addNumber(app, "--dynamics-frames", o.dynamicsFrames, "frames of the dynamics runs")
        ->type_name("N")
        ->check(cli::wholeNumber(1))
        ->default_str(cli::formatNumber(o.dynamicsFrames));
    app.add_flag("--dynamics-probe", probe, "print the cubes' gap per frame of one cheap run and stop");
    app.add_option("--scenes", o.scenesDir, "scene folder")->type_name("DIR")->capture_default_str();
    app.add_option("--out-dir", o.outDir, "CSV folder")->type_name("DIR")->capture_default_str();
    if (const std::optional<int> code = cli::parse(app, argc, argv)) return *code;
    if (o.quick) {
      if (!sizesGiven) o.sizes = {17, 33};
      o.forceCells = {3, 4, 6};
      o.tolerances = {1e-2, 1e-4, 1e-8};
      o.jacobiMaxNodes = 33;
      o.fullSweepMaxNodes = 33;
    }
    for (double s : o.sizes) require(s >= 9 && s <= 513 && s == std::floor(s), "--sizes: ", s, " is not in 9..513");
    require(o.dynamicsDx > 0 && o.dynamicsDx < 0.05, "--dynamics-dx: ", o.dynamicsDx, " m is not in (0, 0.05)");

    std::printf("Lodestone accuracy-vs-time benchmark (%d threads)\n", tbb::info::default_concurrency());
    const auto t0 = Clock::now();
    std::vector<Candidate> cands;
    if (probe) {
      dynamicsProbe(o);
      return 0;
    }
    if (o.studies.count("laws")) lawStudy(o);
    if (o.studies.count("field")) fieldStudy(o, cands);
    if (o.studies.count("precision")) precisionStudy(o);
    if (o.studies.count("force")) forceStudy(o, cands);
    if (o.studies.count("dynamics")) dynamicsStudy(o, cands);
    if (o.studies.count("table2")) table2Study(o);
    if (!cands.empty()) writePresets(o, cands);
    std::printf("\nCSV written to %s (%.0f s in all)\n", o.outDir.c_str(), secondsSince(t0));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone-bench-accuracy: %s\n", e.what());
    return 1;
  }
}
