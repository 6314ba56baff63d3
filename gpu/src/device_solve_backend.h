#pragma once
// The backend of core's Newton solver (lodestone/core/field/newton_solver.h)
// over the device operations of FieldBackend (field_backend.h): the CUDA
// backend and its serial host reference run the same Newton iteration as
// core's TBB backend. What is the device's own stays here: the operations of
// core's CG loop (pcg_iteration.h) and V-cycle (v_cycle.h) over the backend's
// double-precision levels, and the open wall's operations, with the far field
// computed on the host (FieldSolver::setWallUpdate).
//
// Node vectors are the backend's level-0 work slots; swap() exchanges
// pointers. Wall vectors are node vectors whose free entries are 0.
#include <cstddef>
#include <utility>
#include <vector>

#include "field_backend.h"
#include "lodestone/core/field/pcg_iteration.h"
#include "lodestone/core/field/solve_backend.h"
#include "lodestone/core/field/v_cycle.h"
#include "lodestone/core/field/solve_settings.h"
#include "lodestone/gpu/field_solver.h"

namespace lodestone {
namespace gpu {
namespace detail {

/// Level-0 work slots: 0 holds phi on entry; the CG and V-cycle slots;
/// then the Newton solver's vectors.
enum Slot : int {
  kPcgOuter = 8,    // 8..11
  kMgR = 12,
  kPcgCoarse = 13,  // 13..16: CG on the coarsest level
  kMgX = 17,
  kMgB = 18,
  kSolverFirst = 19,  // the node roles but Phi, then the wall vectors, then 2 scratch vectors
};
static_assert(kSolverFirst + (kNodeVecCount - 1) + kWallVecCount + 2 <= kWorkSlots, "too few work slots");

/// The device operations of the CG iteration (core's pcg_iteration.h) on
/// a level, work slots firstSlot..firstSlot+3, with the given preconditioner
/// apply (z = P^-1 r).
template <typename Precondition>
class DevicePcgOps {
 public:
  DevicePcgOps(FieldBackend& be, int level, const double* b, double* x, bool project, int firstSlot,
               const Precondition& precondition)
      : be_(be),
        n_(be.levelNodes(level)),
        b_(b),
        x_(x),
        project_(project),
        precondition_(precondition),
        r_(be.work(level, firstSlot)),
        z_(be.work(level, firstSlot + 1)),
        p_(be.work(level, firstSlot + 2)),
        Ap_(be.work(level, firstSlot + 3)),
        level_(level) {}

  double start() {
    be_.copy(n_, b_, r_);
    be_.fill(n_, 0.0, x_);
    if (project_) be_.removeMean(n_, r_);
    return be_.dot(n_, r_, r_);
  }
  double precondition() {
    precondition_(r_, z_);
    if (project_) be_.removeMean(n_, z_);
    return be_.dot(n_, r_, z_);
  }
  void firstDirection() { be_.copy(n_, z_, p_); }
  double applyA() {
    be_.applyLevel(level_, p_, Ap_);
    return be_.dot(n_, p_, Ap_);
  }
  double step(double alpha) {
    be_.axpby(n_, 1.0, x_, alpha, p_, x_);
    be_.axpby(n_, 1.0, r_, -alpha, Ap_, r_);
    if (project_) be_.removeMean(n_, r_);
    return be_.dot(n_, r_, r_);
  }
  void nextDirection(double beta) { be_.axpby(n_, 1.0, z_, beta, p_, p_); }
  void finish() {
    if (project_) be_.removeMean(n_, x_);
  }

 private:
  FieldBackend& be_;
  std::size_t n_;
  const double* b_;
  double* x_;
  bool project_;
  const Precondition& precondition_;
  double *r_, *z_, *p_, *Ap_;
  int level_;
};

/// Preconditioned CG on a level from x = 0 (see DevicePcgOps).
template <typename Precondition>
PcgResult pcg(FieldBackend& be, int level, const double* b, double* x, double relTol, int maxIterations, bool project,
              int firstSlot, const Precondition& precondition) {
  DevicePcgOps<Precondition> ops(be, level, b, x, project, firstSlot, precondition);
  return pcgIterate(ops, relTol, maxIterations);
}

/// The device operations of core's V-cycle (v_cycle.h) over the backend's
/// levels: level 0's b and x are the caller's, the coarser ones work slots.
class DeviceCycleOps {
 public:
  DeviceCycleOps(FieldBackend& be, const MultigridSettings& s, const double* b, double* x)
      : be_(be), w_(s.jacobiWeight), b0_(b), x0_(x) {}

  bool coarsest(int level) const { return level + 1 == be_.levelCount(); }
  void solveCoarsest(int level) {
    // Diagonally preconditioned CG to a tight tolerance.
    if (be_.solveCoarsest(level, b(level), x(level))) return;
    const std::size_t n = be_.levelNodes(level);
    const double* dinv = be_.inverseDiagonal(level, false);
    pcg(be_, level, b(level), x(level), 1e-10, 10 * int(n), be_.shield(), kPcgCoarse,
        [&](const double* in, double* out) { be_.jacobi(n, 1.0, dinv, in, nullptr, out); });
  }
  void smoothFromZero(int level) {
    be_.jacobi(be_.levelNodes(level), w_, be_.inverseDiagonal(level, false), b(level), nullptr, x(level));
  }
  void smooth(int level, bool last) {
    (void)last;
    double* r = be_.work(level, kMgR);
    be_.applyLevel(level, x(level), r);
    be_.jacobi(be_.levelNodes(level), w_, be_.inverseDiagonal(level, false), b(level), r, x(level));
  }
  void restrictResidual(int level) {
    const std::size_t n = be_.levelNodes(level);
    double* r = be_.work(level, kMgR);
    be_.applyLevel(level, x(level), r);
    be_.axpby(n, 1.0, b(level), -1.0, r, r);
    double* coarseB = be_.work(level + 1, kMgB);
    be_.restrictTo(level, r, coarseB);
    be_.zeroFixed(level + 1, coarseB);
  }
  void prolongAdd(int level) {
    double* r = be_.work(level, kMgR);
    be_.prolong(level, x(level + 1), r);
    be_.zeroFixed(level, r);
    be_.axpby(be_.levelNodes(level), 1.0, x(level), 1.0, r, x(level));
  }

 private:
  const double* b(int level) { return level == 0 ? b0_ : be_.work(level, kMgB); }
  double* x(int level) { return level == 0 ? x0_ : be_.work(level, kMgX); }

  FieldBackend& be_;
  double w_;
  const double* b0_;
  double* x0_;
};

/// z = V-cycle(r) with the backend's levels.
class VCycle {
 public:
  VCycle(FieldBackend& be, const MultigridSettings& s) : be_(be), s_(s) {}
  void operator()(const double* b, double* x) const {
    DeviceCycleOps ops(be_, s_, b, x);
    vCycle(ops, 0, s_.preSmoothing, s_.postSmoothing);
  }

 private:
  FieldBackend& be_;
  const MultigridSettings& s_;
};

class DeviceSolveBackend final : public FieldSolveBackend {
 public:
  /// `phi` is backend memory holding the warm start; `cold` says it is all zeros.
  DeviceSolveBackend(FieldBackend& be, const GridSpec& grid, const FieldSolveSettings& settings, double* phi, bool cold,
                     int wallClearance, const WallUpdate& wallValues, const WallUpdate& wallMove);

  /// Where the solution is at the end (the roles' storage moves with swap()).
  double* phi() { return v_[int(NodeVec::Phi)]; }

  const char* name() const override { return be_.name(); }
  std::size_t nodeCount() const override { return n_; }
  std::size_t materialCellCount() const override { return be_.materialCellCount(); }
  BoundaryKind boundary() const override { return be_.shield() ? BoundaryKind::Shield : BoundaryKind::Open; }
  LawKind lawKind() const override { return be_.law().kind; }
  int materialWallClearance() const override { return clearance_; }
  std::size_t wallNodeCount() const override { return wallNodes_; }
  bool predictsWall() const override { return bool(wallMove_); }
  bool prepareStart() override { return cold_; }

  FieldEvaluation evaluate(NodeVec p, NodeVec f, bool jacobian, NodeVec vacuum = NodeVec::None) override;
  void residualAtZero(NodeVec f) override { be_.residualAtZero(v(f)); }
  void applyVacuum(NodeVec x, NodeVec out) override { be_.applyVacuum(v(x), v(out)); }
  double materialEnergyAlong(NodeVec p, NodeVec d, double lambda, double* absSum) override {
    return be_.energyAlong(v(p), v(d), lambda, absSum);
  }

  double norm(NodeVec x) override;
  void fill(NodeVec x, double value) override { be_.fill(n_, value, v(x)); }
  void copy(NodeVec from, NodeVec to) override { be_.copy(n_, v(from), v(to)); }
  void swap(NodeVec a, NodeVec b) override { std::swap(v_[int(a)], v_[int(b)]); }
  void negate(NodeVec from, NodeVec to) override { be_.axpby(n_, -1.0, v(from), 0.0, v(from), v(to)); }
  void axpy(double a, NodeVec x, NodeVec y) override { be_.axpby(n_, a, v(x), 1.0, v(y), v(y)); }
  void formTrialAlong(double lambda) override;
  void advance(double lambda) override;
  void removeMean(NodeVec x) override { be_.removeMean(n_, v(x)); }
  StepSlopes formFullStep() override;

  void updatePreconditioner() override;
  int preconditionerLevels() const override { return multigrid_ ? be_.levelCount() : 0; }
  PcgResult solveJacobian(NodeVec rhs, NodeVec x, double relTol, int maxIterations) override;

  void setFarField(const FieldEvaluation& e, NodeVec p) override;
  void setLinearizedFarField(NodeVec d, NodeVec out) override;
  void addWallCoupling(NodeVec x, NodeVec out) override;
  void gatherWall(NodeVec p, WallVec out) override { wallPart(v(p), w(out)); }
  void scatterWall(WallVec in, double scale, NodeVec p) override;
  void zeroWall(NodeVec p) override { be_.zeroFixed(0, v(p)); }
  void wallDifference(NodeVec p, WallVec old, WallVec step) override;
  void relaxWall(NodeVec p, WallVec step, double theta) override;
  double wallDot(WallVec a, WallVec b) override { return be_.dot(n_, w(a), w(b)); }
  void copyWall(WallVec from, WallVec to) override { be_.copy(n_, w(from), w(to)); }
  void swapWall(WallVec a, WallVec b) override { std::swap(wall_[int(a)], wall_[int(b)]); }

 private:
  double* v(NodeVec role) { return v_[int(role)]; }
  double* w(WallVec role) { return wall_[int(role)]; }
  /// out = the wall entries of x, 0 on the free nodes.
  void wallPart(const double* x, double* out);
  /// The wall entries of p = those of x (x's free entries are ignored).
  void replaceWall(double* p, const double* x);
  /// A host function of phi (all nodes) into the wall nodes of p.
  void fromHost(const WallUpdate& fn, const double* x, double* p, bool startFromX);

  FieldBackend& be_;
  std::size_t n_;
  MultigridSettings mgSettings_;
  bool multigrid_;
  bool cold_;
  int clearance_;
  std::size_t wallNodes_ = 0;
  WallUpdate wallValues_, wallMove_;
  VCycle vcycle_;
  double* v_[kNodeVecCount];
  double* wall_[kWallVecCount];
  double *scratchA_, *scratchB_;
  std::vector<double> hostIn_, hostOut_;
};

}  // namespace detail
}  // namespace gpu
}  // namespace lodestone
