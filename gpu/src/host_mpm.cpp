// The host reference of MpmStepper: the formulas of mpm_kernels.h in serial
// loops (particles in index order, so P2G sums are reproducible).
#include <algorithm>
#include <cmath>

#include "mpm_backend.h"

namespace lodestone {
namespace gpu {
namespace detail {

namespace {

class HostMpm final : public MpmBackend {
 public:
  HostMpm(const kernels::MpmDims& dims, const std::vector<MpmMaterialParams>& materials)
      : g_(dims),
        materials_(materials),
        mass_(dims.nodes()),
        momentum_(dims.nodes()),
        velocity_(dims.nodes()),
        density_(dims.nodes()),
        surfaceTension_(kernels::anySurfaceTension(materials)) {}

  std::size_t size() const override { return x_.size(); }

  void upload(const ParticleInput& in) override {
    const std::size_t n = in.size;
    x_.assign(in.x, in.x + n);
    v_.assign(in.v, in.v + n);
    C_.assign(in.C, in.C + n);
    F_.assign(in.F, in.F + n);
    J_.assign(in.J, in.J + n);
    m_.assign(in.mass, in.mass + n);
    V0_.assign(in.volume0, in.volume0 + n);
    if (in.count)
      count_.assign(in.count, in.count + n);
    else
      count_.clear();
    mat_.assign(in.material, in.material + n);
  }
  void download(const ParticleOutput& out) const override {
    if (out.x) std::copy(x_.begin(), x_.end(), out.x);
    if (out.v) std::copy(v_.begin(), v_.end(), out.v);
    if (out.C) std::copy(C_.begin(), C_.end(), out.C);
    if (out.F) std::copy(F_.begin(), F_.end(), out.F);
    if (out.J) std::copy(J_.begin(), J_.end(), out.J);
  }

  std::size_t particleToGrid(double dt, const Vec3d* forces) override {
    std::fill(mass_.begin(), mass_.end(), 0.0);
    std::fill(momentum_.begin(), momentum_.end(), Vec3d{});
    std::fill(density_.begin(), density_.end(), 0.0);
    kernels::ParticlePointers P = pointers();
    if (surfaceTension_) {
      // The colour field, then the capillary stress per particle (surface_tension.h).
      colour_.assign(g_.nodes(), 0.0);
      for (std::size_t p = 0; p < x_.size(); ++p)
        if (!kernels::colourParticle(g_, materials_.data(), std::uint32_t(materials_.size()), P, p,
                                     [&](std::size_t node, double c) { colour_[node] += c; }))
          return p;
      capillary_.resize(x_.size());
      for (std::size_t p = 0; p < x_.size(); ++p)
        capillary_[p] = kernels::capillaryParticle(g_, materials_.data(), std::uint32_t(materials_.size()), P, colour_.data(), p);
      P.capillary = capillary_.data();
    }
    for (std::size_t p = 0; p < x_.size(); ++p) {
      const bool ok = kernels::p2gParticle(g_, materials_.data(), std::uint32_t(materials_.size()), dt, P, forces, p,
                                           [&](std::size_t node, double wm, const Vec3d& mv, double wn) {
                                             mass_[node] += wm;
                                             momentum_[node] += mv;
                                             density_[node] += wn;
                                           });
      if (!ok) return p;
    }
    return kNoParticle;
  }

  void gridUpdate(double dt, const Vec3d& gravity, int wallNodes, const BoundaryCondition& walls,
                  const Vec3d* nodalForce) override {
    for (std::size_t n = 0; n < g_.nodes(); ++n)
      velocity_[n] = kernels::gridUpdateNode(g_, n, mass_[n], momentum_[n], nodalForce, dt, gravity, wallNodes, walls);
  }

  MpmStepReport gridToParticle(double dt, const MpmStepSettings& s) override {
    MpmStepReport rep;
    double maxSpeed2 = 0;
    const kernels::ParticlePointers P = pointers();
    for (std::size_t p = 0; p < x_.size(); ++p) {
      const kernels::G2POutcome o =
          kernels::g2pParticle(g_, materials_.data(), dt, P, velocity_.data(), p, s.bounded, s.clamp, s.lo, s.hi);
      maxSpeed2 = std::max(maxSpeed2, o.speed2);
      rep.clamped += o.clamped;
      rep.outside += o.outside;
      rep.nonFinite += o.nonFinite || o.badStencil;
    }
    rep.maxSpeed = std::sqrt(maxSpeed2);
    return rep;
  }

  void downloadGrid(double* mass, Vec3d* momentum, Vec3d* velocity, double* density) const override {
    if (mass) std::copy(mass_.begin(), mass_.end(), mass);
    if (momentum) std::copy(momentum_.begin(), momentum_.end(), momentum);
    if (velocity) std::copy(velocity_.begin(), velocity_.end(), velocity);
    if (density) std::copy(density_.begin(), density_.end(), density);
  }

 private:
  kernels::ParticlePointers pointers() {
    kernels::ParticlePointers P;
    P.x = x_.data();
    P.v = v_.data();
    P.C = C_.data();
    P.F = F_.data();
    P.J = J_.data();
    P.mass = m_.data();
    P.volume0 = V0_.data();
    P.count = count_.empty() ? nullptr : count_.data();
    P.material = mat_.data();
    return P;
  }

  kernels::MpmDims g_;
  std::vector<MpmMaterialParams> materials_;
  std::vector<Vec3d> x_, v_;
  std::vector<Mat3d> C_, F_;
  std::vector<double> J_, m_, V0_, count_;
  std::vector<std::uint32_t> mat_;
  std::vector<double> mass_;
  std::vector<Vec3d> momentum_, velocity_;
  std::vector<double> density_;
  bool surfaceTension_ = false;  // some material has sigma > 0
  std::vector<double> colour_;   // surface tension: colour field per node
  std::vector<Mat3d> capillary_;  // surface tension: capillary stress per particle, Pa
};

}  // namespace

std::unique_ptr<MpmBackend> makeHostMpm(const kernels::MpmDims& dims, const std::vector<MpmMaterialParams>& materials) {
  return std::make_unique<HostMpm>(dims, materials);
}

}  // namespace detail
}  // namespace gpu
}  // namespace lodestone
