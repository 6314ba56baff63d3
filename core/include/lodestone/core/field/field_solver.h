#pragma once
// Newton-PCG solve of the nonlinear magnetostatic problem (Algorithm 1 of the
// paper, with the decisions of docs/physics.md): warm start, inexact Newton
// with Eisenstat-Walker forcing, preconditioned CG for J delta = -F, and a
// backtracking line search on the convex energy that falls back to the
// residual norm when the energy change is at round-off level.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "lodestone/core/field/magnetostatic_problem.h"
#include "lodestone/core/field/multigrid.h"
#include "lodestone/core/field/pcg.h"

namespace lodestone {

enum class PreconditionerKind : int {
  Jacobi = 0,    ///< diagonal scaling: cheap set-up, iterations grow with resolution
  Multigrid = 1  ///< geometric V-cycle: iterations nearly independent of resolution
};
const char* toString(PreconditionerKind kind);

struct FieldSolveSettings {
  double tolerance = 1e-8;        ///< stop at ||F|| <= tolerance * ||F_ref|| (F_ref = residual at phi = 0)
  int maxNewtonIterations = 40;   ///< Newton iteration cap
  int maxCgIterations = 5000;     ///< CG iteration cap per Newton step
  double forcingMax = 0.1;        ///< largest inner relative tolerance eta (Eisenstat-Walker)
  double forcingGamma = 0.9;      ///< Eisenstat-Walker choice 2: eta = gamma (|F_k|/|F_k-1|)^alpha
  double forcingAlpha = 2.0;
  int maxLineSearchCuts = 30;     ///< backtracking steps before giving up
  double armijo = 1e-4;           ///< sufficient-decrease constant
  PreconditionerKind preconditioner = PreconditionerKind::Multigrid;
  MultigridSettings multigrid;    ///< used by PreconditionerKind::Multigrid
  /// Open wall: each Newton step also predicts how its change of M moves the
  /// far-field wall values (linearized block multipoles) and solves for the
  /// interior's response to that move, so that the wall no longer lags one
  /// iteration behind M (docs/physics.md, "Open wall inside the Newton
  /// step"). Multigrid only, and not when material touches the wall. false:
  /// the wall follows M one iteration late (more Newton steps, no extra CG solve).
  bool predictWall = true;
  /// Relative CG tolerance of that response solve, in (0, 1).
  double wallPredictionTolerance = 0.1;
  /// A trial point that the step's CG solves leave below the tolerance is
  /// evaluated without the Jacobian's element matrices (about half an
  /// evaluation), which are built at the next iteration only if the
  /// tolerance was missed after all. false: built at every trial point (the
  /// same iterates, to rounding).
  bool deferFinalJacobian = true;

  /// Throws InvalidArgument naming the first bad value.
  void validate() const;
};

enum class SolveStatus : int {
  Converged = 0,           ///< relative residual <= tolerance
  Trivial = 1,             ///< no magnetization anywhere: phi = 0, H = H_ext
  IterationCap = 2,        ///< Newton iteration cap reached first
  LineSearchFailed = 3,    ///< no step decreased the merit
  LinearSolverFailed = 4,  ///< CG broke down or returned a non-descent step
  NonFinite = 5,           ///< a non-finite value appeared; phi kept at the last finite iterate
  Cancelled = 6            ///< the progress callback asked to stop
};
const char* toString(SolveStatus status);

/// One Newton iteration.
struct NewtonIterationRecord {
  int iteration = 0;
  double relativeResidual = 0;  ///< ||F|| / ||F_ref|| at the start of the iteration
  double forcing = 0;           ///< inner relative tolerance eta
  int cgIterations = 0;
  double cgRelativeResidual = 0;
  double step = 0;              ///< accepted line-search step lambda
  int lineSearchCuts = 0;
  bool residualMerit = false;   ///< step accepted on the residual norm (energy at round-off)
  bool wallPredicted = false;   ///< the step moved the open wall with it (FieldSolveSettings::predictWall)
  int wallCgIterations = 0;     ///< CG iterations of the wall-response solve (also in cgIterations)
  /// The accepted trial point was evaluated without the Jacobian's element
  /// matrices, because the step's CG solves left less than the tolerance
  /// (FieldSolveSettings::deferFinalJacobian). When the tolerance was still
  /// missed, the next iteration built them (jacobianRebuilt there).
  bool jacobianDeferred = false;
  bool jacobianRebuilt = false;  ///< this iteration first built the Jacobian the previous one deferred
  /// This iteration's predicted wall was the second that did not help (see
  /// FieldSolveReport::wallPredictionDropped): later steps let the wall lag.
  bool wallPredictionDropped = false;
  double seconds = 0;           ///< wall time of the iteration, of which:
  double secondsWall = 0;       ///<   open-wall update (far-field sum and residual correction)
  double secondsWallPrediction = 0;  ///< wall prediction (linearized far-field sum, response CG)
  double secondsSetup = 0;      ///<   preconditioner set-up (and a deferred Jacobian, when built)
  double secondsCg = 0;         ///<   preconditioned CG
  double secondsLineSearch = 0; ///<   line search, including the evaluation at the accepted point
                                ///<   (and, for a predicted wall, the wall update there)
};

struct FieldSolveReport {
  SolveStatus status = SolveStatus::Trivial;
  int newtonIterations = 0;
  int cgIterations = 0;            ///< total over all Newton steps
  int lineSearchCuts = 0;          ///< total backtracking cuts
  double relativeResidual = 0;     ///< final ||F|| / ||F_ref||
  double referenceResidual = 0;    ///< ||F_ref||, A*m
  double materialEnergy = 0;       ///< sum w W at the solution, A^2*m
  double seconds = 0;
  double secondsInitial = 0;       ///< reference residual and first evaluation (before the iterations)
  /// The open wall's prediction (FieldSolveSettings::predictWall) was turned
  /// off for the rest of the solve after two predicted steps that did not
  /// help (rejected, or accepted with less than half the residual removed):
  /// a strongly magnetizable body close to the wall.
  bool wallPredictionDropped = false;
  std::size_t materialCells = 0;
  std::string preconditioner;
  std::string message;             ///< human-readable outcome
  std::vector<NewtonIterationRecord> history;

  bool converged() const { return status == SolveStatus::Converged || status == SolveStatus::Trivial; }
};

/// Called after each Newton iteration; return false to cancel the solve.
using SolveProgress = std::function<bool(const NewtonIterationRecord&)>;

/// Storage a caller can keep between solves (the magnetic stage does): the
/// Newton and CG vectors and the preconditioner, whose multigrid hierarchy
/// then only refreshes its values when the grid and the material cells are
/// unchanged. Results are the same with or without it.
struct FieldSolveWorkspace {
  std::vector<double> F, Fref, delta, work, trial, lastGood, Ftrial, Kphi, Kdelta, Ktrial, wallRhs, wallDelta;
  PcgWorkspace pcg;
  std::unique_ptr<Preconditioner> preconditioner;
  PreconditionerKind kind = PreconditionerKind::Jacobi;  ///< what `preconditioner` is
  MultigridSettings multigrid;                           ///< the settings it was made with
};

/// Solves for phi in place (phi holds the warm start on entry: one value per
/// node; pass zeros for a cold start). Never leaves non-finite values in phi.
/// `workspace` (optional) is reused storage, see FieldSolveWorkspace.
/// On return the problem holds the evaluation (M, residual, multipoles) at
/// phi; its Jacobian (element matrices, material stencil, cell tensors) may
/// be that of the previous Newton iterate (NewtonIterationRecord::
/// jacobianDeferred): call problem.evaluate(phi) before applying it.
FieldSolveReport solveField(MagnetostaticProblem& problem, std::vector<double>& phi,
                            const FieldSolveSettings& settings, const SolveProgress& progress = {},
                            FieldSolveWorkspace* workspace = nullptr);

}  // namespace lodestone
