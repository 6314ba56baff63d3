#include "lodestone/gpu/mpm.h"

#include <cmath>

#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/material.h"
#include "mpm_backend.h"

namespace lodestone {
namespace gpu {

void MpmStepSettings::validate() const {
  require(isFinite(gravity), "gpu MPM: gravity must be finite, got (", gravity.x, ", ", gravity.y, ", ", gravity.z,
          ") m/s^2");
  require(wallNodes >= 0, "gpu MPM: wallNodes must be >= 0, got ", wallNodes);
  require(wallMode == WallMode::Sticky || wallMode == WallMode::Slip || wallMode == WallMode::Separate,
          "gpu MPM: unknown wall mode ", int(wallMode));
  require(std::isfinite(wallFriction) && wallFriction >= 0, "gpu MPM: wall friction must be finite and >= 0, got ",
          wallFriction);
  require(!bounded || (isFinite(lo) && isFinite(hi) && lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z),
          "gpu MPM: bounds must be finite with lo <= hi, got lo (", lo.x, ", ", lo.y, ", ", lo.z, ") hi (", hi.x, ", ",
          hi.y, ", ", hi.z, ") m");
}

struct MpmStepper::Impl {
  std::unique_ptr<detail::MpmBackend> backend;
  bool deposited = false;
};

MpmStepper::MpmStepper(const GridSpec& grid, std::vector<MpmMaterialParams> materials, Backend backend)
    : grid_(grid), impl_(std::make_unique<Impl>()) {
  grid_.validate("gpu MPM grid");
  require(grid_.dims.i >= 3 && grid_.dims.j >= 3 && grid_.dims.k >= 3,
          "gpu MPM grid: a quadratic B-spline stencil needs at least 3 nodes per axis, got ", grid_.dims.i, " x ",
          grid_.dims.j, " x ", grid_.dims.k);
  require(!materials.empty(), "gpu MPM: at least one material is needed");
  for (std::size_t m = 0; m < materials.size(); ++m) {
    const MpmMaterialParams& p = materials[m];
    if (p.fluid) {
      require(std::isfinite(p.viscosity) && p.viscosity >= 0 && std::isfinite(p.bulkModulus) && p.bulkModulus > 0,
              "gpu MPM material ", m, ": fluid needs viscosity >= 0 (Pa s) and bulk modulus > 0 (Pa), got ",
              p.viscosity, " and ", p.bulkModulus);
      require(std::isfinite(p.surfaceTension) && p.surfaceTension >= 0 && p.surfaceTension <= kMaxSurfaceTension,
              "gpu MPM material ", m, ": surface tension must be in [0, ", kMaxSurfaceTension, "] N/m, got ",
              p.surfaceTension);
    } else {
      require(std::isfinite(p.mu) && p.mu >= 0 && std::isfinite(p.lambda), "gpu MPM material ", m,
              ": solid needs finite mu >= 0 and lambda (Pa), got ", p.mu, " and ", p.lambda);
      require(p.surfaceTension == 0, "gpu MPM material ", m, ": surface tension applies to fluids only, got ",
              p.surfaceTension, " N/m on a solid");
    }
  }
  backend_ = resolveBackend(backend, &backendMessage_);
  kernels::MpmDims d;
  d.ox = grid_.origin.x;
  d.oy = grid_.origin.y;
  d.oz = grid_.origin.z;
  d.dx = grid_.dx;
  d.nx = grid_.dims.i;
  d.ny = grid_.dims.j;
  d.nz = grid_.dims.k;
  impl_->backend = backend_ == Backend::Cuda ? detail::makeDeviceMpm(d, materials) : detail::makeHostMpm(d, materials);
}

MpmStepper::~MpmStepper() = default;

std::size_t MpmStepper::size() const { return impl_->backend->size(); }

void MpmStepper::upload(const ParticleInput& in) {
  require(in.size == 0 || (in.x && in.v && in.C && in.F && in.J && in.mass && in.volume0 && in.material),
          "gpu MPM upload: every particle array except count is required");
  impl_->backend->upload(in);
  impl_->deposited = false;
}

void MpmStepper::download(const ParticleOutput& out) const {
  require(out.size == size(), "gpu MPM download: ", out.size, " entries given for ", size(), " particles");
  impl_->backend->download(out);
}

void MpmStepper::particleToGrid(double dt, const Vec3d* particleForces) {
  require(std::isfinite(dt) && dt >= 0, "gpu MPM P2G: time step must be finite and >= 0 (s), got ", dt);
  const std::size_t bad = impl_->backend->particleToGrid(dt, particleForces);
  impl_->deposited = bad == detail::kNoParticle;
  if (bad != detail::kNoParticle) {
    Vec3d x;
    std::vector<Vec3d> all(size());
    impl_->backend->download(ParticleOutput{all.data(), nullptr, nullptr, nullptr, nullptr, all.size()});
    x = all[bad];
    const Vec3d hi = grid_.maxCorner();
    throw InvalidArgument(concat("gpu MPM particle ", bad, " at (", x.x, ", ", x.y, ", ", x.z,
                                 ") m: its quadratic stencil leaves the grid (", grid_.origin.x, ", ", grid_.origin.y,
                                 ", ", grid_.origin.z, ") to (", hi.x, ", ", hi.y, ", ", hi.z,
                                 ") m, or its position is not finite, or its material index is out of range"));
  }
}

void MpmStepper::gridUpdate(double dt, const MpmStepSettings& s, const Vec3d* nodalForce) {
  require(std::isfinite(dt) && dt >= 0, "gpu MPM grid update: time step must be finite and >= 0 (s), got ", dt);
  s.validate();
  BoundaryCondition walls;
  walls.mode = BoundaryMode(int(s.wallMode));
  walls.friction = s.wallFriction;
  impl_->backend->gridUpdate(dt, s.gravity, s.wallNodes, walls, nodalForce);
}

MpmStepReport MpmStepper::gridToParticle(double dt, const MpmStepSettings& s) {
  require(std::isfinite(dt) && dt >= 0, "gpu MPM G2P: time step must be finite and >= 0 (s), got ", dt);
  require(impl_->deposited, "gpu MPM G2P: particleToGrid must run first on the current particles");
  s.validate();
  impl_->deposited = false;
  return impl_->backend->gridToParticle(dt, s);
}

MpmStepReport MpmStepper::step(double dt, const MpmStepSettings& s) {
  particleToGrid(dt);
  gridUpdate(dt, s);
  return gridToParticle(dt, s);
}

void MpmStepper::downloadGrid(double* mass, Vec3d* momentum, Vec3d* velocity, double* density) const {
  impl_->backend->downloadGrid(mass, momentum, velocity, density);
}

}  // namespace gpu
}  // namespace lodestone
