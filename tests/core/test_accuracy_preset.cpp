// Accuracy presets keep their stated bounds: the relative deviation from the
// converged answer (same grid, field solved every substep to 1e-10) of the
// interior field of a Langevin sphere and of the motion of a magnetic cube
// pulled toward a magnet stays within each preset's bound, and the presets
// are ordered (a cheaper preset never claims a tighter bound).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "lodestone/core/planner/accuracy_preset.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone/core/sources/uniform_field.h"

using namespace lodestone;

namespace {

const AccuracyPreset kPresets[] = {AccuracyPreset::Draft, AccuracyPreset::Preview, AccuracyPreset::Final};

/// Interior H (A/m) at the nodes inside a sphere of radius N/4 cells of the
/// paper's material in a uniform 1e5 A/m field, solved to `tolerance`.
std::vector<Vec3d> sphereInterior(double tolerance) {
  const int N = 33;
  GridSpec g;
  g.dx = 7.8e-3;
  g.dims = {N, N, N};
  const MagneticMaterial mat = paperMaterial();
  DenseGrid<double> n(g, 0.0);
  const double c = 0.5 * (N - 1), R = 0.25 * (N - 1);
  for (int k = 0; k < N; ++k)
    for (int j = 0; j < N; ++j)
      for (int i = 0; i < N; ++i) {
        const double x = i - c, y = j - c, z = k - c;
        if (x * x + y * y + z * z < R * R) n(i, j, k) = mat.numberDensity;
      }
  MagneticStageSettings s;
  s.solve.tolerance = tolerance;
  MagneticForceStage stage(g, mat, s);
  const MagneticStageReport r = stage.runOnDensity(n.view(), UniformField({0, 0, 1e5}), 0.0);
  EXPECT_TRUE(r.converged()) << r.summary();
  std::vector<Vec3d> H;
  for (std::size_t m = 0; m < g.nodeCount(); ++m)
    if (n.view()[m] > 0) H.push_back(stage.field()[m]);
  return H;
}

double relativeDeviation(const std::vector<Vec3d>& a, const std::vector<Vec3d>& ref) {
  double num = 0, den = 0;
  for (std::size_t m = 0; m < ref.size(); ++m) {
    num += norm2(a[m] - ref[m]);
    den += norm2(ref[m]);
  }
  return std::sqrt(num / den);
}

/// Downward displacement (m) of a 4-cell magnetic cube above a 1.2 T sphere
/// magnet after 3 frames of 2 ms at a fixed 1e-4 s substep.
double cubeDisplacement(double tolerance, int solveInterval) {
  MpmSettings s;
  s.grid.dx = 7.8e-3;
  s.grid.dims = {32, 32, 32};
  s.fixedDt = 1e-4;
  s.magneticSolveInterval = solveInterval;
  s.magnetic.solve.tolerance = tolerance;
  MpmSolver solver(s);
  const std::uint32_t mat = solver.addMaterial(neoHookeanSolid(1e5, 0.3, 2500, paperMaterial()));
  const double c = 0.5 * 31 * s.grid.dx;
  solver.addMagnet(SphereMagnet(Pose::at({c, c, 0.035}), 0.02, {0, 0, magnetizationFromRemanence(1.2)}));
  solver.emit(EmitterShape::box(Pose::at({c, c, 0.075}), {2 * s.grid.dx, 2 * s.grid.dx, 2 * s.grid.dx}), mat, {});
  const double z0 = solver.particles().centreOfMass().z;
  for (int f = 0; f < 3; ++f) solver.advanceFrame(0.002);
  return z0 - solver.particles().centreOfMass().z;
}

}  // namespace

TEST(AccuracyPreset, NamesRoundTripAndBadNamesAreRefused) {
  for (AccuracyPreset p : kPresets) EXPECT_EQ(parseAccuracyPreset(toString(p)), p);
  try {
    parseAccuracyPreset("fast");
    FAIL() << "no exception";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("'fast'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("draft, preview, final"), std::string::npos) << e.what();
  }
  // Cheaper presets claim looser bounds and use looser settings.
  const auto d = accuracyPresetSettings(AccuracyPreset::Draft), p = accuracyPresetSettings(AccuracyPreset::Preview),
             f = accuracyPresetSettings(AccuracyPreset::Final);
  EXPECT_GT(d.bound, p.bound);
  EXPECT_GT(p.bound, f.bound);
  EXPECT_GT(d.solveTolerance, p.solveTolerance);
  EXPECT_GT(p.solveTolerance, f.solveTolerance);
}

TEST(AccuracyPreset, SphereFieldWithinTheBound) {
  const std::vector<Vec3d> ref = sphereInterior(1e-10);
  for (AccuracyPreset p : kPresets) {
    const AccuracyPresetSettings s = accuracyPresetSettings(p);
    const double dev = relativeDeviation(sphereInterior(s.solveTolerance), ref);
    std::printf("%-8s tolerance %.0e: interior H deviates %.2e from the converged field (bound %.0f%%)\n", s.name,
                s.solveTolerance, dev, 100 * s.bound);
    EXPECT_LE(dev, s.bound) << s.name;
    // The field solve is a small part of the budget: a tenth of it at most.
    EXPECT_LE(dev, 0.1 * s.bound) << s.name;
  }
}

TEST(AccuracyPreset, MagneticCubeMotionWithinTheBound) {
  const double ref = cubeDisplacement(1e-10, 1);
  ASSERT_GT(ref, 1e-4);  // it moves (m)
  for (AccuracyPreset p : kPresets) {
    const AccuracyPresetSettings s = accuracyPresetSettings(p);
    const double d = cubeDisplacement(s.solveTolerance, s.solveInterval);
    const double dev = std::fabs(d - ref) / ref;
    std::printf("%-8s tolerance %.0e, solve every %d substeps: cube moved %.4e m vs %.4e m (deviation %.2e, bound "
                "%.0f%%)\n",
                s.name, s.solveTolerance, s.solveInterval, d, ref, dev, 100 * s.bound);
    EXPECT_LE(dev, s.bound) << s.name;
  }
}
