// The C++ side of bench_python_overhead.py: the same stage runs and MPM
// substeps at 1e5 particles that the Python benchmark times through the
// module, timed here through the C++ API. Prints one CSV line per repeat:
//   kind,repeat,seconds
//
// Usage: lodestone_python_bench POSITIONS.f64 COUNTS.f64 REPEATS
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/mpm/material.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/sources/cylinder_magnet.h"
#include "lodestone/core/sources/field_source_set.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "raw_doubles.h"

namespace {

using namespace lodestone;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s POSITIONS.f64 COUNTS.f64 REPEATS\n", argv[0]);
    return 2;
  }
  try {
    const std::vector<Vec3d> x = python::readVec3s(argv[1]);
    const std::vector<double> counts = python::readDoubles(argv[2]);
    const int repeats = std::atoi(argv[3]);

    // Stage: mirrored in bench_python_overhead.py (stage_setup).
    FieldSourceSet sources;
    sources.add(CylinderMagnet(Pose::at({0, 0, -0.03}), 0.02, 0.01, {0, 0, 8e5}));
    MagneticForceStage stage(GridSpec{{-0.05, -0.05, -0.03}, 0.0025, {41, 41, 33}}, paperMaterial());
    std::vector<Vec3d> forces(x.size());
    for (int r = -1; r < repeats; ++r) {  // r = -1: the first (cold) solve, not reported
      const auto t0 = Clock::now();
      stage.run({x.data(), counts.data(), x.size()}, sources, 0.0);
      stage.particleForces({x.data(), counts.data(), x.size()}, forces.data());
      if (r >= 0) std::printf("stage_run,%d,%.9g\n", r, since(t0));
    }

    // MPM: mirrored in bench_python_overhead.py (mpm_setup).
    MpmSettings settings;
    settings.grid = {{-0.05, -0.05, -0.05}, 0.0025, {41, 41, 41}};
    settings.fixedDt = 2e-5;
    MpmSolver solver(settings);
    const std::uint32_t material = solver.addMaterial(neoHookeanSolid(2e5, 0.3, 1000, paperMaterial()));
    EmitterSettings emit;
    emit.cellSize = settings.grid.dx;
    solver.emit(EmitterShape::box(Pose::at({0, 0, 0.005}), {0.029, 0.029, 0.029}), material, emit);
    solver.addMagnet(CylinderMagnet(Pose::at({0, 0, -0.04}), 0.02, 0.005, {0, 0, 8e5}));
    std::fprintf(stderr, "mpm particles: %zu\n", solver.particles().size());
    for (int r = -1; r < repeats; ++r) {
      const auto t0 = Clock::now();
      solver.step(2e-5);
      if (r >= 0) std::printf("mpm_step,%d,%.9g\n", r, since(t0));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone_python_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
