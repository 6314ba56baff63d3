#include "lodestone/core/field/newton_solver.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "lodestone/core/base/error.h"
#include "lodestone/core/field/line_search.h"

// Portable: the standard library and core's portable headers only (no TBB),
// so that gpu/ compiles this file into its standalone build.

namespace lodestone {
inline namespace field {

namespace {
// Predicted-wall steps that did not help (rejected, or accepted with less
// than half of the residual removed) before the wall lags for the rest of
// the solve. Near the wall, a strongly magnetizable body (chi0 ~ 10-100, 2-3
// cells of clearance) makes the linearized wall move a poor guess: such
// steps were accepted at 0.5-0.7 reduction each and the solve crawled (40
// Newton steps without converging where the lagging wall took 16).
constexpr int kWallStrikes = 2;
// A deferred trial point that missed the tolerance by at most this factor
// is followed by a chord step (FieldSolveSettings::chordAfterDeferredMiss).
// Measured: the cube on the planner's 88^3 region at 1e-3 missed by 3.3x,
// and the chord step reached 2.64e-4, as the rebuilt Jacobian's did.
constexpr double kChordMiss = 10.0;
}  // namespace

NewtonSolver::NewtonSolver(FieldSolveBackend& backend, const FieldSolveSettings& settings, SolveProgress progress)
    : be_(backend), s_(settings), progress_(std::move(progress)) {
  s_.validate();
}

FieldSolveReport NewtonSolver::solve() {
  if (!start()) return finish();
  for (int it = 0;; ++it) {
    NewtonIterationRecord rec = beginIteration(it);
    if (finished(rec)) break;
    rec.forcing = eta_ = forcingTerm(it);
    const PcgResult cg = newtonStep(rec);
    const Step step = predictWall(rec, cg);
    if (!acceptStep(rec, step)) break;
    if (!endIteration(rec)) break;
  }
  return finish();
}

// The reference residual is F at phi = 0. From a cold start that is the
// first evaluation itself (K phi = 0), which then also serves the first
// iteration; a warm start evaluates the material part at phi = 0 alone.
bool NewtonSolver::start() {
  t0_ = SteadyClock::now();
  rep_ = FieldSolveReport{};
  rep_.materialCells = be_.materialCellCount();
  rep_.preconditioner = toString(s_.preconditioner);
  rep_.backend = be_.name();
  open_ = be_.boundary() == BoundaryKind::Open;
  project_ = be_.boundary() == BoundaryKind::Shield;
  linear_ = be_.lawKind() == LawKind::Linear;
  const bool cold = be_.prepareStart();
  if (cold) {
    be_.fill(NodeVec::Kphi, 0.0);
    ev_ = be_.evaluate(NodeVec::Phi, NodeVec::F, true, NodeVec::Kphi);
    rep_.referenceResidual = ev_.finite ? be_.norm(NodeVec::F) : std::numeric_limits<double>::quiet_NaN();
  } else {
    be_.residualAtZero(NodeVec::Fref);
    rep_.referenceResidual = be_.norm(NodeVec::Fref);
  }
  if (!std::isfinite(rep_.referenceResidual)) {
    stop(SolveStatus::NonFinite, nullptr, "the magnetization of the applied field is not finite");
    return false;
  }
  if (!(rep_.referenceResidual > 0)) {
    be_.fill(NodeVec::Phi, 0.0);
    stop(SolveStatus::Trivial, nullptr,
         be_.materialCellCount() == 0 ? "no magnetic material: H = H_ext"
                                      : "the applied field magnetizes nothing: H = H_ext");
    return false;
  }
  r0_ = rep_.referenceResidual;
  prevNorm_ = 0;
  prevEta_ = s_.forcingMax;
  wallCurrent_ = jacobianDeferred_ = false;
  wallStrikes_ = wallUpdates_ = 0;
  be_.copy(NodeVec::Phi, NodeVec::LastGood);
  // K phi (the vacuum part of F) is kept up to date through every change of
  // phi (Newton steps: + lambda K delta; wall updates: the wall layer only),
  // so the stencil is applied once per Newton iteration (to delta) instead of
  // once for the line search and once more in each evaluation.
  if (!cold) {
    be_.applyVacuum(NodeVec::Phi, NodeVec::Kphi);
    ev_ = be_.evaluate(NodeVec::Phi, NodeVec::F, true, NodeVec::Kphi);
  }
  rep_.secondsInitial = secondsSince(t0_);
  return true;
}

NewtonIterationRecord NewtonSolver::beginIteration(int it) {
  const auto ti = iterationStart_ = SteadyClock::now();
  NewtonIterationRecord rec;
  rec.iteration = it;
  if (open_ && be_.wallNodeCount() > 0 && ev_.finite && !wallCurrent_) {
    // Far-field values from the magnetization just evaluated.
    updateWall(NodeVec::Phi, NodeVec::F, NodeVec::Kphi, ev_);
    rec.secondsWall = secondsSince(ti);
  }
  wallCurrent_ = false;
  fn_ = be_.norm(NodeVec::F);
  rec.relativeResidual = fn_ / r0_;
  rep_.relativeResidual = rec.relativeResidual;
  rep_.materialEnergy = ev_.materialEnergy;
  return rec;
}

bool NewtonSolver::finished(NewtonIterationRecord& rec) {
  if (!ev_.finite || !std::isfinite(fn_)) {
    be_.copy(NodeVec::LastGood, NodeVec::Phi);
    stop(SolveStatus::NonFinite, nullptr,
         concat("non-finite magnetization or residual at Newton iteration ", rec.iteration));
    return true;
  }
  be_.copy(NodeVec::Phi, NodeVec::LastGood);
  if (rec.relativeResidual <= s_.tolerance) {
    stop(SolveStatus::Converged, &rec,
         concat("converged in ", rec.iteration, " Newton iterations (", rep_.cgIterations,
                " CG) to relative residual ", rec.relativeResidual));
    return true;
  }
  if (rec.iteration >= s_.maxNewtonIterations) {
    stop(SolveStatus::IterationCap, &rec,
         concat("not converged: Newton iteration cap ", s_.maxNewtonIterations, " reached at relative residual ",
                rec.relativeResidual, " (tolerance ", s_.tolerance, ")"));
    return true;
  }
  return false;
}

// The inner tolerance: Eisenstat-Walker choice 2 with safeguards, never
// tighter than needed to reach the outer tolerance.
double NewtonSolver::forcingTerm(int it) {
  const double floorEta = std::min(s_.forcingMax, 0.5 * s_.tolerance * r0_ / fn_);
  double eta = s_.forcingMax;
  if (linear_) {
    eta = floorEta;
  } else if (it > 0) {
    eta = s_.forcingGamma * std::pow(fn_ / prevNorm_, s_.forcingAlpha);
    const double safeguard = s_.forcingGamma * std::pow(prevEta_, s_.forcingAlpha);
    if (safeguard > 0.1) eta = std::max(eta, safeguard);
    eta = std::min(eta, s_.forcingMax);
  }
  // When the open wall lags behind M (predictWall off, or a prediction that
  // missed), one Newton step cannot reduce the residual much below that lag:
  // it shows as a reduction far short of the step's forcing. Solving the
  // inner system beyond a tenth of it only adds CG iterations. Only with
  // multigrid: a Jacobi-preconditioned CG stopped early leaves the smooth
  // error almost untouched, so its residual overstates the step's quality
  // (the linear law then took 12 Newton steps instead of 6).
  if (open_ && s_.preconditioner == PreconditionerKind::Multigrid) {
    if (it > 0) {
      const double achieved = fn_ / prevNorm_;
      if (achieved > 10.0 * prevEta_) eta = std::max(eta, std::min(s_.forcingMax, 0.1 * achieved));
    } else if (linear_) {
      eta = std::max(eta, 0.1 * s_.forcingMax);
    }
  }
  eta = std::max(eta, floorEta);
  // With the wall predicted, a step reduces the residual by about its
  // forcing, so when the forcing that reaches the tolerance in this step is
  // within 30x of eta (one or two more CG iterations with multigrid), that is
  // cheaper than another Newton step.
  if (predicting() && floorEta < eta && floorEta >= eta / 30.0) eta = floorEta;
  return eta;
}

// The wall is predicted except when material touches it (its wall nodes then
// also enter the material rows, which the vacuum coupling K_fw leaves out)
// and with Jacobi: its response solve takes tens of CG iterations, and its
// Newton steps are limited by the smooth error an early-stopped Jacobi-CG
// leaves, not by the wall (measured at 128^3: 5-7 Newton steps either way,
// CG iterations -15% to +48% with the prediction).
bool NewtonSolver::predicting() const {
  return open_ && s_.predictWall && be_.predictsWall() && be_.wallNodeCount() > 0 && wallStrikes_ < kWallStrikes &&
         be_.materialWallClearance() >= 1 && s_.preconditioner == PreconditionerKind::Multigrid;
}

PcgResult NewtonSolver::newtonStep(NewtonIterationRecord& rec) {
  auto tp = SteadyClock::now();
  if (jacobianDeferred_) {
    // The backend still holds the Jacobian of the iterate before Phi (an
    // evaluation without the Jacobian leaves it).
    const bool afterChord = !rep_.history.empty() && rep_.history.back().chord;
    rec.chord = s_.chordAfterDeferredMiss && !afterChord && rec.relativeResidual <= kChordMiss * s_.tolerance;
    if (!rec.chord) {
      ev_ = be_.evaluate(NodeVec::Phi, NodeVec::F, true, NodeVec::Kphi);
      rec.jacobianRebuilt = true;
    }
    jacobianDeferred_ = false;
  }
  if (!rec.chord) be_.updatePreconditioner();
  rep_.multigridLevels = be_.preconditionerLevels();
  rec.secondsSetup = secondsSince(tp);
  tp = SteadyClock::now();
  be_.negate(NodeVec::F, NodeVec::Work);
  const PcgResult cg = be_.solveJacobian(NodeVec::Work, NodeVec::Delta, eta_, s_.maxCgIterations);
  rec.secondsCg = secondsSince(tp);
  rec.cgIterations = cg.iterations;
  rec.cgRelativeResidual = cg.relativeResidual;
  rep_.cgIterations += cg.iterations;
  return cg;
}

// The step changes M, which moves the wall values by dw (linearized: the
// block multipoles of dM); left alone, that move would only be seen at the
// next iteration, as the residual K_fw dw in the free rows next to the wall.
// Solving J delta_w = -K_fw dw and moving the wall by dw with the step makes
// it the step of the system with the wall coupled in. Skipped when K_fw dw
// is below the step's own CG residual, or too small to keep the next iterate
// from meeting the tolerance.
NewtonSolver::Step NewtonSolver::predictWall(NewtonIterationRecord& rec, const PcgResult& cg) {
  Step step;
  step.cg = cg;
  const bool predict = predicting();
  const double cgResidual = cg.relativeResidual * fn_;
  step.expectedResidual = open_ && !predict ? std::numeric_limits<double>::infinity() : cgResidual;
  if (!predict || cg.breakdown) return step;
  const auto tp = SteadyClock::now();
  be_.setLinearizedFarField(NodeVec::Delta, NodeVec::WallDelta);
  be_.gatherWall(NodeVec::WallDelta, WallVec::Move);
  be_.scatterWall(WallVec::Move, -1.0, NodeVec::WallDelta);
  be_.fill(NodeVec::WallRhs, 0.0);
  be_.addWallCoupling(NodeVec::WallDelta, NodeVec::WallRhs);
  const double moveNorm = be_.norm(NodeVec::WallRhs);
  step.expectedResidual = cgResidual + moveNorm;
  if (std::isfinite(moveNorm) && moveNorm > cgResidual && cgResidual + moveNorm > 0.5 * s_.tolerance * r0_) {
    const PcgResult cgw =
        be_.solveJacobian(NodeVec::WallRhs, NodeVec::WallDelta, s_.wallPredictionTolerance, s_.maxCgIterations);
    rec.wallCgIterations = cgw.iterations;
    rec.cgIterations += cgw.iterations;
    rep_.cgIterations += cgw.iterations;
    if (!cgw.breakdown) {
      be_.axpy(1.0, NodeVec::WallDelta, NodeVec::Delta);
      be_.scatterWall(WallVec::Move, 1.0, NodeVec::Delta);
      step.coupled = true;
      step.expectedResidual = cgResidual + cgw.relativeResidual * moveNorm;
    }
  }
  rec.secondsWallPrediction = secondsSince(tp);
  return step;
}

bool NewtonSolver::acceptStep(NewtonIterationRecord& rec, const Step& step) {
  const auto tp = SteadyClock::now();
  const auto linearSolverFailed = [&] {
    stop(SolveStatus::LinearSolverFailed, &rec,
         concat("CG ", step.cg.breakdown ? "broke down" : "returned a non-descent step", " at Newton iteration ",
                rec.iteration, " (", step.cg.iterations, " CG iterations, relative residual ",
                step.cg.relativeResidual, ")"));
    return false;
  };
  StepSlopes slopes = be_.formFullStep();
  if (step.cg.breakdown || (!step.coupled && !(slopes.g0 < 0))) return linearSolverFailed();

  // Full step first, evaluated with the Jacobian: when accepted (nearly
  // always) this is the next iteration's evaluation. When the CG solves of a
  // predicted-wall step left less than the tolerance, the trial nearly
  // always meets it, and its Jacobian (about half an evaluation's cost) would
  // go unused: it is deferred to the next iteration, which builds it only
  // when the tolerance was missed after all.
  const bool aimsAtTolerance = s_.deferFinalJacobian && step.expectedResidual <= s_.tolerance * r0_ &&
                               rec.iteration + 1 < s_.maxNewtonIterations;
  bool trialJacobian = !aimsAtTolerance;
  FieldEvaluation evT = be_.evaluate(NodeVec::Trial, NodeVec::Ftrial, trialJacobian, NodeVec::Ftrial);
  double lambda = 1.0;
  bool accepted = false;
  if (step.coupled) {
    accepted = acceptCoupled(rec, trialJacobian, evT);
    if (!accepted) {
      // Back to the Newton step alone, with the wall fixed.
      be_.axpy(-1.0, NodeVec::WallDelta, NodeVec::Delta);
      be_.zeroWall(NodeVec::Delta);
      slopes = be_.formFullStep();
      if (!(slopes.g0 < 0)) return linearSolverFailed();
      trialJacobian = true;
      evT = be_.evaluate(NodeVec::Trial, NodeVec::Ftrial, true, NodeVec::Ftrial);
    }
  }
  if (!accepted) accepted = lineSearch(rec, slopes, trialJacobian, evT, &lambda);
  rep_.lineSearchCuts += rec.lineSearchCuts;
  if (!accepted) {
    be_.evaluate(NodeVec::Phi, NodeVec::F, true);  // restore the state of the last iterate
    stop(SolveStatus::LineSearchFailed, &rec,
         concat("line search failed at Newton iteration ", rec.iteration, " after ", rec.lineSearchCuts,
                " cuts (relative residual ", rec.relativeResidual, ")"));
    return false;
  }
  rec.step = lambda;
  rec.secondsLineSearch = secondsSince(tp);
  return true;
}

// The step changed the wall too, so the energy of the fixed-wall problem is
// no merit for it: it is accepted when the residual with the wall updated at
// the trial point (the next iteration's) decreases.
bool NewtonSolver::acceptCoupled(NewtonIterationRecord& rec, bool trialJacobian, FieldEvaluation& evT) {
  be_.copyWall(WallVec::Prev, WallVec::PrevSaved);
  const int savedUpdates = wallUpdates_;
  double ft = std::numeric_limits<double>::infinity();
  bool accepted = false;
  if (evT.finite) {
    updateWall(NodeVec::Trial, NodeVec::Ftrial, NodeVec::Ktrial, evT);
    ft = be_.norm(NodeVec::Ftrial);
    accepted = std::isfinite(ft) && ft <= (1.0 - s_.armijo) * fn_;
  }
  // (Counted only while predicting, so it reaches kWallStrikes once.)
  if (!accepted || ft > 0.5 * fn_) ++wallStrikes_;
  if (wallStrikes_ == kWallStrikes) rep_.wallPredictionDropped = rec.wallPredictionDropped = true;
  if (accepted) {
    takeTrial(evT);
    wallCurrent_ = true;
    rec.wallPredicted = true;
    rec.residualMerit = true;
    jacobianDeferred_ = rec.jacobianDeferred = !trialJacobian;
  } else {
    be_.swapWall(WallVec::Prev, WallVec::PrevSaved);
    wallUpdates_ = savedUpdates;
  }
  return accepted;
}

// Line search on E(phi + lambda delta) - E(phi) = lambda s1 + lambda^2 s2 / 2 + dW.
bool NewtonSolver::lineSearch(NewtonIterationRecord& rec, const StepSlopes& slopes, bool trialJacobian,
                              FieldEvaluation& evT, double* lambdaOut) {
  const double g0 = slopes.g0, s1 = slopes.s1, s2 = slopes.s2;
  const double armijoSlope = s_.armijo * g0;
  // Sufficient decrease: on the energy while it resolves the step, else on
  // the residual norm (`trialNorm` = residual at the trial point).
  const auto accept = [&](double lam, double dE, double absW, const auto& trialNorm, bool* residualMerit) {
    const double noise = 64.0 * std::numeric_limits<double>::epsilon() *
                         (absW + ev_.materialEnergyAbs + std::fabs(lam * s1) + 0.5 * lam * lam * std::fabs(s2));
    if (!std::isfinite(dE)) return false;
    if (std::fabs(dE) > noise) return dE <= lam * armijoSlope;
    *residualMerit = true;
    return trialNorm() <= (1.0 - s_.armijo * lam) * fn_;
  };
  double lambda = 1.0;
  double dE = s1 + 0.5 * s2 + (evT.materialEnergy - ev_.materialEnergy);
  bool rm = false;
  bool accepted = evT.finite && accept(1.0, dE, evT.materialEnergyAbs, [&] { return be_.norm(NodeVec::Ftrial); }, &rm);
  rec.residualMerit = rm && accepted;
  if (accepted) {
    takeTrial(evT);
    jacobianDeferred_ = rec.jacobianDeferred = !trialJacobian;
    *lambdaOut = lambda;
    return true;
  }
  for (int cut = 1; cut <= s_.maxLineSearchCuts && !accepted; ++cut) {
    lambda = backtrackedStep(dE, g0, lambda);
    ++rec.lineSearchCuts;
    double absW = 0;
    const double Wl = be_.materialEnergyAlong(NodeVec::Phi, NodeVec::Delta, lambda, &absW);
    dE = lambda * s1 + 0.5 * lambda * lambda * s2 + (Wl - ev_.materialEnergy);
    rm = false;
    accepted = accept(lambda, dE, absW, [&] {
      be_.formTrialAlong(lambda);
      const FieldEvaluation e = be_.evaluate(NodeVec::Trial, NodeVec::Ftrial, false);
      return e.finite ? be_.norm(NodeVec::Ftrial) : std::numeric_limits<double>::infinity();
    }, &rm);
    rec.residualMerit = rm && accepted;
  }
  if (accepted) {
    be_.advance(lambda);
    if (project_) be_.removeMean(NodeVec::Phi);  // a constant shift: K phi is unchanged (rows sum to 0)
    ev_ = be_.evaluate(NodeVec::Phi, NodeVec::F, true, NodeVec::Kphi);
  }
  *lambdaOut = lambda;
  return accepted;
}

bool NewtonSolver::endIteration(NewtonIterationRecord& rec) {
  prevNorm_ = fn_;
  prevEta_ = eta_;
  ++rep_.newtonIterations;
  rec.seconds = secondsSince(iterationStart_);
  rep_.history.push_back(rec);
  if (progress_ && !progress_(rec)) {
    stop(SolveStatus::Cancelled, nullptr, concat("cancelled after ", rep_.newtonIterations, " Newton iterations"));
    return false;
  }
  return true;
}

// Moves the wall values of p to the far field of e's magnetization, and K p
// and the residual f with them.
void NewtonSolver::updateWall(NodeVec p, NodeVec f, NodeVec k, FieldEvaluation& e) {
  be_.gatherWall(p, WallVec::Old);
  be_.setFarField(e, p);
  be_.wallDifference(p, WallVec::Old, WallVec::Step);
  // Successive wall steps d_k shrink by rho = <d_k, d_k-1>/|d_k-1|^2 (|rho|
  // ~ 0.05 normally). A strongly magnetizable body (chi0 ~ 100) can make them
  // oscillate (rho < -1) and diverge; relaxing the step by 1/(1 - rho)
  // restores the contraction.
  if (wallUpdates_ >= 1) {
    const double dd = be_.wallDot(WallVec::Step, WallVec::Prev);
    const double pp = be_.wallDot(WallVec::Prev, WallVec::Prev);
    const double rho = pp > 0 ? dd / pp : 0.0;
    if (rho < -0.5) be_.relaxWall(p, WallVec::Step, std::clamp(1.0 / (1.0 - rho), 0.05, 1.0));
  }
  ++wallUpdates_;
  be_.copyWall(WallVec::Step, WallVec::Prev);
  // The wall values enter K p only in the free rows next to the wall.
  be_.scatterWall(WallVec::Step, 1.0, NodeVec::WallRhs);
  be_.addWallCoupling(NodeVec::WallRhs, k);
  // When no material cell touches the wall they enter the residual only
  // through the vacuum stencil: f is corrected instead of re-evaluated.
  if (be_.materialWallClearance() >= 1) {
    be_.addWallCoupling(NodeVec::WallRhs, f);
  } else {
    e = be_.evaluate(p, f, true, k);
  }
}

// The trial point becomes the iterate, its evaluation the next iteration's.
void NewtonSolver::takeTrial(FieldEvaluation& evT) {
  be_.swap(NodeVec::Phi, NodeVec::Trial);
  be_.swap(NodeVec::F, NodeVec::Ftrial);
  be_.swap(NodeVec::Kphi, NodeVec::Ktrial);
  ev_ = std::move(evT);
}

void NewtonSolver::stop(SolveStatus status, const NewtonIterationRecord* rec, std::string message) {
  rep_.status = status;
  rep_.message = std::move(message);
  if (rec) rep_.history.push_back(*rec);
}

FieldSolveReport NewtonSolver::finish() {
  rep_.seconds = secondsSince(t0_);
  return std::move(rep_);
}

}  // namespace field
}  // namespace lodestone
