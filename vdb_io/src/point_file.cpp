// .vdb files of MPM material points (OpenVDB PointDataGrid).
#include "lodestone/vdb_io/point_file.h"

#include <cmath>
#include <exception>
#include <filesystem>
#include <memory>

#include <openvdb/openvdb.h>
#include <openvdb/points/PointConversion.h>
#include <openvdb/points/PointDataGrid.h>

#include "lodestone/core/base/error.h"
#include "vdb_atomic_write.h"
#include "vdb_checked_read.h"
#include "lodestone/vdb_io/grid_conversion.h"

namespace lodestone {

namespace {

namespace vp = openvdb::points;

constexpr const char* kGridName = "points";  // Houdini's name (VDB_CONVENTIONS.md)


// Appends attribute `name` (value type T, codec Codec) and fills it from
// `values` (one per point, in the order of the positions).
template <typename T, typename Codec = vp::NullCodec>
void addAttribute(vp::PointDataGrid& grid, const openvdb::tools::PointIndexGrid& index, const std::string& name,
                  const std::vector<T>& values) {
  vp::appendAttribute<T, Codec>(grid.tree(), name);
  vp::PointAttributeVector<T> wrapper(values);
  vp::populateAttribute<vp::PointDataTree, openvdb::tools::PointIndexTree, vp::PointAttributeVector<T>>(
      grid.tree(), index.tree(), name, wrapper);
}

template <typename T>
void requireAttribute(const vp::AttributeSet::Descriptor& d, const std::string& path, const char* name) {
  const std::size_t pos = d.find(name);
  require(pos != vp::AttributeSet::INVALID_POS, "VDB file '", path, "': grid 'points' has no attribute '", name,
          "'");
  require(d.valueType(pos) == openvdb::typeNameAsString<T>(), "VDB file '", path, "': attribute '", name,
          "' has value type ", d.valueType(pos), ", expected ", openvdb::typeNameAsString<T>());
}

}  // namespace

void writeParticlesVdb(const std::string& path, const MpmParticles& p, const PointFileOptions& options) {
  initializeVdb();
  require(!path.empty(), "writeParticlesVdb: empty file name");
  require(std::isfinite(options.voxelSize) && options.voxelSize > 0, "VDB file '", path,
          "': voxelSize must be positive and finite, got ", options.voxelSize);
  require(std::isfinite(options.time), "VDB file '", path, "': time must be finite, got ", options.time);
  try {
    p.checkSizes();
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(concat("VDB file '", path, "': ", e.what()));
  }
  const std::size_t n = p.size();
  std::vector<openvdb::Vec3d> x(n);
  std::vector<openvdb::Vec3f> v(n);
  std::vector<float> count(n), J(n), pscale(n);
  std::vector<openvdb::Int32> material(n);
  std::vector<openvdb::Int64> id(n);
  std::vector<openvdb::math::Mat3s> F(options.deformationGradient ? n : 0);
  for (std::size_t i = 0; i < n; ++i) {
    require(isFinite(p.x[i]), "VDB file '", path, "': point ", i, " has a non-finite position");
    x[i] = openvdb::Vec3d(p.x[i].x, p.x[i].y, p.x[i].z);
    v[i] = openvdb::Vec3f(float(p.v[i].x), float(p.v[i].y), float(p.v[i].z));
    count[i] = float(p.count[i]);
    J[i] = float(p.J[i]);
    // Radius of the sphere of the particle's current volume J V0, m.
    pscale[i] = float(std::cbrt(3.0 * std::max(p.J[i], 0.0) * p.volume0[i] / (4.0 * 3.14159265358979323846)));
    material[i] = openvdb::Int32(p.material[i]);
    id[i] = openvdb::Int64(p.id[i]);
    if (options.deformationGradient)
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) F[i](a, b) = float(p.F[i](a, b));
  }

  openvdb::GridPtrVec grids;
  try {
    const auto xf = openvdb::math::Transform::createLinearTransform(options.voxelSize);
    const vp::PointAttributeVector<openvdb::Vec3d> positions(x);
    const auto index = openvdb::tools::createPointIndexGrid<openvdb::tools::PointIndexGrid>(positions, *xf);
    // 16-bit fixed-point positions (Houdini's default).
    auto grid = vp::createPointDataGrid<vp::FixedPointCodec</*OneByte=*/false>, vp::PointDataGrid>(*index, positions,
                                                                                                  *xf);
    if (options.compressVelocity) addAttribute<openvdb::Vec3f, vp::TruncateCodec>(*grid, *index, "v", v);
    else addAttribute(*grid, *index, "v", v);
    addAttribute(*grid, *index, "n_p", count);
    addAttribute(*grid, *index, "material", material);
    addAttribute(*grid, *index, "J", J);
    addAttribute(*grid, *index, "id", id);
    addAttribute(*grid, *index, "pscale", pscale);
    if (options.deformationGradient) addAttribute(*grid, *index, "F", F);
    grid->setName(kGridName);
    grid->insertMeta("description",
                     openvdb::StringMetadata(
                         std::string("MPM material points: P position m (16-bit fixed point in voxel), v velocity m/s (") +
                         (options.compressVelocity ? "half float" : "float") +
                         "), n_p micro-particles carried (1), material index (int32), J volume ratio det F (1), "
                         "id persistent identity (int64), pscale radius of the particle's volume m" +
                         (options.deformationGradient ? ", F deformation gradient (1, Mat3s)" : "")));
    grid->insertMeta("point_count", openvdb::Int64Metadata(openvdb::Int64(n)));
    grids.push_back(grid);
  } catch (const std::exception& e) {
    throw InvalidArgument(concat("VDB file '", path, "': cannot build the point grid: ", e.what()));
  }

  openvdb::MetaMap meta;
  meta.insertMeta("creator", openvdb::StringMetadata("Lodestone " LODESTONE_VERSION_STRING));
  meta.insertMeta("lodestone_version", openvdb::StringMetadata(LODESTONE_VERSION_STRING));
  meta.insertMeta("frame", openvdb::Int64Metadata(options.frame));
  meta.insertMeta("time_s", openvdb::DoubleMetadata(options.time));
  meta.insertMeta("voxel_size_m", openvdb::DoubleMetadata(options.voxelSize));

  detail::writeVdbAtomically(path, grids, meta);
}

ParticleVdbData readParticlesVdb(const std::string& path) {
  ParticleVdbData out;
  const detail::VdbFileContents file = detail::readVdbChecked(path, concat("VDB file '", path, "'"));
  if (auto m = file.meta->getMetadata<openvdb::Int64Metadata>("frame")) out.frame = m->value();
  if (auto m = file.meta->getMetadata<openvdb::DoubleMetadata>("time_s")) out.time = m->value();
  std::string names;
  const openvdb::GridBase::Ptr found = detail::findGrid(file, kGridName, names);
  require(found != nullptr, "VDB file '", path, "': no grid named '", kGridName, "' (the file holds [", names, "])");
  const vp::PointDataGrid::Ptr grid = openvdb::gridPtrCast<vp::PointDataGrid>(found);
  require(grid != nullptr, "VDB file '", path, "': grid '", kGridName, "' is not a PointDataGrid");
  out.voxelSize = grid->voxelSize()[0];

  const auto leaf = grid->tree().cbeginLeaf();
  if (!leaf) return out;
  const auto& d = leaf->attributeSet().descriptor();
  requireAttribute<openvdb::Vec3f>(d, path, "P");
  requireAttribute<openvdb::Vec3f>(d, path, "v");
  requireAttribute<float>(d, path, "n_p");
  requireAttribute<openvdb::Int32>(d, path, "material");
  requireAttribute<float>(d, path, "J");
  requireAttribute<openvdb::Int64>(d, path, "id");
  requireAttribute<float>(d, path, "pscale");
  const bool hasF = d.find("F") != vp::AttributeSet::INVALID_POS;
  if (hasF) requireAttribute<openvdb::math::Mat3s>(d, path, "F");

  const auto& xf = grid->transform();
  try {
    // The count comes from the file: a corrupted one may claim billions of
    // points (std::bad_alloc or length_error here becomes InvalidArgument).
    const auto n = std::size_t(vp::pointCount(grid->tree()));
    out.x.reserve(n);
    out.v.reserve(n);
    out.count.reserve(n);
    out.J.reserve(n);
    out.material.reserve(n);
    out.id.reserve(n);
    out.pscale.reserve(n);
    if (hasF) out.F.reserve(n);
    for (auto it = grid->tree().cbeginLeaf(); it; ++it) {
      // Every attribute array must hold the leaf's points (its index offsets
      // come from the file as well).
      const openvdb::Index last = it->getLastValue();
      for (const char* name : {"P", "v", "n_p", "material", "J", "id", "pscale"})
        if (it->constAttributeArray(name).size() < last)
          throw InvalidArgument(concat("VDB file '", path, "': attribute '", name, "' of a leaf holds ",
                                       it->constAttributeArray(name).size(), " values for ", last, " points"));
      if (hasF && it->constAttributeArray("F").size() < last)
        throw InvalidArgument(concat("VDB file '", path, "': attribute 'F' of a leaf is shorter than its points"));
      const vp::AttributeHandle<openvdb::Vec3f> P(it->constAttributeArray("P"));
      const vp::AttributeHandle<openvdb::Vec3f> V(it->constAttributeArray("v"));
      const vp::AttributeHandle<float> C(it->constAttributeArray("n_p"));
      const vp::AttributeHandle<openvdb::Int32> M(it->constAttributeArray("material"));
      const vp::AttributeHandle<float> Jh(it->constAttributeArray("J"));
      const vp::AttributeHandle<openvdb::Int64> I(it->constAttributeArray("id"));
      const vp::AttributeHandle<float> R(it->constAttributeArray("pscale"));
      std::unique_ptr<vp::AttributeHandle<openvdb::math::Mat3s>> Fh;
      if (hasF) Fh = std::make_unique<vp::AttributeHandle<openvdb::math::Mat3s>>(it->constAttributeArray("F"));
      for (auto idx = it->beginIndexOn(); idx; ++idx) {
        const openvdb::Vec3d w = xf.indexToWorld(openvdb::Vec3d(P.get(*idx)) + idx.getCoord().asVec3d());
        out.x.push_back({w[0], w[1], w[2]});
        const openvdb::Vec3f v = V.get(*idx);
        out.v.push_back({double(v[0]), double(v[1]), double(v[2])});
        out.count.push_back(double(C.get(*idx)));
        out.material.push_back(std::uint32_t(M.get(*idx)));
        out.J.push_back(double(Jh.get(*idx)));
        out.id.push_back(std::uint64_t(I.get(*idx)));
        out.pscale.push_back(double(R.get(*idx)));
        if (Fh) {
          const openvdb::math::Mat3s f = Fh->get(*idx);
          Mat3d m;
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) m(a, b) = double(f(a, b));
          out.F.push_back(m);
        }
      }
    }
  } catch (const InvalidArgument&) {
    throw;
  } catch (const std::exception& e) {
    throw InvalidArgument(concat("VDB file '", path, "': cannot read the points: ", e.what()));
  }
  return out;
}

}  // namespace lodestone
