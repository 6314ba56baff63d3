// Stability suite, patches (stage/magnetic_patches.h): the bounds of
// test_stability.cpp (finite, every solve converged, at most a cell per
// substep, energy) while the effects planner solves separate groups of
// magnetic material as patches coupled through their far fields: two blobs
// in a strong field, one thrown at the other until their patches merge into
// one box, and a single magnetic particle far from a body (a patch of one
// particle). Each frame is checked on its own (the energy bound holds from
// any start: test_stability.cpp).
#include "stability_harness.h"

namespace {

// A long domain (96 x 28 x 28 cells of 1 cm) with the planner on: a budget
// of 2% gives 4 free cells around the material, pad 7.
MpmSettings longSettings() {
  MpmSettings s = smallSettings();
  s.grid.dims = {96, 28, 28};
  s.magneticSolveInterval = 1;
  s.planner.enabled = true;
  s.planner.budget = 0.02;
  return s;
}

struct Frames {
  std::vector<std::size_t> patches;  // the plan's patches after each frame (0: one grid)
  std::string first;                 // the first frame's plan
};

Frames runChecked(MpmSolver& s, int frames, double duration, const std::string& name) {
  Frames f;
  for (int i = 0; i < frames; ++i) {
    const Outcome o = run(s, 1, duration);
    expectStable(s, o, name + ", frame " + std::to_string(i + 1));
    EXPECT_GE(o.solves, 1) << name;
    f.patches.push_back(s.lastMagneticPlan().patches.size());
    if (i == 0) f.first = s.lastMagneticPlan().summary();
  }
  return f;
}

}  // namespace

TEST(Stability, MagneticPatchesThatMeetAndOneParticlePatchStayFinite) {
  const double c = 13.5 * kDx;
  {
    // Two ferrofluid blobs 70 cells apart in 2e5 A/m along z, the left one
    // thrown at the right one at 5 m/s: two patches at first, one grid
    // once they come close (their grids would hold more than 70% of the
    // one box's nodes, or their material comes within two pads).
    auto s = std::make_unique<MpmSolver>(longSettings());
    const std::uint32_t mat = s->addMaterial(ferrofluid());
    s->emit(EmitterShape::box(Pose::at({10 * kDx, c, c}), {2 * kDx, 2 * kDx, 2 * kDx}), mat,
            emitSettings(8, {5, 0, 0}));
    s->emit(EmitterShape::box(Pose::at({80 * kDx, c, c}), {2 * kDx, 2 * kDx, 2 * kDx}), mat, emitSettings());
    s->sources().add(std::make_unique<UniformField>(Vec3d{0, 0, 2e5}));
    const Frames f = runChecked(*s, 10, 0.01, "blobs meeting");
    EXPECT_EQ(f.patches.front(), 2u) << "the blobs start apart: " << f.first;
    EXPECT_EQ(f.patches.back(), 0u) << "the blobs end within two pads: one grid";
  }
  {
    // One magnetic particle 60 cells from a ball over a 1.2 T magnet.
    auto s = std::make_unique<MpmSolver>(longSettings());
    const std::uint32_t mat = s->addMaterial(ferrofluid());
    s->emit(EmitterShape::sphere(Pose::at({16 * kDx, c, c}), 3 * kDx), mat, emitSettings());
    s->emit(EmitterShape::box(Pose::at({76.5 * kDx, c, c}), {0.2 * kDx, 0.2 * kDx, 0.2 * kDx}), mat, emitSettings(1));
    s->addMagnet(SphereMagnet(Pose::at({16 * kDx, c, c - 0.05}), 0.015, {0, 0, magnetizationFromRemanence(1.2)}));
    const Frames f = runChecked(*s, 3, 0.01, "a one-particle patch");
    EXPECT_EQ(f.patches.front(), 2u) << "the particle is a patch of its own: " << f.first;
  }
}
