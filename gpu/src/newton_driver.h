#pragma once
// The Newton-PCG-multigrid driver of the field solve, written once over the
// FieldBackend operations (the algorithm of core/src/field/field_solver.cpp,
// pcg.cpp and multigrid.cpp).
#include "field_backend.h"
#include "lodestone/gpu/field_solver.h"

namespace lodestone {
namespace gpu {
namespace detail {

/// Solves in place; phi is backend memory (level-0 work slot 0), holding the
/// warm start (finite) on entry.
/// `wallUpdate` (may be empty) refreshes the Open wall values per iteration.
FieldSolveReport runNewton(FieldBackend& backend, double* phi, const FieldSolveSettings& settings,
                           const WallUpdate& wallUpdate = {});

struct PcgOutcome {
  int iterations = 0;
  double relativeResidual = 0;
  bool converged = false;
  bool breakdown = false;
};

/// PCG on a level with the given preconditioner apply (z = P^-1 r), from x = 0.
/// Work slots firstSlot..firstSlot+3 of that level.
template <typename Precondition>
PcgOutcome pcg(FieldBackend& be, int level, const double* b, double* x, double relTol, int maxIterations, bool project,
               int firstSlot, const Precondition& precondition);

}  // namespace detail
}  // namespace gpu
}  // namespace lodestone
