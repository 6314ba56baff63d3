#pragma once
// The TBB backend of the Newton solver (newton_solver.h): host vectors, the
// MagnetostaticProblem's matrix-free operators and core's PCG with the
// Jacobi or multigrid preconditioner. solveField (field_solver.h) runs the
// solver on it; a host that drives NewtonSolver itself can make one too.
#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

#include "lodestone/core/field/magnetostatic_problem.h"
#include "lodestone/core/field/multigrid.h"
#include "lodestone/core/field/pcg.h"
#include "lodestone/core/field/solve_backend.h"
#include "lodestone/core/field/solve_settings.h"

namespace lodestone {
inline namespace field {

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

class CpuSolveBackend final : public FieldSolveBackend {
 public:
  /// NodeVec::Phi is `phi` itself (resized to the problem's nodes when its
  /// size differs); the other vectors are the workspace's. The problem,
  /// phi and the workspace must outlive the backend.
  CpuSolveBackend(MagnetostaticProblem& problem, std::vector<double>& phi, const FieldSolveSettings& settings,
                  FieldSolveWorkspace& workspace);

  const char* name() const override { return "cpu"; }
  std::size_t nodeCount() const override { return n_; }
  std::size_t materialCellCount() const override { return problem_.materialCellCount(); }
  BoundaryKind boundary() const override { return problem_.boundary(); }
  LawKind lawKind() const override { return problem_.law().kind; }
  int materialWallClearance() const override { return problem_.materialWallClearance(); }
  std::size_t wallNodeCount() const override { return wall_.size(); }
  bool prepareStart() override;

  FieldEvaluation evaluate(NodeVec p, NodeVec f, bool jacobian, NodeVec vacuum = NodeVec::None) override;
  void residualAtZero(NodeVec f) override;
  void applyVacuum(NodeVec v, NodeVec out) override;
  double materialEnergyAlong(NodeVec p, NodeVec d, double lambda, double* absSum) override;

  double norm(NodeVec v) override;
  void fill(NodeVec v, double value) override;
  void copy(NodeVec from, NodeVec to) override;
  void swap(NodeVec a, NodeVec b) override;
  void negate(NodeVec from, NodeVec to) override;
  void axpy(double a, NodeVec x, NodeVec y) override;
  void formTrialAlong(double lambda) override;
  void advance(double lambda) override;
  void removeMean(NodeVec v) override;
  StepSlopes formFullStep() override;

  void updatePreconditioner() override;
  int preconditionerLevels() const override;
  PcgResult solveJacobian(NodeVec rhs, NodeVec x, double relTol, int maxIterations) override;

  bool predictsWall() const override { return true; }
  void setFarField(const FieldEvaluation& e, NodeVec p) override;
  void setLinearizedFarField(NodeVec d, NodeVec out) override;
  void addWallCoupling(NodeVec v, NodeVec out) override;
  void gatherWall(NodeVec p, WallVec out) override;
  void scatterWall(WallVec w, double scale, NodeVec p) override;
  void zeroWall(NodeVec p) override;
  void wallDifference(NodeVec p, WallVec old, WallVec step) override;
  void relaxWall(NodeVec p, WallVec step, double theta) override;
  double wallDot(WallVec a, WallVec b) override;
  void copyWall(WallVec from, WallVec to) override;
  void swapWall(WallVec a, WallVec b) override;

 private:
  std::vector<double>& v(NodeVec role) { return *nodes_[int(role)]; }
  double* p(NodeVec role) { return nodes_[int(role)]->data(); }
  std::vector<double>& w(WallVec role) { return wallVecs_[int(role)]; }

  MagnetostaticProblem& problem_;
  FieldSolveWorkspace& ws_;
  PreconditionerKind kind_;
  MultigridSettings multigrid_;
  std::size_t n_;
  std::vector<double>* nodes_[kNodeVecCount];
  std::vector<std::size_t> wall_;
  std::vector<double> wallVecs_[kWallVecCount];
  std::function<void(const double*, double*)> applyJ_;
  std::function<double(const double*, double*)> applyJDot_;
  std::function<void(double*)> project_;
};

}  // namespace field
}  // namespace lodestone
