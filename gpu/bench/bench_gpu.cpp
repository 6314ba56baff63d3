// lodestone-bench-gpu: nonlinear field solves on 128^3 and 256^3 node grids
// and MLS-MPM steps with 1e6 particles (without and with surface tension) on
// the chosen backend (default: the CUDA device). Prints a table and writes
// CSV; asserts nothing.
// `lodestone-bench-gpu --help` lists the options.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "lodestone/cli/command_line.h"
#include "lodestone/core/field/langevin.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/gpu/backend.h"
#include "lodestone/gpu/field_solver.h"
#include "lodestone/gpu/mpm.h"

using namespace lodestone;
using namespace lodestone::gpu;

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

struct Args {
  Backend backend = Backend::Cuda;
  std::vector<int> sizes{128, 256};
  long particles = 1000000;
  int steps = 10;
  std::string csv = "bench_gpu.csv";
};

// Fills `a`; returns the code to exit with after --help or a bad option
// (2, as for any failure here), nullopt to go on.
std::optional<int> parse(int argc, char** argv, Args& a) {
  CLI::App app("lodestone-bench-gpu: nonlinear field solves and MLS-MPM steps on the chosen backend",
               "lodestone-bench-gpu");
  cli::helpLayout(app, 30);
  std::string backend = toString(a.backend);
  std::vector<double> sizes(a.sizes.begin(), a.sizes.end());
  app.add_option("--backend", backend, "where to run (auto: CUDA when a device is found)")
      ->type_name("B")
      ->check(cli::oneOf({"cuda", "cpu", "auto"}))
      ->capture_default_str();
  cli::addNumberList(app, "--sizes", sizes, "field-solve grid nodes per axis");
  cli::addNumber(app, "--particles", a.particles, "particles of the MPM steps")
      ->type_name("N")
      ->check(cli::wholeNumber(1))
      ->default_str(cli::formatNumber(double(a.particles)));
  cli::addNumber(app, "--steps", a.steps, "timed MPM steps")
      ->type_name("N")
      ->check(cli::wholeNumber(1))
      ->default_str(cli::formatNumber(a.steps));
  app.add_option("--csv", a.csv, "CSV output")->type_name("FILE")->capture_default_str();
  if (const std::optional<int> code = cli::parse(app, argc, argv, 2)) return code;
  a.backend = parseBackend(backend);
  a.sizes.clear();
  for (double n : sizes) {
    if (!(n == std::floor(n) && n >= 2 && n <= 1e6))
      throw std::runtime_error("--sizes: " + cli::formatNumber(n) + " is not a whole number >= 2");
    a.sizes.push_back(int(n));
  }
  return std::nullopt;
}

MagnetizationLaw<double> paperLaw() {
  MagnetizationLaw<double> law;
  law.kind = LawKind::Langevin;
  law.moment = 1.09e-19;                                            // A m^2
  law.k2 = 1.25663706212e-6 * law.moment / (1.380649e-23 * 300.0);  // m/A at 300 K
  return law;
}

}  // namespace

int main(int argc, char** argv) try {
  Args args;
  if (const std::optional<int> code = parse(argc, argv, args)) return *code;
  std::printf("lodestone-bench-gpu: backend status: %s\n", backendStatus().c_str());
  std::string why;
  const Backend backend = resolveBackend(args.backend, &why);
  if (!why.empty()) std::printf("%s\n", why.c_str());
  std::FILE* csv = std::fopen(args.csv.c_str(), "w");
  if (!csv) throw std::runtime_error("cannot write " + args.csv);
  std::fprintf(csv,
               "benchmark,backend,size,material_cells_or_particles,setup_s,run_s,newton,cg,seconds_per_cg,"
               "relative_residual,status\n");
  std::printf("\n%-12s %-5s %6s %12s %9s %9s %6s %6s %12s %10s  %s\n", "benchmark", "back", "size", "cells/parts",
              "setup s", "run s", "newton", "cg", "s per cg", "rel res", "status");

  // Field solves: a Langevin ball (radius 0.3 of the box) of the paper's
  // material in a uniform field plus a gradient, shield wall, multigrid.
  const double n0 = 3.6e17 / (7.8e-3 * 7.8e-3 * 7.8e-3);
  for (const int N : args.sizes) {
    const double L = 0.25, h = L / (N - 1);
    const GridSpec grid{{-L / 2, -L / 2, -L / 2}, h, {N, N, N}};
    std::vector<double> n(grid.nodeCount(), 0.0);
    for (int k = 0; k < N; ++k)
      for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i)
          if (norm(grid.nodePosition(i, j, k)) < 0.3 * L) n[grid.index(i, j, k)] = n0;
    for (const double H0 : {3e4, 3e5}) {
      const auto t0 = Clock::now();
      FieldSolver solver(grid, paperLaw(), BoundaryKind::Shield, backend);
      solver.setMaterial(n.data(), [&](const Vec3d* x, std::size_t count, Vec3d* H) {
        for (std::size_t m = 0; m < count; ++m) H[m] = Vec3d{0.0, 0.0, H0 * (1.0 + 2.0 * x[m].z)};
      });
      const double setup = since(t0);
      std::vector<double> phi(grid.nodeCount(), 0.0);
      const FieldSolveReport r = solver.solve(phi.data());
      const double perCg = r.cgIterations > 0 ? r.seconds / r.cgIterations : 0.0;
      const std::string name = "field-" + std::to_string(int(H0));
      std::printf("%-12s %-5s %6d %12zu %9.3f %9.3f %6d %6d %12.3e %10.2e  %s\n", name.c_str(), r.backend.c_str(), N,
                  r.materialCells, setup, r.seconds, r.newtonIterations, r.cgIterations, perCg, r.relativeResidual,
                  toString(r.status));
      std::fprintf(csv, "%s,%s,%d,%zu,%.6f,%.6f,%d,%d,%.6e,%.3e,%s\n", name.c_str(), r.backend.c_str(), N,
                   r.materialCells, setup, r.seconds, r.newtonIterations, r.cgIterations, perCg, r.relativeResidual,
                   toString(r.status));
      std::fflush(csv);
    }
  }

  // MPM: a block of fluid, 8 particles per cell, falling in a box of walls;
  // then the same with surface tension (0.07 N/m: the colour field, its
  // gradient and the capillary stress added to every step).
  for (const double sigma : {0.0, 0.07}) {
    const std::string name = sigma > 0 ? "mpm-step-surface-tension" : "mpm-step";
    const long cellsPerAxis = std::max(1L, long(std::llround(std::cbrt(double(args.particles) / 8.0))));
    const int N = int(cellsPerAxis) + 16;
    const double h = 0.01;
    const GridSpec grid{{0.0, 0.0, 0.0}, h, {N, N, N}};
    std::vector<Vec3d> x, v;
    std::vector<Mat3d> C, F;
    std::vector<double> J, mass, vol, count;
    std::vector<std::uint32_t> mat;
    const double q = h / 2;
    for (long c = 0; c < 2 * cellsPerAxis; ++c)
      for (long b = 0; b < 2 * cellsPerAxis; ++b)
        for (long a = 0; a < 2 * cellsPerAxis; ++a) {
          x.push_back({(8 + 0.25 + 0.5 * a) * h, (8 + 0.25 + 0.5 * b) * h, (6 + 0.25 + 0.5 * c) * h});
          v.push_back({0.0, 0.0, -0.5});
          C.push_back(Mat3d{});
          F.push_back(Mat3d::identity());
          J.push_back(1.0);
          mass.push_back(1000.0 * q * q * q);
          vol.push_back(q * q * q);
          count.push_back(1e3);
          mat.push_back(0);
        }
    MpmMaterialParams fluid;
    fluid.fluid = true;
    fluid.viscosity = 0.01;
    fluid.bulkModulus = 1e5;
    fluid.surfaceTension = sigma;  // N/m
    MpmStepper mpm(grid, {fluid}, backend);
    const auto t0 = Clock::now();
    mpm.upload({x.data(), v.data(), C.data(), F.data(), J.data(), mass.data(), vol.data(), count.data(), mat.data(),
                x.size()});
    const double setup = since(t0);
    MpmStepSettings s;
    mpm.step(1e-4, s);  // warm-up
    const auto t1 = Clock::now();
    for (int k = 0; k < args.steps; ++k) mpm.step(1e-4, s);
    std::vector<double> Jout(x.size());
    mpm.download({nullptr, nullptr, nullptr, nullptr, Jout.data(), x.size()});  // waits for the device
    const double perStep = since(t1) / args.steps;
    std::printf("%-12s %-5s %6d %12zu %9.3f %9.3e %6s %6s %12.3e %10s  %s\n", name.c_str(), toString(mpm.backend()),
                N, x.size(), setup, perStep, "-", "-", perStep / double(x.size()), "-", "ok");
    std::fprintf(csv, "%s,%s,%d,%zu,%.6f,%.6e,,,%.6e,,ok\n", name.c_str(), toString(mpm.backend()), N, x.size(), setup,
                 perStep, perStep / double(x.size()));
  }
  std::fclose(csv);
  std::printf(
      "\nwrote %s (run s: whole solve incl. transfers of phi; MPM: seconds per step, per particle in "
      "the s-per-cg column)\n",
      args.csv.c_str());
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "lodestone-bench-gpu: %s\n", e.what());
  return 2;
}
