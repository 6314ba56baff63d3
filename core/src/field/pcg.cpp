#include "lodestone/core/field/pcg.h"

#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lodestone/core/field/magnetostatic_problem.h"
#include "lodestone/core/base/parallel.h"

namespace lodestone {

namespace {
template <typename Fn>
void forEach(std::size_t n, const Fn& fn) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 13), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t m = r.begin(); m != r.end(); ++m) fn(m);
  });
}
}  // namespace

void JacobiPreconditioner::update(const MagnetostaticProblem& problem) {
  inverseDiagonal_.resize(problem.nodeCount());
  problem.jacobianDiagonal(inverseDiagonal_.data());
  double* d = inverseDiagonal_.data();
  forEach(inverseDiagonal_.size(), [&](std::size_t m) { d[m] = d[m] > 0 ? 1.0 / d[m] : 0.0; });
}

void JacobiPreconditioner::apply(const double* r, double* z) const {
  const double* d = inverseDiagonal_.data();
  forEach(inverseDiagonal_.size(), [&](std::size_t m) { z[m] = d[m] * r[m]; });
}

double Preconditioner::applyDot(std::size_t n, const double* r, double* z) const {
  apply(r, z);
  return deterministicDot(r, z, n);
}

PcgResult solvePcg(std::size_t n, const std::function<void(const double*, double*)>& applyA,
                   const Preconditioner& preconditioner, const double* b, double* x, double relTol,
                   int maxIterations, const std::function<void(double*)>& project, PcgWorkspace* workspace,
                   const std::function<double(const double*, double*)>& applyADot) {
  PcgResult res;
  PcgWorkspace local;
  PcgWorkspace& ws = workspace ? *workspace : local;
  ws.r.resize(n);
  ws.z.resize(n);
  ws.p.resize(n);
  ws.Ap.resize(n);
  std::vector<double>&r = ws.r, &z = ws.z, &p = ws.p, &Ap = ws.Ap;
  double bnorm2;
  if (project) {
    forEach(n, [&](std::size_t m) {
      r[m] = b[m];
      x[m] = 0.0;
    });
    project(r.data());
    bnorm2 = deterministicDot(r.data(), r.data(), n);
  } else {
    bnorm2 = deterministicSum<double>(n, [&](std::size_t m) {
      r[m] = b[m];
      x[m] = 0.0;
      return r[m] * r[m];
    });
  }
  const double bnorm = std::sqrt(bnorm2);
  if (!(bnorm > 0)) {
    res.converged = std::isfinite(bnorm);
    res.breakdown = !std::isfinite(bnorm);
    return res;
  }
  // z = M^-1 r and r . z, fused when nothing is projected in between.
  const auto precondition = [&]() {
    if (project) {
      preconditioner.apply(r.data(), z.data());
      project(z.data());
      return deterministicDot(r.data(), z.data(), n);
    }
    return preconditioner.applyDot(n, r.data(), z.data());
  };
  double rz = precondition();
  p.swap(z);  // p = z; z is overwritten by the next precondition()
  double rnorm = bnorm;
  while (res.iterations < maxIterations) {
    double pAp;
    if (applyADot) {
      pAp = applyADot(p.data(), Ap.data());
    } else {
      applyA(p.data(), Ap.data());
      pAp = deterministicDot(p.data(), Ap.data(), n);
    }
    if (!(pAp > 0) || !std::isfinite(pAp) || !std::isfinite(rz)) {
      res.breakdown = true;
      break;
    }
    const double alpha = rz / pAp;
    ++res.iterations;
    if (project) {
      forEach(n, [&](std::size_t m) {
        x[m] += alpha * p[m];
        r[m] -= alpha * Ap[m];
      });
      project(r.data());
      rnorm = std::sqrt(deterministicDot(r.data(), r.data(), n));
    } else {
      // One pass over the vectors: the update and |r|^2 together (each index
      // is visited exactly once; the sum is as deterministic as deterministicDot).
      rnorm = std::sqrt(deterministicSum<double>(n, [&](std::size_t m) {
        x[m] += alpha * p[m];
        r[m] -= alpha * Ap[m];
        return r[m] * r[m];
      }));
    }
    if (rnorm <= relTol * bnorm) {
      res.converged = true;
      break;
    }
    const double rzNew = precondition();
    const double beta = rzNew / rz;
    rz = rzNew;
    forEach(n, [&](std::size_t m) { p[m] = z[m] + beta * p[m]; });
  }
  res.relativeResidual = rnorm / bnorm;
  if (project) project(x);
  return res;
}

}  // namespace lodestone
