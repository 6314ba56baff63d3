#include "lodestone/core/field/pcg.h"

#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lodestone/core/base/kept_capacity.h"
#include "lodestone/core/field/magnetostatic_problem.h"
#include "lodestone/core/base/parallel.h"
#include "lodestone/core/field/pcg_iteration.h"

namespace lodestone {
inline namespace field {

void JacobiPreconditioner::update(const MagnetostaticProblem& problem) {
  resizeKeepingCapacity(inverseDiagonal_, problem.nodeCount());
  problem.jacobianDiagonal(inverseDiagonal_.data());
  double* d = inverseDiagonal_.data();
  parallelForEach(inverseDiagonal_.size(), [&](std::size_t m) { d[m] = d[m] > 0 ? 1.0 / d[m] : 0.0; });
}

void JacobiPreconditioner::apply(const double* r, double* z) const {
  const double* d = inverseDiagonal_.data();
  parallelForEach(inverseDiagonal_.size(), [&](std::size_t m) { z[m] = d[m] * r[m]; });
}

double Preconditioner::applyDot(std::size_t n, const double* r, double* z) const {
  apply(r, z);
  return deterministicDot(r, z, n);
}

namespace {
// The TBB operations of the CG iteration (pcg_iteration.h), each update fused
// with its reduction where nothing is projected in between.
class CpuPcgOps {
 public:
  CpuPcgOps(std::size_t n, const std::function<void(const double*, double*)>& applyA,
            const Preconditioner& preconditioner, const double* b, double* x, const std::function<void(double*)>& project,
            PcgWorkspace& ws, const std::function<double(const double*, double*)>& applyADot)
      : n_(n), applyA_(applyA), pre_(preconditioner), b_(b), x_(x), project_(project), applyADot_(applyADot), ws_(ws) {
    for (std::vector<double>* v : {&ws.r, &ws.z, &ws.p, &ws.Ap}) resizeKeepingCapacity(*v, n);
  }

  double start() {
    double* r = ws_.r.data();
    if (project_) {
      parallelForEach(n_, [&](std::size_t m) {
        r[m] = b_[m];
        x_[m] = 0.0;
      });
      project_(r);
      return deterministicDot(r, r, n_);
    }
    return deterministicSum<double>(n_, [&](std::size_t m) {
      r[m] = b_[m];
      x_[m] = 0.0;
      return r[m] * r[m];
    });
  }
  // z = M^-1 r and r . z, fused when nothing is projected in between.
  double precondition() {
    if (project_) {
      pre_.apply(ws_.r.data(), ws_.z.data());
      project_(ws_.z.data());
      return deterministicDot(ws_.r.data(), ws_.z.data(), n_);
    }
    return pre_.applyDot(n_, ws_.r.data(), ws_.z.data());
  }
  void firstDirection() { ws_.p.swap(ws_.z); }  // p = z; z is overwritten by the next precondition()
  double applyA() {
    if (applyADot_) return applyADot_(ws_.p.data(), ws_.Ap.data());
    applyA_(ws_.p.data(), ws_.Ap.data());
    return deterministicDot(ws_.p.data(), ws_.Ap.data(), n_);
  }
  double step(double alpha) {
    const double *p = ws_.p.data(), *Ap = ws_.Ap.data();
    double *r = ws_.r.data(), *x = x_;
    if (project_) {
      parallelForEach(n_, [&](std::size_t m) {
        x[m] += alpha * p[m];
        r[m] -= alpha * Ap[m];
      });
      project_(r);
      return deterministicDot(r, r, n_);
    }
    // One pass over the vectors: the update and |r|^2 together (each index
    // is visited exactly once; the sum is as deterministic as deterministicDot).
    return deterministicSum<double>(n_, [&](std::size_t m) {
      x[m] += alpha * p[m];
      r[m] -= alpha * Ap[m];
      return r[m] * r[m];
    });
  }
  void nextDirection(double beta) {
    const double* z = ws_.z.data();
    double* p = ws_.p.data();
    parallelForEach(n_, [&](std::size_t m) { p[m] = z[m] + beta * p[m]; });
  }
  void finish() {
    if (project_) project_(x_);
  }

 private:
  std::size_t n_;
  const std::function<void(const double*, double*)>& applyA_;
  const Preconditioner& pre_;
  const double* b_;
  double* x_;
  const std::function<void(double*)>& project_;
  const std::function<double(const double*, double*)>& applyADot_;
  PcgWorkspace& ws_;
};
}  // namespace

PcgResult solvePcg(std::size_t n, const std::function<void(const double*, double*)>& applyA,
                   const Preconditioner& preconditioner, const double* b, double* x, double relTol,
                   int maxIterations, const std::function<void(double*)>& project, PcgWorkspace* workspace,
                   const std::function<double(const double*, double*)>& applyADot) {
  PcgWorkspace local;
  CpuPcgOps ops(n, applyA, preconditioner, b, x, project, workspace ? *workspace : local, applyADot);
  return pcgIterate(ops, relTol, maxIterations);
}

}  // namespace field
}  // namespace lodestone
