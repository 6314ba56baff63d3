// .vdb files of the magnetic stage's fields, and a FieldSource read from one.
#include "lodestone/vdb_io/field_file.h"

#include <cstdio>
#include <exception>
#include <filesystem>

#include <openvdb/openvdb.h>

#include "lodestone/core/base/error.h"
#include "vdb_atomic_write.h"
#include "lodestone/vdb_io/grid_conversion.h"

namespace lodestone {

namespace {

void setUnits(openvdb::GridBase& grid, const char* units, const char* description) {
  grid.insertMeta("units", openvdb::StringMetadata(units));
  grid.insertMeta("description", openvdb::StringMetadata(description));
  grid.setGridClass(openvdb::GRID_FOG_VOLUME);
}

openvdb::GridBase::Ptr scalarGrid(GridView<const double> v, const char* name, double tol, bool dbl,
                                  const openvdb::math::Transform::Ptr& xf) {
  VdbConversionOptions o;
  o.tolerance = tol;
  o.transform = xf;
  if (dbl) return toVdbDoubleGrid(v, name, o);
  return toVdbFloatGrid(v, name, o);
}

openvdb::GridBase::Ptr vectorGrid(GridView<const Vec3d> v, const char* name, double tol, bool dbl,
                                  const openvdb::math::Transform::Ptr& xf, openvdb::VecType type) {
  VdbConversionOptions o;
  o.tolerance = tol;
  o.transform = xf;
  o.vecType = type;
  if (dbl) return toVdbVec3dGrid(v, name, o);
  return toVdbVec3fGrid(v, name, o);
}


}  // namespace

void writeFieldsVdb(const std::string& path, const MagneticForceStage& stage, const VdbFrameMetadata& metadata,
                    const VdbWriteOptions& options) {
  initializeVdb();
  require(!path.empty(), "writeFieldsVdb: empty file name");
  require(std::isfinite(metadata.time), "VDB file '", path, "': time must be finite, got ", metadata.time);
  const GridSpec& spec = stage.grid();
  const auto xf = nodeCentredTransform(spec);  // one transform shared by every grid of the frame
  const bool dbl = options.doublePrecision;
  const VdbFieldChoice& c = options.fields;

  openvdb::GridPtrVec grids;
  if (c.density) {
    grids.push_back(scalarGrid(stage.density(), "n", options.toleranceDensity, dbl, xf));
    setUnits(*grids.back(), "1/m^3", "micro-particle number density n");
  }
  if (c.potential) {
    grids.push_back(scalarGrid(stage.potential(), "phi", options.tolerancePotential, dbl, xf));
    setUnits(*grids.back(), "A", "magnetic scalar potential phi (H = -grad phi)");
  }
  if (c.field) {
    grids.push_back(vectorGrid(stage.field(), "H", options.toleranceField, dbl, xf, openvdb::VEC_COVARIANT));
    setUnits(*grids.back(), "A/m", "magnetic field H");
  }
  if (c.magnetization) {
    grids.push_back(vectorGrid(stage.magnetization(), "M", options.toleranceMagnetization, dbl, xf,
                               openvdb::VEC_CONTRAVARIANT_RELATIVE));
    setUnits(*grids.back(), "A/m", "magnetization M");
  }
  if (c.induction) {
    grids.push_back(vectorGrid(stage.inductionField(), "B", options.toleranceInduction, dbl, xf,
                               openvdb::VEC_CONTRAVARIANT_RELATIVE));
    setUnits(*grids.back(), "T", "magnetic induction B");
  }
  if (c.force) {
    grids.push_back(vectorGrid(stage.forceDensity(), "force", options.toleranceForce, dbl, xf,
                               openvdb::VEC_CONTRAVARIANT_RELATIVE));
    setUnits(*grids.back(), "N/m^3", "magnetic force density t = div T");
  }
  if (options.displayAliases) {
    grids.push_back(scalarGrid(stage.density(), "density", options.toleranceDensity, dbl, xf));
    setUnits(*grids.back(), "1/m^3", "micro-particle number density n (display name of n)");
  }
  const VdbMpmGrids& mpm = options.mpm;
  require(!c.mass || mpm.mass.data, "VDB file '", path, "': the mass grid was asked for but not given");
  require(!c.velocity || mpm.velocity.data, "VDB file '", path, "': the velocity grid was asked for but not given");
  openvdb::math::Transform::Ptr mpmXf;  // one transform for the MPM grids, shared with the fields when equal
  const auto mpmTransform = [&](const GridSpec& s) {
    if (s == spec) return xf;
    if (!mpmXf) mpmXf = nodeCentredTransform(s);
    return mpmXf;
  };
  if (c.mass) {
    grids.push_back(scalarGrid(mpm.mass, "mass", 0, dbl, mpmTransform(mpm.mass.spec)));
    setUnits(*grids.back(), "kg", "MPM node mass");
  }
  if (c.velocity || (options.displayAliases && mpm.velocity.data)) {
    const auto vxf = mpmTransform(mpm.velocity.spec);
    if (c.velocity) {
      grids.push_back(vectorGrid(mpm.velocity, "velocity", 0, dbl, vxf, openvdb::VEC_CONTRAVARIANT_RELATIVE));
      setUnits(*grids.back(), "m/s", "MPM node velocity");
    }
    if (options.displayAliases) {
      grids.push_back(vectorGrid(mpm.velocity, "vel", 0, dbl, vxf, openvdb::VEC_CONTRAVARIANT_RELATIVE));
      setUnits(*grids.back(), "m/s", "MPM node velocity (display name of velocity)");
    }
  }

  openvdb::MetaMap meta;
  meta.insertMeta("creator", openvdb::StringMetadata("Lodestone " LODESTONE_VERSION_STRING));
  meta.insertMeta("lodestone_version", openvdb::StringMetadata(LODESTONE_VERSION_STRING));
  meta.insertMeta("frame", openvdb::Int64Metadata(metadata.frame));
  meta.insertMeta("time_s", openvdb::DoubleMetadata(metadata.time));
  meta.insertMeta("dx_m", openvdb::DoubleMetadata(spec.dx));
  meta.insertMeta("law", openvdb::StringMetadata(metadata.lawDescription.empty() ? stage.material().describe()
                                                                                : metadata.lawDescription));
  meta.insertMeta("solver_report", openvdb::StringMetadata(metadata.solverSummary));

  detail::writeVdbAtomically(path, grids, meta);
}

DenseGrid<double> readScalarField(const std::string& path, const std::string& gridName, const GridSpec& spec) {
  const auto base = readVdbScalarGrid(path, gridName);
  try {
    if (auto f = openvdb::gridConstPtrCast<openvdb::FloatGrid>(base)) return toDenseGrid(*f, spec);
    return toDenseGrid(*openvdb::gridConstPtrCast<openvdb::DoubleGrid>(base), spec);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(concat("VDB file '", path, "': ", e.what()));
  }
}

DenseGrid<double> readDensityVdb(const std::string& path, const GridSpec& spec, const std::string& gridName) {
  DenseGrid<double> n = readScalarField(path, gridName, spec);
  for (int k = 0; k < spec.dims.k; ++k)
    for (int j = 0; j < spec.dims.j; ++j)
      for (int i = 0; i < spec.dims.i; ++i) {
        const double v = n(i, j, k);
        require(std::isfinite(v) && v >= 0, "VDB file '", path, "', grid '", gridName,
                "': micro-particle density must be finite and >= 0 (1/m^3), got ", v, " at node (", i, ", ", j, ", ",
                k, ")");
      }
  return n;
}

DenseGrid<Vec3d> readVec3Field(const std::string& path, const std::string& gridName, const GridSpec& spec) {
  const auto base = readVdbVec3Grid(path, gridName);
  try {
    if (auto f = openvdb::gridConstPtrCast<openvdb::Vec3fGrid>(base)) return toDenseGrid(*f, spec);
    return toDenseGrid(*openvdb::gridConstPtrCast<openvdb::Vec3dGrid>(base), spec);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(concat("VDB file '", path, "': ", e.what()));
  }
}

// ---------------------------------------------------------------- VdbFieldSource

struct VdbFieldSource::Impl {
  openvdb::Vec3dGrid::Ptr grid;  // values promoted to double
  Vec3d background;
  std::string path, name;
};

VdbFieldSource::VdbFieldSource(const std::string& path, const std::string& gridName, const Vec3d& background) {
  require(isFinite(background), "VdbFieldSource '", path, "', grid '", gridName, "': background must be finite");
  const auto base = readVdbVec3Grid(path, gridName);
  const auto& xf = base->constTransform();
  require(xf.isLinear() && xf.hasUniformScale(), "VDB file '", path, "', grid '", gridName,
          "': transform must be a uniform-scale linear map, got ", xf.mapType());
  auto impl = std::make_shared<Impl>();
  impl->background = background;
  impl->path = path;
  impl->name = gridName;
  if (auto d = openvdb::gridPtrCast<openvdb::Vec3dGrid>(base)) {
    impl->grid = d;
  } else {
    const auto f = openvdb::gridConstPtrCast<openvdb::Vec3fGrid>(base);
    auto g = openvdb::Vec3dGrid::create(openvdb::Vec3d(0.0));
    g->setTransform(f->constTransform().copy());
    g->setName(gridName);
    auto acc = g->getAccessor();
    for (auto it = f->cbeginValueOn(); it; ++it) {
      const openvdb::Vec3f v = *it;
      const openvdb::Vec3d vd(v[0], v[1], v[2]);
      if (it.isVoxelValue()) acc.setValueOn(it.getCoord(), vd);
      else g->tree().fill(it.getBoundingBox(), vd, true);
    }
    impl->grid = g;
  }
  impl_ = impl;
}

Vec3d VdbFieldSource::field(const Vec3d& x, double /*t*/) const {
  const auto& grid = *impl_->grid;
  openvdb::Vec3d p = grid.constTransform().worldToIndex(openvdb::Vec3d(x.x, x.y, x.z));
  // Positions within 1e-9 voxel of a node snap onto it, so that nodes give
  // their stored value bit for bit despite rounding in worldToIndex.
  for (int a = 0; a < 3; ++a) {
    const double r = std::round(p[a]);
    if (std::abs(p[a] - r) < 1e-9) p[a] = r;
  }
  const openvdb::Vec3d base(std::floor(p[0]), std::floor(p[1]), std::floor(p[2]));
  const openvdb::Vec3d w = p - base;
  if (!(std::abs(base[0]) < 2e9 && std::abs(base[1]) < 2e9 && std::abs(base[2]) < 2e9)) return impl_->background;
  const openvdb::Coord c0{static_cast<openvdb::Int32>(base[0]), static_cast<openvdb::Int32>(base[1]),
                          static_cast<openvdb::Int32>(base[2])};
  const openvdb::Vec3d bg(impl_->background.x, impl_->background.y, impl_->background.z);
  // One unregistered accessor per call: accessors are not thread-safe, and an
  // unregistered one skips the tree's accessor registry (the tree is immutable).
  openvdb::tree::ValueAccessor<const openvdb::Vec3dTree, /*IsSafe=*/false> acc(grid.tree());
  openvdb::Vec3d corner[2][2][2];
  int active = 0;
  for (int dk = 0; dk < 2; ++dk)
    for (int dj = 0; dj < 2; ++dj)
      for (int di = 0; di < 2; ++di) {
        openvdb::Vec3d v;
        const bool on = acc.probeValue(c0.offsetBy(di, dj, dk), v);
        active += on ? 1 : 0;
        corner[dk][dj][di] = on ? v : bg;
      }
  if (active == 0) return impl_->background;  // outside: exactly the background
  // Skip zero weights exactly, so that on a node the value is the node's bit for bit.
  openvdb::Vec3d sum(0.0);
  for (int dk = 0; dk < 2; ++dk) {
    const double wk = dk ? w[2] : 1 - w[2];
    if (wk == 0) continue;
    for (int dj = 0; dj < 2; ++dj) {
      const double wj = dj ? w[1] : 1 - w[1];
      if (wj == 0) continue;
      for (int di = 0; di < 2; ++di) {
        const double wi = di ? w[0] : 1 - w[0];
        if (wi == 0) continue;
        sum += corner[dk][dj][di] * (wi * wj * wk);
      }
    }
  }
  return {sum[0], sum[1], sum[2]};
}

std::string VdbFieldSource::describe() const {
  return concat("VDB field '", impl_->name, "' from '", impl_->path, "' (", impl_->grid->activeVoxelCount(),
                " active voxels, voxel size ", impl_->grid->voxelSize()[0], " m, background (", impl_->background.x,
                ", ", impl_->background.y, ", ", impl_->background.z, ") A/m, trilinear)");
}

std::unique_ptr<FieldSource> VdbFieldSource::clone() const { return std::make_unique<VdbFieldSource>(*this); }

const Vec3d& VdbFieldSource::background() const { return impl_->background; }
std::size_t VdbFieldSource::activeVoxelCount() const { return std::size_t(impl_->grid->activeVoxelCount()); }

}  // namespace lodestone
