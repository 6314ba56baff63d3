#pragma once
// MPM frame reports as Python dicts (shared by mpm.cpp and scene.cpp).
#include <functional>

#include <pybind11/pybind11.h>

#include "cancel.h"
#include "lodestone/core/mpm/solver.h"

namespace lodestone::python {

namespace py = pybind11;

/// The frame report's counts, times (s) and impulse (N*s) as a dict.
py::dict frameReportDict(const MpmFrameReport& r);

/// solver.advanceFrame(duration) without the GIL, polling `hook` after each
/// substep (report stage "substep", filled by `fill`) and after each Newton
/// iteration of a field solve inside a substep (stage "newton"), so that
/// Ctrl-C stops a long solve too; raises what the hook caught.
MpmFrameReport advanceFrameHooked(MpmSolver& solver, double duration, Hook& hook,
                                  const std::function<void(const MpmProgress&, py::dict&)>& fill);

}  // namespace lodestone::python
