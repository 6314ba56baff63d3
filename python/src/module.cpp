// The Python module `lodestone`: the C++ layers for Python hosts (Houdini
// Python SOPs, Blender, notebooks). docs/python.md is generated from the
// docstrings (python/tools/python_docs.py).
#include <new>

#include <pybind11/pybind11.h>

#include "bindings.h"
#include "lodestone/core/base/error.h"
#include "lodestone/plugin/errors.h"

namespace lodestone::python {
namespace {

const char* kModuleDoc = R"(Lodestone: nonlinear magnetism for material point method solvers.

Units are SI throughout: m, s, A/m (H, M), T (B), N (forces), N/m^3 (force
densities), kg, 1/m^3 (micro-particle densities).

Arrays. Positions and vectors are numpy arrays of shape (N, 3), counts shape
(N,), grid values shape (nx, ny, nz) or (nx, ny, nz, 3) indexed [i, j, k].
float64 packed (C-contiguous) inputs are read in place; float32, strided and
non-contiguous inputs are converted to a float64 copy first. Other dtypes and
shapes raise ValueError naming the argument and the shape. Results are new
float64 arrays, or the caller's `out` array (C-contiguous float64, writable,
not sharing memory with an input). Grid fields of a stage are read-only views
of its storage, overwritten by its next run.

Errors. Lodestone's InvalidArgument becomes ValueError, a missing component
(OpenVDB) NotBuiltError, a failed node cook CookError, any other Lodestone
error RuntimeError; the message is the C++ one.

Threads. Stage runs, MPM steps and frames, scene runs, network cooks and VDB
I/O release the GIL, so other Python threads run meanwhile and several stages
or solvers may run at once on different threads. One object (a stage, a
solver, a network) must be used by one thread at a time, and the numpy arrays
passed to a call must not be changed by another thread during it. Progress
callables run on the calling thread with the GIL held, after each Newton
iteration of a field solve (stages, and the solves inside MPM substeps) and
after each substep (MPM, scenes); Ctrl-C (KeyboardInterrupt) is
noticed there, so a run stops within one iteration or substep. Lodestone
parallelizes inside a call with oneTBB.)";

}  // namespace
}  // namespace lodestone::python

PYBIND11_MODULE(lodestone, m) {
  namespace py = pybind11;
  using namespace lodestone::python;
  m.doc() = kModuleDoc;
  m.attr("__version__") = LODESTONE_VERSION_TEXT;

  static py::exception<lodestone::plugin::NotBuilt> notBuilt(m, "NotBuiltError", PyExc_RuntimeError);
  static py::exception<lodestone::plugin::CookFailed> cookFailed(m, "CookError", PyExc_RuntimeError);
  notBuilt.attr("__doc__") = "A feature needs a component this build lacks (OpenVDB).";
  cookFailed.attr("__doc__") = "A node's cook failed; the message names the node and the cause.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const lodestone::plugin::NotBuilt& e) {
      notBuilt(e.what());
    } catch (const lodestone::plugin::CookFailed& e) {
      if (e.notBuilt()) notBuilt(e.what()); else cookFailed(e.what());
    } catch (const lodestone::InvalidArgument& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const lodestone::Error& e) {
      PyErr_SetString(PyExc_RuntimeError, e.what());
    }
  });

  bindMaterials(m);
  bindSources(m);
  bindStage(m);
  bindMpm(m);
  bindScene(m);
  bindNodes(m);
  bindVdb(m);
}
