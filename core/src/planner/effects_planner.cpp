#include "lodestone/core/planner/effects_planner.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "lodestone/core/base/error.h"
#include "lodestone/core/field/magnetization_law.h"

namespace lodestone {
inline namespace planner {

namespace {
constexpr double kShare = 0.25;            // each decision's share of the budget
constexpr double kForcePerCellMoved = 0.2; // relative force change per cell of motion
constexpr double kMaxReuseCells = 0.5;     // never reuse past half a cell of motion
constexpr int kStencilCells = 3;           // B-spline stencil and force mask around the material
constexpr double kMinRegionGain = 0.7;     // a region must have at most this fraction of the grid's nodes

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

  // Applied field at the magnetic points (the planner's only field evaluation).
  std::vector<Vec3d> H(in.count);
  for (std::size_t m = 0; m < in.count; ++m) H[m] = in.applied->field(in.positions[m], in.time);
  double hMax = 0;
  for (const Vec3d& h : H) hMax = std::max(hMax, norm(h));
  plan.peakAppliedField = hMax;
  const MagnetizationLaw<double>& law = in.material.law;
  const double n0 = in.material.numberDensity;
  const double chi0 = law.lowFieldSusceptibility(n0);
  if (!(hMax > 0)) {
    plan.magnetic = false;
    plan.decisions.push_back({"magnetic stages", false, "skipped", "the applied field is zero at the material", 0, 0});
    return plan;
  }

  // Active region (decided first: it sets the solve's size and cost).
  {
    int margin = 0;
    double err = 0;
    if (share >= 0.005) {
      margin = 4;
      err = 0.005;
    } else if (share >= 0.001) {
      margin = 8;
      err = 0.001;
    }
    Vec3d lo = in.positions[0], hi = in.positions[0];
    for (std::size_t m = 1; m < in.count; ++m)
      for (int ax = 0; ax < 3; ++ax) {
        lo[ax] = std::min(lo[ax], in.positions[m][ax]);
        hi[ax] = std::max(hi[ax], in.positions[m][ax]);
      }
    const int pad = kStencilCells + std::max(margin, 4);
    int a[3], b[3];
    for (int ax = 0; ax < 3; ++ax) {
      const double l = (lo[ax] - in.grid.origin[ax]) / in.grid.dx, h = (hi[ax] - in.grid.origin[ax]) / in.grid.dx;
      a[ax] = std::max(0, int(std::floor(l)) - pad);
      b[ax] = std::min(in.grid.dims[ax] - 1, int(std::ceil(h)) + pad);
    }
    GridSpec r;
    r.dx = in.grid.dx;
    r.origin = in.grid.nodePosition(a[0], a[1], a[2]);
    r.dims = {b[0] - a[0] + 1, b[1] - a[1] + 1, b[2] - a[2] + 1};
    const double fraction = double(r.nodeCount()) / double(in.grid.nodeCount());
    const bool fits = margin > 0 && fraction <= kMinRegionGain;
    const std::string why =
        margin == 0 ? concat("the budget share ", percent(share), " is below the 0.1% a truncated domain costs")
        : fraction > kMinRegionGain
            ? concat("the material's box plus ", margin, " cells is ", percent(fraction), " of the grid: no gain")
            : concat("material box plus ", margin, " free cells: ", r.dims.i, "x", r.dims.j, "x", r.dims.k,
                     " nodes instead of ", in.grid.dims.i, "x", in.grid.dims.j, "x", in.grid.dims.k);
    plan.activeRegion = decide(settings.activeRegion, fits) && fraction < 1;
    if (plan.activeRegion) plan.region = r;
    plan.decisions.push_back({"active region", true, plan.activeRegion ? "material box" : "full grid",
                              because(settings.activeRegion, why), plan.activeRegion ? err : 0,
                              in.secondsPerNodeSolve * double(plan.region.nodeCount())});
  }
  const double solveSeconds = in.secondsPerNodeSolve * double(plan.region.nodeCount());

  // Applied field only: no solve when the material barely changes H.
  {
    // Chord susceptibility M/H is largest at the lowest field; inside a body
    // H >= H_ext / (1 + chi0) (N <= 1), so evaluate it there.
    double chi = 0;
    for (const Vec3d& h : H) {
      const double hl = norm(h) / (1 + chi0);
      const double M = norm(magnetization(law, n0, Vec3d{hl, 0, 0}));
      chi = std::max(chi, hl > 0 ? M / hl : chi0);
    }
    const bool fits = chi <= share;
    plan.appliedFieldOnly = decide(settings.appliedFieldOnly, fits);
    const std::string why = concat("largest susceptibility ", fmt(chi), fits ? " <= " : " > ", "budget share ",
                                   percent(share), ": the demagnetizing field changes H by up to ", percent(chi));
    plan.decisions.push_back({"field solve", !plan.appliedFieldOnly,
                              plan.appliedFieldOnly ? "skipped: H = H_ext" : "Newton-PCG",
                              because(settings.appliedFieldOnly, why), plan.appliedFieldOnly ? chi : 0,
                              plan.appliedFieldOnly ? 0 : solveSeconds});
  }

  // Law: linear where k2 |H| keeps the Langevin curve straight.
  if (law.kind == LawKind::Langevin) {
    const double a = law.k2 * hMax;
    const double err = a * a / 15;
    const bool fits = err <= share;
    plan.linearLaw = decide(settings.linearLaw, fits);
    const std::string why = concat("k2 |H| <= ", fmt(a), " over the material: the linear law's error a^2/15 = ",
                                   percent(err), fits ? " <= " : " > ", "budget share ", percent(share));
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
