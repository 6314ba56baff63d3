#include "lodestone/core/field/solve_settings.h"

#include <cmath>

#include "lodestone/core/base/error.h"

// Portable: compiled into gpu/'s standalone build as well.

namespace lodestone {
inline namespace field {

const char* toString(PreconditionerKind kind) {
  switch (kind) {
    case PreconditionerKind::Jacobi: return "jacobi";
    case PreconditionerKind::Multigrid: return "multigrid";
  }
  return "unknown";
}

void MultigridSettings::validate() const {
  require(preSmoothing >= 1 && preSmoothing <= 20, "multigrid: preSmoothing must be 1..20, got ", preSmoothing);
  require(postSmoothing == preSmoothing, "multigrid: postSmoothing must equal preSmoothing (",
          preSmoothing, ") to keep the cycle symmetric, got ", postSmoothing);
  require(std::isfinite(jacobiWeight) && jacobiWeight > 0 && jacobiWeight <= 1,
          "multigrid: jacobiWeight must be in (0, 1], got ", jacobiWeight);
  require(coarsestNodes >= 3, "multigrid: coarsestNodes must be >= 3, got ", coarsestNodes);
}

void FieldSolveSettings::validate() const {
  require(std::isfinite(tolerance) && tolerance > 0 && tolerance < 1,
          "field solve: tolerance must be in (0, 1), got ", tolerance);
  require(maxNewtonIterations >= 1, "field solve: maxNewtonIterations must be >= 1, got ", maxNewtonIterations);
  require(maxCgIterations >= 1, "field solve: maxCgIterations must be >= 1, got ", maxCgIterations);
  require(std::isfinite(forcingMax) && forcingMax > 0 && forcingMax < 1,
          "field solve: forcingMax must be in (0, 1), got ", forcingMax);
  require(std::isfinite(forcingGamma) && forcingGamma > 0 && forcingGamma <= 1,
          "field solve: forcingGamma must be in (0, 1], got ", forcingGamma);
  require(std::isfinite(forcingAlpha) && forcingAlpha > 1 && forcingAlpha <= 2,
          "field solve: forcingAlpha must be in (1, 2], got ", forcingAlpha);
  require(maxLineSearchCuts >= 1, "field solve: maxLineSearchCuts must be >= 1, got ", maxLineSearchCuts);
  require(std::isfinite(armijo) && armijo > 0 && armijo < 0.5, "field solve: armijo must be in (0, 0.5), got ",
          armijo);
  require(preconditioner == PreconditionerKind::Jacobi || preconditioner == PreconditionerKind::Multigrid,
          "field solve: unknown preconditioner ", int(preconditioner));
  require(std::isfinite(wallPredictionTolerance) && wallPredictionTolerance > 0 && wallPredictionTolerance < 1,
          "field solve: wallPredictionTolerance must be in (0, 1), got ", wallPredictionTolerance);
  multigrid.validate();
}

}  // namespace field
}  // namespace lodestone
