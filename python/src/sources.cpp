// Poses, time profiles and the applied-field sources.
#include <memory>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "lodestone/core/base/pose.h"
#include "lodestone/core/sources/cuboid_magnet.h"
#include "lodestone/core/sources/cylinder_magnet.h"
#include "lodestone/core/sources/field_source_set.h"
#include "lodestone/core/sources/point_dipole.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone/core/sources/time_profile.h"
#include "lodestone/core/sources/uniform_field.h"

namespace lodestone::python {

namespace {

Mat3d toMat3(const py::handle& object, const char* name) {
  const py::array_t<double, py::array::forcecast> a = py::array_t<double, py::array::forcecast>::ensure(object);
  if (!a || a.ndim() != 2 || a.shape(0) != 3 || a.shape(1) != 3)
    throw py::value_error(concat(name, ": expected a 3 x 3 matrix (shape (3, 3))"));
  Mat3d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.at(i, j);
  return r;
}

py::array_t<double> fromMat3(const Mat3d& r) {
  py::array_t<double> a({3, 3});
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) a.mutable_at(i, j) = r.m[i][j];
  return a;
}

// Field-like evaluation of a source at one point (shape (3,)) or many
// (shape (N, 3)); `accumulate` adds into zeroed output.
template <typename Accumulate>
py::object evaluateAt(const py::object& x, const Accumulate& accumulate) {
  const py::array probe = py::array::ensure(x);
  if (probe && probe.ndim() == 1) {  // one point
    const Vec3d p = toVec3(x, "x");
    Vec3d out;
    accumulate(&p, 1, &out);
    return fromVec3(out);
  }
  const Vec3Input in(x, "x");
  Vec3d* out = nullptr;
  py::array_t<double> result = vec3Output(py::none(), in.size(), {}, out);
  std::fill(out, out + in.size(), Vec3d{});
  {
    py::gil_scoped_release release;
    accumulate(in.data(), in.size(), out);
  }
  return std::move(result);
}

}  // namespace

void bindSources(py::module_& m) {
  py::class_<Pose>(m, "Pose",
                   "Rigid placement of a body: x_world = position + rotation @ x_local. position in m; rotation "
                   "a proper 3 x 3 rotation matrix (body to world).")
      .def(py::init([](const py::object& position, const py::object& rotation) {
             Pose p;
             if (!position.is_none()) p.position = toVec3(position, "position");
             if (!rotation.is_none()) p.rotation = toMat3(rotation, "rotation");
             return p;
           }),
           py::arg("position") = py::none(), py::arg("rotation") = py::none(),
           "Pose at `position` (m, default the origin) with `rotation` (3 x 3, default the identity).")
      .def_static(
          "from_axis_angle",
          [](const py::object& position, const py::object& axis, double angle) {
            return Pose::fromAxisAngle(toVec3(position, "position"), toVec3(axis, "axis"), angle);
          },
          py::arg("position"), py::arg("axis"), py::arg("angle"),
          "Rotation by `angle` (rad) about `axis` (any length > 0), then translation to `position` (m).")
      .def_static(
          "from_quaternion",
          [](const py::object& position, double w, double x, double y, double z) {
            return Pose::fromQuaternion(toVec3(position, "position"), w, x, y, z);
          },
          py::arg("position"), py::arg("w"), py::arg("x"), py::arg("y"), py::arg("z"),
          "Unit quaternion (w, x, y, z), normalised here, and translation to `position` (m).")
      .def_property_readonly("position", [](const Pose& p) { return fromVec3(p.position); }, "m")
      .def_property_readonly("rotation", [](const Pose& p) { return fromMat3(p.rotation); },
                             "3 x 3 body-to-world rotation.");

  py::class_<TimeProfile>(m, "TimeProfile",
                          "A dimensionless factor s(t) (t in s) that scales a source: constant, ramp, sine or "
                          "piecewise-linear keyframes.")
      .def(py::init<>(), "s(t) = 1.")
      .def_static("constant", &TimeProfile::constant, py::arg("value") = 1.0, "s(t) = value.")
      .def_static("ramp", &TimeProfile::ramp, py::arg("t0"), py::arg("t1"), py::arg("start") = 0.0,
                  py::arg("end") = 1.0,
                  "Linear ramp from `start` (t <= t0) to `end` (t >= t1); times in s, t1 >= t0.")
      .def_static("sine", &TimeProfile::sine, py::arg("amplitude"), py::arg("frequency"), py::arg("phase") = 0.0,
                  py::arg("offset") = 0.0, "s(t) = offset + amplitude sin(2 pi frequency t + phase); Hz, rad.")
      .def_static("keyframes", &TimeProfile::keyframes, py::arg("times"), py::arg("values"),
                  "Piecewise linear through (times[i] s, values[i]); held outside the keys.")
      .def("__call__", &TimeProfile::operator(), py::arg("t"), "s(t) for t in s.")
      .def("describe", &TimeProfile::describe, "One line.")
      .def("__repr__", [](const TimeProfile& p) { return "<TimeProfile " + p.describe() + ">"; });

  py::class_<FieldSource, std::shared_ptr<FieldSource>>(
      m, "FieldSource",
      "An applied-field source (closed-form field of a coil, uniform field, dipole or permanent magnet). "
      "Sources are immutable apart from a magnet's pose; safe to evaluate from many threads.")
      .def(
          "field",
          [](const FieldSource& s, const py::object& x, double t) {
            return evaluateAt(x, [&](const Vec3d* p, std::size_t n, Vec3d* o) { s.accumulateField(p, n, t, o); });
          },
          py::arg("x"), py::arg("t") = 0.0,
          "Applied field H (A/m) at positions x (m; shape (3,) or (N, 3), float32 or float64) and time t (s). "
          "Returns the same shape, float64.")
      .def(
          "magnetization",
          [](const FieldSource& s, const py::object& x, double t) {
            return evaluateAt(x, [&](const Vec3d* p, std::size_t n, Vec3d* o) {
              for (std::size_t i = 0; i < n; ++i) o[i] = s.magnetization(p[i], t);
            });
          },
          py::arg("x"), py::arg("t") = 0.0,
          "Permanent magnetization (A/m) of the source body at x (m), zero outside bodies.")
      .def_property_readonly("is_uniform", &FieldSource::isUniform, "True when the field is the same everywhere.")
      .def("describe", &FieldSource::describe, "One line naming the source and its parameters with units.")
      .def("__repr__", [](const FieldSource& s) { return "<" + s.describe() + ">"; });

  py::class_<UniformField, FieldSource, std::shared_ptr<UniformField>>(m, "UniformField", "A uniform field H0.")
      .def(py::init([](const py::object& H, const TimeProfile& profile) {
             return std::make_shared<UniformField>(toVec3(H, "H"), profile);
           }),
           py::arg("H"), py::arg("profile") = TimeProfile(), "H0 in A/m, scaled in time by `profile`.")
      .def_property_readonly("amplitude", [](const UniformField& s) { return fromVec3(s.amplitude()); }, "H0, A/m.");

  py::class_<PointDipole, FieldSource, std::shared_ptr<PointDipole>>(m, "PointDipole", "A point dipole.")
      .def(py::init([](const py::object& position, const py::object& moment, const TimeProfile& profile) {
             return std::make_shared<PointDipole>(toVec3(position, "position"), toVec3(moment, "moment"), profile);
           }),
           py::arg("position"), py::arg("moment"), py::arg("profile") = TimeProfile(),
           "Dipole at `position` (m) with moment `moment` (A*m^2), scaled in time by `profile`.")
      .def_property_readonly("position", [](const PointDipole& s) { return fromVec3(s.position()); }, "m")
      .def_property_readonly("moment", [](const PointDipole& s) { return fromVec3(s.moment()); }, "A*m^2");

  py::class_<MagnetSource, FieldSource, std::shared_ptr<MagnetSource>>(
      m, "Magnet", "A uniformly magnetized permanent magnet (sphere, cuboid or cylinder) with a pose.")
      .def_property("pose", &MagnetSource::pose, &MagnetSource::setPose,
                    "Body-to-world pose; setting it moves the magnet (do not move it while another thread "
                    "evaluates it).")
      .def_property_readonly("body_magnetization",
                             [](const MagnetSource& s) { return fromVec3(s.bodyMagnetization()); },
                             "M in the body frame before time scaling, A/m.")
      .def_property_readonly("volume", &MagnetSource::volume, "m^3")
      .def(
          "moment", [](const MagnetSource& s, double t) { return fromVec3(s.moment(t)); }, py::arg("t") = 0.0,
          "Total dipole moment s(t) V R M at time t (s), A*m^2.");

  py::class_<SphereMagnet, MagnetSource, std::shared_ptr<SphereMagnet>>(m, "SphereMagnet", "A spherical magnet.")
      .def(py::init([](const Pose& pose, double radius, const py::object& M, const TimeProfile& profile) {
             return std::make_shared<SphereMagnet>(pose, radius, toVec3(M, "magnetization"), profile);
           }),
           py::arg("pose"), py::arg("radius"), py::arg("magnetization"), py::arg("profile") = TimeProfile(),
           "Centre and orientation from `pose`; radius in m; magnetization in A/m (body frame).")
      .def_property_readonly("radius", &SphereMagnet::radius, "m");

  py::class_<CuboidMagnet, MagnetSource, std::shared_ptr<CuboidMagnet>>(m, "CuboidMagnet", "A box magnet.")
      .def(py::init([](const Pose& pose, const py::object& halfSize, const py::object& M,
                       const TimeProfile& profile) {
             return std::make_shared<CuboidMagnet>(pose, toVec3(halfSize, "half_size"), toVec3(M, "magnetization"),
                                                   profile);
           }),
           py::arg("pose"), py::arg("half_size"), py::arg("magnetization"), py::arg("profile") = TimeProfile(),
           "Centre and orientation from `pose`; half-sizes in m; magnetization in A/m (body frame).")
      .def_property_readonly("half_size", [](const CuboidMagnet& s) { return fromVec3(s.halfSize()); }, "m");

  py::class_<CylinderMagnet, MagnetSource, std::shared_ptr<CylinderMagnet>>(m, "CylinderMagnet",
                                                                            "A cylindrical magnet (axis body z).")
      .def(py::init([](const Pose& pose, double radius, double halfLength, const py::object& M,
                       const TimeProfile& profile) {
             return std::make_shared<CylinderMagnet>(pose, radius, halfLength, toVec3(M, "magnetization"), profile);
           }),
           py::arg("pose"), py::arg("radius"), py::arg("half_length"), py::arg("magnetization"),
           py::arg("profile") = TimeProfile(),
           "Centre and orientation from `pose` (axis: body z); radius and half-length in m; magnetization in "
           "A/m along body z.")
      .def_property_readonly("radius", &CylinderMagnet::radius, "m")
      .def_property_readonly("half_length", &CylinderMagnet::halfLength, "m");

  py::class_<FieldSourceSet, FieldSource, std::shared_ptr<FieldSourceSet>>(
      m, "FieldSourceSet", "A superposition of sources, itself a source. Holds copies of the sources added.")
      .def(py::init([](const py::iterable& sources) {
             auto set = std::make_shared<FieldSourceSet>();
             for (const py::handle s : sources) set->add(s.cast<const FieldSource&>());
             return set;
           }),
           py::arg("sources") = py::list(), "A set of copies of `sources`.")
      .def(
          "add", [](FieldSourceSet& set, const FieldSource& s) { set.add(s); }, py::arg("source"),
          "Adds a copy of `source` (later changes to `source` do not reach the set).")
      .def("__len__", &FieldSourceSet::size)
      .def(
          "set_pose",
          [](FieldSourceSet& set, std::size_t i, const Pose& pose) {
            auto* magnet = dynamic_cast<MagnetSource*>(&set.source(i));
            if (!magnet) throw py::value_error(concat("set_pose: source ", i, " is not a magnet"));
            magnet->setPose(pose);
          },
          py::arg("index"), py::arg("pose"), "Moves magnet `index` of the set.");
}

}  // namespace lodestone::python
