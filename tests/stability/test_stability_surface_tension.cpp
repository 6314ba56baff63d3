// Stability suite, surface tension: the bounds of test_stability.cpp (finite,
// every solve converged, at most a cell per substep, energy) for fluids with
// surface tension in hard places: the largest accepted sigma on a small
// drop, a sheet one cell thick that tension pulls apart, and a ferrofluid
// drop in a field strong enough to pull it into a spike.
#include "stability_harness.h"

namespace {

MpmMaterial withTension(MpmMaterial m, double sigma) {
  m.surfaceTension = sigma;
  m.validate();
  return m;
}

}  // namespace

TEST(Stability, SurfaceTensionInHardPlacesStaysFinite) {
  const double c = centre();
  {
    // The largest accepted sigma (kMaxSurfaceTension, 10 N/m) on a drop of
    // radius 2.5 cells: the capillary limit sets the step.
    auto s = std::make_unique<MpmSolver>(smallSettings());
    s->emit(EmitterShape::sphere(Pose::at({c, c, c}), 0.025),
            s->addMaterial(withTension(ferrofluid(nonMagneticMaterial()), kMaxSurfaceTension)), emitSettings());
    const Outcome o = run(*s, 3, 0.01);
    expectStable(*s, o, "sigma 10 N/m on a 2.5-cell drop");
  }
  {
    // A sheet one cell thick, 10 cells wide, falling: tension pulls its rim
    // in and may tear it.
    auto s = std::make_unique<MpmSolver>(smallSettings());
    s->emit(EmitterShape::box(Pose::at({c, c, 0.1}), {0.05, 0.05, 0.005}),
            s->addMaterial(withTension(ferrofluid(nonMagneticMaterial()), 0.07)), emitSettings());
    const Outcome o = run(*s, 3, 0.01);
    expectStable(*s, o, "a one-cell sheet with sigma 0.07 N/m");
  }
  {
    // A ferrofluid drop with sigma = 0.025 N/m in 1e6 A/m along z, switched
    // on at once: magnetic and capillary stresses together.
    auto s = std::make_unique<MpmSolver>(smallSettings());
    s->emit(EmitterShape::sphere(Pose::at({c, c, c}), 0.03), s->addMaterial(withTension(ferrofluid(), 0.025)),
            emitSettings());
    s->sources().add(std::make_unique<UniformField>(Vec3d{0, 0, 1e6}));
    const Outcome o = run(*s, 3, 0.01);
    expectStable(*s, o, "a ferrofluid drop with sigma in 1e6 A/m");
    EXPECT_GE(o.solves, 3);
  }
}
