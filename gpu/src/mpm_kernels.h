#pragma once
// The MLS-MPM transfer and grid-update formulas of core/src/mpm/grid.cpp and
// solver.cpp, per particle and per node, written once for the host
// reference and the CUDA kernels (LODESTONE_HOSTDEV). P2G (and the colour
// scatter of surface tension) hands every (node, contribution) pair to an
// accumulator: plain += on the host, atomicAdd on the device.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "lodestone/core/base/bspline.h"
#include "lodestone/core/base/hostdev.h"
#include "lodestone/core/base/mat3.h"
#include "lodestone/core/mpm/apic_gather.h"
#include "lodestone/core/mpm/collider.h"
#include "lodestone/core/mpm/constitutive.h"
#include "lodestone/core/mpm/surface_tension.h"
#include "lodestone/core/base/vec3.h"
#include "lodestone/gpu/mpm.h"

namespace lodestone {
namespace gpu {
namespace kernels {

struct MpmDims {
  double ox = 0, oy = 0, oz = 0, dx = 0;  ///< m
  int nx = 0, ny = 0, nz = 0;
  LODESTONE_HOSTDEV std::size_t nodes() const { return std::size_t(nx) * std::size_t(ny) * std::size_t(nz); }
  LODESTONE_HOSTDEV std::size_t index(int i, int j, int k) const {
    return std::size_t(i) + std::size_t(nx) * (std::size_t(j) + std::size_t(ny) * std::size_t(k));
  }
};

/// Particle arrays in one memory space (Vec3d / Mat3d layouts of MpmParticles).
struct ParticlePointers {
  Vec3d* x = nullptr;
  Vec3d* v = nullptr;
  Mat3d* C = nullptr;
  Mat3d* F = nullptr;
  double* J = nullptr;
  const double* mass = nullptr;
  const double* volume0 = nullptr;
  const double* count = nullptr;  ///< n_p, may be null
  const std::uint32_t* material = nullptr;
  /// Surface tension: the capillary (Cauchy) stress per particle, Pa, that
  /// P2G adds to the Kirchhoff stress as J T; null when no material has it.
  const Mat3d* capillary = nullptr;
};

/// Stencil base of grid coordinate u when it fits the grid (base in
/// [0, n - 3]); false for a non-finite u or a stencil outside (mpm_grid.cpp).
LODESTONE_HOSTDEV inline bool stencilBase(double u, int n, int& base) {
  const double f = quadraticBaseFloor(u);
  if (!(f >= 0 && f <= double(n - 3))) return false;
  base = int(f);
  return true;
}

/// P2G of particle p (mpm_grid.h): m_i += w m_p, mv_i += w (m_p v_p + A_p d + dt f_p)
/// with A_p = m_p C_p - dt (4/dx^2) V0 tau_p, and n_i += w n_p / dx^3 when
/// counts are given. acc(node, w m, w momentum, w n / dx^3). Returns false
/// (and deposits nothing) when the stencil does not fit or the material
/// index is out of range.
template <typename Acc>
LODESTONE_HOSTDEV inline bool p2gParticle(const MpmDims& g, const MpmMaterialParams* materials,
                                          std::uint32_t materialCount, double dt, const ParticlePointers& P,
                                          const Vec3d* force, std::size_t p, const Acc& acc) {
  const double invDx = 1.0 / g.dx, dx = g.dx;
  const Vec3d x = P.x[p];
  const double ux = (x.x - g.ox) * invDx, uy = (x.y - g.oy) * invDx, uz = (x.z - g.oz) * invDx;
  int bi, bj, bk;
  if (!stencilBase(ux, g.nx, bi) || !stencilBase(uy, g.ny, bj) || !stencilBase(uz, g.nz, bk)) return false;
  const std::uint32_t mi = P.material[p];
  if (mi >= materialCount) return false;
  const QuadraticWeights<double> wx = quadraticWeightsAt(ux, bi);
  const QuadraticWeights<double> wy = quadraticWeightsAt(uy, bj);
  const QuadraticWeights<double> wz = quadraticWeightsAt(uz, bk);
  const double fx = ux - bi, fy = uy - bj, fz = uz - bk;
  const double m = P.mass[p];
  const MpmMaterialParams& mp = materials[mi];
  Mat3d tau = mp.fluid ? viscousFluidKirchhoff(P.C[p], P.J[p], mp.viscosity, mp.bulkModulus)
                       : neoHookeanKirchhoff(P.F[p], mp.mu, mp.lambda);
  if (P.capillary) {
    const Mat3d& Tc = P.capillary[p];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) tau(a, b) += P.J[p] * Tc(a, b);
  }
  Mat3d A;
  const double s = dt * 4.0 * invDx * invDx * P.volume0[p];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) A(a, b) = m * P.C[p](a, b) - s * tau(a, b);
  Vec3d q0 = m * P.v[p] - A * Vec3d{fx * dx, fy * dx, fz * dx};
  if (force) q0 += dt * force[p];
  const Vec3d A0{A(0, 0) * dx, A(1, 0) * dx, A(2, 0) * dx};
  const Vec3d A1{A(0, 1) * dx, A(1, 1) * dx, A(2, 1) * dx};
  const Vec3d A2{A(0, 2) * dx, A(1, 2) * dx, A(2, 2) * dx};
  const double nScale = P.count ? P.count[p] * invDx * invDx * invDx : 0.0;
  for (int c = 0; c < 3; ++c)
    for (int b = 0; b < 3; ++b) {
      const double wbc = wy.w[b] * wz.w[c];
      const Vec3d q = q0 + double(b) * A1 + double(c) * A2;
      const std::size_t line = g.index(bi, bj + b, bk + c);
      for (int a = 0; a < 3; ++a) {
        const double w = wx.w[a] * wbc;
        acc(line + std::size_t(a), w * m, w * (q + double(a) * A0), w * nScale);
      }
    }
  return true;
}

/// Surface tension, first pass (core's MpmGrid): particle p's share of the
/// colour field c_i = sum_p w_ip V_p / dx^3 (V_p = V_p^0 J_p) when its
/// material is a liquid with sigma > 0; acc(node, w V_p / dx^3). Returns false
/// (and deposits nothing) when the stencil does not fit the grid or the
/// material index is out of range.
template <typename Acc>
LODESTONE_HOSTDEV inline bool colourParticle(const MpmDims& g, const MpmMaterialParams* materials,
                                             std::uint32_t materialCount, const ParticlePointers& P, std::size_t p,
                                             const Acc& acc) {
  const double invDx = 1.0 / g.dx;
  const Vec3d x = P.x[p];
  const double ux = (x.x - g.ox) * invDx, uy = (x.y - g.oy) * invDx, uz = (x.z - g.oz) * invDx;
  int bi, bj, bk;
  if (!stencilBase(ux, g.nx, bi) || !stencilBase(uy, g.ny, bj) || !stencilBase(uz, g.nz, bk)) return false;
  if (P.material[p] >= materialCount) return false;
  if (!(materials[P.material[p]].surfaceTension > 0)) return true;
  const QuadraticWeights<double> wx = quadraticWeightsAt(ux, bi);
  const QuadraticWeights<double> wy = quadraticWeightsAt(uy, bj);
  const QuadraticWeights<double> wz = quadraticWeightsAt(uz, bk);
  const double fraction = P.volume0[p] * P.J[p] * invDx * invDx * invDx;
  for (int c = 0; c < 3; ++c)
    for (int b = 0; b < 3; ++b) {
      const double wbc = fraction * wy.w[b] * wz.w[c];
      const std::size_t line = g.index(bi, bj + b, bk + c);
      for (int a = 0; a < 3; ++a) acc(line + std::size_t(a), wx.w[a] * wbc);
    }
  return true;
}

/// Surface tension, second pass: the capillary stress of particle p (Pa) from
/// the colour gradient and Hessian at it (surface_tension.h); zero for materials without
/// it or whose stencil does not fit the grid (which P2G then reports).
LODESTONE_HOSTDEV inline Mat3d capillaryParticle(const MpmDims& g, const MpmMaterialParams* materials,
                                                 std::uint32_t materialCount, const ParticlePointers& P,
                                                 const double* colour, std::size_t p) {
  const double invDx = 1.0 / g.dx;
  const Vec3d x = P.x[p];
  const double ux = (x.x - g.ox) * invDx, uy = (x.y - g.oy) * invDx, uz = (x.z - g.oz) * invDx;
  int bi, bj, bk;
  if (!stencilBase(ux, g.nx, bi) || !stencilBase(uy, g.ny, bj) || !stencilBase(uz, g.nz, bk)) return Mat3d{};
  if (P.material[p] >= materialCount) return Mat3d{};
  const double sigma = materials[P.material[p]].surfaceTension;
  if (!(sigma > 0)) return Mat3d{};
  const QuadraticWeights<double> wx = quadraticWeightsAt(ux, bi, invDx);
  const QuadraticWeights<double> wy = quadraticWeightsAt(uy, bj, invDx);
  const QuadraticWeights<double> wz = quadraticWeightsAt(uz, bk, invDx);
  return particleCapillaryStress(colour, g.nx, g.ny, g.nz, bi, bj, bk, wx, wy, wz, sigma, invDx);
}

/// Whether some material has surface tension.
inline bool anySurfaceTension(const std::vector<MpmMaterialParams>& materials) {
  for (const MpmMaterialParams& m : materials)
    if (m.surfaceTension > 0) return true;
  return false;
}

/// Grid update at node n (mpm_solver.cpp gridUpdate, without colliders):
/// v = (p + dt f) / m + dt g, then the wall layers' boundary condition.
LODESTONE_HOSTDEV inline Vec3d gridUpdateNode(const MpmDims& g, std::size_t n, double mass, const Vec3d& momentum,
                                              const Vec3d* force, double dt, const Vec3d& gravity, int wallNodes,
                                              const BoundaryCondition& walls) {
  if (!(mass > 0)) return Vec3d{};
  Vec3d p = momentum;
  if (force) p += dt * force[n];
  Vec3d v = p / mass + dt * gravity;
  if (wallNodes > 0) {
    const int idx[3] = {int(n % std::size_t(g.nx)), int((n / std::size_t(g.nx)) % std::size_t(g.ny)),
                        int(n / (std::size_t(g.nx) * std::size_t(g.ny)))};
    const int dims[3] = {g.nx, g.ny, g.nz};
    v = applyDomainWalls(v, idx, dims, wallNodes, walls);
  }
  return v;
}

/// What G2P reports for one particle.
struct G2POutcome {
  double speed2 = 0;
  bool clamped = false, outside = false, nonFinite = false, badStencil = false;
};

/// G2P, F/J update and advection of particle p (mpm_grid.cpp gridToParticle).
LODESTONE_HOSTDEV inline G2POutcome g2pParticle(const MpmDims& g, const MpmMaterialParams* materials, double dt,
                                                const ParticlePointers& P, const Vec3d* vel, std::size_t p,
                                                bool bounded, bool clamp, const Vec3d& lo, const Vec3d& hi) {
  G2POutcome out;
  const double dx = g.dx, invDx = 1.0 / dx, cScale = 4.0 * invDx;
  const Vec3d x = P.x[p];
  const double ux = (x.x - g.ox) * invDx, uy = (x.y - g.oy) * invDx, uz = (x.z - g.oz) * invDx;
  int bi, bj, bk;
  if (!stencilBase(ux, g.nx, bi) || !stencilBase(uy, g.ny, bj) || !stencilBase(uz, g.nz, bk)) {
    out.badStencil = true;
    return out;
  }
  const double u[3] = {ux, uy, uz};
  const int b3[3] = {bi, bj, bk};
  Vec3d vp;
  Mat3d C;
  gatherApic(vel, std::size_t(g.nx), std::size_t(g.ny), u, b3, cScale, vp, C);
  if (materials[P.material[p]].fluid) {
    P.J[p] *= 1.0 + dt * trace(C);
  } else {
    Mat3d G = Mat3d::identity();
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) G(a, b) += dt * C(a, b);
    P.F[p] = G * P.F[p];
    P.J[p] = determinant(P.F[p]);
  }
  P.C[p] = C;
  Vec3d xn = x + dt * vp;
  if (!(isFinite(xn) && isFinite(vp) && std::isfinite(P.J[p]))) {
    out.nonFinite = true;
  } else if (bounded && (xn.x < lo.x || xn.x > hi.x || xn.y < lo.y || xn.y > hi.y || xn.z < lo.z || xn.z > hi.z)) {
    if (clamp) {
      for (int a = 0; a < 3; ++a) {
        if (xn[a] < lo[a]) {
          xn[a] = lo[a];
          vp[a] = vp[a] > 0.0 ? vp[a] : 0.0;
        } else if (xn[a] > hi[a]) {
          xn[a] = hi[a];
          vp[a] = vp[a] < 0.0 ? vp[a] : 0.0;
        }
      }
      out.clamped = true;
    } else {
      out.outside = true;
    }
  }
  P.v[p] = vp;
  P.x[p] = xn;
  out.speed2 = norm2(vp);
  return out;
}

}  // namespace kernels
}  // namespace gpu
}  // namespace lodestone
