#include "lodestone/core/planner/effects_planner.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "lodestone/core/base/bspline.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/core/planner/material_patches.h"

namespace lodestone {
inline namespace planner {

namespace {
constexpr double kShare = 0.25;            // each decision's share of the budget
constexpr double kForcePerCellMoved = 0.2; // relative force change per cell of motion
constexpr double kMaxReuseCells = 0.5;     // never reuse past half a cell of motion
constexpr int kStencilCells = 3;           // B-spline stencil and force mask around the material
constexpr double kMinRegionGain = 0.7;     // a region must have at most this fraction of the grid's nodes
constexpr std::size_t kMaxPatches = 8;     // more groups than this: one box (the coupling costs patches^2)

std::string fmt(double v) {
  std::ostringstream os;
  os.precision(3);
  os << v;
  return os.str();
}
std::string percent(double v) { return fmt(100 * v) + "%"; }

bool decide(PlannerToggle t, bool fits) { return t == PlannerToggle::On || (t == PlannerToggle::Auto && fits); }
std::string because(PlannerToggle t, const std::string& autoReason) {
  if (t == PlannerToggle::On) return "forced on by the scene; " + autoReason;
  if (t == PlannerToggle::Off) return "forced off by the scene; " + autoReason;
  return autoReason;
}
}  // namespace

const char* toString(PlannerToggle toggle) {
  switch (toggle) {
    case PlannerToggle::Auto: return "auto";
    case PlannerToggle::Off: return "off";
    case PlannerToggle::On: return "on";
  }
  return "unknown";
}

PlannerToggle parsePlannerToggle(const std::string& name) {
  for (PlannerToggle t : {PlannerToggle::Auto, PlannerToggle::Off, PlannerToggle::On})
    if (name == toString(t)) return t;
  throw InvalidArgument(concat("planner: '", name, "' is not one of auto, off, on"));
}

void PlannerSettings::validate() const {
  require(std::isfinite(budget) && budget > 0 && budget < 1, "planner: budget must be in (0, 1), got ", budget);
}

std::string MagneticPlan::summary() const {
  std::ostringstream os;
  for (const StageDecision& d : decisions) {
    os << "  " << d.stage << ": " << (d.on ? "on" : "off") << " (" << d.choice << ") - " << d.reason;
    if (d.predictedError > 0) os << "; predicted error " << percent(d.predictedError);
    if (d.estimatedSeconds > 0) os << "; about " << fmt(d.estimatedSeconds) << " s";
    os << "\n";
  }
  return os.str();
}

double relativeFieldChange(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
  require(a.size() == b.size(), "relativeFieldChange: ", a.size(), " and ", b.size(), " samples");
  double diff = 0, scale = 0;
  for (std::size_t m = 0; m < a.size(); ++m) {
    diff = std::max(diff, norm(a[m] - b[m]));
    scale = std::max(scale, norm(b[m]));
  }
  return scale > 0 ? diff / scale : (diff > 0 ? 1.0 : 0.0);
}

int activeRegionMargin(const PlannerSettings& settings) {
  const double share = kShare * settings.budget;
  return share >= 0.005 ? 4 : (share >= 0.001 ? 8 : 0);
}

GridSpec activeRegionGrid(const GridSpec& grid, const Vec3d& lo, const Vec3d& hi, int margin) {
  const int pad = kStencilCells + std::max(margin, 4);
  int a[3], b[3];
  for (int ax = 0; ax < 3; ++ax) {
    const double l = (lo[ax] - grid.origin[ax]) / grid.dx, h = (hi[ax] - grid.origin[ax]) / grid.dx;
    a[ax] = std::max(0, int(std::floor(std::max(l, -1e9))) - pad);
    b[ax] = std::min(grid.dims[ax] - 1, int(std::ceil(std::min(h, 1e9))) + pad);
  }
  GridSpec r;
  r.dx = grid.dx;
  r.origin = grid.nodePosition(a[0], a[1], a[2]);
  r.dims = {b[0] - a[0] + 1, b[1] - a[1] + 1, b[2] - a[2] + 1};
  return r;
}

namespace {
// The solve's grids for material at x[0..count): the active region's box
// and whether the planner takes it, then the patches within it.
struct SolveGrids {
  int margin = 0, pad = 0;
  GridSpec box;           // the active region's box
  double fraction = 1;    // its share of the grid's nodes
  bool region = false;    // the active region is taken
  std::size_t groups = 0; // separate groups of material (0: not looked for)
  double patchNodes = 0;  // their grids' nodes
  double patchGain = 1;   // patchNodes over the box's nodes
  std::vector<GridSpec> patches;  // taken: two or more
};

SolveGrids chooseSolveGrids(const PlannerSettings& settings, const GridSpec& grid, const Vec3d* x, std::size_t count) {
  SolveGrids sg;
  Vec3d lo = x[0], hi = x[0];
  for (std::size_t m = 1; m < count; ++m)
    for (int ax = 0; ax < 3; ++ax) {
      lo[ax] = std::min(lo[ax], x[m][ax]);
      hi[ax] = std::max(hi[ax], x[m][ax]);
    }
  sg.margin = activeRegionMargin(settings);
  sg.pad = kStencilCells + std::max(sg.margin, 4);
  sg.box = activeRegionGrid(grid, lo, hi, sg.margin);
  sg.fraction = double(sg.box.nodeCount()) / double(grid.nodeCount());
  sg.region = decide(settings.activeRegion, sg.margin > 0 && sg.fraction <= kMinRegionGain) && sg.fraction < 1;
  if (!sg.region || settings.patches == PlannerToggle::Off) return sg;
  MaterialPatches found = findMaterialPatches(grid, x, count, sg.pad);
  for (const GridSpec& g : found.grids) sg.patchNodes += double(g.nodeCount());
  sg.groups = found.grids.size();
  sg.patchGain = sg.patchNodes / double(sg.box.nodeCount());
  if (sg.groups >= 2 && sg.groups <= kMaxPatches && decide(settings.patches, sg.patchGain <= kMinRegionGain))
    sg.patches = std::move(found.grids);
  return sg;
}
}  // namespace

GridSpec widenedRegion(const GridSpec& region, const GridSpec& grid, int cells) {
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    const int first = int(std::lround((region.origin[a] - grid.origin[a]) / grid.dx));
    lo[a] = std::max(0, first - cells);
    hi[a] = std::min(grid.dims[a] - 1, first + region.dims[a] - 1 + cells);
  }
  GridSpec w = region;
  w.origin = grid.nodePosition(lo[0], lo[1], lo[2]);
  w.dims = {hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1};
  return w;
}

double plannedSolveNodes(const PlannerSettings& settings, const GridSpec& grid, const Vec3d* x, std::size_t count) {
  if (!settings.enabled || count == 0) return double(grid.nodeCount());
  const SolveGrids sg = chooseSolveGrids(settings, grid, x, count);
  if (!sg.region) return double(grid.nodeCount());
  if (sg.patches.empty()) return double(widenedRegion(sg.box, grid, kActiveRegionSlackCells).nodeCount());
  double nodes = 0;
  for (const GridSpec& g : sg.patches) nodes += double(widenedRegion(g, grid, kActiveRegionSlackCells).nodeCount());
  return nodes;
}

double plannedMaterialCells(const GridSpec& grid, const Vec3d* x, std::size_t count, double halfWidth) {
  require(std::isfinite(halfWidth) && halfWidth >= 0, "material cells: the points' half-width must be finite and >= 0 (m), got ",
          halfWidth);
  if (count == 0 || grid.dims.i < 3 || grid.dims.j < 3 || grid.dims.k < 3) return 0;
  // Stencil bases (quadraticBaseFloor) a point's cube reaches, per axis,
  // clipped to the bases whose stencils fit the grid.
  const double r = halfWidth / grid.dx;
  const auto bases = [&](const Vec3d& p, int axis, int& b0, int& b1) {
    const double u = (p[axis] - grid.origin[axis]) / grid.dx, last = double(grid.dims[axis] - 3);
    b0 = int(std::clamp(quadraticBaseFloor(u - r), 0.0, last));
    b1 = int(std::clamp(quadraticBaseFloor(u + r), 0.0, last));
  };
  int lo[2] = {std::numeric_limits<int>::max(), std::numeric_limits<int>::max()}, hi[2] = {-1, -1};
  std::size_t finite = 0;
  for (std::size_t p = 0; p < count; ++p) {
    if (!isFinite(x[p])) continue;
    ++finite;
    for (int a = 1; a < 3; ++a) {
      int b0 = 0, b1 = 0;
      bases(x[p], a, b0, b1);
      lo[a - 1] = std::min(lo[a - 1], b0);
      hi[a - 1] = std::max(hi[a - 1], b1);
    }
  }
  if (finite == 0) return 0;
  // Each row's extent of bases [first, last] (first > last: none).
  const int nbj = hi[0] - lo[0] + 1, nbk = hi[1] - lo[1] + 1;
  std::vector<int> first(std::size_t(nbj) * std::size_t(nbk), std::numeric_limits<int>::max()), last(first.size(), -1);
  for (std::size_t p = 0; p < count; ++p) {
    if (!isFinite(x[p])) continue;
    int i0, i1, j0, j1, k0, k1;
    bases(x[p], 0, i0, i1);
    bases(x[p], 1, j0, j1);
    bases(x[p], 2, k0, k1);
    for (int k = k0; k <= k1; ++k)
      for (int j = j0; j <= j1; ++j) {
        const std::size_t row = std::size_t(j - lo[0]) + std::size_t(nbj) * std::size_t(k - lo[1]);
        first[row] = std::min(first[row], i0);
        last[row] = std::max(last[row], i1);
      }
  }
  // Base b makes cells b - 1 .. b + 2 material on each axis (the cells with
  // a corner among its nodes b .. b + 2): cell row (j, k) takes the extents
  // of base rows j - 2 .. j + 1 and k - 2 .. k + 1, widened by 1 below and 2
  // above, within the grid's cells.
  double cells = 0;
  for (int k = std::max(0, lo[1] - 1); k <= std::min(grid.dims.k - 2, hi[1] + 2); ++k)
    for (int j = std::max(0, lo[0] - 1); j <= std::min(grid.dims.j - 2, hi[0] + 2); ++j) {
      int f = std::numeric_limits<int>::max(), l = -1;
      for (int bk = std::max(lo[1], k - 2); bk <= std::min(hi[1], k + 1); ++bk)
        for (int bj = std::max(lo[0], j - 2); bj <= std::min(hi[0], j + 1); ++bj) {
          const std::size_t row = std::size_t(bj - lo[0]) + std::size_t(nbj) * std::size_t(bk - lo[1]);
          f = std::min(f, first[row]);
          l = std::max(l, last[row]);
        }
      if (l < f) continue;
      cells += double(std::min(grid.dims.i - 2, l + 2) - std::max(0, f - 1) + 1);
    }
  return cells;
}

MagneticPlan planMagnetic(const PlannerSettings& settings, const PlannerInputs& in) {
  settings.validate();
  MagneticPlan plan;
  plan.region = in.grid;
  const double share = kShare * settings.budget;
  const bool magneticMaterial = in.material.law.kind != LawKind::None && in.count > 0;
  const bool field = in.applied && !in.appliedEmpty;
  if (!magneticMaterial || !field) {
    plan.decisions.push_back({"magnetic stages", false, "skipped",
                              !magneticMaterial ? "no magnetic material in the scene" : "no magnet or applied field",
                              0, 0});
    return plan;
  }
  plan.magnetic = true;

  const MagnetizationLaw<double>& law = in.material.law;
  const double n0 = in.material.numberDensity;
  const double chi0 = law.lowFieldSusceptibility(n0);
  // The two decisions that depend on the applied field, as functions of its
  // extremes over the points. Chord susceptibility M/H is largest at the
  // lowest field (the laws' M(H) are concave from 0); inside a body
  // H >= H_ext / (1 + chi0) (N <= 1), so it is evaluated there, at the
  // weakest applied field. The linear law errs by a^2/15 at a = k2 |H|.
  const auto chordSusceptibility = [&](double hMin) {
    const double hl = hMin / (1 + chi0);
    return hl > 0 ? norm(magnetization(law, n0, Vec3d{hl, 0, 0})) / hl : chi0;
  };
  const auto linearLawError = [&](double hMax) {
    const double a = law.k2 * hMax;
    return a * a / 15;
  };
  // Settled whatever the other points hold (PlannerInputs::settleEarly):
  // off, or ruled out. A decision forced on still needs every point: its
  // predicted error is that of the extreme field.
  const auto settled = [&](double hMin, double hMax) {
    const auto ruledOut = [](PlannerToggle t, bool fitsNot) {
      return t == PlannerToggle::Off || (t == PlannerToggle::Auto && fitsNot);
    };
    const bool noSolve = law.kind != LawKind::Langevin ||
                         ruledOut(settings.appliedFieldOnly, chordSusceptibility(hMin) > share);
    const bool linear = law.kind != LawKind::Langevin || ruledOut(settings.linearLaw, linearLawError(hMax) > share);
    return hMax > 0 && noSolve && linear;
  };

  // Applied field at the magnetic points (the planner's only field
  // evaluation), block by block in the points' order.
  struct Extremes {
    double lo = std::numeric_limits<double>::infinity(), hi = 0;
  };
  double hMax = 0, hMin = std::numeric_limits<double>::infinity();
  const std::size_t block = in.settleEarly ? kPlannerFieldBlock : in.count;
  for (std::size_t b = 0; b < in.count;) {
    const std::size_t e = std::min(in.count, b + block);
    const Extremes x = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(b, e, 1024), Extremes{},
        [&](const tbb::blocked_range<std::size_t>& r, Extremes acc) {
          for (std::size_t m = r.begin(); m != r.end(); ++m) {
            const double n = norm(in.applied->field(in.positions[m], in.time));
            acc.hi = std::max(acc.hi, n);
            acc.lo = std::min(acc.lo, n);
          }
          return acc;
        },
        [](Extremes a, const Extremes& c) {
          a.hi = std::max(a.hi, c.hi);
          a.lo = std::min(a.lo, c.lo);
          return a;
        });
    hMax = std::max(hMax, x.hi);
    hMin = std::min(hMin, x.lo);
    plan.fieldPointsEvaluated = b = e;
    if (in.settleEarly && settled(hMin, hMax)) break;
  }
  plan.peakAppliedField = hMax;
  const std::string scanned =
      plan.fieldPointsEvaluated < in.count
          ? concat(" (the applied field at ", plan.fieldPointsEvaluated, " of ", in.count, " magnetic points settles it)")
          : std::string();
  if (!(hMax > 0)) {
    plan.magnetic = false;
    plan.decisions.push_back({"magnetic stages", false, "skipped", "the applied field is zero at the material", 0, 0});
    return plan;
  }

  // Active region (decided first: it sets the solve's size and cost), and
  // patches within it.
  {
    SolveGrids sg = chooseSolveGrids(settings, in.grid, in.positions, in.count);
    const GridSpec& r = sg.box;
    const int margin = sg.margin;
    const double err = margin == 4 ? 0.005 : (margin == 8 ? 0.001 : 0.0);
    const std::string why =
        margin == 0 ? concat("the budget share ", percent(share), " is below the 0.1% a truncated domain costs")
        : sg.fraction > kMinRegionGain
            ? concat("the material's box plus ", margin, " cells is ", percent(sg.fraction), " of the grid: no gain")
            : concat("material box plus ", margin, " free cells: ", r.dims.i, "x", r.dims.j, "x", r.dims.k,
                     " nodes instead of ", in.grid.dims.i, "x", in.grid.dims.j, "x", in.grid.dims.k);
    plan.activeRegion = sg.region;
    if (plan.activeRegion) plan.region = r;
    plan.decisions.push_back({"active region", true, plan.activeRegion ? "material box" : "full grid",
                              because(settings.activeRegion, why), plan.activeRegion ? err : 0,
                              in.secondsPerNodeSolve * double(plan.region.nodeCount())});
    if (sg.groups > 0) {
      const std::size_t groups = sg.groups;
      const std::string patchWhy =
          groups < 2 ? std::string("the material is one group")
          : groups > kMaxPatches
              ? concat(groups, " groups of material, more than the ", kMaxPatches, " patches coupled pairwise")
          : sg.patchGain > kMinRegionGain
              ? concat(groups, " groups of material whose grids hold ", percent(sg.patchGain), " of the box's nodes: no gain")
              : concat(groups, " groups of material more than ", 2 * sg.pad, " cells apart: ",
                       std::size_t(sg.patchNodes), " nodes instead of the box's ", r.nodeCount());
      const bool on = !sg.patches.empty();
      plan.patches = std::move(sg.patches);
      plan.decisions.push_back({"patches", true, on ? concat(groups, " patches") : "one grid",
                                because(settings.patches, patchWhy), 0,
                                on ? in.secondsPerNodeSolve * sg.patchNodes : 0});
    }
  }
  double solveNodes = double(plan.region.nodeCount());
  if (!plan.patches.empty()) {
    solveNodes = 0;
    for (const GridSpec& g : plan.patches) solveNodes += double(g.nodeCount());
  }
  const double solveSeconds = in.secondsPerNodeSolve * solveNodes;

  // Applied field only: no solve when the material barely changes H.
  {
    const double chi = chordSusceptibility(hMin);
    const bool fits = chi <= share;
    plan.appliedFieldOnly = decide(settings.appliedFieldOnly, fits);
    const std::string why = concat(scanned.empty() ? "largest susceptibility " : "susceptibility reaches ", fmt(chi),
                                   fits ? " <= " : " > ", "budget share ",
                                   percent(share), ": the demagnetizing field changes H by up to ", percent(chi),
                                   scanned);
    plan.decisions.push_back({"field solve", !plan.appliedFieldOnly,
                              plan.appliedFieldOnly ? "skipped: H = H_ext" : "Newton-PCG",
                              because(settings.appliedFieldOnly, why), plan.appliedFieldOnly ? chi : 0,
                              plan.appliedFieldOnly ? 0 : solveSeconds});
  }

  // Law: linear where k2 |H| keeps the Langevin curve straight.
  if (law.kind == LawKind::Langevin) {
    const double a = law.k2 * hMax;
    const double err = linearLawError(hMax);
    const bool fits = err <= share;
    plan.linearLaw = decide(settings.linearLaw, fits);
    const std::string why = concat("k2 |H| ", scanned.empty() ? "<= " : "reaches ", fmt(a),
                                   " over the material: the linear law's error a^2/15 = ",
                                   percent(err), fits ? " <= " : " > ", "budget share ", percent(share), scanned);
    plan.decisions.push_back({"magnetization law", true, plan.linearLaw ? "linear (one linear solve)" : "langevin",
                              because(settings.linearLaw, why), plan.linearLaw ? err : 0, 0});
  } else {
    plan.decisions.push_back({"magnetization law", true, law.kind == LawKind::Linear ? "linear" : "none",
                              "the material's own law", 0, 0});
  }

  // Reuse between solves.
  {
    const double cells = std::min(kMaxReuseCells, share / kForcePerCellMoved);
    const bool on = settings.fieldReuse != PlannerToggle::Off;
    plan.reuseDistance = on ? cells * in.grid.dx : 0;
    plan.reuseFieldChange = on ? share : 0;
    plan.decisions.push_back(
        {"field reuse", on, on ? "re-solve on motion" : "re-solve when due",
         on ? concat("reuse the last solve until the material moves ", fmt(cells), " cells or the applied field changes ",
                     percent(share))
            : std::string("forced off by the scene"),
         on ? share : 0, 0});
  }
  for (const StageDecision& d : plan.decisions) plan.predictedError += d.predictedError;
  return plan;
}

}  // namespace planner
}  // namespace lodestone
