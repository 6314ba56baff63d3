#include "plan_report.h"

#include <cmath>

#include "lodestone/core/base/error.h"

namespace lodestone::examples {

std::vector<StageDecision> mechanicsDecisions(const plugin::Scene& scene, const MpmSolver& solver) {
  std::vector<StageDecision> d;
  const bool gravity = norm(scene.settings.gravity) > 0;
  d.push_back({"gravity", gravity, gravity ? "on" : "idle", gravity ? "the scene sets g" : "g = 0 in the scene", 0, 0});
  const std::size_t colliders = solver.colliderCount();
  d.push_back({"colliders", colliders > 0, colliders > 0 ? concat(colliders, " collider(s)") : "idle",
               colliders > 0 ? "the scene has colliders or magnets" : "no collider or magnet", 0, 0});
  bool fluid = false, solid = false;
  for (const MpmMaterial& m : solver.materials()) (m.model == MpmModel::ViscousFluid ? fluid : solid) = true;
  d.push_back({"fluid pressure and viscosity", fluid, fluid ? "on" : "idle",
               fluid ? "a fluid material is used" : "no fluid material", 0, 0});
  d.push_back({"elastic stress", solid, solid ? "on" : "idle", solid ? "a solid material is used" : "no solid material",
               0, 0});
  return d;
}

void printPlan(const plugin::Scene& scene, const MpmSolver& solver, std::FILE* out) {
  const PlannerSettings& ps = scene.settings.planner;
  std::fprintf(out, "plan (%s):\n",
               ps.enabled ? concat("effects planner on, accuracy budget ", 100 * ps.budget, "%").c_str()
                          : "effects planner off: every configured stage runs (enable with \"planner\" or "
                            "\"accuracy\" in the scene)");
  for (const StageDecision& d : mechanicsDecisions(scene, solver))
    std::fprintf(out, "  %s: %s - %s\n", d.stage.c_str(), d.on ? "on" : "off", d.reason.c_str());
  const MagneticPlan plan = solver.planMagneticNow();
  // Solves per frame with the scene's interval and substep.
  const double dt = scene.settings.fixedDt > 0 ? scene.settings.fixedDt : scene.settings.dtMax;
  const double substeps = std::ceil(scene.frameDuration() / dt - 1e-9);
  const int interval = scene.settings.magneticSolveInterval;
  const double solves = interval == 0 ? 1.0 : std::ceil(substeps / interval);
  if (!ps.enabled) {
    if (!plan.magnetic) {
      std::fprintf(out, "  magnetic stages: off - %s\n", plan.decisions.front().reason.c_str());
      return;
    }
    const GridSpec& mg = scene.settings.magneticGrid ? *scene.settings.magneticGrid : scene.settings.grid;
    const double seconds = PlannerInputs{}.secondsPerNodeSolve * double(mg.nodeCount());
    std::fprintf(out, "  magnetic stages: on (full grid, the material's law, %s) - about %.3g s per solve, %.3g s "
                      "per frame (up to %.0f solves)\n",
                 interval == 0 ? "one solve per frame" : concat("a solve every ", interval, " substeps").c_str(),
                 seconds, seconds * solves, solves);
    return;
  }
  std::fputs(plan.summary().c_str(), out);
  if (plan.magnetic) {
    double seconds = 0;
    for (const StageDecision& d : plan.decisions)
      if (d.stage == "field solve") seconds = d.estimatedSeconds;
    std::fprintf(out, "  predicted total deviation %.3g%% (budget %.3g%%); field solves: up to %.0f per frame, about "
                      "%.3g s each%s\n",
                 100 * plan.predictedError, 100 * ps.budget, solves, seconds,
                 plan.reuseDistance > 0 ? " (fewer while nothing moves)" : "");
  }
}

nlohmann::json decisionsJson(const std::vector<StageDecision>& decisions) {
  nlohmann::json a = nlohmann::json::array();
  for (const StageDecision& d : decisions)
    a.push_back({{"stage", d.stage},
                 {"on", d.on},
                 {"choice", d.choice},
                 {"reason", d.reason},
                 {"predicted_error", d.predictedError},
                 {"estimated_s", d.estimatedSeconds}});
  return a;
}

std::string planSignature(const MagneticPlan& plan) {
  std::string s;
  for (const StageDecision& d : plan.decisions) s += d.stage + "=" + d.choice + ";";
  return s;
}

}  // namespace lodestone::examples
