// The CUDA backend of MpmStepper: one thread per particle for P2G (atomic
// accumulation into the nodes) and G2P, one per node for the grid update.
// The particles stay on the device between steps.
#include <cuda_runtime.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "device_common.cuh"
#include "device_query.h"
#include "mpm_backend.h"

namespace lodestone {
namespace gpu {
namespace detail {

/// Device particle and grid arrays; public members for the extended lambdas.
class DeviceMpm final : public MpmBackend {
 public:
  DeviceMpm(const kernels::MpmDims& dims, const std::vector<MpmMaterialParams>& materials) : g_(dims) {
    std::string status;
    if (!queryDevice(status)) throw Error(concat("gpu MPM: no usable CUDA device (", status, ")"));
    materials_.upload(materials.data(), materials.size());
    materialCount_ = std::uint32_t(materials.size());
    const std::size_t n = dims.nodes();
    mass_.resize(n);
    momentum_.resize(n);
    velocity_.resize(n);
    density_.resize(n);
    force_.resize(n);
    mass_.zero();
    momentum_.zero();
    velocity_.zero();
    density_.zero();
    counters_.resize(5);
    surfaceTension_ = kernels::anySurfaceTension(materials);
    if (surfaceTension_) colour_.resize(n);
  }

  std::size_t size() const override { return size_; }

  void upload(const ParticleInput& in) override {
    size_ = in.size;
    x_.upload(in.x, size_);
    v_.upload(in.v, size_);
    C_.upload(in.C, size_);
    F_.upload(in.F, size_);
    J_.upload(in.J, size_);
    m_.upload(in.mass, size_);
    V0_.upload(in.volume0, size_);
    hasCount_ = in.count != nullptr;
    if (hasCount_) count_.upload(in.count, size_);
    mat_.upload(in.material, size_);
    pforce_.resize(size_);
    if (surfaceTension_) capillary_.resize(size_);
  }
  void download(const ParticleOutput& out) const override {
    if (out.x) x_.download(out.x, size_);
    if (out.v) v_.download(out.v, size_);
    if (out.C) C_.download(out.C, size_);
    if (out.F) F_.download(out.F, size_);
    if (out.J) J_.download(out.J, size_);
  }

  kernels::ParticlePointers pointers() {
    kernels::ParticlePointers P;
    P.x = x_.data();
    P.v = v_.data();
    P.C = C_.data();
    P.F = F_.data();
    P.J = J_.data();
    P.mass = m_.data();
    P.volume0 = V0_.data();
    P.count = hasCount_ ? count_.data() : nullptr;
    P.material = mat_.data();
    return P;
  }

  std::size_t particleToGrid(double dt, const Vec3d* forces) override {
    mass_.zero();
    momentum_.zero();
    density_.zero();
    const Vec3d* f = nullptr;
    if (forces) {
      pforce_.upload(forces, size_);
      f = pforce_.data();
    }
    unsigned long long none = ~0ull;
    LODESTONE_CUDA_CHECK(cudaMemcpy(counters_.data(), &none, sizeof none, cudaMemcpyHostToDevice));
    const kernels::MpmDims g = g_;
    const MpmMaterialParams* mats = materials_.data();
    const std::uint32_t nm = materialCount_;
    kernels::ParticlePointers P = pointers();
    unsigned long long* bad = counters_.data();
    if (surfaceTension_) {
      // The colour field (atomic sums), then the capillary stress per particle (surface_tension.h).
      colour_.zero();
      double* colour = colour_.data();
      const kernels::ParticlePointers Q = P;
      forEach(size_, [=] __device__(std::size_t p) {
        const bool ok = kernels::colourParticle(g, mats, nm, Q, p, [&](std::size_t node, double c) {
          if (c != 0) atomicAdd(colour + node, c);
        });
        if (!ok) atomicMin(bad, static_cast<unsigned long long>(p));
      });
      Mat3d* T = capillary_.data();
      forEach(size_, [=] __device__(std::size_t p) { T[p] = kernels::capillaryParticle(g, mats, nm, Q, colour, p); });
      P.capillary = T;
    }
    double* mass = mass_.data();
    double* mom = reinterpret_cast<double*>(momentum_.data());
    double* dens = density_.data();
    forEach(size_, [=] __device__(std::size_t p) {
      const bool ok =
          kernels::p2gParticle(g, mats, nm, dt, P, f, p, [&](std::size_t node, double wm, const Vec3d& mv, double wn) {
            atomicAdd(mass + node, wm);
            atomicAdd(mom + 3 * node, mv.x);
            atomicAdd(mom + 3 * node + 1, mv.y);
            atomicAdd(mom + 3 * node + 2, mv.z);
            if (wn != 0) atomicAdd(dens + node, wn);
          });
      if (!ok) atomicMin(bad, static_cast<unsigned long long>(p));
    });
    unsigned long long first = 0;
    LODESTONE_CUDA_CHECK(cudaMemcpy(&first, counters_.data(), sizeof first, cudaMemcpyDeviceToHost));
    return first == ~0ull ? kNoParticle : std::size_t(first);
  }

  void gridUpdate(double dt, const Vec3d& gravity, int wallNodes, const BoundaryCondition& walls,
                  const Vec3d* nodalForce) override {
    const Vec3d* f = nullptr;
    if (nodalForce) {
      force_.upload(nodalForce, g_.nodes());
      f = force_.data();
    }
    const kernels::MpmDims g = g_;
    const double* mass = mass_.data();
    const Vec3d* mom = momentum_.data();
    Vec3d* vel = velocity_.data();
    forEach(g.nodes(), [=] __device__(std::size_t n) {
      vel[n] = kernels::gridUpdateNode(g, n, mass[n], mom[n], f, dt, gravity, wallNodes, walls);
    });
  }

  MpmStepReport gridToParticle(double dt, const MpmStepSettings& s) override {
    counters_.zero();  // [0] max |v|^2 bits, [1] clamped, [2] outside, [3] non-finite
    const kernels::MpmDims g = g_;
    const MpmMaterialParams* mats = materials_.data();
    const kernels::ParticlePointers P = pointers();
    const Vec3d* vel = velocity_.data();
    unsigned long long* c = counters_.data();
    const bool bounded = s.bounded, clamp = s.clamp;
    const Vec3d lo = s.lo, hi = s.hi;
    forEach(size_, [=] __device__(std::size_t p) {
      const kernels::G2POutcome o = kernels::g2pParticle(g, mats, dt, P, vel, p, bounded, clamp, lo, hi);
      // |v|^2 >= 0: its IEEE bits order like the value.
      if (o.speed2 > 0 && !(o.nonFinite || o.badStencil))
        atomicMax(c, static_cast<unsigned long long>(__double_as_longlong(o.speed2)));
      if (o.clamped) atomicAdd(c + 1, 1ull);
      if (o.outside) atomicAdd(c + 2, 1ull);
      if (o.nonFinite || o.badStencil) atomicAdd(c + 3, 1ull);
    });
    unsigned long long h[4];
    LODESTONE_CUDA_CHECK(cudaMemcpy(h, counters_.data(), sizeof h, cudaMemcpyDeviceToHost));
    MpmStepReport rep;
    double s2 = 0;
    static_assert(sizeof(double) == sizeof(unsigned long long), "64-bit doubles expected");
    std::memcpy(&s2, &h[0], sizeof s2);
    rep.maxSpeed = std::sqrt(s2);
    rep.clamped = std::size_t(h[1]);
    rep.outside = std::size_t(h[2]);
    rep.nonFinite = std::size_t(h[3]);
    return rep;
  }

  void downloadGrid(double* mass, Vec3d* momentum, Vec3d* velocity, double* density) const override {
    if (mass) mass_.download(mass, g_.nodes());
    if (momentum) momentum_.download(momentum, g_.nodes());
    if (velocity) velocity_.download(velocity, g_.nodes());
    if (density) density_.download(density, g_.nodes());
  }

  kernels::MpmDims g_;
  DeviceBuffer<MpmMaterialParams> materials_;
  std::uint32_t materialCount_ = 0;
  std::size_t size_ = 0;
  bool hasCount_ = false;
  DeviceBuffer<Vec3d> x_, v_, pforce_;
  DeviceBuffer<Mat3d> C_, F_;
  DeviceBuffer<double> J_, m_, V0_, count_;
  DeviceBuffer<std::uint32_t> mat_;
  DeviceBuffer<double> mass_, density_;
  DeviceBuffer<Vec3d> momentum_, velocity_, force_;
  DeviceBuffer<unsigned long long> counters_;
  bool surfaceTension_ = false;         // some material has sigma > 0
  DeviceBuffer<double> colour_;         // surface tension: colour field per node
  DeviceBuffer<Mat3d> capillary_;       // surface tension: capillary stress per particle, Pa
};

std::unique_ptr<MpmBackend> makeDeviceMpm(const kernels::MpmDims& dims,
                                          const std::vector<MpmMaterialParams>& materials) {
  return std::make_unique<DeviceMpm>(dims, materials);
}

}  // namespace detail
}  // namespace gpu
}  // namespace lodestone
