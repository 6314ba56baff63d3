// The C ABI's field-set entries: applied fields from uniform fields, dipoles, magnets and VDB files.
#include "support.h"

#include "lodestone/core/sources/cuboid_magnet.h"
#include "lodestone/core/sources/cylinder_magnet.h"
#include "lodestone/core/sources/point_dipole.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/plugin/node_builders.h"

namespace lodestone::plugin::abi {

lodestone_status fieldsCreate(lodestone_context* c, lodestone_fields** out) {
  return createEntry<lodestone_fields, Fields>(c, out, HandleKind::Fields, "fields_create");
}

lodestone_status fieldsDestroy(lodestone_fields* f) {
  return firewall(ctxOf(f), "fields_destroy", [&] { destroy<Fields>(f, HandleKind::Fields, "fields"); });
}

lodestone_status fieldsAddUniform(lodestone_fields* f, const double H[3]) {
  return firewall(ctxOf(f), "fields_add_uniform", [&] {
    Fields& fs = fieldsOf(f);
    fs.set.add(std::make_unique<UniformField>(vec(H, "H")));
  });
}

lodestone_status fieldsAddDipole(lodestone_fields* f, const double position[3], const double moment[3]) {
  return firewall(ctxOf(f), "fields_add_dipole", [&] {
    Fields& fs = fieldsOf(f);
    fs.set.add(std::make_unique<PointDipole>(vec(position, "position"), vec(moment, "moment")));
  });
}

Pose magnetPose(const double center[3], const double axis[3]) {
  const Vec3d a = vec(axis, "axis");
  if (!(norm(a) > 0)) throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT, "axis must be a non-zero vector");
  return poseAlong(vec(center, "center"), a / norm(a));
}

void checkMagnetization(double M) {
  if (!std::isfinite(M) || std::fabs(M) > 3e6)
    throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT, concat("magnetization must be finite, |M| <= 3e6 A/m, got ", M));
}

lodestone_status fieldsAddSphere(lodestone_fields* f, const double center[3], const double axis[3], double radius,
                                 double M) {
  return firewall(ctxOf(f), "fields_add_sphere_magnet", [&] {
    Fields& fs = fieldsOf(f);
    checkMagnetization(M);
    fs.set.add(std::make_unique<SphereMagnet>(magnetPose(center, axis), radius, Vec3d{0, 0, M}));
  });
}

lodestone_status fieldsAddBox(lodestone_fields* f, const double center[3], const double axis[3],
                              const double halfSize[3], double M) {
  return firewall(ctxOf(f), "fields_add_box_magnet", [&] {
    Fields& fs = fieldsOf(f);
    checkMagnetization(M);
    fs.set.add(std::make_unique<CuboidMagnet>(magnetPose(center, axis), vec(halfSize, "half_size"), Vec3d{0, 0, M}));
  });
}

lodestone_status fieldsAddCylinder(lodestone_fields* f, const double center[3], const double axis[3], double radius,
                                   double halfLength, double M) {
  return firewall(ctxOf(f), "fields_add_cylinder_magnet", [&] {
    Fields& fs = fieldsOf(f);
    checkMagnetization(M);
    fs.set.add(std::make_unique<CylinderMagnet>(magnetPose(center, axis), radius, halfLength, Vec3d{0, 0, M}));
  });
}

lodestone_status fieldsAddVdb(lodestone_fields* f, const char* path, const char* grid) {
  return firewall(ctxOf(f), "fields_add_vdb", [&] {
    Fields& fs = fieldsOf(f);
    const std::string file = needName(path, "path"), name = needName(grid, "grid_name");
    try {
      addVdbField(fs.set, file, name);
    } catch (const InvalidArgument& e) {
      throw AbiError(LODESTONE_ERROR_IO, e.what());
    }
  });
}

lodestone_status fieldsCount(const lodestone_fields* f, uint32_t* out) {
  return firewall(ctxOf(f), "fields_count", [&] {
    Fields& fs = fieldsOf(f);
    *need(out, "out") = uint32_t(fs.set.size());
  });
}

lodestone_status fieldsEvaluate(const lodestone_fields* f, const double x[3], double t, double H[3]) {
  return firewall(ctxOf(f), "fields_evaluate", [&] {
    Fields& fs = fieldsOf(f);
    need(H, "H_out");
    checkTime(t);
    const Vec3d h = fs.set.field(vec(x, "x"), t);
    for (int a = 0; a < 3; ++a) H[a] = h[a];
  });
}

}  // namespace lodestone::plugin::abi
