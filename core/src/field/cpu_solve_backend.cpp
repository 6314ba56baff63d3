#include "lodestone/core/field/cpu_solve_backend.h"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lodestone/core/base/error.h"
#include "lodestone/core/base/kept_capacity.h"
#include "lodestone/core/base/parallel.h"

namespace lodestone {
inline namespace field {

namespace {
std::unique_ptr<Preconditioner> makePreconditioner(PreconditionerKind kind, const MultigridSettings& multigrid) {
  switch (kind) {
    case PreconditionerKind::Jacobi: return std::make_unique<JacobiPreconditioner>();
    case PreconditionerKind::Multigrid: return std::make_unique<MultigridPreconditioner>(multigrid);
  }
  throw InvalidArgument(concat("field solve: unknown preconditioner ", int(kind)));
}

bool sameMultigrid(const MultigridSettings& a, const MultigridSettings& b) {
  return a.preSmoothing == b.preSmoothing && a.postSmoothing == b.postSmoothing && a.jacobiWeight == b.jacobiWeight &&
         a.coarsestNodes == b.coarsestNodes && a.singlePrecision == b.singlePrecision;
}

// StepSlopes summed in a deterministic reduction.
struct SlopeSum : StepSlopes {
  SlopeSum& operator+=(const SlopeSum& o) {
    g0 += o.g0;
    s1 += o.s1;
    s2 += o.s2;
    return *this;
  }
};
}  // namespace

CpuSolveBackend::CpuSolveBackend(MagnetostaticProblem& problem, std::vector<double>& phi,
                                 const FieldSolveSettings& settings, FieldSolveWorkspace& workspace)
    : problem_(problem),
      ws_(workspace),
      kind_(settings.preconditioner),
      multigrid_(settings.multigrid),
      n_(problem.nodeCount()),
      wall_(problem.fixedNodes()) {
  std::vector<double>* roles[kNodeVecCount] = {&phi,      &ws_.F,     &ws_.Fref,  &ws_.Kphi,     &ws_.delta,
                                               &ws_.Kdelta, &ws_.trial, &ws_.Ftrial, &ws_.Ktrial, &ws_.work,
                                               &ws_.lastGood, &ws_.wallRhs, &ws_.wallDelta};
  std::copy(roles, roles + kNodeVecCount, nodes_);
  // Every vector is fully written before it is read: resizing a kept
  // workspace needs no clearing, and new storage none either.
  for (std::vector<double>* x : nodes_)
    if (x != &phi && x != &ws_.lastGood) resizeKeepingCapacity(*x, n_);
  for (std::vector<double>& x : wallVecs_) x.assign(wall_.size(), 0.0);
  applyJ_ = [this](const double* x, double* out) { problem_.applyJacobian(x, out); };
  applyJDot_ = [this](const double* x, double* out) { return problem_.applyJacobianDot(x, out); };
  if (problem_.boundary() == BoundaryKind::Shield) project_ = [this](double* x) { problem_.removeMean(x); };
}

bool CpuSolveBackend::prepareStart() {
  std::vector<double>& phi = v(NodeVec::Phi);
  if (phi.size() != n_) phi.assign(n_, 0.0);
  bool cold = true;
  for (double x : phi) {
    if (!std::isfinite(x)) {
      std::fill(phi.begin(), phi.end(), 0.0);  // a poisoned warm start is discarded
      return true;
    }
    cold = cold && x == 0.0;
  }
  return cold;
}

FieldEvaluation CpuSolveBackend::evaluate(NodeVec x, NodeVec f, bool jacobian, NodeVec vacuum) {
  MagnetostaticProblem::Evaluation e =
      problem_.evaluate(p(x), p(f), jacobian, vacuum == NodeVec::None ? nullptr : p(vacuum));
  FieldEvaluation out;
  out.materialEnergy = e.materialEnergy;
  out.materialEnergyAbs = e.materialEnergyAbs;
  out.multipoles = std::move(e.multipoles);
  out.finite = e.finite;
  return out;
}

void CpuSolveBackend::residualAtZero(NodeVec f) { problem_.residualAtZero(p(f)); }
void CpuSolveBackend::applyVacuum(NodeVec x, NodeVec out) { problem_.applyVacuum(p(x), p(out)); }
double CpuSolveBackend::materialEnergyAlong(NodeVec x, NodeVec d, double lambda, double* absSum) {
  return problem_.materialEnergyAlong(p(x), p(d), lambda, absSum);
}

double CpuSolveBackend::norm(NodeVec x) { return std::sqrt(deterministicDot(p(x), p(x), n_)); }
void CpuSolveBackend::fill(NodeVec x, double value) { std::fill(v(x).begin(), v(x).end(), value); }
void CpuSolveBackend::copy(NodeVec from, NodeVec to) {
  reserveKeepingCapacity(v(to), v(from).size());  // a first copy into an empty vector: storage advised for huge pages
  v(to) = v(from);
}
void CpuSolveBackend::swap(NodeVec a, NodeVec b) { v(a).swap(v(b)); }
void CpuSolveBackend::negate(NodeVec from, NodeVec to) {
  const double* x = p(from);
  double* y = p(to);
  parallelForEach(n_, [&](std::size_t m) { y[m] = -x[m]; });
}
void CpuSolveBackend::axpy(double a, NodeVec xr, NodeVec yr) {
  const double* x = p(xr);
  double* y = p(yr);
  parallelForEach(n_, [&](std::size_t m) { y[m] += a * x[m]; });
}
void CpuSolveBackend::formTrialAlong(double lambda) {
  const double *phi = p(NodeVec::Phi), *delta = p(NodeVec::Delta);
  double* trial = p(NodeVec::Trial);
  parallelForEach(n_, [&](std::size_t m) { trial[m] = phi[m] + lambda * delta[m]; });
}
void CpuSolveBackend::advance(double lambda) {
  double *phi = p(NodeVec::Phi), *Kphi = p(NodeVec::Kphi);
  const double *delta = p(NodeVec::Delta), *Kdelta = p(NodeVec::Kdelta);
  parallelForEach(n_, [&](std::size_t m) {
    phi[m] += lambda * delta[m];
    Kphi[m] += lambda * Kdelta[m];
  });
}
void CpuSolveBackend::removeMean(NodeVec x) { problem_.removeMean(p(x)); }

StepSlopes CpuSolveBackend::formFullStep() {
  problem_.applyVacuum(p(NodeVec::Delta), p(NodeVec::Kdelta));
  const double *phi = p(NodeVec::Phi), *F = p(NodeVec::F), *Kphi = p(NodeVec::Kphi), *delta = p(NodeVec::Delta),
               *Kdelta = p(NodeVec::Kdelta);
  double *trial = p(NodeVec::Trial), *Ftrial = p(NodeVec::Ftrial), *Ktrial = p(NodeVec::Ktrial);
  return deterministicSum<SlopeSum>(n_, [&](std::size_t m) {
    const double d = delta[m], kd = Kdelta[m], kp = Kphi[m];
    trial[m] = phi[m] + d;
    Ftrial[m] = Ktrial[m] = kp + kd;
    SlopeSum s;
    s.g0 = d * F[m];
    s.s1 = d * kp;
    s.s2 = d * kd;
    return s;
  });
}

void CpuSolveBackend::updatePreconditioner() {
  if (!ws_.preconditioner || ws_.kind != kind_ ||
      (kind_ == PreconditionerKind::Multigrid && !sameMultigrid(ws_.multigrid, multigrid_))) {
    ws_.preconditioner = makePreconditioner(kind_, multigrid_);
    ws_.kind = kind_;
    ws_.multigrid = multigrid_;
  }
  ws_.preconditioner->update(problem_);
}

int CpuSolveBackend::preconditionerLevels() const {
  const auto* mg = dynamic_cast<const MultigridPreconditioner*>(ws_.preconditioner.get());
  return mg ? mg->levelCount() : 0;
}

PcgResult CpuSolveBackend::solveJacobian(NodeVec rhs, NodeVec x, double relTol, int maxIterations) {
  return solvePcg(n_, applyJ_, *ws_.preconditioner, p(rhs), p(x), relTol, maxIterations, project_, &ws_.pcg,
                  applyJDot_);
}

namespace {
template <typename Fn>
void forWall(std::size_t count, const Fn& fn) {
  parallelForEach(count, fn, std::size_t(1) << 12);
}
}  // namespace

void CpuSolveBackend::setFarField(const FieldEvaluation& e, NodeVec x) { problem_.applyOpenBoundary(e.multipoles, p(x)); }
void CpuSolveBackend::setLinearizedFarField(NodeVec d, NodeVec out) {
  problem_.applyOpenBoundary(problem_.linearizedMultipoles(p(d)), p(out));
}
void CpuSolveBackend::addWallCoupling(NodeVec x, NodeVec out) { problem_.addWallCoupling(p(x), p(out)); }
void CpuSolveBackend::gatherWall(NodeVec x, WallVec out) {
  const double* src = p(x);
  double* dst = w(out).data();
  forWall(wall_.size(), [&](std::size_t i) { dst[i] = src[wall_[i]]; });
}
void CpuSolveBackend::scatterWall(WallVec in, double scale, NodeVec x) {
  const double* src = w(in).data();
  double* dst = p(x);
  forWall(wall_.size(), [&](std::size_t i) { dst[wall_[i]] = scale * src[i]; });
}
void CpuSolveBackend::zeroWall(NodeVec x) {
  double* dst = p(x);
  forWall(wall_.size(), [&](std::size_t i) { dst[wall_[i]] = 0.0; });
}
void CpuSolveBackend::wallDifference(NodeVec x, WallVec old, WallVec step) {
  const double* src = p(x);
  const double* o = w(old).data();
  double* s = w(step).data();
  forWall(wall_.size(), [&](std::size_t i) { s[i] = src[wall_[i]] - o[i]; });
}
void CpuSolveBackend::relaxWall(NodeVec x, WallVec step, double theta) {
  double* dst = p(x);
  double* s = w(step).data();
  forWall(wall_.size(), [&](std::size_t i) {
    dst[wall_[i]] -= (1.0 - theta) * s[i];
    s[i] *= theta;
  });
}
double CpuSolveBackend::wallDot(WallVec a, WallVec b) { return deterministicDot(w(a).data(), w(b).data(), wall_.size()); }
void CpuSolveBackend::copyWall(WallVec from, WallVec to) { w(to) = w(from); }
void CpuSolveBackend::swapWall(WallVec a, WallVec b) { w(a).swap(w(b)); }

}  // namespace field
}  // namespace lodestone
