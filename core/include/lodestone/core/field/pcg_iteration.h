#pragma once
// The preconditioned conjugate-gradient iteration, written once over the
// vector operations of a backend: core's solvePcg (pcg.h; TBB loops that fuse
// each update with its reduction) and the CUDA backend's CG (device kernels)
// run this loop. Standard library only.
//
// `Ops` provides, on its own vectors b, x, r, z, p, Ap (the null space
// removed from r, z and x where the system is singular):
//   double start();              r = b, x = 0; returns |r|^2
//   double precondition();       z = P^-1 r; returns r . z
//   void firstDirection();       p = z
//   double applyA();             Ap = A p; returns p . Ap
//   double step(double alpha);   x += alpha p, r -= alpha Ap; returns |r|^2
//   void nextDirection(double beta);  p = z + beta p
//   void finish();               the null space removed from x
#include <cmath>

#include "lodestone/core/field/pcg.h"

namespace lodestone {
inline namespace field {

/// Solves A x = b from x = 0 until ||r|| <= relTol ||b|| or maxIterations.
template <typename Ops>
PcgResult pcgIterate(Ops& ops, double relTol, int maxIterations) {
  PcgResult res;
  const double bnorm = std::sqrt(ops.start());
  if (!(bnorm > 0)) {
    res.converged = std::isfinite(bnorm);
    res.breakdown = !std::isfinite(bnorm);
    return res;
  }
  double rz = ops.precondition();
  ops.firstDirection();
  double rnorm = bnorm;
  while (res.iterations < maxIterations) {
    const double pAp = ops.applyA();
    if (!(pAp > 0) || !std::isfinite(pAp) || !std::isfinite(rz)) {
      res.breakdown = true;
      break;
    }
    const double alpha = rz / pAp;
    ++res.iterations;
    rnorm = std::sqrt(ops.step(alpha));
    if (rnorm <= relTol * bnorm) {
      res.converged = true;
      break;
    }
    const double rzNew = ops.precondition();
    const double beta = rzNew / rz;
    rz = rzNew;
    ops.nextDirection(beta);
  }
  res.relativeResidual = rnorm / bnorm;
  ops.finish();
  return res;
}

}  // namespace field
}  // namespace lodestone
