#include "cancel.h"

namespace lodestone::python {

Hook::~Hook() = default;

SolveProgress Hook::newtonProgress() {
  return [this](const NewtonIterationRecord& r) {
    return poll([&](py::dict& d) {
      d["stage"] = "newton";
      d["iteration"] = r.iteration;
      d["relative_residual"] = r.relativeResidual;
      d["cg_iterations"] = r.cgIterations;
      d["seconds"] = r.seconds;
    });
  };
}

void Hook::rethrow() {
  if (!error_) return;
  py::error_already_set e = std::move(*error_);
  error_.reset();
  throw e;
}

}  // namespace lodestone::python
