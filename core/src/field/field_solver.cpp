#include "lodestone/core/field/field_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lodestone/core/base/error.h"
#include "lodestone/core/field/line_search.h"
#include "lodestone/core/base/parallel.h"

namespace lodestone {

namespace {
using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}
template <typename Fn>
void forEach(std::size_t n, const Fn& fn) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 13), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t m = r.begin(); m != r.end(); ++m) fn(m);
  });
}
double norm(const std::vector<double>& v) { return std::sqrt(deterministicDot(v.data(), v.data(), v.size())); }

std::unique_ptr<Preconditioner> makePreconditioner(const FieldSolveSettings& settings) {
  switch (settings.preconditioner) {
    case PreconditionerKind::Jacobi: return std::make_unique<JacobiPreconditioner>();
    case PreconditionerKind::Multigrid: return std::make_unique<MultigridPreconditioner>(settings.multigrid);
  }
  throw InvalidArgument(concat("field solve: unknown preconditioner ", int(settings.preconditioner)));
}
}  // namespace

const char* toString(PreconditionerKind kind) {
  switch (kind) {
    case PreconditionerKind::Jacobi: return "jacobi";
    case PreconditionerKind::Multigrid: return "multigrid";
  }
  return "unknown";
}

const char* toString(SolveStatus status) {
  switch (status) {
    case SolveStatus::Converged: return "converged";
    case SolveStatus::Trivial: return "trivial";
    case SolveStatus::IterationCap: return "iteration-cap";
    case SolveStatus::LineSearchFailed: return "line-search-failed";
    case SolveStatus::LinearSolverFailed: return "linear-solver-failed";
    case SolveStatus::NonFinite: return "non-finite";
    case SolveStatus::Cancelled: return "cancelled";
  }
  return "unknown";
}

void FieldSolveSettings::validate() const {
  require(std::isfinite(tolerance) && tolerance > 0 && tolerance < 1,
          "field solve: tolerance must be in (0, 1), got ", tolerance);
  require(maxNewtonIterations >= 1, "field solve: maxNewtonIterations must be >= 1, got ", maxNewtonIterations);
  require(maxCgIterations >= 1, "field solve: maxCgIterations must be >= 1, got ", maxCgIterations);
  require(std::isfinite(forcingMax) && forcingMax > 0 && forcingMax < 1,
          "field solve: forcingMax must be in (0, 1), got ", forcingMax);
  require(std::isfinite(forcingGamma) && forcingGamma > 0 && forcingGamma <= 1,
          "field solve: forcingGamma must be in (0, 1], got ", forcingGamma);
  require(std::isfinite(forcingAlpha) && forcingAlpha > 1 && forcingAlpha <= 2,
          "field solve: forcingAlpha must be in (1, 2], got ", forcingAlpha);
  require(maxLineSearchCuts >= 1, "field solve: maxLineSearchCuts must be >= 1, got ", maxLineSearchCuts);
  require(std::isfinite(armijo) && armijo > 0 && armijo < 0.5, "field solve: armijo must be in (0, 0.5), got ",
          armijo);
  require(preconditioner == PreconditionerKind::Jacobi || preconditioner == PreconditionerKind::Multigrid,
          "field solve: unknown preconditioner ", int(preconditioner));
  require(std::isfinite(wallPredictionTolerance) && wallPredictionTolerance > 0 && wallPredictionTolerance < 1,
          "field solve: wallPredictionTolerance must be in (0, 1), got ", wallPredictionTolerance);
  multigrid.validate();
}

FieldSolveReport solveField(MagnetostaticProblem& problem, std::vector<double>& phi,
                            const FieldSolveSettings& settings, const SolveProgress& progress,
                            FieldSolveWorkspace* workspace) {
  settings.validate();
  const auto t0 = Clock::now();
  const std::size_t n = problem.nodeCount();
  FieldSolveReport rep;
  rep.materialCells = problem.materialCellCount();
  rep.preconditioner = toString(settings.preconditioner);
  if (phi.size() != n) phi.assign(n, 0.0);
  bool cold = true;
  for (double& v : phi) {
    if (!std::isfinite(v)) {
      std::fill(phi.begin(), phi.end(), 0.0);  // a poisoned warm start is discarded
      cold = true;
      break;
    }
    cold = cold && v == 0.0;
  }

  FieldSolveWorkspace localWorkspace;
  FieldSolveWorkspace& ws = workspace ? *workspace : localWorkspace;
  // Every vector is fully written before it is read: resizing a kept
  // workspace needs no clearing.
  for (auto* v : {&ws.F, &ws.Fref, &ws.delta, &ws.work, &ws.trial, &ws.Ftrial, &ws.Kphi, &ws.Kdelta, &ws.Ktrial,
                  &ws.wallRhs, &ws.wallDelta})
    v->resize(n);
  std::vector<double>&F = ws.F, &Fref = ws.Fref, &delta = ws.delta, &work = ws.work, &trial = ws.trial,
  &lastGood = ws.lastGood, &Ftrial = ws.Ftrial, &Kphi = ws.Kphi, &Kdelta = ws.Kdelta, &Ktrial = ws.Ktrial;
  PcgWorkspace& pcgWork = ws.pcg;
  // The reference residual is F at phi = 0. From a cold start that is the
  // first evaluation itself (K phi = 0), which then also serves the first
  // iteration; a warm start evaluates the material part at phi = 0 alone.
  MagnetostaticProblem::Evaluation ev;
  if (cold) {
    std::fill(Kphi.begin(), Kphi.end(), 0.0);
    ev = problem.evaluate(phi.data(), F.data(), true, Kphi.data());
    rep.referenceResidual = ev.finite ? norm(F) : std::numeric_limits<double>::quiet_NaN();
  } else {
    problem.residualAtZero(Fref.data());
    rep.referenceResidual = norm(Fref);
  }
  if (!std::isfinite(rep.referenceResidual)) {
    rep.status = SolveStatus::NonFinite;
    rep.message = "the magnetization of the applied field is not finite";
    rep.seconds = secondsSince(t0);
    return rep;
  }
  if (!(rep.referenceResidual > 0)) {
    std::fill(phi.begin(), phi.end(), 0.0);
    rep.status = SolveStatus::Trivial;
    rep.message = problem.materialCellCount() == 0 ? "no magnetic material: H = H_ext"
                                                   : "the applied field magnetizes nothing: H = H_ext";
    rep.seconds = secondsSince(t0);
    return rep;
  }
  const double r0 = rep.referenceResidual;
  const bool linear = problem.law().kind == LawKind::Linear;
  const auto sameMultigrid = [](const MultigridSettings& a, const MultigridSettings& b) {
    return a.preSmoothing == b.preSmoothing && a.postSmoothing == b.postSmoothing &&
           a.jacobiWeight == b.jacobiWeight && a.coarsestNodes == b.coarsestNodes &&
           a.singlePrecision == b.singlePrecision;
  };
  if (!ws.preconditioner || ws.kind != settings.preconditioner ||
      (settings.preconditioner == PreconditionerKind::Multigrid && !sameMultigrid(ws.multigrid, settings.multigrid))) {
    ws.preconditioner = makePreconditioner(settings);
    ws.kind = settings.preconditioner;
    ws.multigrid = settings.multigrid;
  }
  Preconditioner* pre = ws.preconditioner.get();
  const auto applyJ = [&](const double* v, double* out) { problem.applyJacobian(v, out); };
  const auto applyJDot = [&](const double* v, double* out) { return problem.applyJacobianDot(v, out); };
  std::function<void(double*)> project;
  if (problem.boundary() == BoundaryKind::Shield) project = [&](double* v) { problem.removeMean(v); };

  double prevNorm = 0, prevEta = settings.forcingMax;
  lastGood = phi;
  // K phi (the vacuum part of F) is kept up to date through every change of
  // phi (Newton steps: + lambda K delta; wall updates: the wall layer only),
  // so the stencil is applied once per Newton iteration (to delta) instead of
  // once for the line search and once more in each evaluation.
  if (!cold) problem.applyVacuum(phi.data(), Kphi.data());
  const bool open = problem.boundary() == BoundaryKind::Open;
  const std::vector<std::size_t> wall = problem.fixedNodes();
  std::vector<double> wallOld(wall.size()), wallStep(wall.size()), wallPrev(wall.size(), 0.0),
      wallPrevSaved(wall.size()), wallMove(wall.size());
  int wallUpdates = 0;
  const auto forWall = [&](const auto& fn) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, wall.size(), 1 << 12),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t w = r.begin(); w != r.end(); ++w) fn(w);
                      });
  };
  std::vector<double>&wallRhs = ws.wallRhs, &wallDelta = ws.wallDelta;
  // Moves the wall values of p to the far field of e's magnetization, and
  // K p and the residual Fp with them.
  const auto updateWall = [&](std::vector<double>& p, std::vector<double>& Fp, std::vector<double>& Kp,
                              MagnetostaticProblem::Evaluation& e) {
    forWall([&](std::size_t w) { wallOld[w] = p[wall[w]]; });
    problem.applyOpenBoundary(e.multipoles, p.data());
    forWall([&](std::size_t w) { wallStep[w] = p[wall[w]] - wallOld[w]; });
    // Successive wall steps d_k shrink by rho = <d_k, d_k-1>/|d_k-1|^2
    // (|rho| ~ 0.05 normally). A strongly magnetizable body (chi0 ~ 100)
    // can make them oscillate (rho < -1) and diverge; relaxing the step by
    // 1/(1 - rho) restores the contraction.
    if (wallUpdates >= 1) {
      const double dd = deterministicDot(wallStep.data(), wallPrev.data(), wall.size());
      const double pp = deterministicDot(wallPrev.data(), wallPrev.data(), wall.size());
      const double rho = pp > 0 ? dd / pp : 0.0;
      if (rho < -0.5) {
        const double theta = std::clamp(1.0 / (1.0 - rho), 0.05, 1.0);
        forWall([&](std::size_t w) {
          p[wall[w]] -= (1.0 - theta) * wallStep[w];
          wallStep[w] *= theta;
        });
      }
    }
    ++wallUpdates;
    wallPrev = wallStep;
    // The wall values enter K p only in the free rows next to the wall.
    forWall([&](std::size_t w) { wallRhs[wall[w]] = wallStep[w]; });
    problem.addWallCoupling(wallRhs.data(), Kp.data());
    // When no material cell touches the wall they enter the residual only
    // through the vacuum stencil: Fp is corrected instead of re-evaluated.
    if (problem.materialWallClearance() >= 1) {
      problem.addWallCoupling(wallRhs.data(), Fp.data());
    } else {
      e = problem.evaluate(p.data(), Fp.data(), true, Kp.data());
    }
  };
  // The slope g0 = delta . F and the line search's s1 = delta . K phi and
  // s2 = delta . K delta, in one pass over the vectors that also forms the
  // full step's trial point, its K phi and the vacuum part of its residual
  // (the evaluation adds the material part to Ftrial in place).
  struct Slopes {
    double g0 = 0, s1 = 0, s2 = 0;
    Slopes& operator+=(const Slopes& o) {
      g0 += o.g0;
      s1 += o.s1;
      s2 += o.s2;
      return *this;
    }
  };
  const auto formTrial = [&]() {
    problem.applyVacuum(delta.data(), Kdelta.data());
    return deterministicSum<Slopes>(n, [&](std::size_t m) {
      const double d = delta[m], kd = Kdelta[m], kp = Kphi[m];
      trial[m] = phi[m] + d;
      Ftrial[m] = Ktrial[m] = kp + kd;
      return Slopes{d * F[m], d * kp, d * kd};
    });
  };
  // Each iteration starts from an evaluation at phi (residual, energy, the
  // Jacobian's element matrices): the first here, later ones are the
  // accepted line-search trial.
  if (!cold) ev = problem.evaluate(phi.data(), F.data(), true, Kphi.data());
  rep.secondsInitial = secondsSince(t0);
  // The wall of phi already holds the far field of ev's magnetization (a
  // step that predicted the wall updated it at the trial point).
  bool wallCurrent = false;
  // ev's element matrices were not built (see aimsAtTolerance below).
  bool jacobianDeferred = false;
  // Predicted-wall steps that did not help: rejected, or accepted with less
  // than half of the residual removed. Near the wall, a strongly
  // magnetizable body (chi0 ~ 10-100, 2-3 cells of clearance) makes the
  // linearized wall move a poor guess: such steps were accepted at 0.5-0.7
  // reduction each and the solve crawled (40 Newton steps without
  // converging where the lagging wall took 16). After kWallStrikes of them
  // the wall lags for the rest of the solve.
  constexpr int kWallStrikes = 2;
  int wallStrikes = 0;
  for (int it = 0;; ++it) {
    const auto ti = Clock::now();
    double secondsWall = 0;
    if (open && ev.finite && !wallCurrent) {
      // Far-field values from the magnetization just evaluated.
      updateWall(phi, F, Kphi, ev);
      secondsWall = secondsSince(ti);
    }
    wallCurrent = false;
    const double fn = norm(F);
    NewtonIterationRecord rec;
    rec.iteration = it;
    rec.secondsWall = secondsWall;
    rec.relativeResidual = fn / r0;
    rep.relativeResidual = rec.relativeResidual;
    rep.materialEnergy = ev.materialEnergy;
    if (!ev.finite || !std::isfinite(fn)) {
      phi = lastGood;
      rep.status = SolveStatus::NonFinite;
      rep.message = concat("non-finite magnetization or residual at Newton iteration ", it);
      break;
    }
    lastGood = phi;
    if (rec.relativeResidual <= settings.tolerance) {
      rep.status = SolveStatus::Converged;
      rep.history.push_back(rec);
      rep.message = concat("converged in ", it, " Newton iterations (", rep.cgIterations, " CG) to relative residual ",
                           rec.relativeResidual);
      break;
    }
    if (it >= settings.maxNewtonIterations) {
      rep.status = SolveStatus::IterationCap;
      rep.history.push_back(rec);
      rep.message = concat("not converged: Newton iteration cap ", settings.maxNewtonIterations,
                           " reached at relative residual ", rec.relativeResidual, " (tolerance ",
                           settings.tolerance, ")");
      break;
    }

    // Inner tolerance: Eisenstat-Walker choice 2 with safeguards, never
    // tighter than needed to reach the outer tolerance.
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
    // When the open wall lags behind M (predictWall off, or a prediction
    // that missed), one Newton step cannot reduce the residual much below
    // that lag: it shows as a reduction far short of the step's forcing.
    // Solving the inner system beyond a tenth of it only adds CG
    // iterations. Only with multigrid: a Jacobi-preconditioned CG stopped
    // early leaves the smooth error almost untouched, so its residual
    // overstates the step's quality (the linear law then took 12 Newton
    // steps instead of 6).
    if (open && settings.preconditioner == PreconditionerKind::Multigrid) {
      if (it > 0) {
        const double achieved = fn / prevNorm;
        if (achieved > 10.0 * prevEta) eta = std::max(eta, std::min(settings.forcingMax, 0.1 * achieved));
      } else if (linear) {
        eta = std::max(eta, 0.1 * settings.forcingMax);
      }
    }
    eta = std::max(eta, floorEta);
    // The wall is predicted (below) except when material touches it (its
    // wall nodes then also enter the material rows, which the vacuum
    // coupling K_fw leaves out) and with Jacobi: its response solve takes
    // tens of CG iterations, and its Newton steps are limited by the smooth
    // error an early-stopped Jacobi-CG leaves, not by the wall (measured at
    // 128^3: 5-7 Newton steps either way, CG iterations -15% to +48% with
    // the prediction).
    const bool predicting = open && settings.predictWall && !wall.empty() && wallStrikes < kWallStrikes &&
                            problem.materialWallClearance() >= 1 &&
                            settings.preconditioner == PreconditionerKind::Multigrid;
    // With the wall predicted, a step reduces the residual by about its
    // forcing, so when the forcing that reaches the tolerance in this step
    // is within 30x of eta (one or two more CG iterations with multigrid),
    // that is cheaper than another Newton step.
    if (predicting && floorEta < eta && floorEta >= eta / 30.0) eta = floorEta;
    rec.forcing = eta;

    // Newton step.
    auto tp = Clock::now();
    if (jacobianDeferred) {
      ev = problem.evaluate(phi.data(), F.data(), true, Kphi.data());
      jacobianDeferred = false;
      rec.jacobianRebuilt = true;
    }
    pre->update(problem);
    rec.secondsSetup = secondsSince(tp);
    tp = Clock::now();
    forEach(n, [&](std::size_t m) { work[m] = -F[m]; });
    const PcgResult cg = solvePcg(n, applyJ, *pre, work.data(), delta.data(), eta, settings.maxCgIterations, project,
                                  &pcgWork, applyJDot);
    rec.secondsCg = secondsSince(tp);
    rec.cgIterations = cg.iterations;
    rec.cgRelativeResidual = cg.relativeResidual;
    rep.cgIterations += cg.iterations;

    // Wall prediction: the step changes M, which moves the wall values by
    // dw (linearized: the block multipoles of dM); left alone, that move
    // would only be seen at the next iteration, as the residual K_fw dw in
    // the free rows next to the wall. Solving J delta_w = -K_fw dw and
    // moving the wall by dw with the step makes it the step of the system
    // with the wall coupled in. Skipped when K_fw dw is below the step's
    // own CG residual, or too small to keep the next iterate from meeting
    // the tolerance.
    bool coupled = false;
    // The residual the step leaves if the linearization is exact (used to
    // guess whether the trial will converge): what the CG solves left, plus
    // the wall's move when it is not predicted. Unknown when the wall lags.
    double expectedResidual = open && !predicting ? std::numeric_limits<double>::infinity()
                                                  : cg.relativeResidual * fn;
    if (predicting && !cg.breakdown) {
      tp = Clock::now();
      problem.applyOpenBoundary(problem.linearizedMultipoles(delta.data()), wallDelta.data());
      forWall([&](std::size_t w) {
        wallMove[w] = wallDelta[wall[w]];
        wallDelta[wall[w]] = -wallMove[w];
      });
      forEach(n, [&](std::size_t m) { wallRhs[m] = 0.0; });
      problem.addWallCoupling(wallDelta.data(), wallRhs.data());
      const double moveNorm = norm(wallRhs);
      const double cgResidual = cg.relativeResidual * fn;
      expectedResidual = cgResidual + moveNorm;
      if (std::isfinite(moveNorm) && moveNorm > cgResidual && cgResidual + moveNorm > 0.5 * settings.tolerance * r0) {
        const PcgResult cgw = solvePcg(n, applyJ, *pre, wallRhs.data(), wallDelta.data(),
                                       settings.wallPredictionTolerance, settings.maxCgIterations, project, &pcgWork,
                                       applyJDot);
        rec.wallCgIterations = cgw.iterations;
        rec.cgIterations += cgw.iterations;
        rep.cgIterations += cgw.iterations;
        if (!cgw.breakdown) {
          forEach(n, [&](std::size_t m) { delta[m] += wallDelta[m]; });
          forWall([&](std::size_t w) { delta[wall[w]] = wallMove[w]; });
          coupled = true;
          expectedResidual = cgResidual + cgw.relativeResidual * moveNorm;
        }
      }
      rec.secondsWallPrediction = secondsSince(tp);
    }
    tp = Clock::now();
    const auto linearSolverFailed = [&] {
      rep.status = SolveStatus::LinearSolverFailed;
      rep.history.push_back(rec);
      rep.message = concat("CG ", cg.breakdown ? "broke down" : "returned a non-descent step", " at Newton iteration ",
                           it, " (", cg.iterations, " CG iterations, relative residual ", cg.relativeResidual, ")");
    };
    // The trial point becomes the iterate, its evaluation the next iteration's.
    const auto takeTrial = [&](MagnetostaticProblem::Evaluation& e) {
      phi.swap(trial);
      F.swap(Ftrial);
      Kphi.swap(Ktrial);
      ev = std::move(e);
    };
    Slopes slopes = formTrial();
    if (cg.breakdown || (!coupled && !(slopes.g0 < 0))) {
      linearSolverFailed();
      break;
    }

    // Full step first, evaluated with the Jacobian: when accepted (nearly
    // always) this is the next iteration's evaluation. When the CG solves
    // of a predicted-wall step left less than the tolerance, the trial
    // nearly always meets it, and its Jacobian (about half an evaluation's
    // cost) would go unused: it is deferred to the next iteration, which
    // builds it only when the tolerance was missed after all.
    double lambda = 1.0;
    bool accepted = false;
    const bool aimsAtTolerance = settings.deferFinalJacobian && expectedResidual <= settings.tolerance * r0 &&
                                 it + 1 < settings.maxNewtonIterations;
    bool trialJacobian = !aimsAtTolerance;
    MagnetostaticProblem::Evaluation evT =
        problem.evaluate(trial.data(), Ftrial.data(), trialJacobian, Ftrial.data());
    if (coupled) {
      // The step changed the wall too, so the energy of the fixed-wall
      // problem is no merit for it: it is accepted when the residual with
      // the wall updated at the trial point (the next iteration's) decreases.
      wallPrevSaved = wallPrev;
      const int savedUpdates = wallUpdates;
      double ft = std::numeric_limits<double>::infinity();
      if (evT.finite) {
        updateWall(trial, Ftrial, Ktrial, evT);
        ft = norm(Ftrial);
        accepted = std::isfinite(ft) && ft <= (1.0 - settings.armijo) * fn;
      }
      // (Counted only while predicting, so it reaches kWallStrikes once.)
      if (!accepted || ft > 0.5 * fn) ++wallStrikes;
      if (wallStrikes == kWallStrikes) rep.wallPredictionDropped = rec.wallPredictionDropped = true;
      if (accepted) {
        takeTrial(evT);
        wallCurrent = true;
        rec.wallPredicted = true;
        rec.residualMerit = true;
        jacobianDeferred = rec.jacobianDeferred = !trialJacobian;
      } else {
        // Back to the Newton step alone, with the wall fixed.
        wallPrev.swap(wallPrevSaved);
        wallUpdates = savedUpdates;
        forEach(n, [&](std::size_t m) { delta[m] -= wallDelta[m]; });
        forWall([&](std::size_t w) { delta[wall[w]] = 0.0; });
        slopes = formTrial();
        if (!(slopes.g0 < 0)) {
          linearSolverFailed();
          break;
        }
        trialJacobian = true;
        evT = problem.evaluate(trial.data(), Ftrial.data(), true, Ftrial.data());
      }
    }
    if (!accepted) {
      // Line search on E(phi + lambda delta) - E(phi) = lambda s1 + lambda^2 s2 / 2 + dW.
      const double g0 = slopes.g0, s1 = slopes.s1, s2 = slopes.s2;
      const double armijoSlope = settings.armijo * g0;
      // Sufficient decrease: on the energy while it resolves the step, else on
      // the residual norm (`Ft` = residual at the trial point).
      const auto accept = [&](double lam, double dE, double absW, const std::function<double()>& trialNorm,
                              bool* residualMerit) {
        const double noise = 64.0 * std::numeric_limits<double>::epsilon() *
                             (absW + ev.materialEnergyAbs + std::fabs(lam * s1) + 0.5 * lam * lam * std::fabs(s2));
        if (!std::isfinite(dE)) return false;
        if (std::fabs(dE) > noise) return dE <= lam * armijoSlope;
        *residualMerit = true;
        return trialNorm() <= (1.0 - settings.armijo * lam) * fn;
      };
      double dE = s1 + 0.5 * s2 + (evT.materialEnergy - ev.materialEnergy);
      {
        bool rm = false;
        accepted = evT.finite && accept(1.0, dE, evT.materialEnergyAbs, [&] { return norm(Ftrial); }, &rm);
        rec.residualMerit = rm && accepted;
      }
      if (accepted) {
        takeTrial(evT);
        jacobianDeferred = rec.jacobianDeferred = !trialJacobian;
      } else {
        for (int cut = 1; cut <= settings.maxLineSearchCuts && !accepted; ++cut) {
          lambda = backtrackedStep(dE, g0, lambda);
          ++rec.lineSearchCuts;
          double absW = 0;
          const double Wl = problem.materialEnergyAlong(phi.data(), delta.data(), lambda, &absW);
          dE = lambda * s1 + 0.5 * lambda * lambda * s2 + (Wl - ev.materialEnergy);
          bool rm = false;
          accepted = accept(lambda, dE, absW, [&] {
            forEach(n, [&](std::size_t m) { trial[m] = phi[m] + lambda * delta[m]; });
            const auto e = problem.evaluate(trial.data(), Ftrial.data(), false);
            return e.finite ? norm(Ftrial) : std::numeric_limits<double>::infinity();
          }, &rm);
          rec.residualMerit = rm && accepted;
        }
        if (accepted) {
          forEach(n, [&](std::size_t m) {
            phi[m] += lambda * delta[m];
            Kphi[m] += lambda * Kdelta[m];
          });
          if (project) project(phi.data());  // a constant shift: K phi is unchanged (rows sum to 0)
          ev = problem.evaluate(phi.data(), F.data(), true, Kphi.data());
        }
      }
    }
    rep.lineSearchCuts += rec.lineSearchCuts;
    if (!accepted) {
      problem.evaluate(phi.data(), F.data());  // restore the state of the last iterate
      rep.status = SolveStatus::LineSearchFailed;
      rep.history.push_back(rec);
      rep.message = concat("line search failed at Newton iteration ", it, " after ", rec.lineSearchCuts,
                           " cuts (relative residual ", rec.relativeResidual, ")");
      break;
    }
    rec.step = lambda;
    rec.secondsLineSearch = secondsSince(tp);
    prevNorm = fn;
    prevEta = eta;
    ++rep.newtonIterations;
    rec.seconds = secondsSince(ti);
    rep.history.push_back(rec);
    if (progress && !progress(rec)) {
      rep.status = SolveStatus::Cancelled;
      rep.message = concat("cancelled after ", rep.newtonIterations, " Newton iterations");
      break;
    }
  }
  rep.seconds = secondsSince(t0);
  return rep;
}

}  // namespace lodestone
