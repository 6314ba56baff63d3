// The multigrid preconditioner's public face: one hierarchy of levels in the
// storage precision the settings choose (multigrid_hierarchy.h).
#include "lodestone/core/field/multigrid.h"

#include "multigrid_hierarchy.h"

#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace field {

MultigridPreconditioner::MultigridPreconditioner(const MultigridSettings& settings) : settings_(settings) {
  settings_.validate();
}
MultigridPreconditioner::~MultigridPreconditioner() = default;

void MultigridPreconditioner::update(const MagnetostaticProblem& problem) {
  if (settings_.singlePrecision) {
    if (!single_) single_ = std::make_unique<Hierarchy<float>>(settings_);
    single_->update(problem);
  } else {
    if (!double_) double_ = std::make_unique<Hierarchy<double>>(settings_);
    double_->update(problem);
  }
}

void MultigridPreconditioner::apply(const double* r, double* z) const {
  if (settings_.singlePrecision) {
    require(bool(single_), "multigrid: apply() before update()");
    single_->apply(r, z);
  } else {
    require(bool(double_), "multigrid: apply() before update()");
    double_->apply(r, z);
  }
}

double MultigridPreconditioner::applyDot(std::size_t, const double* r, double* z) const {
  if (settings_.singlePrecision) {
    require(bool(single_), "multigrid: apply() before update()");
    return single_->applyDot(r, z);
  }
  require(bool(double_), "multigrid: apply() before update()");
  return double_->applyDot(r, z);
}

int MultigridPreconditioner::levelCount() const {
  if (settings_.singlePrecision) return single_ ? single_->levelCount() : 0;
  return double_ ? double_->levelCount() : 0;
}

}  // namespace field
}  // namespace lodestone
