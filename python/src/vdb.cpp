// VDB files of fields and particles (where OpenVDB is built).
#include <memory>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/plugin/errors.h"
#if LODESTONE_PYTHON_HAVE_VDB
#include "lodestone/vdb_io/field_file.h"
#include "lodestone/vdb_io/point_file.h"
#endif

namespace lodestone::python {

namespace {

#if !LODESTONE_PYTHON_HAVE_VDB
[[noreturn]] void notBuilt(const char* what) {
  throw plugin::NotBuilt(concat(what, ": this build of Lodestone has no OpenVDB (VDB import and export)"));
}
#endif

}  // namespace

void bindVdb(py::module_& m) {
  m.def(
      "write_fields_vdb",
      [](const std::string& path, const MagneticForceStage& stage, std::int64_t frame, double time,
         bool doublePrecision) {
#if LODESTONE_PYTHON_HAVE_VDB
        VdbFrameMetadata meta;
        meta.frame = frame;
        meta.time = time;
        VdbWriteOptions options;
        options.doublePrecision = doublePrecision;
        py::gil_scoped_release release;
        writeFieldsVdb(path, stage, meta, options);
#else
        (void)path, (void)stage, (void)frame, (void)time, (void)doublePrecision;
        notBuilt("write_fields_vdb");
#endif
      },
      py::arg("path"), py::arg("stage"), py::arg("frame") = 0, py::arg("time") = 0.0,
      py::arg("double_precision") = false,
      "Writes the stage's last fields (n 1/m^3, phi A, H A/m, M A/m, B T, force N/m^3) to a .vdb file "
      "(docs/vdb.md). NotBuiltError without OpenVDB.");
  m.def(
      "read_vdb_grid",
      [](const std::string& path, const std::string& grid, const GridSpec& spec, bool vector) -> py::array {
#if LODESTONE_PYTHON_HAVE_VDB
        if (vector) {
          auto g = std::make_shared<DenseGrid<Vec3d>>(readVec3Field(path, grid, spec));
          py::capsule owner(new std::shared_ptr<DenseGrid<Vec3d>>(g),
                            [](void* p) { delete static_cast<std::shared_ptr<DenseGrid<Vec3d>>*>(p); });
          return gridView(GridView<const Vec3d>(g->view()), owner);
        }
        auto g = std::make_shared<DenseGrid<double>>(readScalarField(path, grid, spec));
        py::capsule owner(new std::shared_ptr<DenseGrid<double>>(g),
                          [](void* p) { delete static_cast<std::shared_ptr<DenseGrid<double>>*>(p); });
        return gridView(GridView<const double>(g->view()), owner);
#else
        (void)path, (void)grid, (void)spec, (void)vector;
        notBuilt("read_vdb_grid");
#endif
      },
      py::arg("path"), py::arg("grid"), py::arg("spec"), py::arg("vector") = false,
      "Grid `grid` of a .vdb file sampled on the Grid `spec`: shape (nx, ny, nz) for a scalar grid, "
      "(nx, ny, nz, 3) with vector=True. Units are the file's (docs/vdb.md).");
  m.def(
      "read_particles_vdb",
      [](const std::string& path) -> py::dict {
#if LODESTONE_PYTHON_HAVE_VDB
        const ParticleVdbData p = readParticlesVdb(path);
        py::dict d;
        d["positions"] = copyToNumpy(p.x);
        d["velocities"] = copyToNumpy(p.v);
        d["counts"] = copyToNumpy(p.count);
        d["ids"] = copyToNumpy(p.id);
        d["frame"] = p.frame;
        d["time"] = p.time;
        return d;
#else
        (void)path;
        notBuilt("read_particles_vdb");
#endif
      },
      py::arg("path"),
      "The points of a particle .vdb file (file order): positions (m), velocities (m/s), counts, ids, frame, "
      "time (s).");
  m.def(
      "write_particles_vdb",
      [](const std::string& path, const MpmSolver& solver, std::int64_t frame) {
#if LODESTONE_PYTHON_HAVE_VDB
        PointFileOptions o;
        o.voxelSize = solver.settings().grid.dx;
        o.frame = frame;
        o.time = solver.time();
        py::gil_scoped_release release;
        writeParticlesVdb(path, solver.particles(), o);
#else
        (void)path, (void)solver, (void)frame;
        notBuilt("write_particles_vdb");
#endif
      },
      py::arg("path"), py::arg("solver"), py::arg("frame") = 0,
      "Writes the solver's particles to a .vdb PointDataGrid 'points' (Houdini's and Blender's readers).");
}

}  // namespace lodestone::python
