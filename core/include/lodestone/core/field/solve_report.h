#pragma once
// The outcome of a field solve: a status, counts, residuals, timings and one
// record per Newton iteration. Returned by every backend of the Newton
// solver (newton_solver.h); plain values, standard library only.
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace lodestone {
inline namespace field {

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
  /// missed, the next iteration built them (jacobianRebuilt there) or kept
  /// the earlier ones (chord there).
  bool jacobianDeferred = false;
  bool jacobianRebuilt = false;  ///< this iteration first built the Jacobian the previous one deferred
  /// This iteration's step kept the Jacobian and multigrid of the iterate
  /// before the deferred one (FieldSolveSettings::chordAfterDeferredMiss).
  bool chord = false;
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
  std::string preconditioner;      ///< "jacobi" or "multigrid"
  int multigridLevels = 0;         ///< levels of the V-cycle, the fine grid included (0 with Jacobi)
  std::string backend;             ///< the backend that ran the Newton solver ("cpu", "cuda", "host")
  std::string message;             ///< human-readable outcome
  std::vector<NewtonIterationRecord> history;

  bool converged() const { return status == SolveStatus::Converged || status == SolveStatus::Trivial; }
};

/// Called after each Newton iteration; return false to cancel the solve.
using SolveProgress = std::function<bool(const NewtonIterationRecord&)>;

}  // namespace field
}  // namespace lodestone
