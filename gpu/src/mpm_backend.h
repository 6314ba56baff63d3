#pragma once
// The operations of MpmStepper, implemented by the host reference
// (host_mpm.cpp) and the CUDA backend (device_mpm.cu).
#include <cstddef>
#include <limits>
#include <memory>
#include <vector>

#include "lodestone/core/mpm/collider.h"
#include "lodestone/gpu/mpm.h"
#include "mpm_kernels.h"

namespace lodestone {
namespace gpu {
namespace detail {

constexpr std::size_t kNoParticle = std::numeric_limits<std::size_t>::max();

class MpmBackend {
 public:
  virtual ~MpmBackend() = default;
  virtual std::size_t size() const = 0;
  virtual void upload(const ParticleInput& in) = 0;
  virtual void download(const ParticleOutput& out) const = 0;
  /// Returns the lowest particle that could not be deposited, or kNoParticle.
  virtual std::size_t particleToGrid(double dt, const Vec3d* particleForces) = 0;
  virtual void gridUpdate(double dt, const Vec3d& gravity, int wallNodes, const BoundaryCondition& walls,
                          const Vec3d* nodalForce) = 0;
  virtual MpmStepReport gridToParticle(double dt, const MpmStepSettings& s) = 0;
  virtual void downloadGrid(double* mass, Vec3d* momentum, Vec3d* velocity, double* density) const = 0;
};

std::unique_ptr<MpmBackend> makeHostMpm(const kernels::MpmDims& dims, const std::vector<MpmMaterialParams>& materials);
/// Throws lodestone::Error when the CUDA backend is not built.
std::unique_ptr<MpmBackend> makeDeviceMpm(const kernels::MpmDims& dims,
                                          const std::vector<MpmMaterialParams>& materials);

}  // namespace detail
}  // namespace gpu
}  // namespace lodestone
