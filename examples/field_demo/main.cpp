// lodestone-field-demo: one magnetic-force stage on a small scene, written
// out for inspection. A ball of the paper's ferrofluid-like material
// (paperMaterial(), Sun et al. 2021 Table 2), discretized as material points,
// sits above an axially magnetized NdFeB-like cylinder magnet, optionally in
// an extra uniform vertical field. The program solves the nonlinear
// magnetostatic problem, prints the Newton progress and the stage report,
// and writes into the output directory:
//   field_solve.json  scene, grid, settings, solve report with the per-
//                     iteration history, timings, total force, |H| range
//   slice_H.png       |H| on the vertical mid-plane y = 0 (log scale, viridis),
//                     material outline white, magnet outline grey, z up
//   slice_B_ratio.png |B| / |B0| on the same plane (B0: the induction without
//                     the material): the flux the material draws in, log scale
//   slice_force.png   |t| force density on the same plane (log scale, inferno)
//   profile.csv       |H|, H_z, M_z, n, ... along the vertical centre line
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <tbb/global_control.h>
#include <tbb/info.h>

#include "lodestone/cli/command_line.h"

#include "lodestone/plugin/output/colormap.h"
#include "lodestone/core/base/stopwatch.h"
#include "lodestone/core/base/constants.h"
#include "lodestone/core/sources/cylinder_magnet.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/sources/field_source_set.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/base/pose.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/plugin/output/png_writer.h"

namespace {

using namespace lodestone;
using namespace lodestone::output;
using Clock = std::chrono::steady_clock;


// ---------------------------------------------------------------------------
// Scene (SI units). The grid is a cube of side kBoxSide centred on the origin;
// the ball and the magnet share the vertical axis x = y = 0.
constexpr double kBoxSide = 0.16;            // m
constexpr double kBallRadius = 0.03;         // m
constexpr double kBallCentreZ = 0.02;        // m
constexpr double kMagnetRadius = 0.025;      // m
constexpr double kMagnetHalfLength = 0.015;  // m
constexpr double kMagnetCentreZ = -0.045;    // m (top face at z = -0.03 m, 2 cm below the ball)
constexpr double kRemanence = 1.2;           // T (sintered NdFeB, N35-like)
constexpr int kParticlesPerAxis = 2;         // 2^3 = 8 material points per cell

// ---------------------------------------------------------------------------
// Options.
struct Options {
  int resolution = 64;
  double field = 0;  // A/m, along +z
  std::string law = "langevin";
  std::string boundary = "open";
  double tolerance = 1e-8;
  int threads = 0;  // 0: all
  std::string out = "./demo_out";
};

// Declared once; the help text is generated from these declarations. Returns
// the code to exit with after --help or a bad option, nullopt to go on.
std::optional<int> parseOptions(int argc, char** argv, Options& o) {
  std::ostringstream about;
  about << "lodestone-field-demo: nonlinear magnetostatics of a ferrofluid ball above a permanent magnet\n"
           "\n"
           "Scene: a ball (radius " << kBallRadius << " m, centre z = " << kBallCentreZ
        << " m) of the paper's material (Sun et al. 2021, Table 2),\n"
           "8 material points per cell, above an axially magnetized cylinder magnet (radius "
        << kMagnetRadius << " m, length " << 2 * kMagnetHalfLength << " m,\n"
           "remanence " << kRemanence << " T, centre z = " << kMagnetCentreZ << " m) in a cubic grid of side "
        << kBoxSide << " m centred on the origin.";
  CLI::App app(about.str(), "lodestone-field-demo");
  cli::helpLayout(app, 24);
  cli::addNumber(app, "--resolution", o.resolution, "grid nodes per axis")
      ->type_name("N")
      ->check(cli::wholeNumber(16, 256, "nodes per axis"))
      ->default_str(cli::formatNumber(o.resolution));
  cli::addNumber(app, "--field", o.field, "extra uniform field along +z, A/m")
      ->type_name("H0")
      ->check(cli::numberIn(-1e7, 1e7, "A/m"))
      ->default_str(cli::formatNumber(o.field));
  app.add_option("--law", o.law,
                 "magnetization law: langevin (the paper's, saturating) or linear (its low-field linearization, "
                 "chi0 ~ 0.91)")
      ->type_name("L")
      ->check(cli::oneOf({"langevin", "linear"}))
      ->capture_default_str();
  app.add_option("--boundary", o.boundary,
                 "grid boundary: open (far-field multipole potential) or shield (the paper's wall, H.n = H_ext.n)")
      ->type_name("B")
      ->check(cli::oneOf({"open", "shield"}))
      ->capture_default_str();
  cli::addNumber(app, "--tolerance", o.tolerance, "Newton stop: relative residual, dimensionless")
      ->type_name("T")
      ->check(cli::numberIn(1e-14, 1e-2))
      ->default_str(cli::formatNumber(o.tolerance));
  cli::addNumber(app, "--threads", o.threads, "worker threads; 0 = all hardware threads")
      ->type_name("N")
      ->check(cli::wholeNumber(0, 1024))
      ->default_str(cli::formatNumber(o.threads));
  app.add_option("--out", o.out, "output directory, created if missing")
      ->type_name("DIR")
      ->check(cli::rule("", [](const std::string& dir) {
        return dir.empty() ? std::string("the directory name is empty") : std::string();
      }))
      ->capture_default_str();
  app.footer(
      "Writes DIR/field_solve.json, DIR/slice_H.png, DIR/slice_B_ratio.png, DIR/slice_force.png and\n"
      "DIR/profile.csv.\n"
      "Exit status: 0 on success, 1 on bad options, errors or a field solve that did not converge.");
  return cli::parse(app, argc, argv);
}

// ---------------------------------------------------------------------------
// Scene construction.

// A cube of side kBoxSide with a node at index N/2 on each axis exactly at 0,
// so the mid-plane y = 0 and the centre line x = y = 0 are node lines.
GridSpec makeGrid(int N) {
  GridSpec g;
  g.dx = kBoxSide / (N - 1);
  const double c = double(N / 2);
  g.origin = {-c * g.dx, -c * g.dx, -c * g.dx};
  g.dims = {N, N, N};
  return g;
}

struct Particles {
  std::vector<Vec3d> x;
  std::vector<double> count;
  ParticleView view() const { return {x.data(), count.data(), x.size()}; }
};

// SplitMix64: a portable, deterministic stream of uniform numbers in [0, 1).
struct SplitMix64 {
  std::uint64_t state;
  double next() {
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return double(z >> 11) * 0x1.0p-53;
  }
};

// Material points on the sub-cell lattice (kParticlesPerAxis per cell and
// axis) inside the ball, each jittered by up to a quarter of its spacing and
// carrying the micro-particles of its volume at the bulk density n0.
Particles makeBall(const GridSpec& g, const Vec3d& centre, double radius, double n0) {
  Particles p;
  const double h = g.dx / kParticlesPerAxis;
  const double perParticle = n0 * h * h * h;
  SplitMix64 rng{20210801};
  auto lattice = [&](double centreCoord, double originCoord, int& lo, int& hi) {
    lo = int(std::floor((centreCoord - radius - originCoord) / h)) - 1;
    hi = int(std::ceil((centreCoord + radius - originCoord) / h)) + 1;
  };
  int i0, i1, j0, j1, k0, k1;
  lattice(centre.x, g.origin.x, i0, i1);
  lattice(centre.y, g.origin.y, j0, j1);
  lattice(centre.z, g.origin.z, k0, k1);
  for (int k = k0; k <= k1; ++k)
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const Vec3d site = g.origin + h * Vec3d{i + 0.5, j + 0.5, k + 0.5};
        if (norm2(site - centre) >= radius * radius) continue;
        const Vec3d jitter{rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5};
        p.x.push_back(site + 0.5 * h * jitter);
        p.count.push_back(perParticle);
      }
  return p;
}

// ---------------------------------------------------------------------------
// Output helpers.

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream os;
  os << std::setprecision(10) << v;
  return os.str();
}

std::string vec(const Vec3d& v) { return "[" + num(v.x) + ", " + num(v.y) + ", " + num(v.z) + "]"; }

std::string str(const std::string& s) {
  std::string out = "\"";
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += ch;
    } else if (c == '\n') {
      out += "\\n";
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

void writeText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  if (!f) throw Error(concat("cannot open '", path.string(), "' for writing"));
  f << text;
  f.close();
  if (!f) throw Error(concat("cannot write '", path.string(), "' (disk full or I/O error?)"));
}

struct SliceInfo {
  std::string file, quantity, unit;
  ColourRange range;
  Colormap map;
};

// Renders a y = const slice (node index j) with the material (n = n0/2) and
// magnet outlines and a colour bar; returns the colour range used.
SliceInfo writeSlice(const std::filesystem::path& path, const ScalarSlice& values, RenderOptions ro,
                     const ScalarSlice& density, double n0, const FieldSource& magnet, const GridSpec& g, int j,
                     const std::string& quantity, const std::string& unit) {
  ro.pixelsPerSample = std::max(1, 512 / (g.dims.i - 1));
  ColourRange range;
  RgbImage image = renderScalar(values, ro, &range);

  // Magnet outline, from the exact body at each pixel (p = 1 lattice).
  const int p = ro.pixelsPerSample;
  ScalarSlice inMagnet(image.width, image.height);
  for (int row = 0; row < image.height; ++row)  // slice rows count from the bottom (z up)
    for (int x = 0; x < image.width; ++x) {
      const Vec3d pos{g.origin.x + g.dx * x / p, g.origin.y + g.dx * j, g.origin.z + g.dx * row / p};
      inMagnet.at(x, row) = norm2(magnet.magnetization(pos, 0.0)) > 0 ? 1.0 : 0.0;
    }
  drawContour(image, inMagnet, 1, 0.5, Rgb{170, 170, 170});
  drawContour(image, density, p, 0.5 * n0, Rgb{255, 255, 255});
  appendColourBar(image, ro.colormap, range, 16, 4);
  writePng(path.string(), image.width, image.height, image.rgb.data());
  return {path.filename().string(), quantity, unit, range, ro.colormap};
}

std::string sliceJson(const SliceInfo& s, const std::string& indent) {
  std::ostringstream os;
  os << indent << str(s.file) << ": {\"quantity\": " << str(s.quantity) << ", \"unit\": " << str(s.unit)
     << ", \"plane\": \"y = 0 m (x to the right, z up)\", \"scale\": " << str(s.range.log ? "log10" : "linear")
     << ", \"colormap\": " << str(toString(s.map)) << ", \"colour_min\": " << num(s.range.min)
     << ", \"colour_max\": " << num(s.range.max)
     << ", \"overlays\": \"white: material outline (n = n0/2); grey: magnet outline; bottom strip: colour bar, "
        "dark ticks at powers of ten on log scales\"}";
  return os.str();
}

int run(const Options& o) {
  const auto tProgram = Clock::now();
  std::optional<tbb::global_control> threadLimit;
  if (o.threads > 0) threadLimit.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(o.threads));
  const int threads = o.threads > 0 ? o.threads : tbb::info::default_concurrency();

  // Scene.
  const GridSpec grid = makeGrid(o.resolution);
  const MagneticMaterial paper = paperMaterial();
  const MagneticMaterial material = o.law == "linear" ? linearized(paper) : paper;
  const double n0 = material.numberDensity;
  const Vec3d ballCentre{0, 0, kBallCentreZ};
  const Particles ball = makeBall(grid, ballCentre, kBallRadius, n0);
  double ballCount = 0;
  for (double c : ball.count) ballCount += c;

  const double Mmag = magnetizationFromRemanence(kRemanence);
  const Vec3d magnetCentre{0, 0, kMagnetCentreZ};
  CylinderMagnet magnet(Pose::at(magnetCentre), kMagnetRadius, kMagnetHalfLength, {0, 0, Mmag});
  FieldSourceSet sources;
  sources.add(magnet);
  if (o.field != 0) sources.add(UniformField({0, 0, o.field}));

  MagneticStageSettings settings;
  settings.boundary = o.boundary == "shield" ? BoundaryKind::Shield : BoundaryKind::Open;
  settings.solve.tolerance = o.tolerance;

  std::cout << "lodestone-field-demo " << LODESTONE_VERSION_STRING << "\n"
            << "material: " << material.describe() << "\n"
            << "ball: radius " << kBallRadius << " m at (0, 0, " << kBallCentreZ << ") m, " << ball.x.size()
            << " material points, " << ballCount << " micro-particles\n"
            << "sources: " << sources.describe() << "\n"
            << "grid: " << grid.dims.i << "^3 nodes, dx = " << grid.dx << " m, boundary " << o.boundary
            << ", tolerance " << o.tolerance << ", " << threads << " thread(s)\n";

  MagneticForceStage stage(grid, material, settings);
  stage.setProgress([](const NewtonIterationRecord& r) {
    std::ostringstream line;
    line << "  Newton " << std::setw(2) << r.iteration << ": relative residual " << std::scientific
         << std::setprecision(3) << r.relativeResidual << ", CG " << std::setw(4) << r.cgIterations << ", step "
         << std::defaultfloat << std::setprecision(3) << r.step << ", " << std::fixed << r.seconds << " s\n";
    std::cout << line.str() << std::flush;
    return true;
  });
  const MagneticStageReport rep = stage.run(ball.view(), sources, 0.0);
  std::cout << rep.summary();

  // Field statistics.
  const auto H = stage.field();
  const auto M = stage.magnetization();
  const auto Hext = stage.appliedField();
  const auto n = stage.density();
  const auto t = stage.forceDensity();
  const auto B = stage.inductionField();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double hMin = kInf, hMax = 0, hMinMat = kInf, hMaxMat = 0, mMaxMat = 0, bMaxMat = 0, tMax = 0;
  for (std::size_t q = 0; q < H.size(); ++q) {
    const double h = norm(H[q]);
    hMin = std::min(hMin, h);
    hMax = std::max(hMax, h);
    tMax = std::max(tMax, norm(t[q]));
    if (n[q] >= 0.5 * n0) {
      hMinMat = std::min(hMinMat, h);
      hMaxMat = std::max(hMaxMat, h);
      mMaxMat = std::max(mMaxMat, norm(M[q]));
      bMaxMat = std::max(bMaxMat, norm(B[q]));
    }
  }
  std::cout << "|H| over the grid: " << hMin << " .. " << hMax << " A/m; in the material (n >= n0/2): " << hMinMat
            << " .. " << hMaxMat << " A/m, max |M| " << mMaxMat << " A/m (Ms = " << material.saturation()
            << " A/m)\n";

  // Output.
  const std::filesystem::path dir(o.out);
  std::filesystem::create_directories(dir);
  const int c = grid.dims.j / 2;  // the node plane y = 0 and line x = y = 0
  ScalarSlice hSlice(grid.dims.i, grid.dims.k), gainSlice(grid.dims.i, grid.dims.k),
      tSlice(grid.dims.i, grid.dims.k), nSlice(grid.dims.i, grid.dims.k);
  for (int k = 0; k < grid.dims.k; ++k)
    for (int i = 0; i < grid.dims.i; ++i) {
      hSlice.at(i, k) = norm(H(i, c, k));
      // The stage's B holds the material's M only; add the magnet's own.
      const Vec3d Mmagnet = sources.magnetization(grid.nodePosition(i, c, k), 0.0);
      gainSlice.at(i, k) = norm(B(i, c, k) + kMu0 * Mmagnet) / norm(kMu0 * (Hext(i, c, k) + Mmagnet));
      tSlice.at(i, k) = norm(t(i, c, k));
      nSlice.at(i, k) = n(i, c, k);
    }
  // |H|, log scale over two decades up to twice the largest |H| in the
  // material (which covers the pole enhancement just outside it); the
  // magnet's interior and faces (up to ~M) saturate at the top colour.
  RenderOptions hOptions;
  hOptions.logScale = true;
  hOptions.logDecades = 2;
  if (hMaxMat > 0) {
    hOptions.maxValue = 2 * hMaxMat;
    hOptions.minValue = 2e-2 * hMaxMat;
  }
  const SliceInfo hInfo = writeSlice(dir / "slice_H.png", hSlice, hOptions, nSlice, n0, magnet, grid, c,
                                     "|H|, magnetic field magnitude", "A/m");
  // |B| / |B0|: flux concentration by the material, log scale 1/1.6 .. 1.6
  // (1 = unchanged, mid-scale).
  RenderOptions gainOptions;
  gainOptions.logScale = true;
  gainOptions.minValue = 1 / 1.6;
  gainOptions.maxValue = 1.6;
  const SliceInfo gInfo = writeSlice(dir / "slice_B_ratio.png", gainSlice, gainOptions, nSlice, n0, magnet, grid, c,
                                     "|B| / |B0|, B0 = mu0 (H_ext + M_magnet) the induction without the material",
                                     "1");
  // |t|, log scale over four decades below its maximum.
  RenderOptions tOptions;
  tOptions.colormap = Colormap::Inferno;
  tOptions.logScale = true;
  tOptions.logDecades = 4;
  const SliceInfo tInfo = writeSlice(dir / "slice_force.png", tSlice, tOptions, nSlice, n0, magnet, grid, c,
                                     "|t|, Einstein-Laub force density magnitude", "N/m^3");

  {
    std::ostringstream csv;
    csv << "# lodestone-field-demo: vertical centre line x = y = 0 m\n"
           "z_m,H_magnitude_A_per_m,Hz_A_per_m,Hext_z_A_per_m,Mz_A_per_m,n_per_m3,tz_N_per_m3\n";
    csv << std::setprecision(10);
    for (int k = 0; k < grid.dims.k; ++k) {
      const double z = grid.nodePosition(c, c, k).z;
      csv << z << ',' << norm(H(c, c, k)) << ',' << H(c, c, k).z << ',' << Hext(c, c, k).z << ',' << M(c, c, k).z + 0.0
          << ',' << n(c, c, k) << ',' << t(c, c, k).z << '\n';
    }
    writeText(dir / "profile.csv", csv.str());
  }

  {
    const FieldSolveReport& s = rep.solve;
    std::ostringstream js;
    js << "{\n"
       << "  \"program\": \"lodestone-field-demo\",\n"
       << "  \"version\": " << str(LODESTONE_VERSION_STRING) << ",\n"
       << "  \"units\": \"SI: lengths m, fields H and M A/m, B T, force N, force density N/m^3, number density "
          "1/m^3, time s\",\n"
       << "  \"scene\": {\n"
       << "    \"material\": {\"law\": " << str(o.law) << ", \"description\": " << str(material.describe())
       << ", \"bulk_number_density_per_m3\": " << num(n0) << ", \"saturation_magnetization_A_per_m\": "
       << num(material.saturation()) << ", \"low_field_susceptibility\": " << num(material.lowFieldSusceptibility())
       << "},\n"
       << "    \"ball\": {\"centre_m\": " << vec(ballCentre) << ", \"radius_m\": " << num(kBallRadius)
       << ", \"material_points\": " << ball.x.size() << ", \"points_per_cell\": "
       << kParticlesPerAxis * kParticlesPerAxis * kParticlesPerAxis << ", \"micro_particles\": " << num(ballCount)
       << ", \"micro_particles_exact_ball\": " << num(n0 * 4.0 / 3.0 * kPi * std::pow(kBallRadius, 3)) << "},\n"
       << "    \"magnet\": {\"shape\": \"cylinder\", \"centre_m\": " << vec(magnetCentre)
       << ", \"axis\": [0, 0, 1], \"radius_m\": " << num(kMagnetRadius) << ", \"half_length_m\": "
       << num(kMagnetHalfLength) << ", \"remanence_T\": " << num(kRemanence) << ", \"magnetization_A_per_m\": "
       << vec({0, 0, Mmag}) << ", \"moment_A_m2\": " << vec(magnet.moment(0.0)) << "},\n"
       << "    \"uniform_field_A_per_m\": " << vec({0, 0, o.field}) << ",\n"
       << "    \"sources\": " << str(sources.describe()) << "\n"
       << "  },\n"
       << "  \"grid\": {\"nodes\": [" << grid.dims.i << ", " << grid.dims.j << ", " << grid.dims.k
       << "], \"dx_m\": " << num(grid.dx) << ", \"origin_m\": " << vec(grid.origin)
       << ", \"max_corner_m\": " << vec(grid.maxCorner()) << "},\n"
       << "  \"settings\": {\"boundary\": " << str(o.boundary) << ", \"tolerance\": " << num(o.tolerance)
       << ", \"max_newton_iterations\": " << settings.solve.maxNewtonIterations
       << ", \"max_cg_iterations\": " << settings.solve.maxCgIterations << ", \"force_mask\": "
       << str(toString(settings.forceMask)) << ", \"threads\": " << threads << "},\n"
       << "  \"solve\": {\n"
       << "    \"status\": " << str(toString(s.status)) << ", \"converged\": " << (s.converged() ? "true" : "false")
       << ", \"message\": " << str(s.message) << ",\n"
       << "    \"newton_iterations\": " << s.newtonIterations << ", \"cg_iterations\": " << s.cgIterations
       << ", \"line_search_cuts\": " << s.lineSearchCuts << ",\n"
       << "    \"relative_residual\": " << num(s.relativeResidual) << ", \"reference_residual_A_m\": "
       << num(s.referenceResidual) << ", \"material_energy_A2_m\": " << num(s.materialEnergy)
       << ", \"material_cells\": " << s.materialCells << ", \"preconditioner\": " << str(s.preconditioner)
       << ", \"seconds\": " << num(s.seconds) << ",\n"
       << "    \"history\": [";
    for (std::size_t q = 0; q < s.history.size(); ++q) {
      const NewtonIterationRecord& r = s.history[q];
      js << (q ? ",\n" : "\n") << "      {\"iteration\": " << r.iteration << ", \"relative_residual\": "
         << num(r.relativeResidual) << ", \"forcing\": " << num(r.forcing) << ", \"cg_iterations\": "
         << r.cgIterations << ", \"cg_relative_residual\": " << num(r.cgRelativeResidual)
         << ", \"step\": " << num(r.step) << ", \"line_search_cuts\": " << r.lineSearchCuts
         << ", \"residual_merit\": " << (r.residualMerit ? "true" : "false") << ", \"seconds\": " << num(r.seconds)
         << "}";
    }
    js << (s.history.empty() ? "]\n" : "\n    ]\n") << "  },\n"
       << "  \"timings_s\": {\"transfer\": " << num(rep.secondsTransfer) << ", \"applied_field\": "
       << num(rep.secondsAppliedField) << ", \"solve\": " << num(rep.secondsSolve) << ", \"fields\": "
       << num(rep.secondsFields) << ", \"force\": " << num(rep.secondsForce) << ", \"stage_total\": "
       << num(rep.secondsTotal) << ", \"program_until_output\": " << num(secondsSince(tProgram)) << "},\n"
       << "  \"results\": {\n"
       << "    \"total_force_N\": " << vec(rep.totalForce) << ",\n"
       << "    \"total_micro_particles\": " << num(rep.totalCount) << ",\n"
       << "    \"H_magnitude_A_per_m\": {\"min\": " << num(hMin) << ", \"max\": " << num(hMax) << "},\n"
       << "    \"H_magnitude_in_material_A_per_m\": {\"min\": " << num(hMinMat) << ", \"max\": " << num(hMaxMat)
       << ", \"where\": \"nodes with n >= n0/2\"},\n"
       << "    \"M_magnitude_in_material_max_A_per_m\": " << num(mMaxMat) << ",\n"
       << "    \"B_magnitude_in_material_max_T\": " << num(bMaxMat) << ",\n"
       << "    \"force_density_magnitude_max_N_per_m3\": " << num(tMax) << "\n"
       << "  },\n"
       << "  \"images\": {\n"
       << sliceJson(hInfo, "    ") << ",\n"
       << sliceJson(gInfo, "    ") << ",\n"
       << sliceJson(tInfo, "    ") << "\n"
       << "  },\n"
       << "  \"profile\": \"profile.csv: vertical centre line x = y = 0 m, z ascending\",\n"
       << "  \"warnings\": [";
    for (std::size_t q = 0; q < rep.warnings.size(); ++q) js << (q ? ", " : "") << str(rep.warnings[q]);
    js << "]\n}\n";
    writeText(dir / "field_solve.json", js.str());
  }

  std::cout << "colour scales: slice_H.png (log) |H| " << hInfo.range.min << " .. " << hInfo.range.max
            << " A/m; slice_B_ratio.png |B|/|B0| " << gInfo.range.min << " .. " << gInfo.range.max
            << " (log); slice_force.png (log) |t| " << tInfo.range.min << " .. " << tInfo.range.max << " N/m^3\n"
            << "wrote " << (dir / "field_solve.json").string()
            << ", slice_H.png, slice_B_ratio.png, slice_force.png, profile.csv\n"
            << "total time " << std::fixed << std::setprecision(2) << secondsSince(tProgram) << " s\n";
  if (!rep.converged()) {
    std::cerr << "lodestone-field-demo: error: the field solve did not converge (" << toString(rep.solve.status)
              << "): " << rep.solve.message << "\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    Options options;
    if (const std::optional<int> code = parseOptions(argc, argv, options)) return *code;
    return run(options);
  } catch (const lodestone::Error& e) {
    std::cerr << "lodestone-field-demo: error: " << e.what() << "\n";
  } catch (const std::exception& e) {
    std::cerr << "lodestone-field-demo: error: " << e.what() << "\n";
  }
  return 1;
}
