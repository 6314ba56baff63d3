// core <-> OpenVDB grid conversion and typed grid reading.
#include "lodestone/vdb_io/grid_conversion.h"

#include <cmath>
#include <exception>
#include <filesystem>
#include <fstream>
#include <mutex>

#include <openvdb/io/Stream.h>
#include <openvdb/tools/Dense.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/Prune.h>

#include "lodestone/core/base/error.h"
#include "vdb_checked_read.h"

namespace lodestone {

void initializeVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

openvdb::math::Transform::Ptr nodeCentredTransform(const GridSpec& spec) {
  spec.validate("VDB transform grid");
  auto xf = openvdb::math::Transform::createLinearTransform(spec.dx);
  xf->postTranslate(openvdb::Vec3d(spec.origin.x, spec.origin.y, spec.origin.z));
  return xf;
}

namespace {

double magnitude(double v) { return std::abs(v); }
double magnitude(const Vec3d& v) { return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

template <typename VdbValue>
VdbValue toVdbValue(double v) { return static_cast<VdbValue>(v); }
template <typename VdbValue>
VdbValue toVdbValue(const Vec3d& v) {
  using C = typename VdbValue::value_type;
  return VdbValue(static_cast<C>(v.x), static_cast<C>(v.y), static_cast<C>(v.z));
}

template <typename GridT, typename CoreT>
typename GridT::Ptr toVdb(GridView<const CoreT> values, const std::string& name,
                          const VdbConversionOptions& options) {
  initializeVdb();
  values.spec.validate(name.c_str());
  require(values.data != nullptr, "VDB grid '", name, "': no data");
  require(std::isfinite(options.tolerance) && options.tolerance >= 0, "VDB grid '", name,
          "': tolerance must be a finite value >= 0, got ", options.tolerance);
  using ValueT = typename GridT::ValueType;
  auto grid = GridT::create(openvdb::zeroVal<ValueT>());
  grid->setName(name);
  grid->setTransform(options.transform ? options.transform : nodeCentredTransform(values.spec));
  auto acc = grid->getAccessor();
  const GridSpec& s = values.spec;
  for (int k = 0; k < s.dims.k; ++k)
    for (int j = 0; j < s.dims.j; ++j) {
      const CoreT* row = values.data + s.index(0, j, k);
      for (int i = 0; i < s.dims.i; ++i) {
        const CoreT& v = row[i];
        if (!(magnitude(v) <= options.tolerance)) acc.setValueOn(openvdb::Coord(i, j, k), toVdbValue<ValueT>(v));
      }
    }
  openvdb::tools::prune(grid->tree());
  return grid;
}

template <typename GridT>
typename GridT::Ptr withVecType(typename GridT::Ptr grid, openvdb::VecType type) {
  grid->setVectorType(type);
  grid->setIsInWorldSpace(true);
  return grid;
}

double toCore(float v) { return double(v); }
double toCore(double v) { return v; }
Vec3d toCore(const openvdb::Vec3f& v) { return {double(v[0]), double(v[1]), double(v[2])}; }
Vec3d toCore(const openvdb::Vec3d& v) { return {v[0], v[1], v[2]}; }

void requireUniformLinear(const openvdb::GridBase& grid) {
  const auto& xf = grid.constTransform();
  require(xf.isLinear() && xf.hasUniformScale(), "VDB grid '", grid.getName(),
          "': transform must be a uniform-scale linear map, got ", xf.mapType(),
          xf.isLinear() ? " with non-uniform scale" : " (not linear)");
}

template <typename CoreT, typename GridT>
DenseGrid<CoreT> toDense(const GridT& grid, const GridSpec& spec) {
  initializeVdb();
  spec.validate(("target grid of VDB grid '" + grid.getName() + "'").c_str());
  requireUniformLinear(grid);
  DenseGrid<CoreT> out(spec);
  if (transformMatches(grid.constTransform(), spec)) {
    auto acc = grid.getConstAccessor();
    for (int k = 0; k < spec.dims.k; ++k)
      for (int j = 0; j < spec.dims.j; ++j)
        for (int i = 0; i < spec.dims.i; ++i) out(i, j, k) = toCore(acc.getValue(openvdb::Coord(i, j, k)));
  } else {
    // The sampler floors index coordinates to int: the target grid must map
    // to finite index coordinates well inside int (an absurd voxel size or
    // translation in the file would otherwise overflow). The map is linear,
    // so the corners bound the whole grid.
    const auto& xf = grid.constTransform();
    for (int c = 0; c < 8; ++c) {
      const Vec3d x = spec.nodePosition((c & 1) ? spec.dims.i - 1 : 0, (c & 2) ? spec.dims.j - 1 : 0,
                                        (c & 4) ? spec.dims.k - 1 : 0);
      const openvdb::Vec3d u = xf.worldToIndex(openvdb::Vec3d(x.x, x.y, x.z));
      for (int a = 0; a < 3; ++a)
        require(std::isfinite(u[a]) && std::fabs(u[a]) < double(1 << 30), "VDB grid '", grid.getName(),
                "': its transform (voxel size ", xf.voxelSize()[0], " m) maps the target grid to index coordinate ",
                u[a], ", beyond +-2^30 voxels");
    }
    openvdb::tools::GridSampler<GridT, openvdb::tools::BoxSampler> sampler(grid);
    for (int k = 0; k < spec.dims.k; ++k)
      for (int j = 0; j < spec.dims.j; ++j)
        for (int i = 0; i < spec.dims.i; ++i) {
          const Vec3d x = spec.nodePosition(i, j, k);
          out(i, j, k) = toCore(sampler.wsSample(openvdb::Vec3R(x.x, x.y, x.z)));
        }
  }
  return out;
}

template <typename Accept>
openvdb::GridBase::Ptr readChecked(const std::string& path, const std::string& gridName, const char* wanted,
                                   Accept accept) {
  const std::string where = "VDB file '" + path + "', grid '" + gridName + "'";
  std::string names;
  const openvdb::GridBase::Ptr grid = detail::findGrid(detail::readVdbChecked(path, where), gridName, names);
  require(grid != nullptr, where, ": no such grid; the file holds [", names, "]");
  require(accept(*grid), where, ": expected ", wanted, ", found ", grid->type());
  return grid;
}

}  // namespace

openvdb::FloatGrid::Ptr toVdbFloatGrid(GridView<const double> values, const std::string& name,
                                       const VdbConversionOptions& options) {
  return toVdb<openvdb::FloatGrid>(values, name, options);
}
openvdb::DoubleGrid::Ptr toVdbDoubleGrid(GridView<const double> values, const std::string& name,
                                         const VdbConversionOptions& options) {
  return toVdb<openvdb::DoubleGrid>(values, name, options);
}
openvdb::Vec3fGrid::Ptr toVdbVec3fGrid(GridView<const Vec3d> values, const std::string& name,
                                       const VdbConversionOptions& options) {
  return withVecType<openvdb::Vec3fGrid>(toVdb<openvdb::Vec3fGrid>(values, name, options), options.vecType);
}
openvdb::Vec3dGrid::Ptr toVdbVec3dGrid(GridView<const Vec3d> values, const std::string& name,
                                       const VdbConversionOptions& options) {
  return withVecType<openvdb::Vec3dGrid>(toVdb<openvdb::Vec3dGrid>(values, name, options), options.vecType);
}

bool transformMatches(const openvdb::math::Transform& xf, const GridSpec& spec) {
  const auto map = xf.baseMap();
  const bool axisAligned = map->isType<openvdb::math::UniformScaleTranslateMap>() ||
                           map->isType<openvdb::math::UniformScaleMap>() ||
                           map->isType<openvdb::math::ScaleTranslateMap>() ||
                           map->isType<openvdb::math::ScaleMap>() ||
                           map->isType<openvdb::math::TranslationMap>();
  if (!axisAligned || !xf.hasUniformScale()) return false;
  const openvdb::Vec3d vs = xf.voxelSize();
  const openvdb::Vec3d o = xf.indexToWorld(openvdb::Vec3d(0, 0, 0));
  const openvdb::Vec3d one = xf.indexToWorld(openvdb::Vec3d(1, 1, 1));
  const Vec3d n1 = spec.nodePosition(1, 1, 1);
  return vs[0] == spec.dx && vs[1] == spec.dx && vs[2] == spec.dx && o[0] == spec.origin.x &&
         o[1] == spec.origin.y && o[2] == spec.origin.z && one[0] == n1.x && one[1] == n1.y && one[2] == n1.z;
}

DenseGrid<double> toDenseGrid(const openvdb::FloatGrid& grid, const GridSpec& spec) {
  return toDense<double>(grid, spec);
}
DenseGrid<double> toDenseGrid(const openvdb::DoubleGrid& grid, const GridSpec& spec) {
  return toDense<double>(grid, spec);
}
DenseGrid<Vec3d> toDenseGrid(const openvdb::Vec3fGrid& grid, const GridSpec& spec) {
  return toDense<Vec3d>(grid, spec);
}
DenseGrid<Vec3d> toDenseGrid(const openvdb::Vec3dGrid& grid, const GridSpec& spec) {
  return toDense<Vec3d>(grid, spec);
}

openvdb::GridBase::Ptr readVdbScalarGrid(const std::string& path, const std::string& gridName) {
  return readChecked(path, gridName, "a FloatGrid or DoubleGrid", [](const openvdb::GridBase& g) {
    return g.isType<openvdb::FloatGrid>() || g.isType<openvdb::DoubleGrid>();
  });
}
openvdb::GridBase::Ptr readVdbVec3Grid(const std::string& path, const std::string& gridName) {
  return readChecked(path, gridName, "a Vec3fGrid or Vec3dGrid", [](const openvdb::GridBase& g) {
    return g.isType<openvdb::Vec3fGrid>() || g.isType<openvdb::Vec3dGrid>();
  });
}

openvdb::FloatGrid::Ptr readVdbFloatGrid(const std::string& path, const std::string& gridName) {
  return openvdb::gridPtrCast<openvdb::FloatGrid>(readChecked(
      path, gridName, "a FloatGrid", [](const openvdb::GridBase& g) { return g.isType<openvdb::FloatGrid>(); }));
}

SampledSdf toSampledSdf(const openvdb::FloatGrid& grid, const std::string& who) {
  initializeVdb();
  require(grid.getGridClass() == openvdb::GRID_LEVEL_SET, who, ": grid class must be 'level set', got '",
          openvdb::GridBase::gridClassToString(grid.getGridClass()), "'");
  const auto& xf = grid.constTransform();
  const auto map = xf.baseMap();
  const bool axisAligned = map->isType<openvdb::math::UniformScaleTranslateMap>() ||
                           map->isType<openvdb::math::UniformScaleMap>() ||
                           map->isType<openvdb::math::ScaleTranslateMap>() ||
                           map->isType<openvdb::math::ScaleMap>() || map->isType<openvdb::math::TranslationMap>();
  require(axisAligned && xf.hasUniformScale(), who,
          ": transform must be a uniform scale and a translation (no rotation, shear or frustum), got ",
          xf.mapType(), xf.hasUniformScale() ? "" : " with non-uniform scale");
  openvdb::CoordBBox box = grid.evalActiveVoxelBoundingBox();
  require(!box.empty(), who, ": the level set has no active voxel");
  box.expand(2);  // nodes outside the narrow band, so the box's rim is outside the shape
  GridSpec spec;
  spec.dx = xf.voxelSize()[0];
  const openvdb::Vec3d o = xf.indexToWorld(box.min());
  spec.origin = {o[0], o[1], o[2]};
  spec.dims = {box.dim()[0], box.dim()[1], box.dim()[2]};
  openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(box);  // x fastest, as GridSpec::index
  openvdb::tools::copyToDense(grid, dense);
  std::vector<float> values(dense.data(), dense.data() + dense.valueCount());
  return SampledSdf(spec, std::move(values), who);
}

}  // namespace lodestone
