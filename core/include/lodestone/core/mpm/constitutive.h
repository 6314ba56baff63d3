#pragma once
// Constitutive laws of the reference MLS-MPM (Section 3 of the paper,
// PHYSICS.md section 5), written once for host and device: no exceptions, no
// allocation. Stresses are in Pa, energy densities in J/m^3 (per reference
// volume).
//
// Neo-Hookean solid (Eq. 18, after Sifakis and Barbic 2012), with Lame
// parameters mu, lambda (Pa) and J = det F:
//   sigma = (mu/J) (F F^T - I) + (lambda/J) ln J I          (Cauchy)
//   tau   = J sigma = mu (F F^T - I) + lambda ln J I          (Kirchhoff, = P F^T)
//   Psi   = mu/2 (tr(F^T F) - 3) - mu ln J + lambda/2 (ln J)^2
// so that P = dPsi/dF = mu (F - F^-T) + lambda ln J F^-T and tau = P F^T.
//
// Viscous fluid (Eqs. 19-21), viscosity mu_N (Pa*s), bulk modulus K (Pa), and
// only the volume ratio J tracked (Tampubolon et al. 2017):
//   sigma = mu_N (grad v + grad v^T) - K (1 - J) I            (Cauchy)
//   tau   = J sigma                                           (Kirchhoff)
//   Psi   = K/2 (J - 1)^2   (the elastic part: d Psi/dJ = K (J - 1) = -p)
// The pressure is p = K (1 - J). In MLS-MPM the particle's affine matrix C is
// its velocity gradient, so grad v = C.
//
// Viscoplastic fluid (regularized Herschel-Bulkley), J tracked as above, yield
// stress tau_y (Pa), consistency k (Pa*s^n), flow index n (n = 1: Bingham):
//   D = (C + C^T)/2, D_dev = D - tr(D)/3 I, gamma_dot = sqrt(2 D_dev : D_dev)  (1/s)
//   mu_eff = min(mu_max, tau_y / gamma_dot + k gamma_dot^(n-1))               (Pa*s)
//   sigma  = 2 mu_eff D_dev - K (1 - J) I                                      (Cauchy)
// The cap mu_max (a bi-viscosity regularization) makes unyielded material a
// very viscous Newtonian fluid that creeps at strain rate ~ stress / mu_max
// instead of standing exactly still; it bounds the explicit viscous time step
// (dx^2 rho / (6 mu_max)), so a large yield stress never blows up.
//
// Damped elastoplastic solid ("magnetic clay"), F = F_E tracked as the
// elastic part of the deformation (the plastic part is not stored: von Mises
// flow is isochoric and the model has no hardening, so nothing depends on it).
// Hencky (logarithmic-strain St. Venant-Kirchhoff) elasticity with the solid's
// Lame parameters mu, lambda (Pa) on the principal stretches s_i of F_E, where
// F_E F_E^T = U diag(s_i^2) U^T (Klar et al. 2016, Sec. 6; Gao et al. 2017):
//   eps_i = ln s_i,   tau = U diag(2 mu eps_i + lambda sum_k eps_k) U^T      (Kirchhoff)
//   Psi   = mu sum_i eps_i^2 + lambda/2 (sum_i eps_i)^2                       (J/m^3)
// Von Mises plasticity with yield stress sigma_y (Pa, the uniaxial yield
// stress): the equivalent stress q = sqrt(3/2 tau_dev : tau_dev) may not
// exceed sigma_y. Since tau_dev = 2 mu eps_dev, the return mapping is exact in
// principal space (radial return, Simo and Hughes 1998, Box 3.1, with log
// strains):
//   q_tr > sigma_y:  eps_dev <- eps_dev sigma_y / q_tr,  tr(eps) kept,
//   F_E <- U diag(exp(eps_i) / s_i) U^T F_E  (the rotation of F_E is kept),
// so det F_E (the volume) is unchanged by plastic flow. Kelvin-Voigt damping
// with viscosity eta (Pa*s) on the deviatoric rate of deformation:
//   D = (C + C^T)/2,  sigma_visc = 2 eta D_dev,  tau = tau_Hencky + J sigma_visc.
// Principal stretches below kMinStretch are raised to it (ln s stays finite,
// the stress a strong restoring one), like the J floor below.
//
// Inverted or collapsed elements (J <= kMinVolumeRatio) would make ln J
// undefined; J is floored at kMinVolumeRatio inside the logarithm and the
// 1/J factor so the stress stays finite (a strong restoring pressure) instead
// of turning into NaN.
#include <cmath>

#include "lodestone/core/base/hostdev.h"
#include "lodestone/core/base/mat3.h"
#include "lodestone/core/base/symmetric_eigen.h"

namespace lodestone {
inline namespace mpm {

/// Smallest volume ratio used inside ln J and 1/J (dimensionless).
inline constexpr double kMinVolumeRatio = 1e-6;
/// Smallest principal stretch used inside ln s (dimensionless): kMinVolumeRatio^(1/3).
inline constexpr double kMinStretch = 1e-2;

/// det A.
template <typename T>
LODESTONE_HOSTDEV inline T determinant(const Mat3<T>& A) {
  return A(0, 0) * (A(1, 1) * A(2, 2) - A(1, 2) * A(2, 1)) - A(0, 1) * (A(1, 0) * A(2, 2) - A(1, 2) * A(2, 0)) +
         A(0, 2) * (A(1, 0) * A(2, 1) - A(1, 1) * A(2, 0));
}

/// tr A.
template <typename T>
LODESTONE_HOSTDEV inline T trace(const Mat3<T>& A) {
  return A(0, 0) + A(1, 1) + A(2, 2);
}

/// The volume ratio J = det F inside the laws' ln J and 1/J, floored at
/// kMinVolumeRatio.
template <typename T>
LODESTONE_HOSTDEV inline T flooredVolumeRatio(const Mat3<T>& F) {
  T J = determinant(F);
  if (!(J > T(kMinVolumeRatio))) J = T(kMinVolumeRatio);
  return J;
}

/// neoHookeanKirchhoff with logJ = ln flooredVolumeRatio(F) given: for
/// callers that take several particles' logarithms in a loop of their own.
template <typename T>
LODESTONE_HOSTDEV inline Mat3<T> neoHookeanKirchhoffWithLogJ(const Mat3<T>& F, T mu, T lambda, T logJ) {
  const T p = lambda * logJ;
  Mat3<T> tau;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const T ffT = F(i, 0) * F(j, 0) + F(i, 1) * F(j, 1) + F(i, 2) * F(j, 2);
      tau(i, j) = mu * (ffT - (i == j ? T(1) : T(0))) + (i == j ? p : T(0));
    }
  return tau;
}

/// Neo-Hookean Kirchhoff stress tau = mu (F F^T - I) + lambda ln J I (Pa), Eq. 18 times J.
template <typename T>
LODESTONE_HOSTDEV inline Mat3<T> neoHookeanKirchhoff(const Mat3<T>& F, T mu, T lambda) {
  using std::log;
  return neoHookeanKirchhoffWithLogJ(F, mu, lambda, T(log(flooredVolumeRatio(F))));
}

/// Neo-Hookean Cauchy stress sigma = tau / J (Pa), Eq. 18.
template <typename T>
LODESTONE_HOSTDEV inline Mat3<T> neoHookeanCauchy(const Mat3<T>& F, T mu, T lambda) {
  const T J = flooredVolumeRatio(F);
  Mat3<T> s = neoHookeanKirchhoff(F, mu, lambda);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s(i, j) /= J;
  return s;
}

/// Neo-Hookean strain energy per reference volume Psi(F) (J/m^3).
template <typename T>
LODESTONE_HOSTDEV inline T neoHookeanEnergyDensity(const Mat3<T>& F, T mu, T lambda) {
  using std::log;
  const T J = flooredVolumeRatio(F);
  T frob = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) frob += F(i, j) * F(i, j);
  const T lnJ = log(J);
  return T(0.5) * mu * (frob - T(3)) - mu * lnJ + T(0.5) * lambda * lnJ * lnJ;
}

/// Viscous-fluid Cauchy stress sigma = mu_N (C + C^T) - K (1 - J) I (Pa), Eqs. 19-21,
/// with the velocity gradient C (1/s), viscosity mu_N (Pa*s) and bulk modulus K (Pa).
template <typename T>
LODESTONE_HOSTDEV inline Mat3<T> viscousFluidCauchy(const Mat3<T>& C, T J, T viscosity, T bulkModulus) {
  const T p = bulkModulus * (T(1) - J);  // pressure, Pa
  Mat3<T> s;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s(i, j) = viscosity * (C(i, j) + C(j, i)) - (i == j ? p : T(0));
  return s;
}

/// Viscous-fluid Kirchhoff stress tau = J sigma (Pa).
template <typename T>
LODESTONE_HOSTDEV inline Mat3<T> viscousFluidKirchhoff(const Mat3<T>& C, T J, T viscosity, T bulkModulus) {
  Mat3<T> s = viscousFluidCauchy(C, J, viscosity, bulkModulus);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s(i, j) *= J;
  return s;
}

/// Capped Herschel-Bulkley effective viscosity (Pa*s) at shear rate gamma_dot (1/s):
/// min(mu_max, tau_y / gamma_dot + k gamma_dot^(n-1)); mu_max at gamma_dot = 0.
template <typename T>
LODESTONE_HOSTDEV inline T herschelBulkleyViscosity(T gammaDot, T yieldStress, T consistency, T flowIndex,
                                                    T maxViscosity) {
  using std::pow;
  if (!(gammaDot > T(0))) return maxViscosity;
  const T mu = yieldStress / gammaDot + consistency * pow(gammaDot, flowIndex - T(1));
  return mu < maxViscosity ? mu : maxViscosity;
}

/// Viscoplastic-fluid Kirchhoff stress tau = J (2 mu_eff D_dev - K (1 - J) I) (Pa).
template <typename T>
LODESTONE_HOSTDEV inline Mat3<T> viscoplasticFluidKirchhoff(const Mat3<T>& C, T J, T yieldStress, T consistency,
                                                            T flowIndex, T maxViscosity, T bulkModulus) {
  using std::sqrt;
  Mat3<T> D;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) D(i, j) = T(0.5) * (C(i, j) + C(j, i));
  const T third = trace(D) / T(3);
  for (int i = 0; i < 3; ++i) D(i, i) -= third;
  T dd = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) dd += D(i, j) * D(i, j);
  const T mu = herschelBulkleyViscosity(sqrt(T(2) * dd), yieldStress, consistency, flowIndex, maxViscosity);
  const T p = bulkModulus * (T(1) - J);  // pressure, Pa
  Mat3<T> s;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s(i, j) = J * (T(2) * mu * D(i, j) - (i == j ? p : T(0)));
  return s;
}

/// Principal Hencky strains eps_i = ln s_i (s_i floored at kMinStretch) and
/// directions U (columns) of F F^T = U diag(s_i^2) U^T.
template <typename T>
struct HenckyStrain {
  T eps[3];
  T stretch[3];  ///< s_i, floored
  Mat3<T> U;
};

template <typename T>
LODESTONE_HOSTDEV inline HenckyStrain<T> henckyStrain(const Mat3<T>& F) {
  using std::log;
  using std::sqrt;
  const SymmetricEigen3<T> e = symmetricEigen(F * F.transposed());  // b = F F^T
  HenckyStrain<T> h;
  h.U = e.vectors;
  const T floor2 = T(kMinStretch) * T(kMinStretch);
  for (int i = 0; i < 3; ++i) {
    const T s2 = e.values[i] > floor2 ? e.values[i] : floor2;  // also maps NaN to the floor
    h.stretch[i] = sqrt(s2);
    h.eps[i] = T(0.5) * log(s2);
  }
  return h;
}

/// U diag(d) U^T.
template <typename T>
LODESTONE_HOSTDEV inline Mat3<T> principalToMatrix(const Mat3<T>& U, const T d[3]) {
  Mat3<T> m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = U(i, 0) * d[0] * U(j, 0) + U(i, 1) * d[1] * U(j, 1) + U(i, 2) * d[2] * U(j, 2);
  return m;
}

/// Hencky Kirchhoff stress tau = U diag(2 mu eps_i + lambda tr eps) U^T (Pa).
template <typename T>
LODESTONE_HOSTDEV inline Mat3<T> henckyKirchhoff(const Mat3<T>& F, T mu, T lambda) {
  const HenckyStrain<T> h = henckyStrain(F);
  const T tr = h.eps[0] + h.eps[1] + h.eps[2];
  const T d[3] = {T(2) * mu * h.eps[0] + lambda * tr, T(2) * mu * h.eps[1] + lambda * tr,
                  T(2) * mu * h.eps[2] + lambda * tr};
  return principalToMatrix(h.U, d);
}

/// Hencky strain energy per reference volume mu sum eps_i^2 + lambda/2 (tr eps)^2 (J/m^3).
template <typename T>
LODESTONE_HOSTDEV inline T henckyEnergyDensity(const Mat3<T>& F, T mu, T lambda) {
  const HenckyStrain<T> h = henckyStrain(F);
  const T tr = h.eps[0] + h.eps[1] + h.eps[2];
  return mu * (h.eps[0] * h.eps[0] + h.eps[1] * h.eps[1] + h.eps[2] * h.eps[2]) + T(0.5) * lambda * tr * tr;
}

/// Von Mises equivalent stress sqrt(3/2 s : s) of the deviator s of tau (Pa).
template <typename T>
LODESTONE_HOSTDEV inline T vonMisesStress(const Mat3<T>& tau) {
  using std::sqrt;
  const T mean = trace(tau) / T(3);
  T ss = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const T s = tau(i, j) - (i == j ? mean : T(0));
      ss += s * s;
    }
  return sqrt(T(1.5) * ss);
}

/// Von Mises return mapping of a trial elastic deformation gradient F_E (Hencky
/// elasticity, shear modulus mu in Pa, yield stress sigma_y in Pa, perfect
/// plasticity): F_E itself below yield, else F_E with its deviatoric log
/// strain scaled onto q = sigma_y at the same volume and rotation.
template <typename T>
LODESTONE_HOSTDEV inline Mat3<T> vonMisesReturn(const Mat3<T>& F, T mu, T yieldStress) {
  using std::exp;
  using std::sqrt;
  const HenckyStrain<T> h = henckyStrain(F);
  const T mean = (h.eps[0] + h.eps[1] + h.eps[2]) / T(3);
  const T dev[3] = {h.eps[0] - mean, h.eps[1] - mean, h.eps[2] - mean};
  // q = sqrt(3/2) |2 mu eps_dev|.
  const T q = T(2) * mu * sqrt(T(1.5) * (dev[0] * dev[0] + dev[1] * dev[1] + dev[2] * dev[2]));
  if (!(q > yieldStress)) return F;
  const T scale = yieldStress / q;
  T ratio[3];
  for (int i = 0; i < 3; ++i) ratio[i] = exp(mean + scale * dev[i]) / h.stretch[i];
  return principalToMatrix(h.U, ratio) * F;
}

/// Damped elastoplastic Kirchhoff stress tau = tau_Hencky(F_E) + J 2 eta D_dev (Pa),
/// with the elastic part F_E (already returned to the yield surface), the
/// velocity gradient C (1/s) and the Kelvin-Voigt viscosity eta (Pa*s).
template <typename T>
LODESTONE_HOSTDEV inline Mat3<T> elastoplasticKirchhoff(const Mat3<T>& F, const Mat3<T>& C, T mu, T lambda,
                                                        T viscosity) {
  Mat3<T> tau = henckyKirchhoff(F, mu, lambda);
  const T J = flooredVolumeRatio(F);
  const T third = trace(C) / T(3);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      tau(i, j) += J * viscosity * (C(i, j) + C(j, i) - (i == j ? T(2) * third : T(0)));
  return tau;
}

/// Elastic energy per reference volume of the fluid, K/2 (J - 1)^2 (J/m^3).
template <typename T>
LODESTONE_HOSTDEV inline T fluidEnergyDensity(T J, T bulkModulus) {
  return T(0.5) * bulkModulus * (J - T(1)) * (J - T(1));
}

}  // namespace mpm
}  // namespace lodestone
