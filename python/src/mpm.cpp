// The reference MLS-MPM solver with magnetism.
#include <algorithm>
#include <memory>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "cancel.h"
#include "mpm_reports.h"
#include "lodestone/core/mpm/solver.h"

namespace lodestone::python {

namespace {

BoundaryCondition boundaryFrom(const std::string& mode, double friction) {
  BoundaryCondition bc;
  if (mode == "sticky") bc.mode = BoundaryMode::Sticky;
  else if (mode == "slip") bc.mode = BoundaryMode::Slip;
  else if (mode == "separate") bc.mode = BoundaryMode::Separate;
  else throw py::value_error(concat("boundary: expected 'sticky', 'slip' or 'separate', got '", mode, "'"));
  bc.friction = friction;
  bc.validate("boundary");
  return bc;
}

}  // namespace

py::dict frameReportDict(const MpmFrameReport& r) {
  py::dict d;
  d["substeps"] = r.substeps;
  d["time"] = r.time;
  d["min_dt"] = r.minDt;
  d["max_dt"] = r.maxDt;
  d["field_solves"] = r.magneticReports.size();
  d["magnetic_impulse"] = fromVec3(r.magneticImpulse);
  d["seconds_total"] = r.secondsTotal;
  d["seconds_magnetic"] = r.secondsMagnetic;
  d["removed"] = r.removed;
  d["clamped"] = r.clamped;
  d["cancelled"] = r.cancelled;
  d["energy_total"] = r.energies.total();
  d["warnings"] = r.warnings;
  return d;
}

MpmFrameReport advanceFrameHooked(MpmSolver& solver, double duration, Hook& hook,
                                  const std::function<void(const MpmProgress&, py::dict&)>& fill) {
  solver.setFieldSolveProgress(hook.newtonProgress());
  const Unhook unhook([&solver] { solver.setFieldSolveProgress({}); });
  MpmFrameReport r;
  {
    py::gil_scoped_release release;
    r = solver.advanceFrame(duration, [&](const MpmProgress& p) {
      return hook.poll([&](py::dict& d) {
        d["stage"] = "substep";
        fill(p, d);
      });
    });
  }
  hook.rethrow();
  return r;
}

void bindMpm(py::module_& m) {
  py::class_<MpmSettings>(m, "MpmSettings", "Settings of the MPM solver (validated by MpmSolver).")
      .def(py::init([](const GridSpec& grid) {
             MpmSettings s;
             s.grid = grid;
             return s;
           }),
           py::arg("grid"), "Defaults on `grid` (at least 4 nodes per axis).")
      .def_readwrite("grid", &MpmSettings::grid, "The MPM grid.")
      .def_property(
          "gravity", [](const MpmSettings& s) { return fromVec3(s.gravity); },
          [](MpmSettings& s, const py::object& g) { s.gravity = toVec3(g, "gravity"); }, "m/s^2")
      .def_readwrite("fixed_dt", &MpmSettings::fixedDt, "> 0: every substep takes this dt (s); 0: CFL-adaptive.")
      .def_readwrite("cfl", &MpmSettings::cfl, "Fraction of a cell a wave or particle may cross per substep.")
      .def_readwrite("dt_max", &MpmSettings::dtMax, "s")
      .def_readwrite("dt_min", &MpmSettings::dtMin, "s")
      .def_readwrite("wall_nodes", &MpmSettings::wallNodes, "Wall layer thickness in nodes (0 = no walls).")
      .def_readwrite("reorder_interval", &MpmSettings::reorderInterval,
                     "Substeps between particle sorts by cell, and the first substep after an emit sorts (0: never).")
      .def_readwrite("dense_grid", &MpmSettings::denseGrid,
                     "Hold the MPM grid whole, every node of the grid, instead of only the runs of nodes the particles "
                     "reach on each x-row, packed back to back: the same "
                     "particles bit for bit, more memory, never faster (the reference the sparse grid is checked against).")
      .def_readwrite("magnetic_solve_interval", &MpmSettings::magneticSolveInterval,
                     "Substeps between field solves; 0 = automatic.")
      .def_readwrite("magnetic", &MpmSettings::magnetic, "StageSettings of the magnetic stage.")
      .def_property(
          "walls", [](const MpmSettings& s) { return std::string(toString(s.walls.mode)); },
          [](MpmSettings& s, const std::string& mode) { s.walls = boundaryFrom(mode, s.walls.friction); },
          "Boundary condition of the domain walls: 'sticky', 'slip' or 'separate'.");

  py::class_<EmitterShape>(m, "Shape", "A body shape for emission: box, sphere or cylinder, placed by a Pose.")
      .def_static(
          "box", [](const Pose& pose, const py::object& h) { return EmitterShape::box(pose, toVec3(h, "half_size")); },
          py::arg("pose"), py::arg("half_size"), "A box of half-sizes (m).")
      .def_static("sphere", &EmitterShape::sphere, py::arg("pose"), py::arg("radius"), "A sphere of radius (m).")
      .def_static("cylinder", &EmitterShape::cylinder, py::arg("pose"), py::arg("radius"), py::arg("half_length"),
                  "A cylinder along body z; radius and half-length in m.")
      .def_property_readonly("volume", &EmitterShape::volume, "m^3");

  py::class_<MpmCollider>(m, "Collider", "A collider of the MPM: a shape, a motion and a boundary condition.")
      .def(py::init([](const std::string& shape, const Pose& pose, const py::object& halfSize, double radius,
                       double halfLength, const std::string& boundary, double friction, const py::object& velocity,
                       const py::object& angularVelocity) {
             ColliderShape s;
             if (shape == "plane") s = ColliderShape::plane();
             else if (shape == "box") s = ColliderShape::box(toVec3(halfSize, "half_size"));
             else if (shape == "sphere") s = ColliderShape::sphere(radius);
             else if (shape == "cylinder") s = ColliderShape::cylinder(radius, halfLength);
             else throw py::value_error(concat("shape: expected 'plane', 'box', 'sphere' or 'cylinder', got '",
                                               shape, "'"));
             const ColliderMotion motion =
                 ColliderMotion::constantVelocity(pose, toVec3(velocity, "velocity"),
                                                  toVec3(angularVelocity, "angular_velocity"));
             return MpmCollider(s, motion, boundaryFrom(boundary, friction));
           }),
           py::arg("shape"), py::arg("pose") = Pose(), py::arg("half_size") = py::make_tuple(0, 0, 0),
           py::arg("radius") = 0.0, py::arg("half_length") = 0.0, py::arg("boundary") = "separate",
           py::arg("friction") = 0.0, py::arg("velocity") = py::make_tuple(0, 0, 0),
           py::arg("angular_velocity") = py::make_tuple(0, 0, 0),
           "shape 'plane' (solid below body z = 0), 'box' (half_size, m), 'sphere' (radius, m) or 'cylinder' "
           "(radius, half_length, m), placed by `pose` and moving with `velocity` (m/s) and "
           "`angular_velocity` (rad/s); boundary 'sticky', 'slip' or 'separate' with Coulomb `friction`.")
      .def(
          "set_dynamics",
          [](MpmCollider& c, double density, double mass, double restitution, double friction) {
            RigidBodySettings s;
            s.density = density;
            s.mass = mass;
            s.restitution = restitution;
            s.friction = friction;
            c.setDynamics(s);
          },
          py::arg("density") = 1000.0, py::arg("mass") = 0.0, py::arg("restitution") = 0.2,
          py::arg("friction") = 0.4,
          "Makes the collider a free rigid body, two-way coupled with the material: density (kg/m^3) or mass "
          "(kg, > 0 overrides), contact restitution and friction.");

  py::class_<MpmSolver, std::shared_ptr<MpmSolver>>(
      m, "MpmSolver",
      "The reference MLS-MPM with nonlinear magnetism. Particle arrays are returned as copies (the solver "
      "reorders and removes particles as it steps). step() and advance_frame() release the GIL; one solver is "
      "used by one thread at a time.")
      .def(py::init<const MpmSettings&>(), py::arg("settings"))
      .def("add_material", &MpmSolver::addMaterial, py::arg("material"), "Adds an MpmMaterial; returns its index.")
      .def(
          "emit",
          [](MpmSolver& s, const EmitterShape& shape, std::uint32_t material, int ppc, const py::object& velocity,
             double jitter, std::uint64_t seed) {
            EmitterSettings e;
            e.cellSize = s.settings().grid.dx;
            e.particlesPerCell = ppc;
            e.velocity = toVec3(velocity, "velocity");
            e.jitter = jitter;
            e.seed = seed;
            return s.emit(shape, material, e).particles;
          },
          py::arg("shape"), py::arg("material"), py::arg("particles_per_cell") = 8,
          py::arg("velocity") = py::make_tuple(0, 0, 0), py::arg("jitter") = 0.0, py::arg("seed") = 1,
          "Fills `shape` with points of material index `material` at the grid's dx, moving at `velocity` "
          "(m/s); returns how many were added.")
      .def("add_collider", &MpmSolver::addCollider, py::arg("collider"), "Adds a Collider; returns its index.")
      .def(
          "add_source", [](MpmSolver& s, const FieldSource& source) { s.sources().add(source); }, py::arg("source"),
          "Adds a copy of an applied-field source (no collider).")
      .def(
          "add_magnet",
          [](MpmSolver& s, const MagnetSource& magnet, bool collider, const std::string& boundary, double friction) {
            return collider ? s.addMagnet(magnet, boundaryFrom(boundary, friction))
                            : s.addNonCollidingMagnet(magnet, ColliderMotion::fixed(magnet.pose()));
          },
          py::arg("magnet"), py::arg("collider") = true, py::arg("boundary") = "sticky", py::arg("friction") = 0.0,
          "Adds a copy of a permanent magnet, fixed at its pose; an obstacle for the material unless "
          "collider=False. Returns its magnet index.")
      .def(
          "step",
          [](MpmSolver& s, double dt) {
            MpmStepReport r;
            {
              py::gil_scoped_release release;
              r = s.step(dt);
            }
            py::dict d;
            d["dt"] = r.dt;
            d["time"] = r.time;
            d["magnetic_solved"] = r.magneticSolved;
            d["magnetic_impulse"] = fromVec3(r.magneticImpulse);
            d["particles"] = r.particles;
            d["seconds_total"] = r.secondsTotal;
            return d;
          },
          py::arg("dt"), "One substep of dt (s); returns a dict (dt, time, magnetic_solved, ...).")
      .def(
          "advance_frame",
          [](MpmSolver& s, double duration, const py::object& progress) {
            Hook hook(progress);
            return frameReportDict(advanceFrameHooked(s, duration, hook, [](const MpmProgress& p, py::dict& d) {
              d["substep"] = p.substep;
              d["time"] = p.time;
              d["fraction"] = p.fraction;
            }));
          },
          py::arg("duration"), py::arg("progress") = py::none(),
          "Substeps to the end of a frame of `duration` (s). `progress(dict)` runs after each substep (keys: "
          "stage 'substep', substep, time, fraction) and after each Newton iteration of a field solve (stage "
          "'newton', iteration, relative_residual, cg_iterations, seconds); returning False stops the frame "
          "(report 'cancelled': True; a field solve stopped that way leaves its substep with the field reached). "
          "Ctrl-C raises KeyboardInterrupt at the next of these points. Returns the frame report as a dict.")
      .def_property_readonly("time", &MpmSolver::time, "Simulation time, s.")
      .def_property_readonly("particle_count", [](const MpmSolver& s) { return s.particles().size(); })
      .def_property_readonly("positions", [](const MpmSolver& s) { return copyToNumpy(s.particles().x); },
                             "Positions, m, (N, 3) copy.")
      .def_property_readonly("velocities", [](const MpmSolver& s) { return copyToNumpy(s.particles().v); },
                             "Velocities, m/s, (N, 3) copy.")
      .def_property_readonly("counts", [](const MpmSolver& s) { return copyToNumpy(s.particles().count); },
                             "n_p, micro-particles, (N,) copy.")
      .def_property_readonly("masses", [](const MpmSolver& s) { return copyToNumpy(s.particles().mass); },
                             "kg, (N,) copy.")
      .def_property_readonly("ids", [](const MpmSolver& s) { return copyToNumpy(s.particles().id); },
                             "Persistent identities, (N,) uint64 copy.")
      .def_property_readonly("magnetic_forces", [](const MpmSolver& s) { return copyToNumpy(s.particles().magneticForce); },
                             "Per-particle magnetic force of the last solve (N), when the stage grid differs.")
      .def(
          "set_velocities",
          [](MpmSolver& s, const py::object& v) {
            const Vec3Input in(v, "velocities", long(s.particles().size()));
            std::copy(in.data(), in.data() + in.size(), s.particles().v.begin());
          },
          py::arg("velocities"), "Replaces the particle velocities (m/s, shape (N, 3)).")
      .def_property_readonly("suggested_dt", &MpmSolver::suggestedDt, "The CFL substep now, s.")
      .def_property_readonly(
          "magnetic_nodal_force",
          [](py::object self) {
            const auto& s = self.cast<const MpmSolver&>();
            if (!s.magneticNodalForce().data) throw py::value_error("magnetic_nodal_force: no field solve has run yet");
            return gridView(s.magneticNodalForce(), self);
          },
          "Magnetic nodal force on the MPM grid (N), shape (nx, ny, nz, 3), read-only view.")
      .def(
          "rigid_bodies",
          [](const MpmSolver& s) {
            py::list out;
            for (const RigidBodyReport& b : s.rigidBodies()) {
              py::dict d;
              d["collider"] = b.collider;
              d["magnet"] = b.magnet;
              d["position"] = fromVec3(b.pose.position);
              d["velocity"] = fromVec3(b.velocity);
              d["angular_velocity"] = fromVec3(b.angularVelocity);
              d["magnetic_force"] = fromVec3(b.magneticForce);
              out.append(d);
            }
            return out;
          },
          "The dynamic rigid bodies: collider, magnet, position (m), velocity (m/s), angular_velocity "
          "(rad/s), magnetic_force (N).");
}

}  // namespace lodestone::python
