#include "newton_driver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/field/line_search.h"

namespace lodestone {
namespace gpu {
namespace detail {

namespace {
using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Level-0 work slots (slot 0 holds phi).
enum Slot : int {
  kF = 1,
  kFref,
  kDelta,
  kWork,
  kTrial,
  kFtrial,
  kLastGood,
  kPcgOuter = 8,  // 8..11
  kMgR = 12,
  kPcgCoarse = 13,  // 13..16: CG on the coarsest level
  kMgX = 17,
  kMgB = 18
};
}  // namespace

template <typename Precondition>
PcgOutcome pcg(FieldBackend& be, int level, const double* b, double* x, double relTol, int maxIterations, bool project,
               int firstSlot, const Precondition& precondition) {
  PcgOutcome res;
  const std::size_t n = be.levelNodes(level);
  double* r = be.work(level, firstSlot);
  double* z = be.work(level, firstSlot + 1);
  double* p = be.work(level, firstSlot + 2);
  double* Ap = be.work(level, firstSlot + 3);
  be.copy(n, b, r);
  be.fill(n, 0.0, x);
  if (project) be.removeMean(n, r);
  const double bnorm = std::sqrt(be.dot(n, r, r));
  if (!(bnorm > 0)) {
    res.converged = std::isfinite(bnorm);
    res.breakdown = !std::isfinite(bnorm);
    return res;
  }
  precondition(r, z);
  if (project) be.removeMean(n, z);
  be.copy(n, z, p);
  double rz = be.dot(n, r, z);
  double rnorm = bnorm;
  while (res.iterations < maxIterations) {
    be.applyLevel(level, p, Ap);
    const double pAp = be.dot(n, p, Ap);
    if (!(pAp > 0) || !std::isfinite(pAp) || !std::isfinite(rz)) {
      res.breakdown = true;
      break;
    }
    const double alpha = rz / pAp;
    be.axpby(n, 1.0, x, alpha, p, x);
    be.axpby(n, 1.0, r, -alpha, Ap, r);
    if (project) be.removeMean(n, r);
    ++res.iterations;
    rnorm = std::sqrt(be.dot(n, r, r));
    if (rnorm <= relTol * bnorm) {
      res.converged = true;
      break;
    }
    precondition(r, z);
    if (project) be.removeMean(n, z);
    const double rzNew = be.dot(n, r, z);
    const double beta = rzNew / rz;
    rz = rzNew;
    be.axpby(n, 1.0, z, beta, p, p);
  }
  res.relativeResidual = rnorm / bnorm;
  if (project) be.removeMean(n, x);
  return res;
}

namespace {

/// The V-cycle of multigrid.cpp over the backend's levels.
class VCycle {
 public:
  VCycle(FieldBackend& be, const FieldSolveSettings& s) : be_(be), s_(s) {}

  void operator()(const double* b, double* x) const { cycle(0, b, x); }

 private:
  void cycle(int level, const double* b, double* x) const {
    const std::size_t n = be_.levelNodes(level);
    const double* dinv = be_.inverseDiagonal(level, false);
    double* r = be_.work(level, kMgR);
    if (level + 1 == be_.levelCount()) {
      // Coarsest grid: diagonally preconditioned CG to a tight tolerance.
      if (be_.solveCoarsest(level, b, x)) return;
      pcg(be_, level, b, x, 1e-10, 10 * int(n), be_.shield(), kPcgCoarse,
          [&](const double* in, double* out) { be_.jacobi(n, 1.0, dinv, in, nullptr, out); });
      return;
    }
    const double w = s_.jacobiWeight;
    be_.jacobi(n, w, dinv, b, nullptr, x);
    for (int s = 1; s < s_.smoothing; ++s) {
      be_.applyLevel(level, x, r);
      be_.jacobi(n, w, dinv, b, r, x);
    }
    be_.applyLevel(level, x, r);
    be_.axpby(n, 1.0, b, -1.0, r, r);
    double* cb = be_.work(level + 1, kMgB);
    double* cx = be_.work(level + 1, kMgX);
    be_.restrictTo(level, r, cb);
    be_.zeroFixed(level + 1, cb);
    cycle(level + 1, cb, cx);
    be_.prolong(level, cx, r);
    be_.zeroFixed(level, r);
    be_.axpby(n, 1.0, x, 1.0, r, x);
    for (int s = 0; s < s_.smoothing; ++s) {
      be_.applyLevel(level, x, r);
      be_.jacobi(n, w, dinv, b, r, x);
    }
  }

  FieldBackend& be_;
  const FieldSolveSettings& s_;
};

template <typename... Args>
std::string cat(const Args&... args) {
  return lodestone::concat(args...);
}

}  // namespace

FieldSolveReport runNewton(FieldBackend& be, double* phiIn, const FieldSolveSettings& settings,
                           const WallUpdate& wallUpdate) {
  settings.validate();
  const auto t0 = Clock::now();
  const std::size_t n = be.nodeCount();
  FieldSolveReport rep;
  rep.materialCells = be.materialCellCount();
  rep.backend = be.name();
  double* phi = phiIn;
  double* F = be.work(0, kF);
  double* Fref = be.work(0, kFref);
  double* delta = be.work(0, kDelta);
  double* work = be.work(0, kWork);
  double* trial = be.work(0, kTrial);
  double* Ftrial = be.work(0, kFtrial);
  double* lastGood = be.work(0, kLastGood);
  const auto norm = [&](const double* v) { return std::sqrt(be.dot(n, v, v)); };
  const auto finish = [&](FieldSolveReport& r) {
    if (phi != phiIn) be.copy(n, phi, phiIn);
    r.seconds = secondsSince(t0);
    return r;
  };

  be.residualAtZero(Fref);
  rep.referenceResidual = norm(Fref);
  if (!std::isfinite(rep.referenceResidual)) {
    rep.status = SolveStatus::NonFinite;
    rep.message = "the magnetization of the applied field is not finite";
    return finish(rep);
  }
  if (!(rep.referenceResidual > 0)) {
    // phi = 0 on the free nodes (Open keeps its wall values).
    if (be.shield()) {
      be.fill(n, 0.0, phi);
    } else {
      be.copy(n, phi, work);
      be.zeroFixed(0, work);
      be.axpby(n, 1.0, phi, -1.0, work, phi);
    }
    rep.status = SolveStatus::Trivial;
    rep.message = be.materialCellCount() == 0 ? "no magnetic material: H = H_ext"
                                              : "the applied field magnetizes nothing: H = H_ext";
    return finish(rep);
  }
  const double r0 = rep.referenceResidual;
  const bool linear = be.law().kind == LawKind::Linear;
  const bool multigrid = settings.preconditioner == Preconditioner::Multigrid;
  const bool project = be.shield();
  VCycle vcycle(be, settings);

  double prevNorm = 0, prevEta = settings.forcingMax;
  be.copy(n, phi, lastGood);
  Evaluation ev = be.evaluate(phi, F, true);
  std::vector<double> hostPhi, hostWall;
  for (int it = 0;; ++it) {
    if (wallUpdate && !be.shield() && ev.finite) {
      // New far-field wall values from the host; only the wall nodes change
      // (delta = new - old, its free nodes zeroed), then a fresh evaluation.
      hostPhi.resize(n);
      be.download(phi, n, hostPhi.data());
      hostWall = hostPhi;
      wallUpdate(hostPhi.data(), hostWall.data());
      be.upload(hostWall.data(), n, work);
      be.axpby(n, 1.0, work, -1.0, phi, work);
      be.copy(n, work, trial);
      be.zeroFixed(0, trial);
      be.axpby(n, 1.0, work, -1.0, trial, work);
      be.axpby(n, 1.0, phi, 1.0, work, phi);
      ev = be.evaluate(phi, F, true);
    }
    const double fn = norm(F);
    const double rel = fn / r0;
    rep.relativeResidual = rel;
    rep.materialEnergy = ev.energy;
    if (!ev.finite || !std::isfinite(fn)) {
      be.copy(n, lastGood, phi);
      rep.status = SolveStatus::NonFinite;
      rep.message = cat("non-finite magnetization or residual at Newton iteration ", it);
      break;
    }
    be.copy(n, phi, lastGood);
    if (rel <= settings.tolerance) {
      rep.status = SolveStatus::Converged;
      rep.message =
          cat("converged in ", it, " Newton iterations (", rep.cgIterations, " CG) to relative residual ", rel);
      break;
    }
    if (it >= settings.maxNewtonIterations) {
      rep.status = SolveStatus::IterationCap;
      rep.message = cat("not converged: Newton iteration cap ", settings.maxNewtonIterations,
                        " reached at relative residual ", rel, " (tolerance ", settings.tolerance, ")");
      break;
    }
    // Eisenstat-Walker choice 2 with safeguards (field_solver.cpp).
    const double floorEta = std::min(settings.forcingMax, 0.5 * settings.tolerance * r0 / fn);
    double eta = settings.forcingMax;
    if (linear) {
      eta = floorEta;
    } else if (it > 0) {
      eta = settings.forcingGamma * std::pow(fn / prevNorm, settings.forcingAlpha);
      const double safeguard = settings.forcingGamma * std::pow(prevEta, settings.forcingAlpha);
      if (safeguard > 0.1) eta = std::max(eta, safeguard);
      eta = std::min(eta, settings.forcingMax);
    }
    eta = std::max(eta, floorEta);

    // Newton step: J delta = -F.
    be.buildPreconditioner(multigrid, settings.coarsestNodes);
    rep.multigridLevels = multigrid ? be.levelCount() : 0;
    be.axpby(n, -1.0, F, 0.0, F, work);
    PcgOutcome cg;
    if (multigrid) {
      cg = pcg(be, 0, work, delta, eta, settings.maxCgIterations, project, kPcgOuter, vcycle);
    } else {
      const double* dinv = be.inverseDiagonal(0, true);
      cg = pcg(be, 0, work, delta, eta, settings.maxCgIterations, project, kPcgOuter,
               [&](const double* in, double* out) { be.jacobi(n, 1.0, dinv, in, nullptr, out); });
    }
    rep.cgIterations += cg.iterations;
    const double g0 = be.dot(n, delta, F);
    if (cg.breakdown || !(g0 < 0)) {
      rep.status = SolveStatus::LinearSolverFailed;
      rep.message = cat("CG ", cg.breakdown ? "broke down" : "returned a non-descent step", " at Newton iteration ", it,
                        " (", cg.iterations, " CG iterations, relative residual ", cg.relativeResidual, ")");
      break;
    }

    // Line search on E(phi + lambda delta) - E(phi) = lambda s1 + lambda^2 s2 / 2 + dW.
    be.applyVacuum(phi, work);
    const double s1 = be.dot(n, delta, work);
    be.applyVacuum(delta, work);
    const double s2 = be.dot(n, delta, work);
    const double armijoSlope = settings.armijo * g0;
    int cuts = 0;
    const auto accept = [&](double lambda, double dE, double absW, auto&& trialNorm) {
      const double noise = 64.0 * std::numeric_limits<double>::epsilon() *
                           (absW + ev.energyAbs + std::fabs(lambda * s1) + 0.5 * lambda * lambda * std::fabs(s2));
      if (!std::isfinite(dE)) return false;
      if (std::fabs(dE) > noise) return dE <= lambda * armijoSlope;
      return trialNorm() <= (1.0 - settings.armijo * lambda) * fn;
    };
    double lambda = 1.0;
    be.axpby(n, 1.0, phi, 1.0, delta, trial);
    Evaluation evT = be.evaluate(trial, Ftrial, true);
    double dE = s1 + 0.5 * s2 + (evT.energy - ev.energy);
    bool accepted = evT.finite && accept(1.0, dE, evT.energyAbs, [&] { return norm(Ftrial); });
    if (accepted) {
      std::swap(phi, trial);
      std::swap(F, Ftrial);
      ev = evT;
    } else {
      for (int cut = 1; cut <= settings.maxLineSearchCuts && !accepted; ++cut) {
        lambda = backtrackedStep(dE, g0, lambda);
        ++cuts;
        double absW = 0;
        const double Wl = be.energyAlong(phi, delta, lambda, &absW);
        dE = lambda * s1 + 0.5 * lambda * lambda * s2 + (Wl - ev.energy);
        accepted = accept(lambda, dE, absW, [&] {
          be.axpby(n, 1.0, phi, lambda, delta, trial);
          const Evaluation e = be.evaluate(trial, Ftrial, false);
          return e.finite ? norm(Ftrial) : std::numeric_limits<double>::infinity();
        });
      }
      if (accepted) {
        be.axpby(n, 1.0, phi, lambda, delta, phi);
        if (project) be.removeMean(n, phi);
        ev = be.evaluate(phi, F, true);
      }
    }
    rep.lineSearchCuts += cuts;
    if (!accepted) {
      be.evaluate(phi, F, true);
      rep.status = SolveStatus::LineSearchFailed;
      rep.message =
          cat("line search failed at Newton iteration ", it, " after ", cuts, " cuts (relative residual ", rel, ")");
      break;
    }
    prevNorm = fn;
    prevEta = eta;
    ++rep.newtonIterations;
  }
  return finish(rep);
}

}  // namespace detail
}  // namespace gpu
}  // namespace lodestone
