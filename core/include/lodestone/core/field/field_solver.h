#pragma once
// Newton-PCG solve of the nonlinear magnetostatic problem (Algorithm 1 of the
// paper, with the decisions of docs/physics.md): warm start, inexact Newton
// with Eisenstat-Walker forcing, preconditioned CG for J delta = -F, and a
// backtracking line search on the convex energy that falls back to the
// residual norm when the energy change is at round-off level. The one call
// below runs the Newton solver (newton_solver.h) on core's TBB backend
// (cpu_solve_backend.h); gpu/ runs the same solver on its CUDA backend.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "lodestone/core/field/cpu_solve_backend.h"
#include "lodestone/core/field/magnetostatic_problem.h"
#include "lodestone/core/field/newton_solver.h"
#include "lodestone/core/field/solve_report.h"
#include "lodestone/core/field/solve_settings.h"

namespace lodestone {
inline namespace field {

/// Solves for phi in place (phi holds the warm start on entry: one value per
/// node; pass zeros for a cold start). Never leaves non-finite values in phi.
/// `workspace` (optional) is reused storage, see FieldSolveWorkspace.
/// On return the problem holds the evaluation (M, residual, multipoles) at
/// phi; its Jacobian (element matrices, material stencil, cell tensors) may
/// be that of the previous Newton iterate (NewtonIterationRecord::
/// jacobianDeferred): call problem.evaluate(phi) before applying it.
FieldSolveReport solveField(MagnetostaticProblem& problem, std::vector<double>& phi,
                            const FieldSolveSettings& settings, const SolveProgress& progress = {},
                            FieldSolveWorkspace* workspace = nullptr);

}  // namespace field
}  // namespace lodestone
