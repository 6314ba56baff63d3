#pragma once
// Magnetization laws M(H; n) of a magnetizable species with micro-particle
// number density n (1/m^3), their co-energy density W (dW/dH = M) and Jacobian
// block dM/dH (PHYSICS.md section 1, Eq. 5 and 26 of the paper). Written once
// for host and device. Construct laws with the validated factories in
// material.h; this header only evaluates them.
#include <limits>

#include "lodestone/core/base/hostdev.h"
#include "lodestone/core/field/langevin.h"
#include "lodestone/core/base/mat3.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace field {

enum class LawKind : int {
  None = 0,     ///< not magnetizable: M = 0
  Linear = 1,   ///< M = chi(n) H with chi = chiPerDensity * n
  Langevin = 2  ///< M = n m L(k2 |H|) H/|H|, k2 = mu0 m/(kB T)
};

template <typename T>
struct MagnetizationLaw {
  LawKind kind = LawKind::None;
  T moment = 0;         ///< micro-particle moment m, A*m^2 (Langevin)
  T k2 = 0;             ///< mu0 m/(kB T), m/A (Langevin)
  T chiPerDensity = 0;  ///< susceptibility per unit number density, m^3 (Linear)

  /// Saturation magnetization Ms = n m, A/m (infinite for Linear, 0 for None).
  LODESTONE_HOSTDEV T saturation(T n) const {
    if (kind == LawKind::Langevin) return n * moment;
#if defined(__CUDA_ARCH__)
    return kind == LawKind::Linear ? T(HUGE_VAL) : T(0);  // +inf; numeric_limits is host-only in device code
#else
    return kind == LawKind::Linear ? std::numeric_limits<T>::infinity() : T(0);
#endif
  }
  /// Low-field susceptibility chi0 at density n (dimensionless).
  LODESTONE_HOSTDEV T lowFieldSusceptibility(T n) const {
    if (kind == LawKind::Langevin) return n * moment * k2 / T(3);
    return kind == LawKind::Linear ? chiPerDensity * n : T(0);
  }
  /// Same kind and the same constants, bit for bit.
  LODESTONE_HOSTDEV bool operator==(const MagnetizationLaw& o) const {
    return kind == o.kind && moment == o.moment && k2 == o.k2 && chiPerDensity == o.chiPerDensity;
  }
  LODESTONE_HOSTDEV bool operator!=(const MagnetizationLaw& o) const { return !(*this == o); }
};

/// M, dM/dH and W at one point.
template <typename T>
struct MagnetizationResponse {
  Vec3<T> M;        ///< magnetization, A/m
  SymMat3<T> dMdH;  ///< Jacobian block, dimensionless, symmetric positive semi-definite
  /// The same block as iso * I + rank1 * h h^T (h unit, or zero): the
  /// structure of every isotropic law, which element assembly exploits.
  T iso = 0, rank1 = 0;
  Vec3<T> h;
  T W = 0;          ///< co-energy density with dW/dH = M, A^2/m^2 (mu0 W is J/m^3)
};

/// Magnetization only (cheapest evaluation).
template <typename T>
LODESTONE_HOSTDEV inline Vec3<T> magnetization(const MagnetizationLaw<T>& law, T n, const Vec3<T>& H) {
  switch (law.kind) {
    case LawKind::Linear:
      return (law.chiPerDensity * n) * H;
    case LawKind::Langevin: {
      // M = Ms L(a) H/|H| = Ms k2 g(a) H with g = L(a)/a: finite at H = 0.
      const T a = law.k2 * norm(H);
      return (n * law.moment * law.k2 * langevinOverArg(a)) * H;
    }
    default:
      return {};
  }
}

/// Co-energy density W(H), A^2/m^2.
template <typename T>
LODESTONE_HOSTDEV inline T coEnergy(const MagnetizationLaw<T>& law, T n, const Vec3<T>& H) {
  switch (law.kind) {
    case LawKind::Linear:
      return T(0.5) * law.chiPerDensity * n * norm2(H);
    case LawKind::Langevin:
      // W = (Ms/k2) ln(sinh a / a)
      return n * law.moment / law.k2 * logSinhOverArg(law.k2 * norm(H));
    default:
      return T(0);
  }
}

/// M, dM/dH and W together.
template <typename T>
LODESTONE_HOSTDEV inline MagnetizationResponse<T> respond(const MagnetizationLaw<T>& law, T n,
                                                          const Vec3<T>& H) {
  MagnetizationResponse<T> r;
  switch (law.kind) {
    case LawKind::Linear: {
      const T chi = law.chiPerDensity * n;
      r.M = chi * H;
      r.dMdH = SymMat3<T>::scaledIdentity(chi);
      r.iso = chi;
      r.W = T(0.5) * chi * norm2(H);
      break;
    }
    case LawKind::Langevin: {
      // Eq. 26: dM/dH = Ms k2 [L'(a) h h^T + g(a) (I - h h^T)], h = H/|H|.
      const T Hn = norm(H);
      const T a = law.k2 * Hn;
      const T chi0x3 = n * law.moment * law.k2;  // Ms k2 = 3 chi0
      const LangevinTriple<T> L = langevinTriple(a);
      const Vec3<T> h = Hn > T(0) ? (T(1) / Hn) * H : Vec3<T>{};
      r.M = (chi0x3 * L.overArg) * H;
      r.iso = chi0x3 * L.overArg;
      r.rank1 = chi0x3 * (L.derivative - L.overArg);
      r.h = h;
      r.dMdH = SymMat3<T>::identityPlusOuter(r.iso, r.rank1, h);
      r.W = n * law.moment / law.k2 * L.logSinhc;
      break;
    }
    default:
      break;
  }
  return r;
}

}  // namespace field
}  // namespace lodestone
