// The render outputs of one frame of particles. See render_frame.h.
#include "lodestone/vdb_io/render_frame.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "lodestone/core/base/error.h"
#include "lodestone/vdb_io/grid_conversion.h"
#include "vdb_atomic_write.h"

namespace lodestone {

struct RenderFrame::Cache {
  openvdb::FloatGrid::Ptr surface;
  bool volumesBuilt = false;
  ParticleVolumeGrids volumes;
  bool meshBuilt = false;
  TriangleMesh mesh;
  openvdb::FloatGrid::Ptr magnetization;
};

namespace {

openvdb::MetaMap fileMetadata(const VdbFrameMetadata& metadata, double voxelSize) {
  openvdb::MetaMap meta;
  meta.insertMeta("creator", openvdb::StringMetadata("Lodestone " LODESTONE_VERSION_STRING));
  meta.insertMeta("lodestone_version", openvdb::StringMetadata(LODESTONE_VERSION_STRING));
  meta.insertMeta("frame", openvdb::Int64Metadata(metadata.frame));
  meta.insertMeta("time_s", openvdb::DoubleMetadata(metadata.time));
  meta.insertMeta("voxel_size_m", openvdb::DoubleMetadata(voxelSize));
  return meta;
}

openvdb::FloatGrid::Ptr magnitudeGrid(const openvdb::Vec3fGrid& m) {
  auto out = openvdb::FloatGrid::create(0.0f);
  out->setTransform(m.transform().copy());
  auto acc = out->getAccessor();
  for (auto it = m.cbeginValueOn(); it; ++it) {
    const float value = (*it).length();
    if (value > 0) {
      if (it.isVoxelValue())
        acc.setValue(it.getCoord(), value);
      else
        out->tree().fill(it.getBoundingBox(), value, true);
    }
  }
  out->pruneGrid();
  return out;
}

}  // namespace

RenderFrame::RenderFrame(SurfaceParticles particles, const SurfaceOptions& options,
                         std::vector<std::string> materialNames)
    : particles_(std::move(particles)),
      options_(options),
      names_(std::move(materialNames)),
      cache_(std::make_unique<Cache>()) {
  options_.check("render outputs");
  require(particles_.v.size() == particles_.size() && particles_.volume.size() == particles_.size() &&
              particles_.material.size() == particles_.size(),
          "render outputs: particle arrays of different lengths");
}

RenderFrame::~RenderFrame() = default;

void RenderFrame::setMagnetization(GridView<const Vec3d> magnetization) {
  DenseGrid<double> magnitude(magnetization.spec);
  for (std::size_t n = 0; n < magnetization.size(); ++n)
    magnitude[n] = std::sqrt(dot(magnetization[n], magnetization[n]));
  cache_->magnetization = toVdbFloatGrid(GridView<const double>{magnitude.data(), magnitude.spec()}, "magnetization");
}

bool RenderFrame::setMagnetizationFromFile(const std::string& path, const std::string& gridName) {
  initializeVdb();
  bool present = false;
  try {
    openvdb::io::File file(path);
    file.open(false);
    present = file.hasGrid(gridName);
    file.close();
  } catch (const std::exception& e) {
    throw InvalidArgument(concat("VDB file '", path, "': cannot be read: ", e.what()));
  }
  if (!present) return false;
  const openvdb::GridBase::Ptr grid = readVdbVec3Grid(path, gridName);
  if (auto f = openvdb::GridBase::grid<openvdb::Vec3fGrid>(grid)) {
    cache_->magnetization = magnitudeGrid(*f);
  } else {
    const auto d = openvdb::GridBase::grid<openvdb::Vec3dGrid>(grid);
    auto copy = openvdb::Vec3fGrid::create(openvdb::Vec3f(0.0f));
    copy->setTransform(d->transform().copy());
    auto acc = copy->getAccessor();
    for (auto it = d->cbeginValueOn(); it; ++it)
      if (it.isVoxelValue()) acc.setValue(it.getCoord(), openvdb::Vec3f(*it));
    cache_->magnetization = magnitudeGrid(*copy);
  }
  cache_->magnetization->setName("magnetization");
  return true;
}

namespace {

/// The particles of each material present, in material order.
std::map<std::uint32_t, std::vector<std::size_t>> byMaterial(const SurfaceParticles& p) {
  std::map<std::uint32_t, std::vector<std::size_t>> out;
  for (std::size_t i = 0; i < p.size(); ++i) out[p.material[i]].push_back(i);
  return out;
}

}  // namespace

void RenderFrame::writeSurfaceVdb(const std::string& path, const VdbFrameMetadata& metadata) const {
  surfaceVolume();  // builds `surface`
  openvdb::GridPtrVec grids;
  if (cache_->surface) grids.push_back(cache_->surface);
  const auto materials = byMaterial(particles_);
  if (materials.size() > 1)
    for (const auto& [m, indices] : materials) {
      const std::string name = m < names_.size() && !names_[m].empty() ? names_[m] : concat("material", m);
      if (auto grid = particleLevelSet(particles_, options_, "surface_" + name, &indices)) grids.push_back(grid);
    }
  openvdb::MetaMap meta = fileMetadata(metadata, options_.voxelSize);
  meta.insertMeta("surface_method", openvdb::StringMetadata(surfaceMethodName(options_.method)));
  detail::writeVdbAtomically(path, grids, meta);
}

void RenderFrame::writeVolumeVdb(const std::string& path, const VdbFrameMetadata& metadata) const {
  if (!cache_->volumesBuilt) {
    cache_->volumes = particleVolumeGrids(particles_, options_.voxelSize, options_.kernelWidth);
    cache_->volumesBuilt = true;
  }
  const ParticleVolumeGrids& v = cache_->volumes;
  // density: the fraction clamped to [0, 1]; vel: momentum / fraction.
  auto density = v.fraction->deepCopy();
  for (auto it = density->tree().beginValueOn(); it; ++it) it.setValue(std::clamp(*it, 0.0f, 1.0f));
  density->setName("density");
  density->setGridClass(openvdb::GRID_FOG_VOLUME);
  density->insertMeta("units", openvdb::StringMetadata("1"));
  density->insertMeta("description", openvdb::StringMetadata("volume fraction of material, 0 .. 1"));
  auto vel = openvdb::Vec3fGrid::create(openvdb::Vec3f(0.0f));
  vel->setTransform(v.fraction->transformPtr());
  {
    auto f = v.fraction->getConstAccessor();
    auto out = vel->getAccessor();
    for (auto it = v.momentum->cbeginValueOn(); it; ++it) {
      const float w = f.getValue(it.getCoord());
      if (w > 1e-6f) out.setValue(it.getCoord(), *it / w);
    }
  }
  vel->setName("vel");
  vel->setGridClass(openvdb::GRID_FOG_VOLUME);
  vel->setVectorType(openvdb::VEC_CONTRAVARIANT_RELATIVE);
  vel->setIsInWorldSpace(true);
  vel->insertMeta("units", openvdb::StringMetadata("m/s"));
  vel->insertMeta("description", openvdb::StringMetadata("velocity of the material (kernel-weighted mean)"));
  openvdb::GridPtrVec grids{density, vel};
  if (cache_->magnetization) {
    auto m = cache_->magnetization;
    m->setName("magnetization");
    m->setGridClass(openvdb::GRID_FOG_VOLUME);
    m->insertMeta("units", openvdb::StringMetadata("A/m"));
    m->insertMeta("description", openvdb::StringMetadata("magnitude of the magnetization M (field grid)"));
    grids.push_back(m);
  }
  detail::writeVdbAtomically(path, grids, fileMetadata(metadata, options_.voxelSize));
}

const TriangleMesh& RenderFrame::mesh() const {
  if (!cache_->meshBuilt) {
    surfaceVolume();
    if (!cache_->volumesBuilt) {
      cache_->volumes = particleVolumeGrids(particles_, options_.voxelSize, options_.kernelWidth);
      cache_->volumesBuilt = true;
    }
    if (cache_->surface) cache_->mesh = levelSetMesh(*cache_->surface, &cache_->volumes);
    cache_->meshBuilt = true;
  }
  return cache_->mesh;
}

double RenderFrame::surfaceVolume() const {
  if (!cache_->surface) cache_->surface = particleLevelSet(particles_, options_, "surface");
  return cache_->surface ? levelSetVolume(*cache_->surface) : 0.0;
}

double RenderFrame::particleVolume() const {
  double sum = 0;
  for (const double v : particles_.volume) sum += v;
  return sum;
}

}  // namespace lodestone
