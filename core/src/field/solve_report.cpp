#include "lodestone/core/field/solve_report.h"

// Portable: compiled into gpu/'s standalone build as well.

namespace lodestone {
inline namespace field {

const char* toString(SolveStatus status) {
  switch (status) {
    case SolveStatus::Converged: return "converged";
    case SolveStatus::Trivial: return "trivial";
    case SolveStatus::IterationCap: return "iteration-cap";
    case SolveStatus::LineSearchFailed: return "line-search-failed";
    case SolveStatus::LinearSolverFailed: return "linear-solver-failed";
    case SolveStatus::NonFinite: return "non-finite";
    case SolveStatus::Cancelled: return "cancelled";
  }
  return "unknown";
}

}  // namespace field
}  // namespace lodestone
