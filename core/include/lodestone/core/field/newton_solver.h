#pragma once
// The Newton-Krylov solve of the nonlinear magnetostatic problem, written
// once over FieldSolveBackend (solve_backend.h) and run by every backend:
// core's TBB backend (field_solver.h: solveField) and gpu/'s CUDA backend.
//
// One iteration is Algorithm 1 of the paper with the changes docs/physics.md
// documents, each a named step:
//   beginIteration  refresh the open wall from the last evaluation's
//                   magnetization (unless the step already moved it) and
//                   measure the residual;
//   finished        stop on a non-finite value, convergence or the cap;
//   forcingTerm     Eisenstat-Walker choice 2 with safeguards, never tighter
//                   than the outer tolerance needs, loosened where the
//                   lagging wall limits the step;
//   newtonStep      PCG for J delta = -F (building a deferred Jacobian first);
//   predictWall     the open wall's move with the step (linearized block
//                   multipoles) and the interior's response to it;
//   acceptStep      a wall-coupled step on the residual, otherwise the
//                   safeguarded backtracking line search on the convex
//                   energy (residual norm where the energy change is at
//                   round-off);
//   endIteration    record the iteration and report progress.
#include <cstddef>
#include <string>

#include "lodestone/core/base/stopwatch.h"
#include "lodestone/core/field/solve_backend.h"
#include "lodestone/core/field/solve_report.h"
#include "lodestone/core/field/solve_settings.h"

namespace lodestone {
inline namespace field {

class NewtonSolver {
 public:
  /// Throws InvalidArgument when the settings are invalid.
  NewtonSolver(FieldSolveBackend& backend, const FieldSolveSettings& settings, SolveProgress progress = {});

  /// Solves for the backend's NodeVec::Phi in place (it holds the warm start
  /// on entry). Never leaves non-finite values in Phi. On return the backend
  /// holds the evaluation at Phi; its Jacobian may be the previous iterate's
  /// (NewtonIterationRecord::jacobianDeferred).
  FieldSolveReport solve();

 private:
  /// What a Newton step's CG solves leave, and whether it moves the wall.
  struct Step {
    PcgResult cg;
    bool coupled = false;  ///< the step moves the open wall (predictWall)
    /// Residual the step leaves if the linearization is exact (A m):
    /// infinite where the wall lags.
    double expectedResidual = 0;
  };

  bool start();
  NewtonIterationRecord beginIteration(int it);
  bool finished(NewtonIterationRecord& rec);
  double forcingTerm(int it);
  bool predicting() const;
  PcgResult newtonStep(NewtonIterationRecord& rec);
  Step predictWall(NewtonIterationRecord& rec, const PcgResult& cg);
  bool acceptStep(NewtonIterationRecord& rec, const Step& step);
  bool acceptCoupled(NewtonIterationRecord& rec, bool trialJacobian, FieldEvaluation& evT);
  bool lineSearch(NewtonIterationRecord& rec, const StepSlopes& slopes, bool trialJacobian, FieldEvaluation& evT,
                  double* lambda);
  bool endIteration(NewtonIterationRecord& rec);
  void updateWall(NodeVec p, NodeVec f, NodeVec k, FieldEvaluation& e);
  void takeTrial(FieldEvaluation& evT);
  void stop(SolveStatus status, const NewtonIterationRecord* rec, std::string message);
  FieldSolveReport finish();

  FieldSolveBackend& be_;
  FieldSolveSettings s_;
  SolveProgress progress_;
  FieldSolveReport rep_;
  SteadyClock::time_point t0_, iterationStart_;
  FieldEvaluation ev_;  ///< the evaluation at Phi
  bool open_ = false, linear_ = false, project_ = false;
  double r0_ = 0;       ///< reference residual ||F_ref||, A m
  double fn_ = 0;       ///< ||F|| at the current iterate
  double prevNorm_ = 0, prevEta_ = 0, eta_ = 0;
  bool wallCurrent_ = false;       ///< Phi's wall holds the far field of ev_ (a coupled step set it)
  bool jacobianDeferred_ = false;  ///< ev_ was evaluated without the Jacobian
  int wallStrikes_ = 0;            ///< predicted-wall steps that did not help
  int wallUpdates_ = 0;            ///< far-field updates so far (relaxation)
};

}  // namespace field
}  // namespace lodestone
