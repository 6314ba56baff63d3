#pragma once
// Long calls (stage runs, MPM steps and frames, scene runs) release the GIL
// and come back to Python only through the C++ progress hooks the solvers
// already have (SolveProgress after each Newton iteration, MpmProgressCallback
// after each substep; the `lodestone run` command stops on Ctrl-C the same
// way). At each hook a Hook takes the GIL, runs Python's pending signal
// handlers (PyErr_CheckSignals: Ctrl-C raises KeyboardInterrupt there) and
// the caller's progress callable; an exception from either, or a callable
// returning False, asks the solver to stop. The exception is kept and raised
// once the call has returned and the GIL is held again.
#include <optional>
#include <utility>

#include <pybind11/pybind11.h>

#include "lodestone/core/field/solve_report.h"

namespace lodestone::python {

namespace py = pybind11;

/// Runs `clear` when it goes out of scope (also by an exception): takes a
/// hook off the solver it was given to before the hook is destroyed.
template <typename Clear>
class Unhook {
 public:
  explicit Unhook(Clear clear) : clear_(std::move(clear)) {}
  ~Unhook() { clear_(); }
  Unhook(const Unhook&) = delete;
  Unhook& operator=(const Unhook&) = delete;

 private:
  Clear clear_;
};

class Hook {
 public:
  /// `progress`: None or a callable taking one dict (the hook's report).
  explicit Hook(py::object progress) : progress_(std::move(progress)) {}
  ~Hook();
  Hook(const Hook&) = delete;
  Hook& operator=(const Hook&) = delete;

  /// Called by the solver without the GIL; true to continue. `fill` adds
  /// the report's entries to the dict (with the GIL held).
  template <typename Fill>
  bool poll(const Fill& fill) {
    py::gil_scoped_acquire gil;
    if (stop_) return false;
    try {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      if (!progress_.is_none()) {
        py::dict report;
        fill(report);
        const py::object keepGoing = progress_(report);
        if (!keepGoing.is_none() && !keepGoing.cast<bool>()) {
          cancelledByCallback_ = true;
          stop_ = true;
        }
      }
    } catch (py::error_already_set& e) {
      error_.emplace(std::move(e));
      stop_ = true;
    }
    return !stop_;
  }

  /// This hook as a field solve's progress (SolveProgress), called after each
  /// Newton iteration: the report has stage "newton", iteration,
  /// relative_residual, cg_iterations and seconds. The hook must outlive
  /// every solve that calls it.
  SolveProgress newtonProgress();

  /// With the GIL held: raises the kept exception, if any.
  void rethrow();
  /// The progress callable returned False.
  bool cancelledByCallback() const { return cancelledByCallback_; }

 private:
  py::object progress_;
  std::optional<py::error_already_set> error_;
  bool stop_ = false;
  bool cancelledByCallback_ = false;
};

}  // namespace lodestone::python
