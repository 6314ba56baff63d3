#pragma once
// Geometric multigrid V-cycle as a preconditioner for the Newton systems of
// the field solve. Level 0 is the fine Jacobian itself (matrix-free); each
// coarser level doubles dx and rediscretizes with trilinear elements whose
// per-cell coefficient I + D averages the fine cells' mean dM/dH, so only
// cells touching material carry element matrices and the rest is the
// constant vacuum stencil. Damped-Jacobi smoothing before and after, full
// weighting R = P^T with trilinear P, CG on the coarsest grid: the cycle is a
// fixed symmetric positive definite operator, as PCG requires.
//
// Level 0 reads the Jacobian's material part as the problem assembled it,
// in 27-point rows at the material nodes (HullStencil): its products stream
// those rows along the grid rows instead of scattering element products.
//
// Storage precision: by default every level, the fine one included (a copy
// of the Jacobian's assembled rows), is stored and cycled in single
// precision. The preconditioner only shapes the CG search directions; the
// Newton residual and the CG operator stay in double, so the solution is
// unchanged (tests/core/test_multigrid.cpp compares both) while the cycle
// moves half the bytes. The cycle is then symmetric to float round-off.
//
// Cost per Newton step: update() keeps the levels' structure (cell lists,
// storage, work vectors) while the problem's grid and material cell set stay
// the same, as between the Newton steps of one solve, and only recomputes
// the values; a new material set on the same grid reuses the storage. The
// cycle fuses each smoothing sweep (and the residual with its restriction)
// into one pass over the level's vectors.
#include <memory>
#include <string>
#include <vector>

#include "lodestone/core/field/pcg.h"
#include "lodestone/core/field/solve_settings.h"

namespace lodestone {
inline namespace field {

class MultigridPreconditioner final : public Preconditioner {
 public:
  explicit MultigridPreconditioner(const MultigridSettings& settings = {});
  ~MultigridPreconditioner() override;
  /// Builds the levels for `problem`, or refreshes their values when its grid
  /// and material cells are those of the previous call.
  void update(const MagnetostaticProblem& problem) override;
  void apply(const double* r, double* z) const override;
  /// apply() with r . z summed in its last fine-level sweep (row by row).
  double applyDot(std::size_t n, const double* r, double* z) const override;
  std::string name() const override { return "multigrid"; }
  /// Number of levels including the fine grid (after update()).
  int levelCount() const;

  template <typename T>
  class Hierarchy;  // the levels in one storage precision (core/src/field/multigrid_hierarchy.h)

 private:
  MultigridSettings settings_;
  std::unique_ptr<Hierarchy<float>> single_;
  std::unique_ptr<Hierarchy<double>> double_;
};

}  // namespace field
}  // namespace lodestone
