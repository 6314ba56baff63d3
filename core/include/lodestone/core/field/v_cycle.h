#pragma once
// The multigrid V-cycle, written once over a backend's level operations:
// core's MultigridPreconditioner (multigrid.h: single- or double-precision
// levels, sweeps fused into row passes) and the CUDA backend's device levels
// run this recursion. Standard library only.
//
// `Ops` provides, for level l (0 is the fine grid) with its own b and x:
//   bool coarsest(int l);          l is the coarsest level
//   void solveCoarsest(int l);     x = A_l^-1 b (CG to a tight tolerance)
//   void smoothFromZero(int l);    x = w D_l^-1 b (the first sweep from x = 0)
//   void smooth(int l, bool last); x += w D_l^-1 (b - A_l x) (`last`: the cycle's final sweep)
//   void restrictResidual(int l);  b_{l+1} = R (b - A_l x) (fixed nodes 0)
//   void prolongAdd(int l);        x += P x_{l+1} (fixed nodes unchanged)
// With as many sweeps after the coarse correction as before, the cycle is a
// symmetric positive definite operator, as CG requires.

namespace lodestone {
inline namespace field {

template <typename Ops>
void vCycle(Ops& ops, int level, int preSmoothing, int postSmoothing) {
  if (ops.coarsest(level)) {
    ops.solveCoarsest(level);
    return;
  }
  ops.smoothFromZero(level);
  for (int s = 1; s < preSmoothing; ++s) ops.smooth(level, false);
  ops.restrictResidual(level);
  vCycle(ops, level + 1, preSmoothing, postSmoothing);
  ops.prolongAdd(level);
  for (int s = 0; s < postSmoothing; ++s) ops.smooth(level, s + 1 == postSmoothing);
}

}  // namespace field
}  // namespace lodestone
