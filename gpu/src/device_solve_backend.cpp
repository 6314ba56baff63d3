#include "device_solve_backend.h"

#include <cmath>

namespace lodestone {
namespace gpu {
namespace detail {

DeviceSolveBackend::DeviceSolveBackend(FieldBackend& be, const GridSpec& grid, const FieldSolveSettings& settings,
                                       double* phi, bool cold, int wallClearance, const WallUpdate& wallValues,
                                       const WallUpdate& wallMove)
    : be_(be),
      n_(be.nodeCount()),
      mgSettings_(settings.multigrid),
      multigrid_(settings.preconditioner == PreconditionerKind::Multigrid),
      cold_(cold),
      clearance_(wallClearance),
      vcycle_(be, mgSettings_) {
  v_[0] = phi;
  int slot = kSolverFirst;
  for (int r = 1; r < kNodeVecCount; ++r) v_[r] = be_.work(0, slot++);
  if (!be_.shield() && wallValues) {
    const auto inner = [](int count) { return std::size_t(count > 2 ? count - 2 : 0); };
    wallNodes_ = grid.nodeCount() - inner(grid.dims.i) * inner(grid.dims.j) * inner(grid.dims.k);
    wallValues_ = wallValues;
    wallMove_ = wallMove;
    for (double*& x : wall_) x = be_.work(0, slot++);
    scratchA_ = be_.work(0, slot++);
    scratchB_ = be_.work(0, slot++);
  } else {
    for (double*& x : wall_) x = nullptr;
    scratchA_ = scratchB_ = nullptr;
  }
}

FieldEvaluation DeviceSolveBackend::evaluate(NodeVec p, NodeVec f, bool jacobian, NodeVec vacuum) {
  // The device evaluates the whole residual (the vacuum part included), so
  // `vacuum` is not needed; the block multipoles are the host's (setFarField).
  (void)vacuum;
  const Evaluation e = be_.evaluate(v(p), v(f), jacobian);
  FieldEvaluation out;
  out.materialEnergy = e.energy;
  out.materialEnergyAbs = e.energyAbs;
  out.finite = e.finite;
  return out;
}

double DeviceSolveBackend::norm(NodeVec x) { return std::sqrt(be_.dot(n_, v(x), v(x))); }

void DeviceSolveBackend::formTrialAlong(double lambda) {
  be_.axpby(n_, 1.0, v(NodeVec::Phi), lambda, v(NodeVec::Delta), v(NodeVec::Trial));
}

void DeviceSolveBackend::advance(double lambda) {
  be_.axpby(n_, 1.0, v(NodeVec::Phi), lambda, v(NodeVec::Delta), v(NodeVec::Phi));
  be_.axpby(n_, 1.0, v(NodeVec::Kphi), lambda, v(NodeVec::Kdelta), v(NodeVec::Kphi));
}

StepSlopes DeviceSolveBackend::formFullStep() {
  be_.applyVacuum(v(NodeVec::Delta), v(NodeVec::Kdelta));
  be_.axpby(n_, 1.0, v(NodeVec::Phi), 1.0, v(NodeVec::Delta), v(NodeVec::Trial));
  be_.axpby(n_, 1.0, v(NodeVec::Kphi), 1.0, v(NodeVec::Kdelta), v(NodeVec::Ktrial));
  be_.copy(n_, v(NodeVec::Ktrial), v(NodeVec::Ftrial));
  StepSlopes s;
  s.g0 = be_.dot(n_, v(NodeVec::Delta), v(NodeVec::F));
  s.s1 = be_.dot(n_, v(NodeVec::Delta), v(NodeVec::Kphi));
  s.s2 = be_.dot(n_, v(NodeVec::Delta), v(NodeVec::Kdelta));
  return s;
}

void DeviceSolveBackend::updatePreconditioner() { be_.buildPreconditioner(multigrid_, mgSettings_.coarsestNodes); }

PcgResult DeviceSolveBackend::solveJacobian(NodeVec rhs, NodeVec x, double relTol, int maxIterations) {
  if (multigrid_) return pcg(be_, 0, v(rhs), v(x), relTol, maxIterations, be_.shield(), kPcgOuter, vcycle_);
  const double* dinv = be_.inverseDiagonal(0, true);
  return pcg(be_, 0, v(rhs), v(x), relTol, maxIterations, be_.shield(), kPcgOuter,
             [&](const double* in, double* out) { be_.jacobi(n_, 1.0, dinv, in, nullptr, out); });
}

void DeviceSolveBackend::wallPart(const double* x, double* out) {
  // x - (x with its wall zeroed): the free entries are exactly 0.
  be_.copy(n_, x, scratchB_);
  be_.zeroFixed(0, scratchB_);
  be_.axpby(n_, 1.0, x, -1.0, scratchB_, out);
}

void DeviceSolveBackend::replaceWall(double* p, const double* x) {
  wallPart(x, scratchA_);
  be_.zeroFixed(0, p);
  be_.axpby(n_, 1.0, p, 1.0, scratchA_, p);
}

void DeviceSolveBackend::fromHost(const WallUpdate& fn, const double* x, double* p, bool startFromX) {
  hostIn_.resize(n_);
  be_.download(x, n_, hostIn_.data());
  if (startFromX) {
    hostOut_ = hostIn_;
  } else {
    hostOut_.assign(n_, 0.0);
  }
  fn(hostIn_.data(), hostOut_.data());
  be_.upload(hostOut_.data(), n_, scratchA_);
  replaceWall(p, scratchA_);
}

void DeviceSolveBackend::setFarField(const FieldEvaluation& e, NodeVec p) {
  (void)e;  // the host recomputes the magnetization's far field from phi
  fromHost(wallValues_, v(p), v(p), true);
}

void DeviceSolveBackend::setLinearizedFarField(NodeVec d, NodeVec out) { fromHost(wallMove_, v(d), v(out), false); }

void DeviceSolveBackend::addWallCoupling(NodeVec x, NodeVec out) {
  // K applied to x's wall values alone is K_fw x in the free rows.
  wallPart(v(x), scratchA_);
  be_.applyVacuum(scratchA_, scratchB_);
  be_.axpby(n_, 1.0, v(out), 1.0, scratchB_, v(out));
}

void DeviceSolveBackend::scatterWall(WallVec in, double scale, NodeVec p) {
  be_.zeroFixed(0, v(p));
  be_.axpby(n_, 1.0, v(p), scale, w(in), v(p));
}

void DeviceSolveBackend::wallDifference(NodeVec p, WallVec old, WallVec step) {
  wallPart(v(p), w(step));
  be_.axpby(n_, 1.0, w(step), -1.0, w(old), w(step));
}

void DeviceSolveBackend::relaxWall(NodeVec p, WallVec step, double theta) {
  be_.axpby(n_, 1.0, v(p), -(1.0 - theta), w(step), v(p));
  be_.axpby(n_, theta, w(step), 0.0, w(step), w(step));
}

}  // namespace detail
}  // namespace gpu
}  // namespace lodestone
