#pragma once
// The settings of the field solve (field_solver.h): Newton iteration,
// forcing terms, line search, the preconditioner and the open wall. Plain
// values with no dependency beyond the standard library, shared by every
// backend of the one Newton solver (newton_solver.h): the TBB backend of core
// and the CUDA backend of gpu/.

namespace lodestone {
inline namespace field {

enum class PreconditionerKind : int {
  Jacobi = 0,    ///< diagonal scaling: cheap set-up, iterations grow with resolution
  Multigrid = 1  ///< geometric V-cycle: iterations nearly independent of resolution
};
const char* toString(PreconditionerKind kind);

/// The geometric multigrid V-cycle that preconditions the Newton systems
/// (multigrid.h): smoothing sweeps, damping, coarsest level, storage precision.
struct MultigridSettings {
  int preSmoothing = 2;         ///< damped-Jacobi sweeps before the coarse correction, 1..20
  int postSmoothing = 2;        ///< and after (same count keeps the cycle symmetric)
  double jacobiWeight = 0.7;    ///< smoother damping in (0, 1]
  int coarsestNodes = 5;        ///< stop coarsening when an axis has this many nodes or fewer (>= 3)
  bool singlePrecision = true;  ///< store and cycle the levels in float (false: double)

  /// Throws InvalidArgument naming the first bad value.
  void validate() const;
};

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
  /// When such a trial point missed the tolerance by less than 10x, the next
  /// step solves with the Jacobian and multigrid of the iterate before it (a
  /// chord step) instead of building them at the trial point: what a step
  /// aimed at the tolerance leaves is mostly the open wall's lag behind M,
  /// which the Jacobian's change does not touch. At most one chord step in a
  /// row. false: the Jacobian is built (the iterates of deferFinalJacobian
  /// off, to rounding).
  bool chordAfterDeferredMiss = true;

  /// Throws InvalidArgument naming the first bad value.
  void validate() const;
};

}  // namespace field
}  // namespace lodestone
