// The MPM solver's magnetic stage: which points are magnetic, the planner's
// decisions, and the field solve on one grid or on separate patches; see
// mpm/solver.h.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/base/kept_capacity.h"
#include "lodestone/core/base/parallel.h"
#include "lodestone/core/base/stopwatch.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/stage/magnetic_force.h"
#include "solver_internal.h"

namespace lodestone {
inline namespace mpm {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

bool MpmSolver::isMagneticPoint(std::size_t p) const {
  const std::uint32_t mat = particles_.material[p];
  return particles_.count[p] > 0 && mat < materials_.size() && materials_[mat].isMagnetic();
}

const MagneticMaterial* MpmSolver::magneticLaw() const {
  for (const MpmMaterial& m : materials_)
    if (m.isMagnetic()) return &m.magnetic;
  return nullptr;
}

const ColliderMotion& MpmSolver::magnetMotion(std::size_t m) const {
  return magnetCollider_[m] == kNoCollider ? magnetMotion_[m] : colliders_[magnetCollider_[m]].motion();
}

void MpmSolver::poseMagnetsAt(double t) const {
  for (std::size_t m = 0; m < magnets_.size(); ++m) magnets_[m]->setPose(magnetMotion(m).poseAt(t));
}

bool MpmSolver::movedSinceSolve() const {
  if (!(settings_.magneticSolveDistance > 0)) return false;
  const double d = settings_.magneticSolveDistance * magneticGrid_.dx;
  if (!magneticPointsWithin(d)) return true;
  // Magnets: posed at the last solve (or the planner's last reuse test).
  for (std::size_t m = 0; m < magnets_.size(); ++m) {
    const Pose now = magnetMotion(m).poseAt(time_), & then = magnets_[m]->pose();
    double turn = 0;  // Frobenius norm of the rotation's change
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) turn += std::pow(now.rotation.m[r][c] - then.rotation.m[r][c], 2);
    if (norm(now.position - then.position) + std::cbrt(magnets_[m]->volume()) * std::sqrt(turn) > d) return true;
  }
  return false;
}

bool MpmSolver::lastSolveHolds() {
  // The planner's reuse (field_reuse.h): only with a force to keep and a
  // plan that allows it; the applied field is compared only when no magnetic
  // point moved too far, with the magnets where they are now.
  if (!haveMagneticForce_ || !settings_.planner.enabled || !(lastPlan_.reuseDistance > 0)) return false;
  if (!magneticPointsWithin(lastPlan_.reuseDistance)) return false;
  poseMagnetsAt(time_);
  return reuse_.fieldWithin(*scene_, time_, lastPlan_.reuseFieldChange);
}

MagneticPlan MpmSolver::planMagneticNow() const { return planMagneticAt(time_); }

MagneticPlan MpmSolver::planMagneticAt(double t) const {
  MagneticPoints points;
  magneticPoints(points);
  const std::vector<Vec3d>& positions = points.x;
  const MagneticMaterial* law = magneticLaw();
  poseMagnetsAt(t);
  PlannerInputs in = plannerInputs(positions, law ? *law : nonMagneticMaterial());
  in.time = t;
  MagneticPlan plan = planMagnetic(settings_.planner, in);
  poseMagnetsAt(time_);
  return plan;
}

PlannerInputs MpmSolver::plannerInputs(const std::vector<Vec3d>& positions, const MagneticMaterial& law) const {
  PlannerInputs in;
  in.positions = positions.data();
  in.count = positions.size();
  in.material = law;
  in.applied = scene_.get();
  in.appliedEmpty = scene_->empty();
  in.time = time_;
  in.grid = magneticGrid_;
  return in;
}

bool MpmSolver::anyMagneticParticles() const {
  bool anyMaterial = false;
  for (const MpmMaterial& m : materials_) anyMaterial = anyMaterial || m.isMagnetic();
  if (!anyMaterial) return false;
  bool any = false;
  for (std::size_t p = 0; p < particles_.size() && !any; ++p) any = particles_.count[p] > 0;
  return partition_ ? partition_->maxOverRanks(any ? 1.0 : 0.0) > 0 : any;
}

void MpmSolver::solveMagnetic(MpmStepReport& rep) {
  const auto t0 = Clock::now();
  // The magnetic points, handed to the stage as an external host would
  // (with a partition: every process's, so that each runs the same solve).
  magneticPoints(magneticPoints_);
  const MagneticPoints& points = magneticPoints_;
  const std::vector<std::uint32_t>& index = points.index;
  const std::vector<Vec3d>& positions = points.x;
  const std::vector<double>& counts = points.count;
  const MagneticMaterial* law = magneticLaw();
  std::fill(particles_.magneticForce.begin(), particles_.magneticForce.end(), Vec3d{});
  if (sameGrid_ && !(magneticForce_.spec() == settings_.grid)) magneticForce_.reset(settings_.grid, Vec3d{});
  if (sameGrid_) magneticForce_.fill(Vec3d{});
  magneticDropped_ = {};
  haveMagneticForce_ = false;
  stepsSinceSolve_ = 0;
  magnetReaction_.assign(magnets_.size(), MagnetWrench{});
  if (index.empty() || !law || scene_->empty()) return;

  poseMagnetsAt(time_);
  bool usePatches = false;
  if (settings_.planner.enabled) {
    // The planner picks the law, whether to solve at all, and the solve grid.
    PlannerInputs in = plannerInputs(positions, *law);
    in.settleEarly = true;  // the decisions of a full scan, from as few points as settle them
    lastPlan_ = planMagnetic(settings_.planner, in);
    usePatches = lastPlan_.patches.size() >= 2 && settings_.magnetic.boundary == BoundaryKind::Open;
    GridSpec solveGrid = magneticGrid_;
    if (usePatches) {
      stage_.reset();
    } else if (lastPlan_.activeRegion) {
      // Keep the current region while it holds the material's; otherwise a
      // new one with kActiveRegionSlackCells of slack (clipped to the full grid).
      const GridSpec& r = lastPlan_.region;
      if (stage_ && !(stage_->grid() == magneticGrid_) && stage_->grid().contains(r)) {
        solveGrid = stage_->grid();
      } else {
        solveGrid = widenedRegion(r, magneticGrid_, kActiveRegionSlackCells);
      }
    }
    if (!usePatches) {
      patches_.reset();
      if (!stage_ || !(stage_->grid() == solveGrid))
        stage_ = std::make_unique<MagneticForceStage>(solveGrid, *law, settings_.magnetic);
      MagneticStageSettings st = settings_.magnetic;
      st.appliedFieldOnly = lastPlan_.appliedFieldOnly;
      stage_->setSettings(st);
      stage_->setMaterial(lastPlan_.linearLaw ? linearized(*law) : *law);
    }
    sameGrid_ = !usePatches && solveGrid == settings_.grid;
    if (sameGrid_ && !(magneticForce_.spec() == settings_.grid)) magneticForce_.reset(settings_.grid, Vec3d{});
  } else {
    patches_.reset();
  }
  // What the reuse test and the automatic solve frequency compare against.
  if (partition_) {
    std::vector<std::uint32_t> all(positions.size());
    for (std::size_t q = 0; q < all.size(); ++q) all[q] = std::uint32_t(q);
    reuse_.record(positions, all, *scene_, time_);
    solvedIds_ = points.id;
  } else {
    reuse_.record(particles_.x, index, *scene_, time_);
  }
  if (usePatches) {
    solvePatches(points, lastPlan_.linearLaw ? linearized(*law) : *law, rep);
    for (std::size_t m = 0; m < magnets_.size(); ++m)
      if (magnetCollider_[m] != kNoCollider && colliders_[magnetCollider_[m]].isDynamic())
        magnetReaction_[m] = patches_->reactionOn(*magnets_[m], *scene_, magnets_[m]->pose().position, time_);
    haveMagneticForce_ = true;
    rep.secondsMagnetic = secondsSince(t0);
    return;
  }
  if (!stage_) stage_ = std::make_unique<MagneticForceStage>(magneticGrid_, *law, settings_.magnetic);
  const ParticleView view{positions.data(), counts.data(), positions.size()};
  stage_->setProgress(fieldSolveProgress_);
  rep.magnetic = stage_->run(view, *scene_, time_);
  rep.magneticSolved = true;
  if (settings_.checkFinite) checkFiniteStage(*stage_, "magnetic-stage node index", rep.magnetic.solve);
  if (sameGrid_) {
    magneticDropped_ = gatherToSupport(stage_->nodalForce(), stage_->density(), magneticForce_.view());
  } else {
    std::vector<Vec3d>& forces = magneticPointForces_;
    resizeKeepingCapacity(forces, positions.size());  // written whole by particleForces
    stage_->particleForces(view, forces.data());
    for (std::size_t q = 0; q < index.size(); ++q)
      if (index[q] != MagneticPoints::kElsewhere) particles_.magneticForce[index[q]] = forces[q];
  }
  // The material's pull on the dynamic magnets (kept, like the force, until the next solve).
  for (std::size_t m = 0; m < magnets_.size(); ++m)
    if (magnetCollider_[m] != kNoCollider && colliders_[magnetCollider_[m]].isDynamic())
      magnetReaction_[m] = stage_->reactionOn(*magnets_[m], *scene_, magnets_[m]->pose().position, time_);
  haveMagneticForce_ = true;
  rep.secondsMagnetic = secondsSince(t0);
}

void MpmSolver::checkFiniteStage(const MagneticForceStage& stage, const char* nodeKind,
                                 const FieldSolveReport& solve) const {
  const GridView<const Vec3d> H = stage.field(), f = stage.nodalForce();
  const std::size_t nn = stage.grid().nodeCount();  // the stage's own grid (an active region, a patch)
  const std::size_t bad = firstIndexWhere(nn, [&](std::size_t i) { return !isFinite(H.data[i]) || !isFinite(f.data[i]); });
  if (bad < nn)
    throw Error(concat("MPM finite check: non-finite magnetic ", isFinite(H.data[bad]) ? "nodal force (N)" : "field H (A/m)",
                       " at ", nodeKind, " ", bad, " after the field solve in substep ", substeps_ + 1, " at t = ", time_,
                       " s (solve: ", toString(solve.status), ", ", solve.message, ")"));
}

void MpmSolver::solvePatches(const MagneticPoints& points, const MagneticMaterial& law, MpmStepReport& rep) {
  // Keep the patches while each new one lies inside the kept one of its
  // rank (their warm starts stay); otherwise new ones with
  // kActiveRegionSlackCells of slack where that keeps them apart.
  const std::vector<GridSpec>& planned = lastPlan_.patches;
  bool keep = patches_ && patches_->size() == planned.size();
  for (std::size_t p = 0; keep && p < planned.size(); ++p) keep = patches_->grid(p).contains(planned[p]);
  if (!keep) {
    std::vector<GridSpec> grids;
    for (const GridSpec& g : planned) grids.push_back(widenedRegion(g, magneticGrid_, kActiveRegionSlackCells));
    bool apart = true;
    for (std::size_t a = 0; a < grids.size(); ++a)
      for (std::size_t b = a + 1; b < grids.size(); ++b) apart = apart && !grids[a].meets(grids[b]);
    if (!apart) grids = planned;  // no slack: the planned grids lie apart
    MagneticPatchSettings ps;
    ps.couplingTolerance = std::min(1e-3, std::max(1e-6, settings_.magnetic.solve.tolerance));
    patches_ = std::make_unique<MagneticPatches>(grids, law, settings_.magnetic, ps);
  }
  MagneticStageSettings st = settings_.magnetic;
  st.appliedFieldOnly = lastPlan_.appliedFieldOnly;
  patches_->setSettings(st);
  patches_->setMaterial(law);
  patches_->setProgress(fieldSolveProgress_);
  // Each point to the patch whose grid holds its stencil.
  const std::size_t n = patches_->size(), count = points.x.size();
  std::vector<std::vector<Vec3d>> x(n);
  std::vector<std::vector<double>> c(n);
  std::vector<std::vector<std::size_t>> which(n);
  for (std::size_t q = 0; q < count; ++q) {
    std::size_t home = n;
    for (std::size_t p = 0; p < n && home == n; ++p) {
      const GridSpec& g = patches_->grid(p);
      bool inside = true;
      for (int a = 0; a < 3 && inside; ++a) {
        const double u = (points.x[q][a] - g.origin[a]) / g.dx;
        inside = u >= 1 && u <= g.dims[a] - 2;
      }
      if (inside) home = p;
    }
    require(home < n, "MPM magnetic patches: magnetic point ", q, " at (", points.x[q].x, ", ", points.x[q].y, ", ",
            points.x[q].z, ") m lies in none of the ", n, " patches");
    x[home].push_back(points.x[q]);
    c[home].push_back(points.count[q]);
    which[home].push_back(q);
  }
  std::vector<ParticleView> views;
  for (std::size_t p = 0; p < n; ++p) views.push_back({x[p].data(), c[p].data(), x[p].size()});
  const MagneticPatchReport pr = patches_->run(views, *scene_, time_);
  rep.magnetic = pr.combined();
  rep.magneticSolved = true;
  for (std::size_t p = 0; p < n; ++p) {
    if (settings_.checkFinite)
      checkFiniteStage(patches_->stage(p), concat("node of magnetic patch ", p, ", index").c_str(), rep.magnetic.solve);
    std::vector<Vec3d> forces(x[p].size());
    patches_->particleForces(p, views[p], forces.data());
    for (std::size_t m = 0; m < forces.size(); ++m) {
      const std::uint32_t i = points.index[which[p][m]];
      if (i != MagneticPoints::kElsewhere) particles_.magneticForce[i] = forces[m];
    }
  }
}

}  // namespace mpm
}  // namespace lodestone
