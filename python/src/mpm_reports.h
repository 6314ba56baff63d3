#pragma once
// MPM frame reports as Python dicts (shared by mpm.cpp and scene.cpp).
#include <pybind11/pybind11.h>

#include "lodestone/core/mpm/solver.h"

namespace lodestone::python {

namespace py = pybind11;

/// The frame report's counts, times (s) and impulse (N*s) as a dict.
py::dict frameReportDict(const MpmFrameReport& r);

}  // namespace lodestone::python
