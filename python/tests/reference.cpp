// The C++ side of test_reference.py: the same stage run, sampled fields and
// MPM substep that the test makes through the Python module, computed by the
// C++ API directly and written as raw float64 files for a bit-for-bit
// comparison. The setup constants are mirrored in test_reference.py.
//
// Usage: lodestone_python_reference POSITIONS.f64 COUNTS.f64 OUT_DIR
//        lodestone_python_reference --errors
// The second form prints the message of each bad input of errorCases, one
// after the other, each followed by a line "---" (test_errors.py makes the
// same calls through Python and compares the messages).
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/mpm/material.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/sources/cuboid_magnet.h"
#include "lodestone/core/sources/field_source_set.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/core/sources/cylinder_magnet.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone/core/sources/time_profile.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/plugin/node_registry.h"
#include "lodestone/plugin/scene.h"
#include "raw_doubles.h"

namespace {

using namespace lodestone;
using python::readDoubles;
using python::readVec3s;
using python::writeDoubles;

void writeVec3(const std::string& path, const std::vector<Vec3d>& v) {
  writeDoubles(path, reinterpret_cast<const double*>(v.data()), 3 * v.size());
}

// Each case is one bad input; the order is that of test_errors.py.
int errorCases() {
  const GridSpec grid{{-0.04, -0.04, -0.02}, 0.004, {21, 21, 16}};
  std::vector<std::function<void()>> cases = {
      [] { GridSpec{{0, 0, 0}, -1.0, {3, 3, 3}}.validate(); },
      [] { langevinMaterial(-1.0, 300.0, 1e23); },
      [] { linearMaterial(-0.5, 1e23); },
      [] { TimeProfile::ramp(1.0, 0.0); },
      [] { SphereMagnet(Pose::at({0, 0, 0}), -0.01, {0, 0, 1e5}); },
      [] { CylinderMagnet(Pose::at({0, 0, 0}), 0.01, 0.01, {1e5, 0, 1e5}); },
      [] { Pose::fromQuaternion({0, 0, 0}, 0, 0, 0, 0); },
      [&] {
        MagneticForceStage stage(grid, paperMaterial());
        const Vec3d x[2] = {{0, 0, 0}, {0.5, 0, 0}};
        const double n[2] = {1e15, 1e15};
        stage.run({x, n, 2}, UniformField({0, 0, 1e4}), 0.0);
      },
      [&] {
        MagneticForceStage stage(grid, paperMaterial());
        const Vec3d x[1] = {{0, std::nan(""), 0}};
        const double n[1] = {1e15};
        stage.run({x, n, 1}, UniformField({0, 0, 1e4}), 0.0);
      },
      [&] {
        MagneticForceStage stage(grid, paperMaterial());
        const Vec3d x[2] = {{0, 0, 0}, {0.001, 0, 0}};
        const double n[2] = {1e15, 1e15};
        stage.run({x, n, 2}, UniformField({0, 0, 1e4}), 0.0);
        Vec3d out[1];
        stage.particleForces({x, n, 1}, out);
      },
      [&] {
        MagneticStageSettings settings;
        settings.solve.tolerance = -1;
        MagneticForceStage stage(grid, paperMaterial(), settings);
      },
      [] { neoHookeanSolid(2e5, 0.6, 1000.0); },
      [] {
        MpmSettings settings;
        settings.grid = {{0, 0, 0}, 0.01, {3, 8, 8}};
        MpmSolver solver(settings);
      },
      [] { plugin::parseScene(R"({"name": "s", "domian": {}})", "bad.json"); },
      [] { plugin::requireNode("magnetic_forse"); },
  };
  for (const auto& c : cases) {
    try {
      c();
      std::printf("(no error)\n---\n");
    } catch (const InvalidArgument& e) {
      std::printf("%s\n---\n", e.what());
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 2 && std::string(argv[1]) == "--errors") return errorCases();
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s POSITIONS.f64 COUNTS.f64 OUT_DIR\n", argv[0]);
    return 2;
  }
  try {
    const std::vector<Vec3d> x = readVec3s(argv[1]);
    const std::vector<double> counts = readDoubles(argv[2]);
    const std::string out = argv[3];

    // The stage: a ball of the paper's material above a box magnet, in a weak uniform field.
    FieldSourceSet sources;
    sources.add(CuboidMagnet(Pose::at({0, 0, -0.035}), {0.01, 0.01, 0.005}, {0, 0, 8e5}));
    sources.add(UniformField({0, 0, 1e4}));
    const GridSpec grid{{-0.04, -0.04, -0.02}, 0.004, {21, 21, 16}};
    MagneticForceStage stage(grid, paperMaterial());
    const MagneticStageReport report = stage.run({x.data(), counts.data(), x.size()}, sources, 0.0);
    std::vector<Vec3d> forces(x.size()), field(x.size());
    stage.particleForces({x.data(), counts.data(), x.size()}, forces.data());
    stage.sampleField(x.data(), x.size(), field.data());
    writeVec3(out + "/particle_forces.f64", forces);
    writeVec3(out + "/sampled_field.f64", field);
    writeDoubles(out + "/nodal_force.f64", reinterpret_cast<const double*>(stage.nodalForce().data),
                 3 * grid.nodeCount());
    writeDoubles(out + "/potential.f64", stage.potential().data, grid.nodeCount());
    writeDoubles(out + "/total_force.f64", &report.totalForce.x, 3);

    // The magnet's applied field at the particles.
    std::vector<Vec3d> applied(x.size());
    sources.accumulateField(x.data(), x.size(), 0.0, applied.data());
    writeVec3(out + "/applied_field.f64", applied);

    // One MPM substep: a magnetic elastic cube over a box magnet.
    MpmSettings settings;
    settings.grid = {{-0.04, -0.04, -0.04}, 0.005, {17, 17, 17}};
    settings.fixedDt = 1e-4;
    MpmSolver solver(settings);
    const std::uint32_t material = solver.addMaterial(neoHookeanSolid(2e5, 0.3, 1000, paperMaterial()));
    EmitterSettings emit;
    emit.cellSize = settings.grid.dx;
    solver.emit(EmitterShape::box(Pose::at({0, 0, 0}), {0.01, 0.01, 0.01}), material, emit);
    solver.addMagnet(CuboidMagnet(Pose::at({0, 0, -0.025}), {0.01, 0.01, 0.004}, {0, 0, 8e5}),
                     BoundaryCondition{BoundaryMode::Sticky, 0.0});
    solver.step(1e-4);
    writeVec3(out + "/mpm_x.f64", solver.particles().x);
    writeVec3(out + "/mpm_v.f64", solver.particles().v);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodestone_python_reference: %s\n", e.what());
    return 1;
  }
  return 0;
}
