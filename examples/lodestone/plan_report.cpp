#include "plan_report.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/number_text.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/plugin/node_builders.h"

namespace lodestone::examples {

namespace {

// How the MPM grid holds its nodes: the runs the material reaches, packed
// (mpm/grid.h), or whole (MpmSettings::denseGrid).
StageDecision mpmGridDecision(const MpmSolver& solver) {
  const GridSpec& g = solver.settings().grid;
  const std::string domain = concat(g.dims.i, " x ", g.dims.j, " x ", g.dims.k);
  const char* measured = "docs/benchmarks.md, \"The MPM grid against particle count and domain size\"";
  if (solver.settings().denseGrid)
    return {"MPM grid", true, "dense",
            concat("dense: held whole (dense_grid), P2G zeroes and the grid update visits all ", domain,
                   " nodes every substep, the same particles bit for bit as sparse and never measured faster (",
                   measured, ")"),
            0, 0};
  return {"MPM grid", true, "sparse",
          concat("sparse: only the runs of nodes the material's stencils reach on each x-row, packed back to back, of "
                 "the domain's ",
                 domain,
                 " nodes; held whole (dense_grid) it would zero and visit every node each substep, never measured "
                 "faster (",
                 measured, ")"),
          0, 0};
}

}  // namespace

std::vector<StageDecision> mechanicsDecisions(const plugin::Scene& scene, const MpmSolver& solver) {
  std::vector<StageDecision> d;
  const bool gravity = norm(scene.settings.gravity) > 0;
  d.push_back({"gravity", gravity, gravity ? "on" : "idle", gravity ? "the scene sets g" : "g = 0 in the scene", 0, 0});
  const std::size_t colliders = solver.colliderCount();
  std::string reason = colliders > 0 ? "the scene has colliders or magnets" : "no collider or magnet";
  double thinnest = std::numeric_limits<double>::infinity(), allowance = 0;
  for (std::size_t c = 0; c < colliders; ++c)
    if (solver.collider(c).shape().halfThickness() < thinnest) {
      thinnest = solver.collider(c).shape().halfThickness();
      allowance = solver.colliderAllowance(c);
    }
  if (std::isfinite(thinnest) && scene.settings.colliderProjection)
    reason += concat("; thinnest wall half-thickness ", numberText(thinnest, 3), " m: particles deeper than ",
                     numberText(allowance, 3), " m are pushed back, and no substep moves one more than ",
                     numberText(thinnest - allowance, 3), " m relative to it (docs/physics.md, \"Colliders that hold\")");
  d.push_back({"colliders", colliders > 0, colliders > 0 ? concat(colliders, " collider(s)") : "idle", reason, 0, 0});
  bool fluid = false, solid = false;
  for (const MpmMaterial& m : solver.materials()) (m.isFluid() ? fluid : solid) = true;
  d.push_back({"fluid pressure and viscosity", fluid, fluid ? "on" : "idle",
               fluid ? "a fluid material is used" : "no fluid material", 0, 0});
  double sigma = 0;
  std::size_t wetting = 0;
  for (const MpmMaterial& m : solver.materials())
    if (m.hasSurfaceTension()) {
      sigma = std::max(sigma, m.surfaceTension);
      ++wetting;
    }
  d.push_back({"surface tension", wetting > 0, wetting > 0 ? concat(wetting, " fluid(s), up to ", numberText(sigma, 3), " N/m") : "idle",
               wetting > 0 ? "a fluid has surface_tension > 0: a colour-field pass and a surface stress in every P2G "
                             "(about 1.5x its cost), and the capillary time-step limit"
                           : "no fluid has surface_tension: no colour field, and no capillary time-step limit (a "
                             "scene with none runs bit for bit as without the feature)",
               0, 0});
  bool plastic = false;
  for (const MpmMaterial& m : solver.materials()) plastic = plastic || m.model == MpmModel::ElastoplasticSolid;
  d.push_back({"elastic stress", solid, solid ? "on" : "idle",
               !solid    ? "no solid material"
               : plastic ? "a solid material is used; the elastoplastic one adds its return mapping and damping "
                           "(about 4x the substep cost)"
                         : "a solid material is used",
               0, 0});
  std::size_t dynamic = 0, freeMagnets = 0;
  for (std::size_t c = 0; c < solver.colliderCount(); ++c) dynamic += solver.collider(c).isDynamic() ? 1 : 0;
  for (const RigidBodyReport& b : solver.rigidBodies()) freeMagnets += b.magnet >= 0 ? 1 : 0;
  d.push_back({"rigid bodies", dynamic > 0, dynamic > 0 ? concat(dynamic, " dynamic") : "idle",
               dynamic > 0 ? concat(dynamic, " dynamic collider(s), ", freeMagnets,
                                    " of them free magnets: contacts, momentum exchange with the grid nodes inside "
                                    "them", freeMagnets > 0 ? ", the material's pull on each free magnet at every field solve" : "")
                           : "no dynamic collider or magnet: every collider moves as scripted",
               0, 0});
  const double end = solver.time() + scene.frames * scene.frameDuration();
  std::size_t on = 0;
  for (std::size_t e = 0; e < solver.emitterCount(); ++e)
    on += solver.emitter(e).settings().schedule.onWithin(solver.time(), end) ? 1 : 0;
  d.push_back({"emission", on > 0, on > 0 ? concat(on, " emitter(s)") : "idle",
               on > 0                       ? concat(on, " of ", solver.emitterCount(), " emitter(s) on during the run")
               : solver.emitterCount() > 0 ? "no emitter is on during the run"
                                           : "no emitter",
               0, 0});
  d.push_back(mpmGridDecision(solver));
  return d;
}

std::string emitterTimeline(const plugin::Scene& scene, const MpmSolver& solver, std::size_t e) {
  const EmissionSchedule& schedule = solver.emitter(e).settings().schedule;
  const int offset = scene.initialFrame();  // f = 1..frames is scene frame offset + f
  std::string text;
  int first = 1;
  bool on = false;
  for (int f = 1; f <= scene.frames + 1; ++f) {
    const bool now = f <= scene.frames && schedule.onWithin(solver.time() + (f - 1) * scene.frameDuration(),
                                                            solver.time() + f * scene.frameDuration());
    if (f > 1 && (now != on || f > scene.frames)) {
      text += concat(text.empty() ? "" : ", ", on ? "on" : "idle", " in frame", first == f - 1 ? " " : "s ",
                     offset + first, first == f - 1 ? std::string() : concat("-", offset + f - 1));
      first = f;
    }
    on = now;
  }
  return text;
}

double substepsPerFrame(const plugin::Scene& scene, const MpmSolver& solver) {
  return std::max(std::ceil(scene.frameDuration() / solver.suggestedDt() - 1e-9),
                  double(scene.settings.minSubsteps));
}

namespace {
// MPM cost per particle and substep (P2G, grid update, G2P), s: measured on
// the spike scene (13,392 particles, 2.5 ms a substep on 2 cores).
constexpr double kSecondsPerParticleSubstep = 1.9e-7;
// The elastoplastic solid's substep costs about 4 times that (two 3x3
// eigen-decompositions per particle; docs/accuracy_vs_time.md).
constexpr double kElastoplasticCostFactor = 4;

// The MPM cost per particle and substep of the scene's costliest material, s.
double secondsPerParticleSubstep(const MpmSolver& solver) {
  double factor = 1;
  for (const MpmMaterial& m : solver.materials())
    if (m.model == MpmModel::ElastoplasticSolid) factor = std::max(factor, kElastoplasticCostFactor);
  return factor * kSecondsPerParticleSubstep;
}

// Smallest half-width (m) of the bounding box of the magnetic material; 0 when there is none.
double magneticHalfWidth(const MpmSolver& solver) {
  const MpmParticles& p = solver.particles();
  Vec3d lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  bool any = false;
  for (std::size_t q = 0; q < p.size(); ++q) {
    if (!solver.materials()[p.material[q]].isMagnetic()) continue;
    any = true;
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p.x[q][a]), hi[a] = std::max(hi[a], p.x[q][a]);
  }
  if (!any) return 0;
  return 0.5 * std::min({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
}
}  // namespace

std::vector<std::string> fluidCompressionWarnings(const plugin::Scene& scene, const MpmSolver& solver,
                                                  double peakField) {
  // The pressure a fluid builds: hydrostatic rho |g| h over the material's
  // height h, plus, for a magnetic fluid, mu0 W(|H|) where the applied field
  // is strongest (ferrohydrostatics: p - mu0 int_0^H M dH is constant along
  // the fluid, so the pull raises the pressure by the co-energy density).
  // A bulk modulus K compresses the fluid by about p / K.
  std::vector<std::string> out;
  const MpmParticles& p = solver.particles();
  double zlo = 1e300, zhi = -1e300;
  for (const Vec3d& x : p.x) zlo = std::min(zlo, x.z), zhi = std::max(zhi, x.z);
  const double height = p.size() > 0 ? zhi - zlo : 0.0;
  for (std::size_t k = 0; k < solver.materials().size(); ++k) {
    const MpmMaterial& m = solver.materials()[k];
    if (!m.isFluid()) continue;
    const double hydrostatic = m.density * norm(scene.settings.gravity) * height;
    const double magnetic =
        m.isMagnetic() && peakField > 0
            ? kMu0 * coEnergy(m.magnetic.law, m.magnetic.numberDensity, Vec3d{peakField, 0, 0})
            : 0.0;
    const double pressure = hydrostatic + magnetic;
    const double squeeze = pressure / m.bulkModulus;
    if (!(squeeze > kFluidCompressionLimit)) continue;
    const double advised = pressure / kFluidCompressionTarget;
    out.push_back(concat(
        "material '", k < scene.materialNames.size() ? scene.materialNames[k] : concat(k), "': bulk_modulus ",
        numberText(m.bulkModulus), " Pa against a pressure of about ", numberText(pressure, 3), " Pa (",
        magnetic > 0 ? concat("magnetic ", numberText(magnetic, 3), " Pa at |H_ext| up to ", numberText(peakField, 3),
                              " A/m, ")
                     : std::string(),
        "hydrostatic ", numberText(hydrostatic, 3), " Pa): the fluid's volume will change by up to about ",
        numberText(100 * std::min(squeeze, 1.0), 2), "% where the pull presses it, and material pressed onto "
        "colliders will pile up; use bulk_modulus >= ", numberText(advised, 2), " Pa (",
        numberText(100 * kFluidCompressionTarget, 2), "% change), which costs about ", numberText(std::sqrt(advised / m.bulkModulus), 2),
        "x the substeps where the sound speed sets the step (docs/physics.md, \"Choosing the bulk modulus\")"));
  }
  return out;
}

plugin::MemoryEstimate printMemoryEstimate(const plugin::Scene& scene, const MpmSolver& solver, double processBytes,
                                           const OutputSelection& outputs, std::FILE* out) {
  plugin::MemoryCounts c = plugin::sceneMemory(scene, &solver);
  if (!outputs.has("png")) c.previewPixels = 0;
  if (outputs.has("fields")) c.fieldFileNodes = c.fieldNodes;
  if (outputs.rendersSurface()) c.surfaceParticles = c.particles;
  const plugin::MemoryEstimate e = plugin::estimateMemory(c, processBytes);
  std::fprintf(out,
               "  estimated peak memory: %s for %.4g MPM nodes, %.4g field-solve nodes (%.4g material cells), %.0f "
               "particles%s; limit %s\n",
               e.describe().c_str(), c.mpmNodes, c.fieldNodes, c.fieldMaterialCells, c.particles,
               solver.emitterCount() > 0 ? " (at the end, with the emitted ones)" : "",
               plugin::memoryLimitText().c_str());
  // Where the grid takes four times its nodes' 64 B or more, and a tenth of
  // the estimate, the note says why: the bookkeeping of the x-rows of the
  // box around all the material, of which the material reaches few.
  const double packed = plugin::kMpmNodeBytes * c.mpmNodes;
  if (c.mpmGridBytes > 4 * packed && c.mpmGridBytes - packed > 0.1 * e.total())
    std::fprintf(out,
                 "  note: the MPM grid takes %.3g GiB for %.4g nodes (%.0f B a node, 64 B where the material's "
                 "runs fill the rows of its box): it keeps 40 B for each x-row of the box around all the material, "
                 "and the material reaches few of them (bodies far apart along y or z); its nodes alone take "
                 "%.3g GiB\n",
                 c.mpmGridBytes / (1024.0 * 1024.0 * 1024.0), c.mpmNodes, c.mpmGridBytes / c.mpmNodes,
                 packed / (1024.0 * 1024.0 * 1024.0));
  return e;
}

void printPlan(const plugin::Scene& scene, const MpmSolver& solver, std::FILE* out) {
  const PlannerSettings& ps = scene.settings.planner;
  std::fprintf(out, "plan (%s):\n",
               ps.enabled ? concat("effects planner on, accuracy budget ", 100 * ps.budget, "%").c_str()
                          : "effects planner off: every configured stage runs (enable with \"planner\" or "
                            "\"accuracy\" in the scene)");
  for (const StageDecision& d : mechanicsDecisions(scene, solver))
    std::fprintf(out, "  %s: %s - %s\n", d.stage.c_str(), d.on ? "on" : "off", d.reason.c_str());

  // The magnetic plan over the whole time line: the sources (magnets'
  // motion, time profiles) sampled at the start of up to 16 frames, the
  // material where it starts; runs of frames with the same decisions.
  const int samples = std::min(scene.frames, 16);
  struct Span {
    int first, last;
    MagneticPlan plan;
  };
  std::vector<Span> spans;
  double peakField = 0;  // A/m, over the sampled frames
  for (int k = 0; k < samples; ++k) {
    const int frame = samples == 1 ? 1 : 1 + int(std::lround(double(k) * (scene.frames - 1) / (samples - 1)));
    MagneticPlan plan = solver.planMagneticAt(solver.time() + (frame - 1) * scene.frameDuration());
    peakField = std::max(peakField, plan.peakAppliedField);
    const bool same = !spans.empty() && (ps.enabled ? planSignature(plan) == planSignature(spans.back().plan)
                                                    : plan.magnetic == spans.back().plan.magnetic);
    if (same)
      spans.back().last = frame;
    else
      spans.push_back({frame, frame, std::move(plan)});
  }
  for (std::size_t s = 0; s + 1 < spans.size(); ++s) spans[s].last = spans[s + 1].first - 1;
  spans.back().last = scene.frames;
  for (Span& span : spans) {  // scene frame numbers
    span.first += scene.initialFrame();
    span.last += scene.initialFrame();
  }

  const double substeps = substepsPerFrame(scene, solver);
  const int interval = scene.settings.magneticSolveInterval;
  const bool automatic = interval == 0 && scene.settings.magneticSolveDistance > 0;
  const double fewest = interval == 0 ? 1.0 : std::ceil(substeps / interval);
  const double most = automatic ? substeps : fewest;
  const GridSpec& mg = scene.settings.magneticGrid ? *scene.settings.magneticGrid : scene.settings.grid;
  double solveSeconds = PlannerInputs{}.secondsPerNodeSolve * double(mg.nodeCount());
  bool magnetic = false;
  // Magnetic material that only an emitter brings: the plan samples the
  // material present now, the stages run once the emitter has added some.
  bool magneticNow = false;
  for (const Span& span : spans) magneticNow = magneticNow || span.plan.magnetic;
  const bool sources = !scene.fields.empty() || solver.magnetCount() > 0;
  bool emitterMagnetic = false;
  for (std::size_t e = 0; e < solver.emitterCount() && sources && !magneticNow && !emitterMagnetic; ++e) {
    const RateEmitter& emitter = solver.emitter(e);
    if (!solver.materials()[emitter.materialIndex()].isMagnetic()) continue;
    const double born = emitter.birthTime(emitter.chunksBy(solver.time()));  // its first chunk from now on
    if (born >= solver.time() + scene.frames * scene.frameDuration()) continue;
    emitterMagnetic = magnetic = true;
    std::fprintf(out,
                 "  magnetic stages (from frame %d, when emitter '%s' first emits): on - it emits magnetic material "
                 "(each solve plans for the material then present)\n",
                 scene.startFrame + std::max(0, int(std::floor((born - solver.time()) / scene.frameDuration()))),
                 scene.emitters[e].name.c_str());
  }
  for (const Span& span : spans) {
    if (emitterMagnetic) break;  // said above
    const MagneticPlan& plan = span.plan;
    magnetic = magnetic || plan.magnetic;
    const std::string frames = spans.size() == 1 ? std::string("all frames")
                                                 : concat("frames ", span.first, "-", span.last);
    if (!ps.enabled) {
      if (!plan.magnetic)
        std::fprintf(out, "  magnetic stages (%s): off - %s\n", frames.c_str(), plan.decisions.front().reason.c_str());
      else
        std::fprintf(out, "  magnetic stages (%s): on (full grid, the material's law) - about %.3g s per solve\n",
                     frames.c_str(), solveSeconds);
      continue;
    }
    std::fprintf(out, "  %s:\n", frames.c_str());
    std::fputs(plan.summary().c_str(), out);
    if (plan.magnetic) {
      for (const StageDecision& d : plan.decisions)
        if (d.stage == "field solve") solveSeconds = d.estimatedSeconds;
      std::fprintf(out, "  predicted total deviation %.3g%% (budget %.3g%%)\n", 100 * plan.predictedError,
                   100 * ps.budget);
    }
  }
  if (spans.size() > 1)
    std::fprintf(out, "  (the decisions change over the time line: each solve plans again for its own time)\n");
  // Emitters: when each is on, and the particles it adds (before any is
  // blocked by material already there).
  const double end = solver.time() + scene.frames * scene.frameDuration();
  double emittedMean = 0;  // particles, the mean over the frames
  for (std::size_t e = 0; e < solver.emitterCount(); ++e) {
    const RateEmitter& emitter = solver.emitter(e);
    // Chunks born before the start time are never emitted.
    const double before = emitter.particlesBy(solver.time());
    for (int f = 1; f <= scene.frames; ++f)
      emittedMean += (emitter.particlesBy(solver.time() + f * scene.frameDuration()) - before) / scene.frames;
    std::fprintf(out, "  emitter '%s': %s; up to %.0f particles by t = %.4g s (%s)\n", scene.emitters[e].name.c_str(),
                 emitterTimeline(scene, solver, e).c_str(), emitter.particlesBy(end) - before, end,
                 emitter.describe().c_str());
  }

  // Run time: the MPM substeps plus the field solves.
  const double mpmSeconds =
      secondsPerParticleSubstep(solver) * (double(solver.particles().size()) + emittedMean) * substeps;
  std::fprintf(out, "  %.4g substeps per frame (%s = %.3g s)", substeps,
               scene.settings.fixedDt > 0 ? "time.dt" : "first CFL step", solver.suggestedDt());
  if (magnetic) {
    std::fprintf(out, "; field solves per frame: %s, about %.3g s each",
                 automatic ? concat(fewest, " to ", most, " (automatic: as often as material and magnets move)").c_str()
                 : interval == 0 ? "1"
                                 : concat(fewest).c_str(),
                 solveSeconds);
  }
  std::fprintf(out, "\n");
  const double low = scene.frames * (mpmSeconds + (magnetic ? fewest * solveSeconds : 0));
  const double high = scene.frames * (mpmSeconds + (magnetic ? most * solveSeconds : 0));
  if (high > low * 1.01)
    std::fprintf(out, "  estimated run time: %.3g to %.3g s for %d frames (2 cores)\n", low, high, scene.frames);
  else
    std::fprintf(out, "  estimated run time: about %.3g s for %d frames (2 cores)\n", low, scene.frames);

  // Warnings: resolution, and settings that will blow up or lag.
  const double halfWidth = magneticHalfWidth(solver);
  if (magnetic && halfWidth > 0 && halfWidth / mg.dx < 6)
    std::fprintf(out,
                 "  warning: the magnetic material is %.2g cells across its smallest half-width (dx = %.3g m); forces "
                 "need at least 6 cells per body radius to be within 1%% (4 cells: 11%% off; "
                 "docs/accuracy_vs_time.md)\n",
                 halfWidth / mg.dx, mg.dx);
  const double stable = solver.stabilityLimitDt();
  if (scene.settings.fixedDt > 0 && std::isfinite(stable) && scene.settings.fixedDt > stable)
    std::fprintf(out, "  warning: time.dt = %.3g s is above the stable step %.3g s: the run will shorten it\n",
                 scene.settings.fixedDt, stable);
  for (const std::string& w : fluidCompressionWarnings(scene, solver, magnetic ? peakField : 0.0))
    std::fprintf(out, "  warning: %s\n", w.c_str());
  if (magnetic && interval == 0 && !automatic && substeps > 20)
    std::fprintf(out,
                 "  warning: the field is solved once per frame over %.4g substeps: material that moves fast "
                 "between solves feels a stale force (set time.field_solve_distance, or time.field_solve_every)\n",
                 substeps);
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
