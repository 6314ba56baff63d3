#include "lodestone/core/field_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lodestone/core/error.h"
#include "lodestone/core/parallel.h"

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
  for (auto* v : {&ws.F, &ws.Fref, &ws.delta, &ws.work, &ws.trial, &ws.Ftrial, &ws.Kphi, &ws.Kdelta, &ws.Ktrial})
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
  std::vector<double> wallOld(wall.size()), wallStep(wall.size()), wallPrev(wall.size(), 0.0);
  const auto forWall = [&](const auto& fn) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, wall.size(), 1 << 12),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t w = r.begin(); w != r.end(); ++w) fn(w);
                      });
  };
  // Each iteration starts from an evaluation at phi (residual, energy, the
  // Jacobian's element matrices): the first here, later ones are the
  // accepted line-search trial.
  if (!cold) ev = problem.evaluate(phi.data(), F.data(), true, Kphi.data());
  rep.secondsInitial = secondsSince(t0);
  for (int it = 0;; ++it) {
    const auto ti = Clock::now();
    double secondsWall = 0;
    if (open && ev.finite) {
      // Far-field values from the magnetization just evaluated.
      forWall([&](std::size_t w) { wallOld[w] = phi[wall[w]]; });
      problem.applyOpenBoundary(ev.multipoles, phi.data());
      forWall([&](std::size_t w) { wallStep[w] = phi[wall[w]] - wallOld[w]; });
      // The wall values follow M one iteration late: a fixed-point
      // iteration whose steps d_k shrink by rho = <d_k, d_k-1>/|d_k-1|^2
      // per iteration (|rho| ~ 0.05 normally). A strongly magnetizable
      // body (chi0 ~ 100) makes it oscillate (rho < -1) and diverge;
      // relaxing the step by 1/(1 - rho) restores the contraction.
      if (it >= 1) {
        const double dd = deterministicDot(wallStep.data(), wallPrev.data(), wall.size());
        const double pp = deterministicDot(wallPrev.data(), wallPrev.data(), wall.size());
        const double rho = pp > 0 ? dd / pp : 0.0;
        if (rho < -0.5) {
          const double theta = std::clamp(1.0 / (1.0 - rho), 0.05, 1.0);
          forWall([&](std::size_t w) {
            phi[wall[w]] -= (1.0 - theta) * wallStep[w];
            wallStep[w] *= theta;
          });
        }
      }
      wallPrev = wallStep;
      // The wall values enter K phi only in the free rows next to the wall.
      forWall([&](std::size_t w) { delta[wall[w]] = wallStep[w]; });
      problem.addWallCoupling(delta.data(), Kphi.data());
      // When no material cell touches the wall they enter the residual only
      // through the vacuum stencil: F is corrected instead of re-evaluated.
      if (problem.materialWallClearance() >= 1) {
        problem.addWallCoupling(delta.data(), F.data());
      } else {
        ev = problem.evaluate(phi.data(), F.data(), true, Kphi.data());
      }
      secondsWall = secondsSince(ti);
    }
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
    // With the open wall the wall values follow M one iteration behind, so
    // one Newton step cannot reduce the residual much below that lag (about
    // 0.01 per step at 32 free cells): it shows as a reduction far short of
    // the step's forcing. Solving the inner system beyond a tenth of it only
    // adds CG iterations (measured: Newton counts unchanged, CG -5..-10% for
    // Langevin, -35..-45% for the linear law, whose first step would
    // otherwise be solved to the final tolerance). Only with multigrid: a
    // Jacobi-preconditioned CG stopped early leaves the smooth error almost
    // untouched, so its residual overstates the step's quality (the linear
    // law then took 12 Newton steps instead of 6).
    if (open && settings.preconditioner == PreconditionerKind::Multigrid) {
      if (it > 0) {
        const double achieved = fn / prevNorm;
        if (achieved > 10.0 * prevEta) eta = std::max(eta, std::min(settings.forcingMax, 0.1 * achieved));
      } else if (linear) {
        eta = std::max(eta, 0.1 * settings.forcingMax);
      }
    }
    eta = std::max(eta, floorEta);
    rec.forcing = eta;

    // Newton step.
    auto tp = Clock::now();
    pre->update(problem);
    rec.secondsSetup = secondsSince(tp);
    tp = Clock::now();
    forEach(n, [&](std::size_t m) { work[m] = -F[m]; });
    const PcgResult cg = solvePcg(n, applyJ, *pre, work.data(), delta.data(), eta, settings.maxCgIterations, project,
                                  &pcgWork, applyJDot);
    rec.secondsCg = secondsSince(tp);
    tp = Clock::now();
    rec.cgIterations = cg.iterations;
    rec.cgRelativeResidual = cg.relativeResidual;
    rep.cgIterations += cg.iterations;
    // The slope g0 = delta . F and the line search's s1 = delta . K phi and
    // s2 = delta . K delta, in one pass over the vectors that also forms the
    // full step's trial point, its K phi and the vacuum part of its residual
    // (the evaluation below adds the material part to Ftrial in place).
    problem.applyVacuum(delta.data(), Kdelta.data());
    struct Slopes {
      double g0 = 0, s1 = 0, s2 = 0;
      Slopes& operator+=(const Slopes& o) {
        g0 += o.g0;
        s1 += o.s1;
        s2 += o.s2;
        return *this;
      }
    };
    const Slopes slopes = deterministicSum<Slopes>(n, [&](std::size_t m) {
      const double d = delta[m], kd = Kdelta[m], kp = Kphi[m];
      trial[m] = phi[m] + d;
      Ftrial[m] = Ktrial[m] = kp + kd;
      return Slopes{d * F[m], d * kp, d * kd};
    });
    const double g0 = slopes.g0;
    if (cg.breakdown || !(g0 < 0)) {
      rep.status = SolveStatus::LinearSolverFailed;
      rep.history.push_back(rec);
      rep.message = concat("CG ", cg.breakdown ? "broke down" : "returned a non-descent step", " at Newton iteration ",
                           it, " (", cg.iterations, " CG iterations, relative residual ", cg.relativeResidual, ")");
      break;
    }

    // Line search on E(phi + lambda delta) - E(phi) = lambda s1 + lambda^2 s2 / 2 + dW.
    const double s1 = slopes.s1, s2 = slopes.s2;
    const double armijoSlope = settings.armijo * g0;
    // Sufficient decrease: on the energy while it resolves the step, else on
    // the residual norm (`Ft` = residual at the trial point).
    const auto accept = [&](double lambda, double dE, double absW, const std::function<double()>& trialNorm,
                            bool* residualMerit) {
      const double noise = 64.0 * std::numeric_limits<double>::epsilon() *
                           (absW + ev.materialEnergyAbs + std::fabs(lambda * s1) + 0.5 * lambda * lambda * std::fabs(s2));
      if (!std::isfinite(dE)) return false;
      if (std::fabs(dE) > noise) return dE <= lambda * armijoSlope;
      *residualMerit = true;
      return trialNorm() <= (1.0 - settings.armijo * lambda) * fn;
    };
    // Full step first, evaluated with the Jacobian: when accepted (nearly
    // always) this is the next iteration's evaluation.
    double lambda = 1.0;
    bool accepted = false;
    MagnetostaticProblem::Evaluation evT = problem.evaluate(trial.data(), Ftrial.data(), true, Ftrial.data());
    double dE = s1 + 0.5 * s2 + (evT.materialEnergy - ev.materialEnergy);
    {
      bool rm = false;
      accepted = evT.finite && accept(1.0, dE, evT.materialEnergyAbs, [&] { return norm(Ftrial); }, &rm);
      rec.residualMerit = rm && accepted;
    }
    if (accepted) {
      phi.swap(trial);
      F.swap(Ftrial);
      Kphi.swap(Ktrial);
      ev = std::move(evT);
    } else {
      for (int cut = 1; cut <= settings.maxLineSearchCuts && !accepted; ++cut) {
        // Safeguarded quadratic backtracking.
        double next = 0.5 * lambda;
        if (std::isfinite(dE)) {
          const double denom = 2.0 * (dE - g0 * lambda);
          if (denom > 0) next = -g0 * lambda * lambda / denom;
        }
        lambda = std::clamp(next, 0.1 * lambda, 0.5 * lambda);
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
