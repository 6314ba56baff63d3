// Scene files: load, validate, build the solver and run frames.
#include <memory>

#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "cancel.h"
#include "mpm_reports.h"
#include "lodestone/plugin/scene.h"

namespace lodestone::python {

void bindScene(py::module_& m) {
  using plugin::Scene;
  py::class_<Scene>(m, "Scene",
                    "A scene file (docs/scenes.md): domain, materials, bodies, magnets, fields, colliders and time "
                    "line, read strictly (unknown keys, wrong types and out-of-range values raise ValueError "
                    "naming the entry).")
      .def_static(
          "load",
          [](const std::string& path, bool full, double dx) {
            plugin::SceneOptions o;
            o.full = full;
            o.dx = dx;
            return plugin::loadScene(path, o);
          },
          py::arg("path"), py::arg("full") = false, py::arg("dx") = 0.0,
          "Reads and validates a scene file; `full` uses its full-resolution dx, `dx` > 0 overrides the grid "
          "spacing (m).")
      .def_static(
          "parse",
          [](const std::string& text, const std::string& sourceName, double dx) {
            plugin::SceneOptions o;
            o.dx = dx;
            return plugin::parseScene(text, sourceName, o);
          },
          py::arg("text"), py::arg("source_name") = "<string>", py::arg("dx") = 0.0,
          "The same from JSON text; `source_name` appears in messages and resolves relative file paths.")
      .def_readonly("name", &Scene::name)
      .def_readonly("description", &Scene::description)
      .def_readonly("start_frame", &Scene::startFrame, "The number of the first simulated frame.")
      .def_readonly("frames", &Scene::frames, "Frames to simulate.")
      .def_readonly("fps", &Scene::fps, "Frames per second.")
      .def_property_readonly("frame_duration", &Scene::frameDuration, "s")
      .def_property_readonly("grid", [](const Scene& s) { return s.settings.grid; }, "The MPM Grid.")
      .def_property_readonly("settings", [](const Scene& s) { return s.settings; }, "The MpmSettings (a copy).")
      .def(
          "memory_estimate",
          [](const Scene& s) {
            const std::unique_ptr<MpmSolver> solver = plugin::buildSolver(s);
            const plugin::MemoryCounts c = plugin::sceneMemory(s, solver.get());
            const plugin::MemoryEstimate e = plugin::estimateMemory(c);
            py::dict d;
            d["total_bytes"] = e.total();
            d["mpm_grid_bytes"] = e.mpmGrid;
            d["field_solve_bytes"] = e.fieldGrid;
            d["particles_bytes"] = e.particles;
            d["previews_bytes"] = e.outputs;
            d["mpm_nodes"] = c.mpmNodes;
            d["field_solve_nodes"] = c.fieldNodes;
            d["field_material_cells"] = c.fieldMaterialCells;
            d["particles"] = c.particles;
            d["limit_bytes"] = plugin::memoryLimitBytes();
            return d;
          },
          "The memory a run of the scene needs at its largest, bytes, by part (docs/cli.md, \"Memory\"): "
          "total_bytes, mpm_grid_bytes, field_solve_bytes, particles_bytes, previews_bytes (frame previews), "
          "the counts behind them (mpm_nodes: the MPM grid's nodes in the runs of each x-row the material reaches; "
          "field_solve_nodes; field_material_cells: the field solve's cells the magnetic material reaches; particles: with all that emitters add by the last frame) and limit_bytes (80% of this machine's memory or of a lower control-group limit, or "
          "LODESTONE_MEMORY_LIMIT_GIB). Without what this process already holds; builds the solver to count.")
      .def("build_solver", [](const Scene& s) { return std::shared_ptr<MpmSolver>(plugin::buildSolver(s)); },
           "A new MpmSolver with the scene's bodies, magnets, fields and colliders at the scene's start time.")
      .def(
          "run",
          [](const Scene& scene, int frames, const py::object& progress, const py::object& onFrame) {
            std::shared_ptr<MpmSolver> solver(plugin::buildSolver(scene));
            const int count = frames > 0 ? frames : scene.frames;
            py::list reports;
            Hook hook(progress);
            for (int f = 0; f < count; ++f) {
              const int frame = scene.startFrame + f;
              const MpmFrameReport r =
                  advanceFrameHooked(*solver, scene.frameDuration(), hook, [&](const MpmProgress& p, py::dict& d) {
                    d["frame"] = frame;
                    d["substep"] = p.substep;
                    d["time"] = p.time;
                    d["fraction"] = (f + p.fraction) / count;
                  });
              py::dict d = frameReportDict(r);
              d["frame"] = frame;
              reports.append(d);
              if (r.cancelled) break;
              if (!onFrame.is_none()) onFrame(frame, solver);
            }
            return py::make_tuple(solver, reports);
          },
          py::arg("frames") = 0, py::arg("progress") = py::none(), py::arg("on_frame") = py::none(),
          "Builds the solver and simulates `frames` frames (0: the scene's count), releasing the GIL while it "
          "steps. `progress(dict)` runs after each substep (keys: stage 'substep', frame, substep, time (s), "
          "fraction of the run) and after each Newton iteration of a field solve (stage 'newton', iteration, "
          "relative_residual, cg_iterations, seconds); returning False stops the run, and Ctrl-C raises "
          "KeyboardInterrupt at the next of these points (a field solve stopped that way leaves its substep with "
          "the field reached; the frame is not complete). `on_frame(frame, solver)` runs after each frame, with the "
          "GIL. Returns (solver, list of frame report dicts).");
}

}  // namespace lodestone::python
