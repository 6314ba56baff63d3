#pragma once
// Geometric multigrid V-cycle as a preconditioner for the Newton systems of
// the field solve. Level 0 is the fine Jacobian itself (matrix-free); each
// coarser level doubles dx and rediscretizes with trilinear elements whose
// per-cell coefficient I + D averages the fine cells' mean dM/dH, so only
// cells touching material carry element matrices and the rest is the
// constant vacuum stencil. Damped-Jacobi smoothing before and after, full
// weighting R = P^T with trilinear P, CG on the coarsest grid: the cycle is a
// fixed symmetric positive definite operator, as PCG requires.
#include <memory>
#include <string>
#include <vector>

#include "lodestone/core/pcg.h"

namespace lodestone {

struct MultigridSettings {
  int preSmoothing = 2;         ///< damped-Jacobi sweeps before the coarse correction
  int postSmoothing = 2;        ///< and after (same count keeps the cycle symmetric)
  double jacobiWeight = 0.7;    ///< smoother damping in (0, 1]
  int coarsestNodes = 5;        ///< stop coarsening when an axis has this many nodes or fewer

  void validate() const;
};

class MultigridPreconditioner final : public Preconditioner {
 public:
  explicit MultigridPreconditioner(const MultigridSettings& settings = {});
  ~MultigridPreconditioner() override;
  void update(const MagnetostaticProblem& problem) override;
  void apply(const double* r, double* z) const override;
  std::string name() const override { return "multigrid"; }
  /// Number of levels including the fine grid (after update()).
  int levelCount() const { return int(levels_.size()); }

 private:
  struct Level;
  struct Work {
    std::vector<double> x, b, r, t1, t2;
  };
  void cycle(std::size_t level, const double* b, double* x) const;
  void applyLevel(std::size_t level, const double* v, double* out) const;

  MultigridSettings settings_;
  const MagnetostaticProblem* problem_ = nullptr;
  std::vector<std::unique_ptr<Level>> levels_;
  mutable std::vector<Work> workspace_;
};

}  // namespace lodestone
