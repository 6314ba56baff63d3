// The reference MLS-MPM step (Section 4.3 of the paper); see mpm/solver.h.
#include "lodestone/core/mpm/solver.h"

#include "solver_internal.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "lodestone/core/base/stopwatch.h"
#include "lodestone/core/sources/cuboid_magnet.h"
#include "lodestone/core/sources/cylinder_magnet.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/stage/magnetic_force.h"
#include "lodestone/core/mpm/constitutive.h"
#include "lodestone/core/mpm/particle_order.h"
#include "lodestone/core/base/parallel.h"
#include "lodestone/core/sources/sphere_magnet.h"

namespace lodestone {
inline namespace mpm {

namespace {
using Clock = std::chrono::steady_clock;


bool finiteMat(const Mat3d& m) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(m(r, c))) return false;
  return true;
}

struct DomainCounts {
  std::size_t clamped = 0, remove = 0, nonFinite = 0;
  void join(const DomainCounts& o) {
    clamped += o.clamped;
    remove += o.remove;
    nonFinite += o.nonFinite;
  }
};
}  // namespace


// ---------------------------------------------------------------------------
// Settings and reports

void MpmSettings::validate() const {
  grid.validate("MPM grid");
  const int minDim = std::min(grid.dims.i, std::min(grid.dims.j, grid.dims.k));
  require(minDim >= 4, "MPM grid: at least 4 nodes per axis are needed, got ", grid.dims.i, " x ", grid.dims.j, " x ",
          grid.dims.k);
  require(isFinite(gravity), "MPM settings: gravity must be finite (m/s^2), got (", gravity.x, ", ", gravity.y, ", ",
          gravity.z, ")");
  walls.validate("MPM walls");
  require(wallNodes >= 0 && 2 * wallNodes + 2 <= minDim, "MPM settings: wallNodes must be in 0..", (minDim - 2) / 2,
          " for a grid of ", minDim, " nodes on its shortest axis, got ", wallNodes);
  require(outOfDomain == OutOfDomainPolicy::Clamp || outOfDomain == OutOfDomainPolicy::Remove,
          "MPM settings: unknown out-of-domain policy ", int(outOfDomain));
  require(std::isfinite(fixedDt) && fixedDt >= 0,
          "MPM settings: fixedDt must be finite and >= 0 (s; 0 = adaptive), got ", fixedDt);
  require(std::isfinite(cfl) && cfl > 0 && cfl <= 1, "MPM settings: cfl must be in (0, 1], got ", cfl);
  require(std::isfinite(dtMax) && dtMax > 0, "MPM settings: dtMax must be a positive finite time in s, got ", dtMax);
  require(std::isfinite(dtMin) && dtMin > 0 && dtMin <= dtMax,
          "MPM settings: dtMin must be a positive finite time in s, at most dtMax = ", dtMax, " s, got ", dtMin);
  require(minSubsteps >= 1, "MPM settings: minSubsteps must be >= 1 substep per frame, got ", minSubsteps);
  require(maxSubsteps == 0 || maxSubsteps >= minSubsteps,
          "MPM settings: maxSubsteps must be 0 (no limit) or >= minSubsteps = ", minSubsteps,
          " substeps per frame, got ", maxSubsteps);
  require(reorderInterval >= 0, "MPM settings: reorderInterval must be >= 0 substeps, got ", reorderInterval);
  require(magneticSolveInterval >= 0,
          "MPM settings: magneticSolveInterval must be >= 0 substeps (0 = automatic), got ", magneticSolveInterval);
  require(std::isfinite(magneticSolveDistance) && magneticSolveDistance >= 0,
          "MPM settings: magneticSolveDistance must be finite and >= 0 cells (0 = once per frame), got ",
          magneticSolveDistance);
  if (magneticGrid) magneticGrid->validate("magnetic stage grid");
  magnetic.validate();
  planner.validate();
}

std::string MpmFrameReport::summary() const {
  std::ostringstream os;
  os.precision(4);
  os << "frame to t = " << time << " s: " << substeps << " substeps, dt " << minDt << " .. " << maxDt << " s";
  if (dtAtMinimum) os << " (" << dtAtMinimum << " at dtMin)";
  os << (cancelled ? ", cancelled" : "") << "\n";
  os << "time: P2G " << secondsP2G << " s, magnetic " << secondsMagnetic << " s, grid " << secondsGridUpdate
     << " s, G2P " << secondsG2P << " s, total " << secondsTotal << " s\n";
  os << "field solves: " << magneticReports.size() << "\n";
  os << "particles clamped " << clamped << ", removed " << removed << " (non-finite " << nonFinite
     << "), pushed out of colliders " << projected << "\n";
  if (dtLimitedByColliders)
    os << dtLimitedByColliders << " substep(s) shortened so that no particle crosses a collider's half-thickness\n";
  if (emitted.chunks > 0)
    os << "emitted " << emitted.particles << " particles (" << emitted.volume << " m^3) in " << emitted.chunks
       << " chunks; " << emitted.blocked << " points blocked by material, " << emitted.outside << " outside\n";
  os << "energy: kinetic " << energies.kinetic << " J, gravitational " << energies.gravitational << " J, elastic "
     << energies.elastic << " J, total " << energies.total() << " J\n";
  for (const auto& w : warnings) os << "warning: " << w << "\n";
  return os.str();
}

// ---------------------------------------------------------------------------
// Set-up

MpmSolver::MpmSolver(const MpmSettings& settings) : settings_(settings) {
  settings_.validate();
  magneticGrid_ = settings_.magneticGrid ? *settings_.magneticGrid : settings_.grid;
  sameGrid_ = magneticGrid_ == settings_.grid;
  grid_ = MpmGrid(settings_.grid);
  grid_.setWholeLayout(settings_.denseGrid);
  scene_ = std::make_unique<SceneField>(sources_, magnets_);
  // magneticForce_ is allocated by the first field solve on the MPM grid.
}

MpmSolver::~MpmSolver() = default;

std::uint32_t MpmSolver::addMaterial(const MpmMaterial& material) {
  material.validate();
  if (material.isMagnetic()) {
    for (const MpmMaterial& m : materials_)
      if (m.isMagnetic())
        require(m.magnetic.law == material.magnetic.law,
                "MPM solver: every magnetic material must share one magnetization law (one field solve serves them "
                "all); existing ",
                m.magnetic.describe(), ", new ", material.magnetic.describe());
  }
  require(materials_.size() < 0xFFFFFFFFu, "MPM solver: too many materials");
  materials_.push_back(material);
  return std::uint32_t(materials_.size() - 1);
}

EmitReport MpmSolver::emit(const EmitterShape& shape, std::uint32_t material, EmitterSettings settings) {
  particlesDirty_ = true;
  emittedSinceSort_ = true;
  require(material < materials_.size(), "MPM solver: material index ", material, " out of range (", materials_.size(),
          " materials)");
  if (settings.cellSize == 0) settings.cellSize = settings_.grid.dx;
  if (!partition_) return emitParticles(particles_, shape, materials_[material], material, settings);
  // Every process emits the same shape and keeps its own points.
  const int me = partition_->rank();
  const MpmPartition& split = *partition_;
  return emitParticles(particles_, shape, materials_[material], material, settings,
                       [&](const Vec3d& x) { return split.owner(x) == me; });
}

std::size_t MpmSolver::addEmitter(const EmitterShape& shape, std::uint32_t material, RateEmitterSettings settings) {
  require(material < materials_.size(), "MPM solver: material index ", material, " out of range (", materials_.size(),
          " materials)");
  if (settings.lattice.cellSize == 0) settings.lattice.cellSize = settings_.grid.dx;
  emitters_.emplace_back(shape, settings, materials_[material], material);
  return emitters_.size() - 1;
}

const RateEmitter& MpmSolver::emitter(std::size_t i) const {
  require(i < emitters_.size(), "MPM solver: emitter ", i, " out of range (", emitters_.size(), " emitters)");
  return emitters_[i];
}

void MpmSolver::emitFromEmitters(double dt, MpmStepReport& rep) {
  if (emitters_.empty()) return;
  const ParticleBounds bounds = domainBounds();
  const std::size_t before = particles_.size();
  // Every process emits the same chunks (the emitters are deterministic) and
  // keeps those it owns.
  for (const RateEmitter& e : emitters_) rep.emitted += e.emitBetween(particles_, time_, time_ + dt, bounds);
  keepOwnedParticles(before);
}

double MpmSolver::maxEmissionSpeed() const {
  double speed = 0;
  for (const RateEmitter& e : emitters_) speed = std::max(speed, e.emissionSpeed(time_, time_ + settings_.dtMax));
  return speed;
}

std::size_t MpmSolver::addCollider(const MpmCollider& collider) {
  colliders_.push_back(collider);
  return colliders_.size() - 1;
}

MpmCollider& MpmSolver::collider(std::size_t i) {
  require(i < colliders_.size(), "MPM solver: collider ", i, " out of range (", colliders_.size(), " colliders)");
  return colliders_[i];
}

const MpmCollider& MpmSolver::collider(std::size_t i) const {
  require(i < colliders_.size(), "MPM solver: collider ", i, " out of range (", colliders_.size(), " colliders)");
  return colliders_[i];
}

namespace {
std::unique_ptr<MagnetSource> ownedCopy(const MagnetSource& magnet) {
  std::unique_ptr<FieldSource> copy = magnet.clone();
  std::unique_ptr<MagnetSource> owned(dynamic_cast<MagnetSource*>(copy.get()));
  require(owned != nullptr, "MPM solver: the magnet's clone is not a magnet");
  copy.release();
  return owned;
}
}  // namespace

std::size_t MpmSolver::addMagnet(const MagnetSource& magnet, const ColliderMotion& motion,
                                 const BoundaryCondition& boundary) {
  ColliderShape shape;
  if (const auto* s = dynamic_cast<const SphereMagnet*>(&magnet)) {
    shape = ColliderShape::sphere(s->radius());
  } else if (const auto* c = dynamic_cast<const CylinderMagnet*>(&magnet)) {
    shape = ColliderShape::cylinder(c->radius(), c->halfLength());
  } else if (const auto* b = dynamic_cast<const CuboidMagnet*>(&magnet)) {
    shape = ColliderShape::box(b->halfSize());
  } else {
    throw InvalidArgument(
        concat("MPM solver: addMagnet supports sphere, cylinder and cuboid magnets, got ", magnet.describe()));
  }
  std::unique_ptr<MagnetSource> owned = ownedCopy(magnet);
  owned->setPose(motion.poseAt(time_));
  colliders_.emplace_back(shape, motion, boundary);
  magnets_.push_back(std::move(owned));
  magnetCollider_.push_back(colliders_.size() - 1);
  magnetMotion_.emplace_back();
  return colliders_.size() - 1;
}

std::size_t MpmSolver::addNonCollidingMagnet(const MagnetSource& magnet, const ColliderMotion& motion) {
  std::unique_ptr<MagnetSource> owned = ownedCopy(magnet);
  owned->setPose(motion.poseAt(time_));
  magnets_.push_back(std::move(owned));
  magnetCollider_.push_back(kNoCollider);
  magnetMotion_.push_back(motion);
  return magnets_.size() - 1;
}

std::size_t MpmSolver::addMagnet(const MagnetSource& magnet, const BoundaryCondition& boundary) {
  return addMagnet(magnet, ColliderMotion::fixed(magnet.pose()), boundary);
}

const MagnetSource& MpmSolver::magnet(std::size_t i) const {
  require(i < magnets_.size(), "MPM solver: magnet ", i, " out of range (", magnets_.size(), " magnets)");
  return *magnets_[i];
}

const FieldSource& MpmSolver::appliedField() const { return *scene_; }

void MpmSolver::setTime(double t) {
  require(std::isfinite(t), "MPM solver: time must be finite (s), got ", t);
  time_ = t;
}

// ---------------------------------------------------------------------------
// Domain

ParticleBounds MpmSolver::domainBounds() const {
  const GridSpec& g = settings_.grid;
  ParticleBounds b;
  b.lo = g.origin + g.dx * Vec3d{1, 1, 1};
  b.hi = g.nodePosition(g.dims.i - 2, g.dims.j - 2, g.dims.k - 2);
  b.clamp = settings_.outOfDomain == OutOfDomainPolicy::Clamp;
  return b;
}

std::size_t MpmSolver::enforceDomain(std::size_t& removedOut, std::size_t& nonFiniteOut) {
  const ParticleBounds bounds = domainBounds();
  const Vec3d lo = bounds.lo, hi = bounds.hi;
  const bool removeOutside = settings_.outOfDomain == OutOfDomainPolicy::Remove;
  const std::size_t np = particles_.size();
  std::vector<std::uint8_t> flags(np, 0);
  Vec3d* X = particles_.x.data();
  Vec3d* V = particles_.v.data();
  const double* J = particles_.J.data();
  const DomainCounts counts = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, np, 4096), DomainCounts{},
      [&](const tbb::blocked_range<std::size_t>& r, DomainCounts acc) {
        for (std::size_t p = r.begin(); p != r.end(); ++p) {
          if (!isFinite(X[p]) || !isFinite(V[p]) || !std::isfinite(J[p])) {
            flags[p] = 1;
            ++acc.remove;
            ++acc.nonFinite;
            continue;
          }
          bool outside = false;
          for (int a = 0; a < 3; ++a) outside = outside || X[p][a] < lo[a] || X[p][a] > hi[a];
          if (!outside) continue;
          if (removeOutside) {
            flags[p] = 1;
            ++acc.remove;
            continue;
          }
          for (int a = 0; a < 3; ++a) {
            if (X[p][a] < lo[a]) {
              X[p][a] = lo[a];
              if (V[p][a] < 0) V[p][a] = 0;
            } else if (X[p][a] > hi[a]) {
              X[p][a] = hi[a];
              if (V[p][a] > 0) V[p][a] = 0;
            }
          }
          ++acc.clamped;
        }
        return acc;
      },
      [](DomainCounts a, const DomainCounts& b) {
        a.join(b);
        return a;
      });
  if (counts.remove > 0) particles_.removeFlagged(flags);
  removedOut += counts.remove;
  nonFiniteOut += counts.nonFinite;
  return counts.clamped;
}

// ---------------------------------------------------------------------------
// Magnetism

// ---------------------------------------------------------------------------
// Grid update (step 4)

void MpmSolver::gridUpdate(double dt, MpmStepReport& rep) {
  const GridSpec& g = settings_.grid;
  // `off` takes window indices (mpm/partition.h; the grid's own without a partition) to the grid's.
  const Index3 off = partition_ ? partition_->windowLo() : Index3{0, 0, 0};
  const Index3 boxLo = partition_ ? partition_->boxLo() : Index3{0, 0, 0};
  const Index3 boxHi = partition_ ? partition_->boxHi() : g.dims;
  const auto owned = [&](int i, int j, int k) {
    return i >= boxLo.i && j >= boxLo.j && k >= boxLo.k && i < boxHi.i && j < boxHi.j && k < boxHi.k;
  };
  const Index3 lo = grid_.activeLo(), hi = grid_.activeHi();
  if (lo.i >= hi.i || lo.j >= hi.j || lo.k >= hi.k) return;
  const double tNew = time_ + dt;
  std::vector<ColliderState> states(colliders_.size());
  for (std::size_t c = 0; c < colliders_.size(); ++c) states[c] = colliders_[c].stateAt(tNew);
  const Vec3d dg = dt * settings_.gravity;
  const int W = settings_.wallNodes;
  const BoundaryCondition walls = settings_.walls;
  const Vec3d* fmag = magneticForce_.empty() ? nullptr : magneticForce_.data();
  // The nodal force applies only when it lives on this grid (a restored
  // state may carry a cached force from another stage grid).
  const bool magnetic = sameGrid_ && haveMagneticForce_ && fmag && magneticForce_.spec() == settings_.grid;
  const PageArray<MpmNode>& nodes = grid_.nodes();
  PageArray<Vec3d>& vel = grid_.velocity();
  const int nj = hi.j - lo.j;
  const std::size_t rows = std::size_t(nj) * std::size_t(hi.k - lo.k);
  std::vector<Vec3d> rowImpulse(magnetic ? rows : 0);

  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows, 4), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t row = r.begin(); row != r.end(); ++row) {
      const int j = lo.j + int(row % std::size_t(nj));
      const int k = lo.k + int(row / std::size_t(nj));
      Vec3d impulse{};
      int first = 0, end = 0;  // the row's run: every other node is zero (mpm/grid.h)
      grid_.activeRun(j, k, first, end);
      for (int i = first; i < end; ++i) {
        const std::size_t n = grid_.nodeIndex(i, j, k);
        const double m = nodes[n].mass;
        if (!(m > 0)) {
          vel[n] = Vec3d{};
          continue;
        }
        const int gi = i + off.i, gj = j + off.j, gk = k + off.k;  // grid indices
        Vec3d p = nodes[n].momentum;
        if (magnetic) {
          const Vec3d I = dt * fmag[g.index(gi, gj, gk)];  // N*s
          p += I;
          if (!partition_ || owned(gi, gj, gk)) impulse += I;  // each node's once over the processes
        }
        Vec3d v = p / m + dg;
        if (!colliders_.empty()) {
          const Vec3d x = g.nodePosition(gi, gj, gk);
          for (std::size_t c = 0; c < colliders_.size(); ++c)
            if (!colliders_[c].isDynamic()) v = colliders_[c].apply(states[c], x, v);
        }
        if (W > 0) {
          const int idx[3] = {gi, gj, gk};
          const int dims[3] = {g.dims.i, g.dims.j, g.dims.k};
          v = applyDomainWalls(v, idx, dims, W, walls);
        }
        vel[n] = v;
      }
      if (magnetic) rowImpulse[row] = impulse;
    }
  });
  if (magnetic) {
    Vec3d total{};
    for (const Vec3d& I : rowImpulse) total += I;
    rep.magneticImpulse = total;
  }
  if (anyDynamicBodies()) exchangeWithRigidBodies(dt);
}

// ---------------------------------------------------------------------------
// Finite checks (MpmSettings::checkFinite)


void MpmSolver::checkFiniteParticles(const char* where) const {
  const MpmParticles& P = particles_;
  const std::size_t np = P.size();
  const bool forces = P.magneticForce.size() == np;
  const std::size_t p = firstIndexWhere(np, [&](std::size_t i) {
    return !isFinite(P.x[i]) || !isFinite(P.v[i]) || !finiteMat(P.C[i]) || !finiteMat(P.F[i]) ||
           !std::isfinite(P.J[i]) || (forces && !isFinite(P.magneticForce[i]));
  });
  if (p == np) return;
  const char* what = !isFinite(P.x[p])        ? "position x (m)"
                     : !isFinite(P.v[p])      ? "velocity v (m/s)"
                     : !finiteMat(P.C[p])     ? "APIC matrix C (1/s)"
                     : !finiteMat(P.F[p])     ? "deformation gradient F"
                     : !std::isfinite(P.J[p]) ? "volume ratio J"
                                              : "magnetic force (N)";
  throw Error(concat("MPM finite check: non-finite ", what, " of particle ", p, " (id ", P.id[p], ", material ",
                     P.material[p], ") ", where, " in substep ", substeps_ + 1, " at t = ", time_,
                     " s; position (", P.x[p].x, ", ", P.x[p].y, ", ", P.x[p].z, ") m, velocity (", P.v[p].x, ", ",
                     P.v[p].y, ", ", P.v[p].z, ") m/s, J = ", P.J[p]));
}

void MpmSolver::checkFiniteGrid(const char* where) const {
  const GridSpec& g = grid_.spec();  // the window, with a partition (its nodes' indices are the window's)
  const PageArray<MpmNode>& nodes = grid_.nodes();
  const PageArray<Vec3d>& vel = grid_.velocity();
  const Vec3d* fmag =
      !partition_ && sameGrid_ && haveMagneticForce_ && !magneticForce_.empty() ? magneticForce_.data() : nullptr;
  // The runs of the active box only: every other node is zero (mpm/grid.h).
  const Index3 lo = grid_.activeLo(), hi = grid_.activeHi();
  if (lo.i >= hi.i || lo.j >= hi.j || lo.k >= hi.k) return;
  const std::size_t nj = std::size_t(hi.j - lo.j), rows = nj * std::size_t(hi.k - lo.k);
  // Node n of the arrays, f of the magnetic force's grid.
  const auto bad = [&](std::size_t n, std::size_t f) {
    return !std::isfinite(nodes[n].mass) || !isFinite(nodes[n].momentum) || !isFinite(vel[n]) ||
           (fmag && !isFinite(fmag[f]));
  };
  // The first bad node of a row (its i), or -1.
  const auto firstInRow = [&](std::size_t row) -> int {
    const int j = lo.j + int(row % nj), k = lo.k + int(row / nj);
    int first = 0, end = 0;
    grid_.activeRun(j, k, first, end);
    for (int i = first; i < end; ++i)
      if (bad(grid_.nodeIndex(i, j, k), g.index(i, j, k))) return i;
    return -1;
  };
  const std::size_t row = firstIndexWhere(rows, [&](std::size_t r) { return firstInRow(r) >= 0; });
  if (row == rows) return;
  const std::size_t i = std::size_t(firstInRow(row)), j = std::size_t(lo.j) + row % nj,
                    k = std::size_t(lo.k) + row / nj;
  const std::size_t n = grid_.nodeIndex(int(i), int(j), int(k));
  const char* what = !std::isfinite(nodes[n].mass)      ? "mass (kg)"
                     : !isFinite(nodes[n].momentum)      ? "momentum (kg m/s)"
                     : !isFinite(vel[n])                 ? "velocity (m/s)"
                                                         : "magnetic nodal force (N)";
  const Index3 off = partition_ ? partition_->windowLo() : Index3{0, 0, 0};
  throw Error(concat("MPM finite check: non-finite grid ", what, " at node (", i + std::size_t(off.i), ", ",
                     j + std::size_t(off.j), ", ", k + std::size_t(off.k), ") ", where,
                     " in substep ", substeps_ + 1, " at t = ", time_, " s (node mass ", nodes[n].mass, " kg)"));
}

void MpmSolver::resetMagneticWarmStart() {
  if (stage_) stage_->resetWarmStart();
  patches_.reset();  // a fresh start: the patches' potentials and far fields go too
}

// ---------------------------------------------------------------------------
// Substeps and frames

MpmStepReport MpmSolver::step(double dt) {
  require(std::isfinite(dt) && dt > 0, "MPM step: dt must be a positive finite time in s, got ", dt);
  require(time_ + dt > time_, "MPM step: dt = ", dt, " s is below the resolution of the time ", time_, " s");
  particles_.checkSizes();
  const auto tStart = Clock::now();
  MpmStepReport rep;
  rep.dt = dt;

  // 0. Particles handed out (particles(), emit()) since the last substep are
  // put back where their stencil fits; G2P keeps the others there.
  auto t = Clock::now();
  knownMaxSpeed_ = -1.0;  // the substep moves the particles; G2P knows their speed again
  enforceDomainOfHandedOut(rep);
  // With a partition: particles whose stencil base left this process's box
  // go to their owner (mpm/partition.h).
  if (partition_) partition_->migrate(particles_);
  const double secondsDomain = secondsSince(t);

  // 2-3. The magnetic force: n_p -> n_i, the field solve and the
  // Einstein-Laub force (MagneticForceStage::run; nodal f_i, or f_p per
  // particle on a stage grid of its own) when a solve is due and the last one
  // does not still hold (mpm/field_reuse.h). It comes before P2G in the code
  // because it reads the positions P2G sees and P2G deposits the f_p.
  updateMagneticForce(rep);

  // 1. P2G (mpm/grid.h): m_i = sum_p w_ip m_p and the APIC momentum with the
  // MLS stress impulse, mv_i = sum_p w_ip (m_p v_p + A_p d_ip + dt f_p),
  // A_p = m_p C_p - dt (4/dx^2) V_p^0 tau_p; f_p is the per-particle magnetic
  // force when the stage has its own grid.
  t = Clock::now();
  particleToGrid(dt, rep);
  rep.secondsP2G = secondsDomain + secondsSince(t);

  // 4. Grid update: v_i = ((m v)_i + dt f_i) / m_i + dt g, then the
  // colliders' and the walls' boundary conditions.
  // With dynamic rigid bodies: gravity, magnetic forces and contacts first,
  // the momentum exchange with the grid inside the grid update, then their
  // poses advance ("Rigid bodies" in solver.h).
  t = Clock::now();
  const bool bodies = anyDynamicBodies();
  if (bodies) predictRigidBodies(dt);
  gridUpdate(dt, rep);
  if (bodies) advanceRigidBodies(dt);
  if (settings_.checkFinite) checkFiniteGrid("after the grid update");
  rep.secondsGridUpdate = secondsSince(t);

  // 5-7. G2P (APIC): v_p = sum_i w_ip v_i, C_p = (4/dx^2) sum_i w_ip v_i
  // d_ip^T; the F update F_p <- (I + dt C_p) F_p (fluids: J_p <- (1 + dt
  // tr C_p) J_p); advection x_p <- x_p + dt v_p, keeping the particles in the
  // domain. Then, on the reorder interval, the particles are sorted by cell
  // (mpm/particle_order.h).
  t = Clock::now();
  const bool removedAfterP2G = gridToParticle(dt, rep);
  ++substeps_;
  ++stepsSinceSolve_;
  if (!removedAfterP2G && particleReorderDue(settings_.reorderInterval, substeps_, emittedSinceSort_)) {
    FieldReuse byId;  // with a partition the record is in id order, not the particles'
    reorderParticles(grid_.binnedOrder(), particles_, partition_ ? byId : reuse_);
    emittedSinceSort_ = false;
  }
  // 8. The rate emitters: the chunks born in (t, t + dt], at their place at t + dt.
  emitFromEmitters(dt, rep);
  if (rep.emitted.particles > 0) knownMaxSpeed_ = -1.0;
  rep.secondsG2P = secondsSince(t);

  time_ += dt;
  rep.time = time_;
  rep.particles = particles_.size();
  rep.secondsTotal = secondsSince(tStart);
  return rep;
}

void MpmSolver::enforceDomainOfHandedOut(MpmStepReport& rep) {
  if (!particlesDirty_) return;
  if (settings_.checkFinite) checkFiniteParticles("at the start of the substep");
  rep.clamped += enforceDomain(rep.removed, rep.nonFinite);
  particlesDirty_ = false;
}

void MpmSolver::updateMagneticForce(MpmStepReport& rep) {
  const bool magneticScene = !scene_->empty() && anyMagneticParticles();
  if (magneticScene) {
    bool due = settings_.magneticSolveInterval > 0 ? stepsSinceSolve_ >= settings_.magneticSolveInterval
                                                   : frameStart_ || movedSinceSolve();
    if (due && lastSolveHolds()) {
      due = false;  // nothing moved or changed enough: the last solve still holds
      rep.magneticReused = true;
      stepsSinceSolve_ = 0;
    }
    if (due || !haveMagneticForce_) solveMagnetic(rep);
  } else if (haveMagneticForce_) {
    solveMagnetic(rep);  // clears the cached force
  }
  frameStart_ = false;
}

void MpmSolver::particleToGrid(double dt, MpmStepReport& rep) {
  const bool particleForces = !sameGrid_ && haveMagneticForce_;
  grid_.particleToGrid(particles_, materials_, dt, particleForces ? particles_.magneticForce.data() : nullptr);
  if (partition_) {
    // Every window node now holds the mass deposited elsewhere too.
    partition_->sumNodes(grid_.nodes().data(), grid_.nodes().size());
    grid_.activateWholeGrid();
  } else if (settings_.denseGrid) {
    grid_.activateWholeGrid();
  }
  if (particleForces) {
    rep.magneticImpulse =
        deterministicSum<Vec3d>(particles_.size(), [&](std::size_t p) { return dt * particles_.magneticForce[p]; });
  }
  rep.secondsBinning = grid_.lastBinningSeconds();
}

bool MpmSolver::gridToParticle(double dt, MpmStepReport& rep) {
  const ParticleBounds bounds = domainBounds();
  const GridToParticleReport g2p = grid_.gridToParticle(particles_, materials_, dt, &bounds);
  std::size_t pushedOutside = 0;
  if (settings_.colliderProjection) rep.projected = projectOutOfColliders(dt, pushedOutside);
  if (settings_.checkFinite) checkFiniteParticles("after G2P and advection");
  rep.maxSpeed = g2p.maxSpeed;
  rep.clamped += g2p.clamped;
  const std::size_t removedBefore = rep.removed;
  const bool enforced = g2p.outside + g2p.nonFinite + pushedOutside > 0;
  if (enforced) rep.clamped += enforceDomain(rep.removed, rep.nonFinite);
  // G2P's maximum is every particle's speed unless a projection or the
  // domain's enforcement changed a velocity or removed a particle since.
  knownMaxSpeed_ = rep.projected == 0 && !enforced ? g2p.maxSpeed : -1.0;
  return rep.removed != removedBefore;
}

std::size_t MpmSolver::projectOutOfColliders(double dt, std::size_t& outside) {
  outside = 0;
  if (colliders_.empty()) return 0;
  // The colliders where the grid update placed them: at the end of the substep.
  std::vector<ColliderState> states(colliders_.size());
  std::vector<double> allowed(colliders_.size());
  for (std::size_t c = 0; c < colliders_.size(); ++c) {
    states[c] = colliders_[c].stateAt(time_ + dt);
    allowed[c] = colliderAllowance(c);
  }
  const ParticleBounds bounds = domainBounds();
  Vec3d* X = particles_.x.data();
  Vec3d* V = particles_.v.data();
  struct Count {
    std::size_t pushed = 0, outside = 0;
    Count& operator+=(const Count& o) {
      pushed += o.pushed;
      outside += o.outside;
      return *this;
    }
  };
  std::size_t pushed = 0;
  for (std::size_t c = 0; c < colliders_.size(); ++c) {
    if (colliders_[c].isDynamic()) {
      pushed += pushOutOfBody(c, states[c], allowed[c], bounds, outside);
      continue;
    }
    const Count n = deterministicSum<Count>(particles_.size(), [&](std::size_t p) {
      Count k;
      if (!colliders_[c].projectOut(states[c], X[p], V[p], allowed[c])) return k;
      ++k.pushed;
      if (bounds.excludes(X[p])) ++k.outside;
      return k;
    });
    pushed += n.pushed;
    outside += n.outside;
  }
  return pushed;
}

Vec3d MpmSolver::domainLower() const {
  const GridSpec& g = settings_.grid;
  const double w = settings_.wallNodes > 0 ? settings_.wallNodes - 0.5 : 1.0;
  return g.origin + (w * g.dx) * Vec3d{1, 1, 1};
}

Vec3d MpmSolver::domainUpper() const {
  const GridSpec& g = settings_.grid;
  const double w = settings_.wallNodes > 0 ? settings_.wallNodes - 0.5 : 1.0;
  return g.nodePosition(g.dims.i - 1, g.dims.j - 1, g.dims.k - 1) - (w * g.dx) * Vec3d{1, 1, 1};
}

MpmEnergies MpmSolver::energies() const {
  struct Sum {
    double k = 0, g = 0, e = 0;
    Sum& operator+=(const Sum& o) {
      k += o.k;
      g += o.g;
      e += o.e;
      return *this;
    }
  };
  const Vec3d grav = settings_.gravity;
  const Sum s = deterministicSum<Sum>(particles_.size(), [&](std::size_t p) {
    Sum t;
    const double m = particles_.mass[p];
    t.k = 0.5 * m * norm2(particles_.v[p]);
    t.g = -m * dot(grav, particles_.x[p]);
    const std::uint32_t id = particles_.material[p];
    if (id < materials_.size()) {
      const MpmMaterial& mat = materials_[id];
      // The elastoplastic solid's F is its elastic part F_E: the stored energy.
      t.e = particles_.volume0[p] *
            (mat.isFluid() ? fluidEnergyDensity(particles_.J[p], mat.bulkModulus)
             : mat.model == MpmModel::ElastoplasticSolid ? henckyEnergyDensity(particles_.F[p], mat.mu, mat.lambda)
                                                         : neoHookeanEnergyDensity(particles_.F[p], mat.mu, mat.lambda));
    }
    return t;
  });
  MpmEnergies e;
  e.kinetic = s.k;
  e.gravitational = s.g;
  e.elastic = s.e;
  return e;
}

}  // namespace mpm
}  // namespace lodestone
