// The effects planner against full physics: for each automatic decision, a
// scene where it is taken and the measured deviation from the full-physics
// run stays within the budget, and one where the budget is too tight (or the
// physics too strong) and it is not; stage-run counts for non-magnetic,
// static and moving scenes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "lodestone/core/planner/effects_planner.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/core/stage/transfer.h"
#include "lodestone/core/base/error.h"

using namespace lodestone;

namespace {

constexpr double kDx = 7.8e-3;  // m

struct PlannerCase {
  MagneticMaterial material = paperMaterial();
  double remanence = 1.2;      // T, of the sphere magnet below the cube
  double uniformH = 0;         // A/m, an extra uniform field along z (0: none)
  bool magnet = true;
  int nodes = 32;
  double gravity = 0;          // m/s^2 along -z
  int frames = 2;
  bool planner = false;
  double budget = 0.05;
  bool checkFinite = false;
};

struct Outcome {
  double firstForce = 0;  // z force of the first solve, N
  double moved = 0;       // centre-of-mass displacement along -z, m
  int solves = 0, reused = 0, substeps = 0;
  MagneticPlan plan;      // of the first solve
};

Outcome run(const PlannerCase& s) {
  MpmSettings ms;
  ms.grid.dx = kDx;
  ms.grid.dims = {s.nodes, s.nodes, s.nodes};
  ms.gravity = {0, 0, -s.gravity};
  ms.fixedDt = 1e-4;
  ms.magneticSolveInterval = 1;
  ms.magnetic.solve.tolerance = 1e-9;
  ms.planner.enabled = s.planner;
  ms.planner.budget = s.budget;
  ms.checkFinite = s.checkFinite;
  MpmSolver solver(ms);
  const std::uint32_t mat = solver.addMaterial(neoHookeanSolid(1e5, 0.3, 2500, s.material));
  const double c = 0.5 * (s.nodes - 1) * kDx;
  if (s.magnet)
    solver.addMagnet(SphereMagnet(Pose::at({c, c, c - 0.045}), 0.02, {0, 0, magnetizationFromRemanence(s.remanence)}));
  if (s.uniformH != 0) solver.sources().add(std::make_unique<UniformField>(Vec3d{0, 0, s.uniformH}));
  solver.emit(EmitterShape::box(Pose::at({c, c, c}), {2 * kDx, 2 * kDx, 2 * kDx}), mat, {});
  Outcome o;
  const double z0 = solver.particles().centreOfMass().z;
  for (int f = 0; f < s.frames; ++f) {
    const MpmFrameReport r = solver.advanceFrame(0.002);
    if (o.solves == 0 && !r.magneticReports.empty()) {
      o.firstForce = r.magneticReports.front().totalForce.z;
      o.plan = solver.lastMagneticPlan();
    }
    o.solves += int(r.magneticReports.size());
    o.reused += r.magneticReused;
    o.substeps += r.substeps;
  }
  o.moved = z0 - solver.particles().centreOfMass().z;
  return o;
}

double relative(double a, double ref) { return std::fabs(a - ref) / std::fabs(ref); }

void report(const char* what, const Outcome& full, const Outcome& planned, double budget) {
  std::printf("%s (budget %.1f%%): force %.4g vs %.4g N (%.2e), moved %.4g vs %.4g m (%.2e), solves %d of %d "
              "substeps (%d reused)\n%s",
              what, 100 * budget, planned.firstForce, full.firstForce, relative(planned.firstForce, full.firstForce),
              planned.moved, full.moved, full.moved != 0 ? relative(planned.moved, full.moved) : 0.0, planned.solves,
              planned.substeps, planned.reused, planned.plan.summary().c_str());
}

}  // namespace

TEST(EffectsPlanner, NonMagneticSceneRunsNoMagneticStage) {
  PlannerCase s;
  s.material = nonMagneticMaterial();
  s.planner = true;
  const Outcome o = run(s);
  EXPECT_EQ(o.solves, 0);
  // The plan says so, with the reason.
  MpmSettings ms;
  ms.grid.dx = kDx;
  ms.grid.dims = {16, 16, 16};
  ms.planner.enabled = true;
  MpmSolver solver(ms);
  solver.addMaterial(neoHookeanSolid(1e5, 0.3, 2500));
  solver.emit(EmitterShape::box(Pose::at({0.06, 0.06, 0.06}), {0.02, 0.02, 0.02}), 0, {});
  const MagneticPlan plan = solver.planMagneticNow();
  EXPECT_FALSE(plan.magnetic);
  ASSERT_EQ(plan.decisions.size(), 1u);
  EXPECT_NE(plan.decisions[0].reason.find("no magnetic material"), std::string::npos) << plan.summary();
}

TEST(EffectsPlanner, StaticSceneSolvesOnceMovingSceneResolves) {
  // Static: a cube in a uniform field (no net force, no gravity) stays put.
  PlannerCase still;
  still.magnet = false;
  still.uniformH = 2e4;
  still.planner = true;
  const Outcome s = run(still);
  std::printf("static: %d solves in %d substeps (%d reused), moved %.2e m\n", s.solves, s.substeps, s.reused, s.moved);
  EXPECT_EQ(s.solves, 1);
  EXPECT_EQ(s.reused, s.substeps - 1);
  // Moving: pulled by the magnet, it re-solves as it moves, but not every substep.
  PlannerCase moving;
  moving.planner = true;
  const Outcome m = run(moving);
  const Outcome full = run(PlannerCase{});
  report("moving cube", full, m, moving.budget);
  EXPECT_GT(m.solves, 1);
  EXPECT_LT(m.solves, m.substeps);
  EXPECT_EQ(full.solves, full.substeps);
  EXPECT_LE(relative(m.moved, full.moved), moving.budget);
}

TEST(EffectsPlanner, LinearLawWhenTheFieldIsWeak) {
  PlannerCase weak;
  weak.remanence = 0.003;  // |H| ~ 1e3 A/m at the cube: k2 |H| ~ 0.1
  const Outcome full = run(weak);
  weak.planner = true;
  const Outcome planned = run(weak);
  report("weak field", full, planned, weak.budget);
  EXPECT_TRUE(planned.plan.linearLaw);
  EXPECT_LE(relative(planned.firstForce, full.firstForce), weak.budget);
  // A budget too tight for the linear law's a^2/15: Langevin stays.
  weak.budget = 1e-5;
  EXPECT_FALSE(run(weak).plan.linearLaw);
  // A strong field: Langevin stays at the default budget.
  PlannerCase strong;
  strong.planner = true;
  EXPECT_FALSE(run(strong).plan.linearLaw);
}

TEST(EffectsPlanner, AppliedFieldOnlyWhenTheSusceptibilityIsSmall) {
  PlannerCase faint;
  faint.material = linearMaterial(2e-3, paperMaterial().numberDensity);
  const Outcome full = run(faint);
  faint.planner = true;
  const Outcome planned = run(faint);
  report("chi = 2e-3", full, planned, faint.budget);
  EXPECT_TRUE(planned.plan.appliedFieldOnly);
  EXPECT_LE(relative(planned.firstForce, full.firstForce), faint.budget);
  // chi = 0.5: the demagnetizing field matters, the solve runs.
  PlannerCase strong;
  strong.material = linearMaterial(0.5, paperMaterial().numberDensity);
  strong.planner = true;
  EXPECT_FALSE(run(strong).plan.appliedFieldOnly);
  // The same faint material under a budget tighter than its chi.
  faint.budget = 1e-3;
  EXPECT_FALSE(run(faint).plan.appliedFieldOnly);
}

TEST(EffectsPlanner, ActiveRegionAroundTheMaterial) {
  PlannerCase wide;
  wide.nodes = 40;
  wide.frames = 1;
  const Outcome full = run(wide);
  wide.planner = true;
  const Outcome planned = run(wide);
  report("40^3 domain", full, planned, wide.budget);
  EXPECT_TRUE(planned.plan.activeRegion);
  EXPECT_LT(planned.plan.region.nodeCount(), wide.nodes * wide.nodes * wide.nodes / 4);
  EXPECT_LE(relative(planned.firstForce, full.firstForce), 0.005);  // the stated truncation error of 4 cells
  EXPECT_LE(relative(planned.moved, full.moved), wide.budget);
  wide.budget = 0.002;  // share 0.05%: below what a truncated domain costs
  EXPECT_FALSE(run(wide).plan.activeRegion);
}

TEST(EffectsPlanner, ActiveRegionPassesTheFiniteCheck) {
  // The finite check after a solve scanned as many nodes as the full
  // magnetic grid, reading past the smaller grid of the active region, and
  // stopped healthy runs at t = 0 with a different node index on each run.
  PlannerCase wide;
  wide.nodes = 40;
  wide.frames = 1;
  wide.planner = true;
  const Outcome unchecked = run(wide);
  ASSERT_TRUE(unchecked.plan.activeRegion);
  wide.checkFinite = true;
  Outcome checked;
  EXPECT_NO_THROW(checked = run(wide));
  EXPECT_EQ(checked.firstForce, unchecked.firstForce);
  EXPECT_EQ(checked.moved, unchecked.moved);
}

TEST(EffectsPlanner, ReuseFollowsTheBudget) {
  PlannerCase loose;
  loose.planner = true;
  loose.budget = 0.1;
  const Outcome full = run(PlannerCase{});
  const Outcome planned = run(loose);
  report("reuse at 10%", full, planned, loose.budget);
  EXPECT_GT(planned.reused, 0);
  EXPECT_LE(relative(planned.moved, full.moved), loose.budget);
  PlannerCase tight = loose;
  tight.budget = 1e-4;
  const Outcome t = run(tight);
  EXPECT_EQ(t.reused, 0);
  EXPECT_EQ(t.solves, t.substeps);
}

TEST(EffectsPlanner, SeparateBodiesAreSolvedAsPatchesWithTheOneBoxesForces) {
  // Two magnetic cubes at the two ends of a long domain, each above a
  // magnet of its own: the active region's one box holds the air between
  // them, the patches only the cubes' surroundings. The forces on each
  // cube and the motion over a frame against the one-box solve.
  struct Result {
    Vec3d force[2];  // summed particle forces per cube, N
    double moved[2] = {0, 0};
    MagneticPlan plan;
    std::size_t solveNodes = 0;
  };
  const auto simulate = [](PlannerToggle patches) {
    MpmSettings ms;
    ms.grid.dx = kDx;
    ms.grid.dims = {96, 28, 28};
    ms.fixedDt = 1e-4;
    ms.magneticSolveInterval = 1;
    ms.magnetic.solve.tolerance = 1e-8;
    ms.planner.enabled = true;
    ms.planner.budget = 0.02;  // a share of 0.5%: 4 free cells, pad 7
    ms.planner.patches = patches;
    MpmSolver solver(ms);
    const std::uint32_t mat = solver.addMaterial(neoHookeanSolid(1e5, 0.3, 2500, paperMaterial()));
    const double c = 13.5 * kDx, xs[2] = {16.2 * kDx, 79.7 * kDx};
    for (double x : xs) {
      solver.addMagnet(SphereMagnet(Pose::at({x, c, c - 0.045}), 0.02, {0, 0, magnetizationFromRemanence(1.2)}));
      solver.emit(EmitterShape::box(Pose::at({x, c, c}), {2 * kDx, 2 * kDx, 2 * kDx}), mat, {});
    }
    const double mid = 48 * kDx;
    const auto centres = [&](double out[2]) {
      double n[2] = {0, 0};
      out[0] = out[1] = 0;
      for (std::size_t p = 0; p < solver.particles().size(); ++p) {
        const int b = solver.particles().x[p].x > mid;
        out[b] += solver.particles().x[p].z;
        n[b] += 1;
      }
      out[0] /= n[0];
      out[1] /= n[1];
    };
    double z0[2];
    centres(z0);
    Result r;
    solver.advanceFrame(0.001);  // 10 substeps, a solve each
    for (std::size_t p = 0; p < solver.particles().size(); ++p)
      r.force[solver.particles().x[p].x > mid] += solver.particles().magneticForce[p];
    double z1[2];
    centres(z1);
    for (int b = 0; b < 2; ++b) r.moved[b] = z0[b] - z1[b];
    r.plan = solver.lastMagneticPlan();
    if (const MagneticPatches* p = solver.magneticPatches()) {
      for (std::size_t q = 0; q < p->size(); ++q) r.solveNodes += p->grid(q).nodeCount();
    } else {
      r.solveNodes = solver.magneticStage()->grid().nodeCount();
    }
    return r;
  };
  const Result box = simulate(PlannerToggle::Off), patched = simulate(PlannerToggle::Auto);
  ASSERT_TRUE(box.plan.activeRegion);
  EXPECT_TRUE(box.plan.patches.empty());
  ASSERT_EQ(patched.plan.patches.size(), 2u) << patched.plan.summary();
  EXPECT_NE(patched.plan.summary().find("patches: on (2 patches)"), std::string::npos) << patched.plan.summary();
  std::printf("%s", patched.plan.summary().c_str());
  std::printf("solve nodes: one box %zu, patches %zu\n", box.solveNodes, patched.solveNodes);
  EXPECT_LT(double(patched.solveNodes), 0.7 * double(box.solveNodes));
  for (int b = 0; b < 2; ++b) {
    std::printf("cube %d: force z %.6g N (one box %.6g N, relative %.2e), moved %.4g m (one box %.4g m)\n", b,
                patched.force[b].z, box.force[b].z, norm(patched.force[b] - box.force[b]) / norm(box.force[b]),
                patched.moved[b], box.moved[b]);
    EXPECT_LT(box.force[b].z, 0.0);  // pulled down onto its magnet
    EXPECT_LT(norm(patched.force[b] - box.force[b]), 0.005 * norm(box.force[b]));
    EXPECT_NEAR(patched.moved[b], box.moved[b], 0.005 * std::fabs(box.moved[b]));
  }
}

TEST(EffectsPlanner, SettlingEarlyGivesTheFullScansDecisionsFromFewerPoints) {
  // 100,000 points in a box above a sphere magnet, ordered from the top (far
  // from the magnet) down, so that the field grows along the points' order.
  const GridSpec grid{{0, 0, 0}, kDx, {64, 64, 64}};
  std::vector<Vec3d> x;
  for (int k = 39; k >= 0 && x.size() < 100000; --k)
    for (int j = 0; j < 50; ++j)
      for (int i = 0; i < 50; ++i) x.push_back(grid.nodePosition(7 + i, 7 + j, 20 + k) + Vec3d{1e-3, 2e-3, 3e-3});
  ASSERT_EQ(x.size(), 100000u);
  const std::vector<Vec3d> nearFirst(x.rbegin(), x.rend());
  const double c = 0.5 * 63 * kDx;
  const auto plan = [&](double remanence, bool early, PlannerSettings settings, bool near) {
    const SphereMagnet magnet(Pose::at({c, c, 10 * kDx}), 0.04, {0, 0, magnetizationFromRemanence(remanence)});
    PlannerInputs in;
    in.positions = near ? nearFirst.data() : x.data();
    in.count = x.size();
    in.material = paperMaterial();
    in.applied = &magnet;
    in.appliedEmpty = false;
    in.grid = grid;
    in.settleEarly = early;
    settings.enabled = true;
    return planMagnetic(settings, in);
  };
  const auto expectSameDecisions = [](const MagneticPlan& a, const MagneticPlan& b, const char* what) {
    ASSERT_EQ(a.decisions.size(), b.decisions.size()) << what;
    for (std::size_t d = 0; d < a.decisions.size(); ++d) {
      EXPECT_EQ(a.decisions[d].on, b.decisions[d].on) << what << ": " << a.decisions[d].stage;
      EXPECT_EQ(a.decisions[d].choice, b.decisions[d].choice) << what << ": " << a.decisions[d].stage;
      EXPECT_EQ(a.decisions[d].predictedError, b.decisions[d].predictedError) << what << ": " << a.decisions[d].stage;
    }
    EXPECT_EQ(a.magnetic, b.magnetic) << what;
    EXPECT_EQ(a.linearLaw, b.linearLaw) << what;
    EXPECT_EQ(a.appliedFieldOnly, b.appliedFieldOnly) << what;
    EXPECT_TRUE(a.region == b.region) << what;
    EXPECT_EQ(a.predictedError, b.predictedError) << what;
  };
  struct Case {
    const char* what;
    double remanence;
    PlannerToggle linear;
    std::size_t evaluated;  // expected with settleEarly (0: every point)
    bool nearFirst;         // the points ordered from the magnet up
  };
  // Strong, near points first: the first block already rules out the linear law (and the paper's
  // chi0 = 0.91 always rules out skipping the solve). Weak: the linear law
  // fits, which only every point can show. Forced off: nothing is left to
  // settle; forced on: its predicted error needs the largest field. Medium:
  // the far points allow the linear law, the near ones do not.
  const Case cases[] = {{"strong", 1.2, PlannerToggle::Auto, kPlannerFieldBlock, true},
                        {"weak", 0.003, PlannerToggle::Auto, 0, true},
                        {"weak, linear law forced on", 0.003, PlannerToggle::On, 0, false},
                        {"weak, linear law forced off", 0.003, PlannerToggle::Off, kPlannerFieldBlock, false},
                        {"medium, far points first", 0.2, PlannerToggle::Auto, 0, false}};
  for (const Case& k : cases) {
    PlannerSettings s;
    s.linearLaw = k.linear;
    const MagneticPlan full = plan(k.remanence, false, s, k.nearFirst), early = plan(k.remanence, true, s, k.nearFirst);
    expectSameDecisions(full, early, k.what);
    EXPECT_EQ(full.fieldPointsEvaluated, x.size()) << k.what;
    std::printf("%s: %zu of %zu points evaluated; peak |H_ext| %.4g A/m (full scan %.4g A/m)\n%s", k.what,
                early.fieldPointsEvaluated, x.size(), early.peakAppliedField, full.peakAppliedField,
                early.summary().c_str());
    if (k.evaluated > 0) {
      EXPECT_EQ(early.fieldPointsEvaluated, k.evaluated) << k.what;
      EXPECT_LE(early.peakAppliedField, full.peakAppliedField) << k.what;  // over the points evaluated
      EXPECT_NE(early.summary().find("magnetic points settles it"), std::string::npos) << k.what;
    } else if (k.remanence < 0.01) {
      EXPECT_EQ(early.fieldPointsEvaluated, x.size()) << k.what;
      EXPECT_EQ(early.peakAppliedField, full.peakAppliedField) << k.what;
      EXPECT_EQ(early.summary(), full.summary()) << k.what;
    } else {  // medium: stopped at the first block that rules the linear law out, after the first
      EXPECT_GT(early.fieldPointsEvaluated, kPlannerFieldBlock) << k.what;
      EXPECT_LT(early.fieldPointsEvaluated, x.size()) << k.what;
      EXPECT_FALSE(early.linearLaw) << k.what;
    }
  }
}

namespace {

/// Cells of `grid` with a corner where the deposit of the points puts n > 0:
/// the field solve's material cells, counted node by node.
double depositedMaterialCells(const GridSpec& grid, const std::vector<Vec3d>& x) {
  std::vector<double> counts(x.size(), 1.0), n(grid.nodeCount(), 0.0);
  depositNumberDensity({x.data(), counts.data(), x.size()}, GridView<double>{n.data(), grid});
  double cells = 0;
  for (int k = 0; k + 1 < grid.dims.k; ++k)
    for (int j = 0; j + 1 < grid.dims.j; ++j)
      for (int i = 0; i + 1 < grid.dims.i; ++i) {
        bool material = false;
        for (int c = 0; c < 8 && !material; ++c)
          material = n[grid.index(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))] > 0;
        cells += material;
      }
  return cells;
}

/// `count` points uniform in the sphere of `radius` (m) around `centre`,
/// from a fixed seed.
std::vector<Vec3d> pointsInSphere(const Vec3d& centre, double radius, std::size_t count, unsigned seed) {
  std::vector<Vec3d> x;
  std::uint64_t s = seed;
  const auto uniform = [&] {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    return double(s >> 11) * 0x1.0p-53 * 2 - 1;
  };
  while (x.size() < count) {
    const Vec3d d{uniform(), uniform(), uniform()};
    if (norm2(d) <= 1) x.push_back(centre + radius * d);
  }
  return x;
}

}  // namespace

TEST(EffectsPlanner, MaterialCellsAreTheCellsTheDepositReaches) {
  GridSpec g;
  g.dx = 0.01;
  g.dims = {40, 36, 32};
  g.origin = {-0.2, -0.18, -0.16};
  // A ball: every x-row of its cells is one run, so the count is exact.
  const std::vector<Vec3d> ball = pointsInSphere({0.01, -0.02, 0.015}, 0.08, 200000, 7);
  const double exact = depositedMaterialCells(g, ball);
  EXPECT_GT(exact, 4.0 / 3.0 * 3.14159 * 8 * 8 * 8);  // more than the ball's own cells
  EXPECT_EQ(plannedMaterialCells(g, ball.data(), ball.size()), exact);
  // Two balls side by side along x: rows through both hold the gap between
  // them too, so the count is an upper bound, and within the gap's share.
  std::vector<Vec3d> two = pointsInSphere({-0.1, 0, 0}, 0.05, 50000, 8);
  const std::vector<Vec3d> other = pointsInSphere({0.1, 0, 0}, 0.05, 50000, 9);
  two.insert(two.end(), other.begin(), other.end());
  const double apart = depositedMaterialCells(g, two), planned = plannedMaterialCells(g, two.data(), two.size());
  EXPECT_GE(planned, apart);
  EXPECT_LT(planned, 2.5 * apart);
  // A lattice of one point per cell standing for the cells around it gives
  // what its material points give: a box filled at 8 points a cell.
  std::vector<Vec3d> fine, coarse;
  for (int k = 0; k < 12; ++k)
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i < 14; ++i) fine.push_back(Vec3d{-0.07 + (i + 0.5) * 0.005, -0.05 + (j + 0.5) * 0.005, -0.03 + (k + 0.5) * 0.005});
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 7; ++i) coarse.push_back(Vec3d{-0.07 + (i + 0.5) * 0.01, -0.05 + (j + 0.5) * 0.01, -0.03 + (k + 0.5) * 0.01});
  const double box = depositedMaterialCells(g, fine);
  EXPECT_EQ(plannedMaterialCells(g, fine.data(), fine.size()), box);
  EXPECT_EQ(plannedMaterialCells(g, coarse.data(), coarse.size(), 0.5 * g.dx), box);
  // Without the half-width the lattice misses the cells its points stand for.
  EXPECT_LT(plannedMaterialCells(g, coarse.data(), coarse.size()), box);
  EXPECT_EQ(plannedMaterialCells(g, nullptr, 0), 0);
  EXPECT_THROW(plannedMaterialCells(g, ball.data(), ball.size(), -1.0), InvalidArgument);
}
