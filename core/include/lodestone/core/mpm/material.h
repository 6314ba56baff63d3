#pragma once
// Materials of the reference MLS-MPM: a mechanical model (Neo-Hookean solid,
// viscous or viscoplastic fluid, damped elastoplastic solid; constitutive.h) with its density, plus an optional
// magnetic material (law none / linear / Langevin and the bulk micro-particle
// number density n0, material.h). Built by validated factories that throw
// InvalidArgument naming the bad value and its unit.
#include <string>

#include "lodestone/core/field/material.h"

namespace lodestone {
inline namespace mpm {

enum class MpmModel : int {
  NeoHookeanSolid = 0,  ///< tracks the deformation gradient F (Eq. 18)
  ViscousFluid = 1,     ///< tracks only the volume ratio J (Eqs. 19-21)
  ViscoplasticFluid = 2, ///< tracks J; capped Herschel-Bulkley deviatoric stress (constitutive.h)
  ElastoplasticSolid = 3  ///< tracks the elastic part F_E of F; Hencky, von Mises, Kelvin-Voigt damping
};
const char* toString(MpmModel model);

/// Largest accepted surface tension, N/m (water is 0.072, mercury 0.49).
constexpr double kMaxSurfaceTension = 10.0;

struct MpmMaterial {
  MpmModel model = MpmModel::NeoHookeanSolid;
  double density = 0;         ///< rest mass density rho, kg/m^3
  double mu = 0;              ///< solids: shear modulus (second Lame parameter) mu, Pa
  double lambda = 0;          ///< solids: Lame parameter lambda, Pa
  double viscosity = 0;       ///< fluid: dynamic viscosity mu_N; elastoplastic solid: damping eta; Pa*s
  double bulkModulus = 0;     ///< fluid: bulk modulus K, Pa
  double yieldStress = 0;     ///< viscoplastic fluid: shear yield stress tau_y; elastoplastic solid:
                              ///< von Mises (uniaxial) yield stress sigma_y; Pa
  double consistency = 0;     ///< viscoplastic fluid: consistency k, Pa*s^n
  double flowIndex = 1;       ///< viscoplastic fluid: flow index n in (0, 2] (1: Bingham)
  double maxViscosity = 0;    ///< viscoplastic fluid: cap mu_max of the effective viscosity, Pa*s
  double surfaceTension = 0;  ///< fluids: surface tension coefficient sigma, N/m, in [0, kMaxSurfaceTension]
                              ///< (0: none); a capillary stress on the colour field (surface_tension.h)

  /// True for the models that track only J (viscous and viscoplastic fluids).
  bool isFluid() const { return model == MpmModel::ViscousFluid || model == MpmModel::ViscoplasticFluid; }
  MagneticMaterial magnetic;  ///< magnetization law and n0 (1/m^3); LawKind::None when not magnetic

  bool hasSurfaceTension() const { return surfaceTension > 0; }
  bool isMagnetic() const { return magnetic.law.kind != LawKind::None; }
  /// Fastest elastic (P-)wave speed at rest, m/s: sqrt((lambda + 2 mu)/rho)
  /// for the solids, sqrt(K/rho) for the fluids.
  double waveSpeed() const;
  /// Largest kinematic viscosity (m^2/s) the model can produce: mu_N / rho for
  /// the viscous fluid, mu_max / rho for the viscoplastic fluid, eta / rho for
  /// the elastoplastic solid, 0 for the Neo-Hookean solid.
  double kinematicViscosity() const;
  /// Throws InvalidArgument naming the first bad value.
  void validate() const;
  /// One line with units.
  std::string describe() const;
};

/// Neo-Hookean solid from Young's modulus E (Pa, finite, > 0), Poisson's ratio
/// nu (in (-1, 0.5)) and density rho (kg/m^3, finite, > 0):
/// mu = E / (2 (1 + nu)), lambda = E nu / ((1 + nu)(1 - 2 nu)).
MpmMaterial neoHookeanSolid(double youngModulus, double poissonRatio, double density,
                            const MagneticMaterial& magnetic = nonMagneticMaterial());

/// Viscous fluid from viscosity mu_N (Pa*s, finite, >= 0), bulk modulus K
/// (Pa, finite, > 0) and density rho (kg/m^3, finite, > 0).
MpmMaterial viscousFluid(double viscosity, double bulkModulus, double density,
                         const MagneticMaterial& magnetic = nonMagneticMaterial());

/// Viscoplastic (regularized Herschel-Bulkley) fluid: yield stress tau_y (Pa,
/// finite, >= 0), consistency k (Pa*s^n, finite, >= 0), flow index n (in (0, 2]),
/// cap of the effective viscosity mu_max (Pa*s, finite, > 0), bulk modulus K
/// (Pa, finite, > 0), density rho (kg/m^3, finite, > 0).
MpmMaterial viscoplasticFluid(double yieldStress, double consistency, double flowIndex, double maxViscosity,
                              double bulkModulus, double density,
                              const MagneticMaterial& magnetic = nonMagneticMaterial());

/// Damped elastoplastic solid ("magnetic clay"): Young's modulus E (Pa, finite,
/// > 0) and Poisson's ratio nu (in (-1, 0.5)) give mu and lambda as for the
/// Neo-Hookean solid; von Mises yield stress sigma_y (Pa, finite, >= 0; perfect
/// plasticity), Kelvin-Voigt damping viscosity eta (Pa*s, finite, >= 0),
/// density rho (kg/m^3, finite, > 0). CPU only (the gpu stepper has no such model).
MpmMaterial elastoplasticSolid(double youngModulus, double poissonRatio, double yieldStress, double viscosity,
                               double density, const MagneticMaterial& magnetic = nonMagneticMaterial());

/// Throws InvalidArgument unless the magnetic material is usable by the MPM:
/// LawKind::None, or a linear / Langevin law with finite positive parameters
/// and a positive finite n0 (1/m^3).
void validateMagneticMaterial(const MagneticMaterial& magnetic, const char* who);

}  // namespace mpm
}  // namespace lodestone
