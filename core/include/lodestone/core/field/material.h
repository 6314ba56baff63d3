#pragma once
// Magnetic materials: a magnetization law plus the bulk micro-particle number
// density n0 (1/m^3) that a filled cell carries. Factories validate their
// arguments and throw InvalidArgument naming the bad value.
#include <string>

#include "lodestone/core/field/magnetization_law.h"

namespace lodestone {
inline namespace field {

struct MagneticMaterial {
  MagnetizationLaw<double> law;
  double numberDensity = 0;  ///< n0 of the bulk material, micro-particles per m^3

  /// Saturation magnetization of the bulk material, A/m.
  double saturation() const { return law.saturation(numberDensity); }
  /// Low-field susceptibility chi0 of the bulk material.
  double lowFieldSusceptibility() const { return law.lowFieldSusceptibility(numberDensity); }
  /// One line for logs and reports, with units.
  std::string describe() const;
};

/// Langevin paramagnet: micro-particles of moment m (A*m^2) at temperature T (K)
/// and bulk number density n0 (1/m^3).
MagneticMaterial langevinMaterial(double moment, double temperature, double numberDensity);

/// Linear material of susceptibility chi (>= 0) at bulk density n0; where the
/// transferred density is n, the local susceptibility is chi * n / n0.
MagneticMaterial linearMaterial(double chi, double numberDensity);

/// The low-field linearisation of a Langevin material (chi = chi0, same n0),
/// the paper's "linear" comparison material (Fig. 7).
MagneticMaterial linearized(const MagneticMaterial& material);

/// A non-magnetic material (M = 0).
MagneticMaterial nonMagneticMaterial();

/// The paper's material (Table 2): m = 1.09e-19 A*m^2, T = 300 K, and
/// 3.6e17 micro-particles per filled cell of dx = 7.8e-3 m (n0 ~ 7.59e23 1/m^3,
/// Ms ~ 8.27e4 A/m, chi0 ~ 0.91).
MagneticMaterial paperMaterial();

/// Validated law factories used by the material factories.
MagnetizationLaw<double> langevinLaw(double moment, double temperature);
MagnetizationLaw<double> linearLaw(double chi, double numberDensity);

/// Magnetization (A/m) of a permanent magnet of remanence Br (T): M = Br / mu0.
double magnetizationFromRemanence(double remanence);

}  // namespace field
}  // namespace lodestone
