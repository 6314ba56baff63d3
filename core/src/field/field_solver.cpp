#include "lodestone/core/field/field_solver.h"

namespace lodestone {
inline namespace field {

FieldSolveReport solveField(MagnetostaticProblem& problem, std::vector<double>& phi,
                            const FieldSolveSettings& settings, const SolveProgress& progress,
                            FieldSolveWorkspace* workspace) {
  settings.validate();
  FieldSolveWorkspace localWorkspace;
  CpuSolveBackend backend(problem, phi, settings, workspace ? *workspace : localWorkspace);
  return NewtonSolver(backend, settings, progress).solve();
}

}  // namespace field
}  // namespace lodestone
