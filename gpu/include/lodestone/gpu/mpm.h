#pragma once
// Device-resident MLS-MPM kernels: P2G (mass, APIC momentum, MLS stress
// impulse, optional per-particle forces, and the micro-particle density
// n_i = sum_p w_ip n_p / dx^3 of the magnetic stage), the grid update
// (gravity, an optional nodal force such as the magnetic force, domain walls)
// and G2P (APIC velocity and affine matrix, MLS update of F or J, advection,
// domain bounds). The formulas are those of core's MpmGrid and MpmSolver
// (core/src/mpm/grid.cpp, mpm_solver.cpp), surface tension included (the
// colour field of the liquids with sigma > 0, its gradient at each particle
// and the capillary stress of core/mpm/surface_tension.h, two passes before
// the deposit; nothing of it runs when no material has it), evaluated by the same
// LODESTONE_HOSTDEV functions on the host (Backend::Cpu, serial) and on the
// device (Backend::Cuda). Colliders other than the domain walls stay on the
// host's side of the step.
//
// Memory: upload() copies the particles to the device once; step() then runs
// P2G, grid update and G2P without transfers; download() copies them back.
// Layouts are those of core's MpmParticles (Vec3d = 3 doubles, Mat3d = 9
// doubles row-major), so a host passes its arrays directly:
//
//   lodestone::gpu::MpmStepper mpm(grid, {params}, lodestone::gpu::Backend::Auto);
//   mpm.upload({p.x.data(), p.v.data(), p.C.data(), p.F.data(), p.J.data(), p.mass.data(),
//               p.volume0.data(), p.count.data(), p.material.data(), p.size()});
//   for (int s = 0; s < steps; ++s) mpm.step(dt, settings);
//   mpm.download({p.x.data(), p.v.data(), p.C.data(), p.F.data(), p.J.data(), p.size()});
//
// P2G on the device accumulates with atomic additions: sums are not bitwise
// reproducible run to run (their relative differences are at round-off).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/base/mat3.h"
#include "lodestone/core/base/vec3.h"
#include "lodestone/gpu/backend.h"

namespace lodestone {
namespace gpu {

/// The constants of one material (core's MpmMaterial without the magnetic part).
struct MpmMaterialParams {
  bool fluid = false;      ///< viscous fluid (tracks J) or Neo-Hookean solid (tracks F)
  double mu = 0;           ///< solid: shear modulus, Pa
  double lambda = 0;       ///< solid: first Lame parameter, Pa
  double viscosity = 0;    ///< fluid: dynamic viscosity, Pa s
  double bulkModulus = 0;  ///< fluid: bulk modulus, Pa
  /// fluid: surface tension coefficient sigma, N/m, in [0, 10] (core's
  /// kMaxSurfaceTension); 0 = none. The explicit step must stay below
  /// capillaryTimeStep(rho, dx, sigma) (core/mpm/surface_tension.h).
  double surfaceTension = 0;
};

/// Host particle arrays to upload (non-owning, `size` entries each).
struct ParticleInput {
  const Vec3d* x = nullptr;                 ///< positions, m
  const Vec3d* v = nullptr;                 ///< velocities, m/s
  const Mat3d* C = nullptr;                 ///< APIC affine matrices, 1/s
  const Mat3d* F = nullptr;                 ///< deformation gradients
  const double* J = nullptr;                ///< volume ratios
  const double* mass = nullptr;             ///< kg
  const double* volume0 = nullptr;          ///< rest volumes, m^3
  const double* count = nullptr;            ///< n_p (may be null: no density deposit)
  const std::uint32_t* material = nullptr;  ///< index into the material list
  std::size_t size = 0;
};

/// Host arrays that download() fills (any pointer may be null to skip it).
struct ParticleOutput {
  Vec3d* x = nullptr;
  Vec3d* v = nullptr;
  Mat3d* C = nullptr;
  Mat3d* F = nullptr;
  double* J = nullptr;
  std::size_t size = 0;
};

/// Wall boundary modes (core's BoundaryMode).
enum class WallMode : int { Sticky = 0, Slip = 1, Separate = 2 };

struct MpmStepSettings {
  Vec3d gravity{0.0, 0.0, -9.81};  ///< m/s^2
  int wallNodes = 2;               ///< wall layer thickness in nodes (0 = no walls)
  WallMode wallMode = WallMode::Separate;
  double wallFriction = 0;  ///< Coulomb coefficient, >= 0
  bool bounded = false;     ///< keep particles inside [lo, hi] after advection
  bool clamp = true;        ///< clamp (true) or only count (false) particles leaving [lo, hi]
  Vec3d lo, hi;             ///< bounds, m

  void validate() const;
};

struct MpmStepReport {
  double maxSpeed = 0;        ///< largest |v_p| after G2P, m/s
  std::size_t clamped = 0;    ///< particles clamped back into the bounds
  std::size_t outside = 0;    ///< particles outside the bounds, left there (clamp = false)
  std::size_t nonFinite = 0;  ///< particles whose state became non-finite
};

class MpmStepper {
 public:
  /// Throws InvalidArgument on a bad grid (fewer than 3 nodes per axis) or
  /// materials, Error when `backend` is Cuda and no device is usable.
  MpmStepper(const GridSpec& grid, std::vector<MpmMaterialParams> materials, Backend backend = Backend::Auto);
  ~MpmStepper();
  MpmStepper(const MpmStepper&) = delete;
  MpmStepper& operator=(const MpmStepper&) = delete;

  Backend backend() const { return backend_; }
  const std::string& backendMessage() const { return backendMessage_; }
  const GridSpec& grid() const { return grid_; }
  std::size_t size() const;

  /// Copies the particles in (replacing any uploaded before).
  void upload(const ParticleInput& particles);
  /// Copies the evolving particle state out; out.size must equal size().
  void download(const ParticleOutput& out) const;

  /// P2G with time step dt (s) and optional per-particle forces (N, host
  /// array of size() entries). Throws InvalidArgument naming the lowest
  /// particle whose stencil leaves the grid or whose material is out of range.
  void particleToGrid(double dt, const Vec3d* particleForces = nullptr);
  /// Grid update with an optional nodal force (N, host array, one per node).
  void gridUpdate(double dt, const MpmStepSettings& settings, const Vec3d* nodalForce = nullptr);
  /// G2P, F/J update and advection.
  MpmStepReport gridToParticle(double dt, const MpmStepSettings& settings);
  /// The three in order, with no transfers.
  MpmStepReport step(double dt, const MpmStepSettings& settings);

  /// Node data of the last P2G / grid update (host arrays, one entry per
  /// node; any pointer may be null): mass (kg), momentum (kg m/s), velocity
  /// (m/s) and micro-particle density n (1/m^3).
  void downloadGrid(double* mass, Vec3d* momentum, Vec3d* velocity, double* density) const;

  struct Impl;

 private:
  GridSpec grid_;
  Backend backend_;
  std::string backendMessage_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace gpu
}  // namespace lodestone
