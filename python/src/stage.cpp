// Grids and the magnetic force stage.
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "cancel.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/stage/magnetic_stage.h"

namespace lodestone::python {

namespace {

// Runs `body` without the GIL with a Hook as the stage's progress; raises
// what the hook caught.
template <typename Body>
MagneticStageReport runHooked(MagneticForceStage& stage, const py::object& progress, const Body& body) {
  Hook hook(progress);
  stage.setProgress(hook.newtonProgress());
  const Unhook unhook([&stage] { stage.setProgress({}); });
  MagneticStageReport report;
  {
    py::gil_scoped_release release;
    report = body();
  }
  hook.rethrow();
  return report;
}

// A grid field sampled at positions without the GIL.
template <typename Sample>
py::array_t<double> sampleAt(const py::object& positions, const py::object& out, const Sample& sample) {
  const Vec3Input x(positions, "positions");
  Vec3d* o = nullptr;
  py::array_t<double> result = vec3Output(out, x.size(), {{"positions", {x.begin(), x.end()}}}, o);
  py::gil_scoped_release release;
  sample(x.data(), x.size(), o);
  return result;
}

}  // namespace

void bindStage(py::module_& m) {
  py::class_<GridSpec>(m, "Grid",
                       "A node-centred Cartesian grid: node (i, j, k) at origin + dx (i, j, k). Arrays of one "
                       "value per node have shape (nx, ny, nz), index [i, j, k].")
      .def(py::init([](const py::object& origin, double dx, const std::tuple<int, int, int>& dims) {
             GridSpec g{toVec3(origin, "origin"), dx, {std::get<0>(dims), std::get<1>(dims), std::get<2>(dims)}};
             g.validate();
             return g;
           }),
           py::arg("origin"), py::arg("dx"), py::arg("dims"),
           "origin: world position of node (0, 0, 0), m; dx: node spacing, m; dims: nodes per axis (>= 2 each).")
      .def_property_readonly("origin", [](const GridSpec& g) { return fromVec3(g.origin); }, "m")
      .def_readonly("dx", &GridSpec::dx, "Node spacing, m.")
      .def_property_readonly("dims", [](const GridSpec& g) { return py::make_tuple(g.dims.i, g.dims.j, g.dims.k); },
                             "Nodes per axis (nx, ny, nz).")
      .def_property_readonly("node_count", &GridSpec::nodeCount)
      .def("__repr__", [](const GridSpec& g) {
        return concat("<Grid origin (", g.origin.x, ", ", g.origin.y, ", ", g.origin.z, ") m, dx ", g.dx, " m, ",
                      g.dims.i, " x ", g.dims.j, " x ", g.dims.k, " nodes>");
      });

  py::class_<MagneticStageSettings>(m, "StageSettings",
                                    "Settings of the magnetic force stage (validated when the stage takes them).")
      .def(py::init<>())
      .def_property(
          "boundary", [](const MagneticStageSettings& s) { return std::string(toString(s.boundary)); },
          [](MagneticStageSettings& s, const std::string& v) {
            if (v == "open") s.boundary = BoundaryKind::Open;
            else if (v == "shield") s.boundary = BoundaryKind::Shield;
            else throw py::value_error(concat("boundary: expected 'open' or 'shield', got '", v, "'"));
          },
          "'open' (far-field potential, default) or 'shield' (the paper's Neumann wall).")
      .def_property(
          "out_of_grid",
          [](const MagneticStageSettings& s) { return s.outOfGrid == OutOfGridPolicy::Skip ? "skip" : "throw"; },
          [](MagneticStageSettings& s, const std::string& v) {
            if (v == "throw") s.outOfGrid = OutOfGridPolicy::Throw;
            else if (v == "skip") s.outOfGrid = OutOfGridPolicy::Skip;
            else throw py::value_error(concat("out_of_grid: expected 'throw' or 'skip', got '", v, "'"));
          },
          "'throw' (ValueError naming the particle) or 'skip' (ignored, counted in the report).")
      .def_property(
          "tolerance", [](const MagneticStageSettings& s) { return s.solve.tolerance; },
          [](MagneticStageSettings& s, double v) { s.solve.tolerance = v; },
          "Relative Newton residual to stop at (default 1e-8).")
      .def_property(
          "max_newton_iterations", [](const MagneticStageSettings& s) { return s.solve.maxNewtonIterations; },
          [](MagneticStageSettings& s, int v) { s.solve.maxNewtonIterations = v; }, "Newton iteration cap.")
      .def_readwrite("warm_start", &MagneticStageSettings::warmStart,
                     "Start each solve from the previous potential.")
      .def_readwrite("applied_field_only", &MagneticStageSettings::appliedFieldOnly,
                     "Skip the solve: H = H_ext (weak magnetization).")
      .def_readwrite("force_mask_dilation", &MagneticStageSettings::forceMaskDilation,
                     "Nodes beyond the material where the force may act (0..8).");

  py::class_<MagneticStageReport>(m, "StageReport", "Outcome and timings (s) of one stage run.")
      .def_property_readonly("converged", &MagneticStageReport::converged)
      .def_property_readonly("status", [](const MagneticStageReport& r) { return std::string(toString(r.solve.status)); },
                             "'converged', 'trivial', 'cancelled', ...")
      .def_property_readonly("newton_iterations", [](const MagneticStageReport& r) { return r.solve.newtonIterations; })
      .def_property_readonly("cg_iterations", [](const MagneticStageReport& r) { return r.solve.cgIterations; })
      .def_property_readonly("relative_residual", [](const MagneticStageReport& r) { return r.solve.relativeResidual; })
      .def_property_readonly("total_force", [](const MagneticStageReport& r) { return fromVec3(r.totalForce); },
                             "Sum of nodal forces, N.")
      .def_readonly("total_count", &MagneticStageReport::totalCount, "Integral of n over the grid (micro-particles).")
      .def_property_readonly("skipped", [](const MagneticStageReport& r) { return r.transfer.skipped; },
                             "Particles outside the grid ignored under out_of_grid = 'skip'.")
      .def_readonly("seconds_transfer", &MagneticStageReport::secondsTransfer, "s")
      .def_readonly("seconds_solve", &MagneticStageReport::secondsSolve, "s")
      .def_readonly("seconds_force", &MagneticStageReport::secondsForce, "s")
      .def_readonly("seconds_total", &MagneticStageReport::secondsTotal, "s")
      .def_readonly("warnings", &MagneticStageReport::warnings)
      .def("summary", &MagneticStageReport::summary, "Multi-line summary with units.")
      .def("__repr__", [](const MagneticStageReport& r) {
        return concat("<StageReport ", toString(r.solve.status), ", ", r.solve.newtonIterations, " Newton, ",
                      r.secondsTotal, " s>");
      });

  py::class_<MagneticForceStage, std::shared_ptr<MagneticForceStage>>(
      m, "MagneticForceStage",
      "The magnetic-force stage an MPM host calls per step: transfers the micro-particle counts n_p of the "
      "material points to the nodal density n (1/m^3), solves the nonlinear magnetostatic problem for the "
      "potential phi (A), and recovers H, M (A/m), B (T), the force density t (N/m^3) and nodal force f (N). "
      "Field arrays are read-only views of the stage's storage (shape (nx, ny, nz[, 3])), valid until the "
      "stage is gone and overwritten by the next run: copy them to keep them. One stage is used by one "
      "thread at a time; run() releases the GIL.")
      .def(py::init<const GridSpec&, const MagneticMaterial&, const MagneticStageSettings&>(), py::arg("grid"),
           py::arg("material"), py::arg("settings") = MagneticStageSettings(),
           "A stage on `grid` for `material`; ValueError on a bad grid or settings.")
      .def(
          "run",
          [](MagneticForceStage& stage, const py::object& positions, const py::object& counts,
             const FieldSource& sources, double time, const py::object& progress) {
            const Vec3Input x(positions, "positions");
            const ScalarInput n(counts, "counts", long(x.size()));
            const ParticleView view{x.data(), n.data(), x.size()};
            return runHooked(stage, progress, [&] { return stage.run(view, sources, time); });
          },
          py::arg("positions"), py::arg("counts"), py::arg("sources"), py::arg("time") = 0.0,
          py::arg("progress") = py::none(),
          "Transfer + solve + force for material points at positions (m, shape (N, 3)) carrying counts n_p "
          "(micro-particles, shape (N,)) in the field of `sources` at `time` (s). `progress(dict)` is called "
          "after each Newton iteration (keys: stage, iteration, relative_residual, cg_iterations, seconds); "
          "returning False stops the solve (report status 'cancelled'). Ctrl-C raises KeyboardInterrupt at "
          "the next iteration. Returns a StageReport.")
      .def(
          "run_on_density",
          [](MagneticForceStage& stage, const py::object& density, const FieldSource& sources, double time,
             const py::object& progress) {
            const GridInput n(density, "density", stage.grid());
            return runHooked(stage, progress, [&] { return stage.runOnDensity(n.view(), sources, time); });
          },
          py::arg("density"), py::arg("sources"), py::arg("time") = 0.0, py::arg("progress") = py::none(),
          "Solve + force for a micro-particle density n (1/m^3, shape (nx, ny, nz) of the stage grid) the host "
          "transferred itself.")
      .def(
          "particle_forces",
          [](const MagneticForceStage& stage, const py::object& positions, const py::object& counts,
             const py::object& out) {
            const Vec3Input x(positions, "positions");
            const ScalarInput n(counts, "counts", long(x.size()));
            Vec3d* o = nullptr;
            py::array_t<double> result =
                vec3Output(out, x.size(), {{"positions", {x.begin(), x.end()}}, {"counts", {n.begin(), n.end()}}}, o);
            {
              py::gil_scoped_release release;
              stage.particleForces({x.data(), n.data(), x.size()}, o);
            }
            return result;
          },
          py::arg("positions"), py::arg("counts"), py::arg("out") = py::none(),
          "Conservative force on each material point (N, shape (N, 3)); the particles must be those of the "
          "last run(). `out`: an optional C-contiguous float64 (N, 3) array to write into (not one of the "
          "inputs).")
      .def(
          "sample_force_density",
          [](const MagneticForceStage& stage, const py::object& positions, const py::object& out) {
            return sampleAt(positions, out, [&](const Vec3d* x, std::size_t n, Vec3d* o) {
              stage.sampleForceDensity(x, n, o);
            });
          },
          py::arg("positions"), py::arg("out") = py::none(),
          "Force density (N/m^3) interpolated at positions (m, shape (N, 3)).")
      .def(
          "sample_field",
          [](const MagneticForceStage& stage, const py::object& positions, const py::object& out) {
            return sampleAt(positions, out,
                            [&](const Vec3d* x, std::size_t n, Vec3d* o) { stage.sampleField(x, n, o); });
          },
          py::arg("positions"), py::arg("out") = py::none(), "H (A/m) interpolated at positions (m, shape (N, 3)).")
      .def("reset_warm_start", &MagneticForceStage::resetWarmStart, "The next solve starts from phi = 0.")
      .def_property("settings", &MagneticForceStage::settings, &MagneticForceStage::setSettings,
                    "The stage's settings (a copy; assign to change them).")
      .def_property("material", &MagneticForceStage::material, &MagneticForceStage::setMaterial,
                    "The magnetic material.")
      .def_property_readonly("grid", &MagneticForceStage::grid, "The stage's Grid.")
      .def_property_readonly(
          "density", [](py::object self) { return gridView(self.cast<const MagneticForceStage&>().density(), self); },
          "n, 1/m^3, shape (nx, ny, nz).")
      .def_property_readonly(
          "potential",
          [](py::object self) { return gridView(self.cast<const MagneticForceStage&>().potential(), self); },
          "phi, A, shape (nx, ny, nz).")
      .def_property_readonly(
          "applied_field",
          [](py::object self) { return gridView(self.cast<const MagneticForceStage&>().appliedField(), self); },
          "H_ext as the material sees it, A/m, shape (nx, ny, nz, 3).")
      .def_property_readonly(
          "field", [](py::object self) { return gridView(self.cast<const MagneticForceStage&>().field(), self); },
          "H, A/m, shape (nx, ny, nz, 3).")
      .def_property_readonly(
          "magnetization",
          [](py::object self) { return gridView(self.cast<const MagneticForceStage&>().magnetization(), self); },
          "M (material plus magnets), A/m, shape (nx, ny, nz, 3).")
      .def_property_readonly(
          "induction",
          [](py::object self) { return gridView(self.cast<const MagneticForceStage&>().inductionField(), self); },
          "B = mu0 (H + M), T, shape (nx, ny, nz, 3).")
      .def_property_readonly(
          "force_density",
          [](py::object self) { return gridView(self.cast<const MagneticForceStage&>().forceDensity(), self); },
          "t = div T, N/m^3, shape (nx, ny, nz, 3).")
      .def_property_readonly(
          "nodal_force",
          [](py::object self) { return gridView(self.cast<const MagneticForceStage&>().nodalForce(), self); },
          "f, N, shape (nx, ny, nz, 3).");
}

}  // namespace lodestone::python
