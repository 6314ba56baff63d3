#pragma once
// What the Newton solver (newton_solver.h) needs from the machine it runs on.
// The solver is written once over this interface and never touches a vector
// itself: vectors live in the backend's memory (host arrays for the TBB
// backend of core, device arrays for the CUDA backend of gpu/) and are named
// by their role in the Newton iteration. swap() exchanges the storage behind
// two roles, so "the trial point becomes the iterate" costs no copy.
//
// Every operation is a pass over node vectors (one value per grid node) or
// over the open wall's nodes (WallVec: one value per fixed wall node, in the
// order of the backend's wall list). Reductions are deterministic: the same
// inputs give bitwise the same sums for any thread count.
//
// Standard library and core's portable headers only (no TBB, no CUDA), so
// that gpu/ can build the solver without TBB.
#include <cstddef>
#include <vector>

#include "lodestone/core/field/boundary_kind.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/core/field/multipole.h"
#include "lodestone/core/field/pcg.h"

namespace lodestone {
inline namespace field {

/// The node vectors of a solve, by role.
enum class NodeVec : int {
  Phi = 0,    ///< the iterate (A); holds the warm start on entry and the solution on return
  F,          ///< residual at Phi (A m)
  Fref,       ///< residual of the material part at phi = 0 (warm starts only)
  Kphi,       ///< vacuum part K Phi of the residual, kept up to date through every change of Phi
  Delta,      ///< Newton step
  Kdelta,     ///< K Delta
  Trial,      ///< trial point of the line search
  Ftrial,     ///< residual at Trial
  Ktrial,     ///< K Trial
  Work,       ///< right-hand side of the Newton system
  LastGood,   ///< last finite iterate
  WallRhs,    ///< wall coupling of a wall move (free rows next to the wall)
  WallDelta,  ///< predicted wall move, then the interior's response to it
  None        ///< no vector (an optional argument)
};
constexpr int kNodeVecCount = int(NodeVec::None);

/// The open wall's vectors, one value per fixed wall node.
enum class WallVec : int {
  Old = 0,    ///< wall values before a far-field update
  Step,       ///< the update's step
  Prev,       ///< the previous update's step (relaxation)
  PrevSaved,  ///< Prev before a predicted step, restored when the step is rejected
  Move,       ///< the predicted wall move of a Newton step
};
constexpr int kWallVecCount = 5;

/// One evaluation of the material at a potential.
struct FieldEvaluation {
  double materialEnergy = 0;          ///< sum_q w_q W_q, A^2 m
  double materialEnergyAbs = 0;       ///< sum_q w_q |W_q|, for round-off estimates
  std::vector<Multipole> multipoles;  ///< block multipoles of M (Open wall; empty otherwise)
  bool finite = true;                 ///< false when any M or dM/dH was not finite
};

/// g0 = Delta . F, s1 = Delta . K Phi, s2 = Delta . K Delta: the slope and
/// the vacuum energy's line coefficients along the Newton step.
struct StepSlopes {
  double g0 = 0, s1 = 0, s2 = 0;
};

class FieldSolveBackend {
 public:
  virtual ~FieldSolveBackend() = default;

  /// "cpu", "cuda" or "host" (the serial reference of gpu/).
  virtual const char* name() const = 0;

  // The problem.
  virtual std::size_t nodeCount() const = 0;
  virtual std::size_t materialCellCount() const = 0;
  virtual BoundaryKind boundary() const = 0;
  virtual LawKind lawKind() const = 0;
  /// Open wall: cells between the material and the wall (0: material touches it).
  virtual int materialWallClearance() const = 0;
  /// Open wall: number of fixed wall nodes (0 for Shield).
  virtual std::size_t wallNodeCount() const = 0;

  /// Readies Phi as the warm start: a non-finite value anywhere discards it
  /// (Phi = 0). Returns true when Phi is then all zeros (a cold start).
  virtual bool prepareStart() = 0;

  // The material and the residual (MagnetostaticProblem's operations).
  /// M and W at p, the residual into f; with `jacobian` also the element
  /// matrices the Jacobian and the preconditioner use. `vacuum`, when given,
  /// holds K p (it may be f itself: the material part is then added in place).
  virtual FieldEvaluation evaluate(NodeVec p, NodeVec f, bool jacobian, NodeVec vacuum = NodeVec::None) = 0;
  virtual void residualAtZero(NodeVec f) = 0;
  virtual void applyVacuum(NodeVec v, NodeVec out) = 0;
  /// sum_q w_q W at p + lambda d (A^2 m), and sum_q w_q |W| into absSum.
  virtual double materialEnergyAlong(NodeVec p, NodeVec d, double lambda, double* absSum) = 0;

  // Node vectors.
  virtual double norm(NodeVec v) = 0;
  virtual void fill(NodeVec v, double value) = 0;
  virtual void copy(NodeVec from, NodeVec to) = 0;
  virtual void swap(NodeVec a, NodeVec b) = 0;
  virtual void negate(NodeVec from, NodeVec to) = 0;
  /// y += a x.
  virtual void axpy(double a, NodeVec x, NodeVec y) = 0;
  /// Trial = Phi + lambda Delta.
  virtual void formTrialAlong(double lambda) = 0;
  /// Phi += lambda Delta and Kphi += lambda Kdelta, in one pass.
  virtual void advance(double lambda) = 0;
  /// Shield's null space: subtracts the mean.
  virtual void removeMean(NodeVec v) = 0;
  /// Kdelta = K Delta, then in one pass Trial = Phi + Delta, Ftrial = Ktrial =
  /// Kphi + Kdelta (the vacuum part of the full step's residual), and the slopes.
  virtual StepSlopes formFullStep() = 0;

  // The Newton system J x = rhs.
  /// Rebuilds the preconditioner from the last evaluation with the Jacobian.
  virtual void updatePreconditioner() = 0;
  /// Levels of the preconditioner's V-cycle (0 for Jacobi), after updatePreconditioner().
  virtual int preconditionerLevels() const = 0;
  /// Preconditioned CG from x = 0 to ||rhs - J x|| <= relTol ||rhs||.
  virtual PcgResult solveJacobian(NodeVec rhs, NodeVec x, double relTol, int maxIterations) = 0;

  // The open wall.
  /// setLinearizedFarField() is available: the wall can move with each
  /// Newton step (FieldSolveSettings::predictWall).
  virtual bool predictsWall() const = 0;
  /// Moves the wall values of p to the far field of e's magnetization.
  virtual void setFarField(const FieldEvaluation& e, NodeVec p) = 0;
  /// Wall values of the far field of the linearized change of M along d
  /// into the wall nodes of out (the predicted wall move of step d).
  virtual void setLinearizedFarField(NodeVec d, NodeVec out) = 0;
  /// out += K_fw v: the wall values of v in the free rows next to the wall.
  virtual void addWallCoupling(NodeVec v, NodeVec out) = 0;
  /// out[w] = p[wall w].
  virtual void gatherWall(NodeVec p, WallVec out) = 0;
  /// p[wall w] = scale * w[w].
  virtual void scatterWall(WallVec w, double scale, NodeVec p) = 0;
  /// p[wall w] = 0.
  virtual void zeroWall(NodeVec p) = 0;
  /// step[w] = p[wall w] - old[w].
  virtual void wallDifference(NodeVec p, WallVec old, WallVec step) = 0;
  /// p[wall w] -= (1 - theta) step[w]; step[w] *= theta.
  virtual void relaxWall(NodeVec p, WallVec step, double theta) = 0;
  virtual double wallDot(WallVec a, WallVec b) = 0;
  virtual void copyWall(WallVec from, WallVec to) = 0;
  virtual void swapWall(WallVec a, WallVec b) = 0;
};

}  // namespace field
}  // namespace lodestone
