// Time stepping of the reference MLS-MPM: the substep's size (the CFL step,
// the stability bound, the collider crossing limit) and frames of substeps
// (advanceFrame, with the substep limits per frame); see mpm/solver.h.

#include <algorithm>
#include <cmath>
#include <limits>

#include "lodestone/core/base/error.h"
#include "lodestone/core/base/number_text.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/mpm/surface_tension.h"

namespace lodestone {
inline namespace mpm {

// ---------------------------------------------------------------------------
// Time step

double MpmSolver::suggestedDt() const {
  if (settings_.fixedDt > 0) return settings_.fixedDt;
  return cflDt(settings_.cfl, false);
}

double MpmSolver::stabilityLimitDt() const { return cflDt(1.0, true); }

double MpmSolver::maxParticleSpeed() const {
  // The last substep's G2P found it, unless the particles were handed out
  // (particles(), emit(), a restore) or changed after it.
  double vmax = knownMaxSpeed_;
  if (vmax < 0 || particlesDirty_) vmax = MpmGrid::maxSpeed(particles_.v.data(), particles_.size());
  return partition_ ? partition_->maxOverRanks(vmax) : vmax;
}

double MpmSolver::colliderCrossingDt() const { return colliderCrossingDt(maxParticleSpeed()); }

double MpmSolver::colliderCrossingDt(double vmax) const {
  double dt = std::numeric_limits<double>::infinity();
  if (colliders_.empty()) return dt;
  const bool any = particles_.size() > 0;
  if (!(partition_ ? partition_->maxOverRanks(any ? 1.0 : 0.0) > 0 : any)) return dt;
  const GridSpec& g = settings_.grid;
  const Vec3d lo = g.origin, hi = g.maxCorner();
  for (std::size_t k = 0; k < colliders_.size(); ++k) {
    const MpmCollider& c = colliders_[k];
    const double half = c.shape().halfThickness();
    if (!std::isfinite(half)) continue;
    const ColliderState st = c.stateAt(time_);
    double reach = 0;  // farthest domain corner from the collider's origin, m
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3d x{corner & 1 ? hi.x : lo.x, corner & 2 ? hi.y : lo.y, corner & 4 ? hi.z : lo.z};
      reach = std::max(reach, norm(x - st.pose.position));
    }
    const double speed = vmax + norm(st.velocity) + norm(st.angularVelocity) * reach;
    if (speed > 0) dt = std::min(dt, (half - colliderAllowance(k)) / speed);
  }
  return dt;
}

double MpmSolver::colliderAllowance(std::size_t c) const {
  return std::min(0.5 * settings_.grid.dx, 0.5 * collider(c).shape().halfThickness());
}

double MpmSolver::cflDt(double cfl, bool bound, bool* byColliders) const {
  const double vmax = maxParticleSpeed();
  double c = 0, nu = 0;
  const double dx = settings_.grid.dx;
  double capillary = std::numeric_limits<double>::infinity();  // s, Brackbill's capillary limit
  for (const MpmMaterial& m : materials_) {
    c = std::max(c, m.waveSpeed());
    nu = std::max(nu, m.kinematicViscosity());
    if (m.hasSurfaceTension()) capillary = std::min(capillary, capillaryTimeStep(m.density, dx, m.surfaceTension));
  }
  const double speed = std::max(vmax, maxEmissionSpeed()) + c;  // material about to be emitted counts
  // The crossing limit of thin colliders (the projection after advection
  // pushes a particle back out through the face it entered by only while it
  // is less than the half-thickness deep).
  const double crossing =
      settings_.colliderProjection ? colliderCrossingDt(vmax) : std::numeric_limits<double>::infinity();
  // The bound: a cell per substep, the explicit viscous limit dx^2/(6 nu)
  // (cfl dx^2/(3 nu) at the default cfl = 1/2 of it) and, with surface
  // tension, the capillary limit sqrt(rho dx^3/(2 pi sigma)) of the least
  // dense liquid with the largest sigma (2 cfl times it, like the viscous one).
  double dt = 0;
  if (bound) {
    dt = speed > 0 ? dx / speed : std::numeric_limits<double>::infinity();
    if (nu > 0) dt = std::min(dt, dx * dx / (6 * nu));
    dt = std::min(dt, capillary);
  } else {
    dt = speed > 0 ? cfl * dx / speed : settings_.dtMax;
    if (nu > 0) dt = std::min(dt, cfl * dx * dx / (3 * nu));
    if (std::isfinite(capillary)) dt = std::min(dt, 2 * cfl * capillary);
    dt = std::min(dt, settings_.dtMax);
  }
  const double colliderDt = bound ? crossing : cfl * crossing;
  if (byColliders) *byColliders = colliderDt < dt && colliderDt > settings_.dtMin;
  dt = std::min(dt, colliderDt);
  return bound ? dt : std::max(dt, settings_.dtMin);
}

MpmFrameReport MpmSolver::advanceFrame(double frameDuration, const MpmProgressCallback& progress) {
  require(std::isfinite(frameDuration) && frameDuration > 0,
          "MPM frame: duration must be a positive finite time in s, got ", frameDuration);
  MpmFrameReport fr;
  const double t0 = time_;
  const double tEnd = time_ + frameDuration;
  frameStart_ = true;
  for (Vec3d& p : materialImpulse_) p = Vec3d{};
  for (Vec3d& p : contactImpulse_) p = Vec3d{};
  bool first = true;
  const double longest = frameDuration / settings_.minSubsteps;  // s: minSubsteps per frame
  while (time_ < tEnd) {
    if (settings_.maxSubsteps > 0 && fr.substeps >= settings_.maxSubsteps)
      throw Error(concat("MPM frame from t = ", numberText(t0, 6), " s: ", fr.substeps,
                         " substeps reached the limit of ", settings_.maxSubsteps, " per frame at t = ",
                         numberText(time_, 6), " s with ", numberText((tEnd - time_) / frameDuration * 100, 3),
                         "% of the frame left; its substeps took ", numberText(fr.minDt, 4), " .. ",
                         numberText(fr.maxDt, 4), " s (the step now is ", numberText(suggestedDt(), 4),
                         " s, the fastest particle moves at ", numberText(maxParticleSpeed(), 4),
                         " m/s); raise the limit (time.max_substeps) or find what sped up or stiffened"));
    bool byColliders = false;
    double dt = settings_.fixedDt > 0 ? settings_.fixedDt : cflDt(settings_.cfl, false, &byColliders);
    if (settings_.fixedDt == 0 && dt <= settings_.dtMin) ++fr.dtAtMinimum;
    if (dt > longest) {
      dt = longest;
      byColliders = false;
    }
    if (byColliders) ++fr.dtLimitedByColliders;
    if (settings_.fixedDt > 0) {
      // A fixed dt above the stability bound would blow up: substep it.
      const double limit = stabilityLimitDt();
      if (dt > limit) {
        dt = std::max(settings_.cfl * limit, settings_.dtMin);
        ++fr.dtLimitedByCfl;
      }
    }
    const double remaining = tEnd - time_;
    bool last = false;
    if (remaining <= dt * (1 + 1e-9)) {
      dt = remaining;
      last = true;
    } else if (settings_.fixedDt == 0 && remaining < 2 * dt) {
      dt = 0.5 * remaining;  // two even substeps rather than a sliver
    }
    const MpmStepReport r = step(dt);
    if (last) time_ = tEnd;
    ++fr.substeps;
    fr.minDt = first ? dt : std::min(fr.minDt, dt);
    fr.maxDt = first ? dt : std::max(fr.maxDt, dt);
    first = false;
    fr.secondsP2G += r.secondsP2G;
    fr.secondsBinning += r.secondsBinning;
    fr.secondsMagnetic += r.secondsMagnetic;
    fr.secondsGridUpdate += r.secondsGridUpdate;
    fr.secondsG2P += r.secondsG2P;
    fr.secondsTotal += r.secondsTotal;
    fr.magneticImpulse += r.magneticImpulse;
    fr.clamped += r.clamped;
    fr.removed += r.removed;
    fr.nonFinite += r.nonFinite;
    fr.projected += r.projected;
    fr.emitted += r.emitted;
    if (r.magneticSolved) {
      if (!r.magnetic.converged())
        fr.warnings.push_back(
            concat("field solve at t = ", time_ - dt, " s did not converge: ", r.magnetic.solve.message));
      fr.magneticReports.push_back(r.magnetic);
    }
    fr.magneticReused += r.magneticReused ? 1 : 0;
    if (progress) {
      MpmProgress pr;
      pr.substep = fr.substeps;
      pr.time = time_;
      pr.fraction = std::min(1.0, (time_ - t0) / frameDuration);
      if (!progress(pr)) {
        fr.cancelled = !last;
        break;
      }
    }
    if (last) break;
  }
  fr.energies = energies();
  if (partition_) {
    // The whole simulation's energies and counts, the same on every process.
    double sums[10] = {fr.energies.kinetic, fr.energies.gravitational, fr.energies.elastic, double(fr.clamped),
                       double(fr.removed),  double(fr.nonFinite),      double(fr.projected), fr.magneticImpulse.x,
                       fr.magneticImpulse.y, fr.magneticImpulse.z};
    partition_->sumOverRanks(sums, 10);
    fr.energies.kinetic = sums[0];
    fr.energies.gravitational = sums[1];
    fr.energies.elastic = sums[2];
    fr.clamped = std::size_t(sums[3]);
    fr.removed = std::size_t(sums[4]);
    fr.nonFinite = std::size_t(sums[5]);
    fr.projected = std::size_t(sums[6]);
    fr.magneticImpulse = {sums[7], sums[8], sums[9]};
  }
  if (fr.dtAtMinimum > 0)
    fr.warnings.push_back(concat(fr.dtAtMinimum, " substep(s) needed less than dtMin = ", settings_.dtMin,
                                 " s and were taken at dtMin; the step may be unstable"));
  if (fr.nonFinite > 0)
    fr.warnings.push_back(concat(fr.nonFinite, " particle(s) with a non-finite state were removed"));
  if (fr.dtLimitedByCfl > 0)
    fr.warnings.push_back(concat(fr.dtLimitedByCfl, " substep(s): the fixed dt = ", settings_.fixedDt,
                                 " s exceeded the stability bound (a cell per substep, dx^2/(6 nu), the capillary limit sqrt(rho dx^3/(2 pi sigma)), a collider's half-thickness) and was "
                                 "shortened to cfl times the bound"));
  fr.time = time_;
  fr.bodies = rigidBodies();
  return fr;
}

}  // namespace mpm
}  // namespace lodestone
