#pragma once
// The module's topics, one binding function each (module.cpp calls them in
// this order, which is the order of docs/python.md).
#include <pybind11/pybind11.h>

namespace lodestone::python {

namespace py = pybind11;

void bindMaterials(py::module_& m);  // materials.cpp: magnetization laws, magnetic and MPM materials
void bindSources(py::module_& m);    // sources.cpp: poses, time profiles, field sources
void bindStage(py::module_& m);      // stage.cpp: grids, the magnetic force stage
void bindMpm(py::module_& m);        // mpm.cpp: the MPM solver
void bindScene(py::module_& m);      // scene.cpp: scene files and their runs
void bindNodes(py::module_& m);      // nodes.cpp: the node registry and networks
void bindVdb(py::module_& m);        // vdb.cpp: VDB files (where OpenVDB is built)

}  // namespace lodestone::python
