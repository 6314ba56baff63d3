#pragma once
// The effects planner: which magnetic stages a substep's field solve needs,
// and at what fidelity, within a relative accuracy budget b (the scene's
// `accuracy`). Each decision is predicted from the current state, taken only
// when its predicted error fits its share of the budget (b/4 each: law,
// applied-field-only, reuse, active region), and recorded with its reason,
// so that `lodestone plan` and `lodestone run` can say what was skipped and
// what it costs. docs/planner.md gives the derivations; the tests
// (tests/core/test_effects_planner.cpp) measure every decision against the
// full-physics run.
//
// Predicted errors (relative, of the field inside the material):
//  - linear law: the Langevin function L(a)/a = 1/3 - a^2/45 + ..., so the
//    linear law (slope 1/3) overestimates M by a^2/15 at a = k2 |H|;
//    a_max uses the largest applied |H_ext| over the magnetic points (the
//    demagnetizing field only lowers |H| inside a body).
//  - applied field only (no solve, H = H_ext): the demagnetizing field of a
//    body of susceptibility chi changes H by N chi / (1 + N chi) <= chi
//    (N <= 1), with chi the largest chord susceptibility M/H over the points.
//  - reuse: between solves the force on a point is that of where it was;
//    the force density changes by about 0.2 per cell of motion (measured in
//    the tests: 0.38 dx of motion gave 8% on a cube pulled by a magnet), so
//    a solve is reused while every magnetic point moved less than
//    (b/4) / 0.2 cells and the applied field at the points changed by less
//    than b/4 (relative).
//  - active region: the open (far-field) boundary makes the truncation of the
//    domain cheap: a margin of 4 free cells around the material costs
//    < 0.5% of the force, 8 cells < 0.1% (measured in the tests).
#include <cstddef>
#include <string>
#include <vector>

#include "lodestone/core/sources/field_source.h"
#include "lodestone/core/base/grid.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace planner {

enum class PlannerToggle : int {
  Auto = 0,  ///< the planner decides from the budget
  Off = 1,   ///< never (full physics for this decision)
  On = 2     ///< always, whatever the predicted error
};
const char* toString(PlannerToggle toggle);
/// "auto", "off" or "on"; throws InvalidArgument naming the bad value.
PlannerToggle parsePlannerToggle(const std::string& name);

struct PlannerSettings {
  bool enabled = false;  ///< off: every stage as configured (full physics)
  double budget = 0.01;  ///< relative deviation from full physics the planner may spend, (0, 1)
  PlannerToggle linearLaw = PlannerToggle::Auto;
  PlannerToggle appliedFieldOnly = PlannerToggle::Auto;
  PlannerToggle fieldReuse = PlannerToggle::Auto;
  PlannerToggle activeRegion = PlannerToggle::Auto;
  /// Separate groups of material solved on grids of their own, coupled
  /// through their far fields (stage/magnetic_patches.h), when their grids
  /// hold fewer nodes than the active region's one box. Needs the active region.
  PlannerToggle patches = PlannerToggle::Auto;

  /// Throws InvalidArgument naming the first bad value.
  void validate() const;
};

/// One stage's decision.
struct StageDecision {
  std::string stage;           ///< e.g. "field solve", "magnetization law"
  bool on = true;              ///< the stage (or the full-physics variant) runs
  std::string choice;          ///< what runs, e.g. "langevin", "linear", "skipped"
  std::string reason;          ///< why, with the numbers
  double predictedError = 0;   ///< relative deviation from full physics this decision costs
  double estimatedSeconds = 0; ///< predicted cost of the stage as decided, s (0: not estimated)
};

/// The planner's magnetic decisions for one field solve.
struct MagneticPlan {
  bool magnetic = false;         ///< any magnetic stage runs
  bool linearLaw = false;        ///< solve with the linearized law
  bool appliedFieldOnly = false; ///< skip the solve: H = H_ext
  bool activeRegion = false;     ///< solve on `region` instead of the full magnetic grid
  GridSpec region;               ///< the solve grid (the full grid when !activeRegion)
  /// Two or more: solve on these grids instead, one a group of material
  /// (planner/material_patches.h), coupled through their far fields; each
  /// lies inside `region`. Empty: one grid.
  std::vector<GridSpec> patches;
  double reuseDistance = 0;      ///< m: reuse the solve while points moved less (0: re-solve when due)
  double reuseFieldChange = 0;   ///< relative change of H_ext at the points that forces a re-solve
  double predictedError = 0;     ///< sum of the decisions' predicted errors
  /// Largest |H_ext| at the magnetic points evaluated, A/m (0 when no
  /// stage runs): all of them unless PlannerInputs::settleEarly stopped the
  /// scan (fieldPointsEvaluated < the point count).
  double peakAppliedField = 0;
  std::size_t fieldPointsEvaluated = 0;  ///< magnetic points at which the applied field was evaluated
  std::vector<StageDecision> decisions;

  /// One line per decision: stage, on/off, choice, reason, predicted error.
  std::string summary() const;
};

/// The state the planner decides from.
struct PlannerInputs {
  const Vec3d* positions = nullptr;  ///< magnetic points, m
  std::size_t count = 0;
  MagneticMaterial material;         ///< law and bulk n0 of the magnetic material
  const FieldSource* applied = nullptr;  ///< applied field (null or empty: none)
  bool appliedEmpty = true;
  double time = 0;                   ///< s
  GridSpec grid;                     ///< the full magnetic grid
  double secondsPerNodeSolve = 3e-7; ///< field-solve cost per grid node, s (docs/benchmarks.md: 2 cores, 1e-6, cold and warm)
  /// The applied field is evaluated at the points in blocks of
  /// kPlannerFieldBlock, in their order. false: at every point (the
  /// extremes and every reason's figures are over all of them). true: the
  /// scan stops after the first block at which both field-dependent
  /// decisions (no solve, linear law) are settled against: once a point's
  /// field makes the linear law too coarse, more points can only raise
  /// |H| max, and once a point's field makes the material's susceptibility
  /// too large to skip the solve, more points can only lower |H| min. The
  /// decisions, the plan's grids and its predicted error are those of the
  /// full scan; only peakAppliedField and the figures in the two reasons
  /// cover fewer points (the reasons say how many). The MPM solver's
  /// per-solve plans settle early; its planMagneticAt scans every point.
  bool settleEarly = false;
};

/// Points per block of the planner's applied-field scan (PlannerInputs::settleEarly).
inline constexpr std::size_t kPlannerFieldBlock = 16384;

/// The active region's margin of free cells around the material that the
/// budget allows: 4 cells (< 0.5% of the force) from a decision share of
/// 0.5%, 8 cells (< 0.1%) from 0.1%, 0 below (no active region).
int activeRegionMargin(const PlannerSettings& settings);
/// The active region's grid: the nodes of `grid` over the material's box
/// [lo, hi] (m) plus the stencil's 3 cells and max(margin, 4) free cells,
/// clipped to `grid`.
GridSpec activeRegionGrid(const GridSpec& grid, const Vec3d& lo, const Vec3d& hi, int margin);
/// Cells of slack the MPM solver adds around an active region or patch it
/// builds, so that it keeps it while the material moves less than that.
inline constexpr int kActiveRegionSlackCells = 4;
/// `region` (nodes on `grid`'s lattice) widened by `cells` on every side,
/// clipped to `grid`.
GridSpec widenedRegion(const GridSpec& region, const GridSpec& grid, int cells);

/// The nodes a field solve of material at x[0..count) (m) takes under
/// `settings` on `grid`: the patches' or the active region's when the
/// planner would choose them, with the solver's slack
/// (kActiveRegionSlackCells), else the grid's. What the memory estimate
/// counts before a run (from points sampled over the bodies).
double plannedSolveNodes(const PlannerSettings& settings, const GridSpec& grid, const Vec3d* x, std::size_t count);

/// The field-solve cells that material at x[0..count) (m) turns into
/// material cells on `grid` (cells with a corner where the quadratic
/// B-spline deposit of the points puts n > 0: 4 cells an axis around each
/// stencil base), counted over each x-row from its first to its last such
/// cell. Each point stands for the cube of half-width `halfWidth` (m) around
/// it: 0 for material points, half the spacing for a lattice that samples a
/// body (the points of every part of the cube count). What the memory
/// estimate counts per material cell.
double plannedMaterialCells(const GridSpec& grid, const Vec3d* x, std::size_t count, double halfWidth = 0);

/// Decides the magnetic stages for the state `in` (see the header comment).
MagneticPlan planMagnetic(const PlannerSettings& settings, const PlannerInputs& in);

/// Largest relative change of the applied field between two samplings at
/// the same points (|a - b| / max |b|); 0 when both are zero.
double relativeFieldChange(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b);

}  // namespace planner
}  // namespace lodestone
