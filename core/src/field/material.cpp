#include "lodestone/core/field/material.h"

#include <cmath>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace field {

MagnetizationLaw<double> langevinLaw(double moment, double temperature) {
  require(std::isfinite(moment) && moment > 0,
          "Langevin law: micro-particle moment must be a positive finite value in A*m^2, got ", moment);
  require(std::isfinite(temperature) && temperature > 0,
          "Langevin law: temperature must be a positive finite value in K, got ", temperature);
  MagnetizationLaw<double> law;
  law.kind = LawKind::Langevin;
  law.moment = moment;
  law.k2 = kMu0 * moment / (kBoltzmann * temperature);
  require(std::isfinite(law.k2) && law.k2 > 0, "Langevin law: k2 = mu0 m/(kB T) = ", law.k2,
          " 1/(A/m) is not a positive finite value (moment ", moment, " A*m^2, temperature ",
          temperature, " K)");
  return law;
}

MagnetizationLaw<double> linearLaw(double chi, double numberDensity) {
  require(std::isfinite(chi) && chi >= 0,
          "linear law: susceptibility chi must be finite and >= 0 (diamagnetic materials are not "
          "supported), got ",
          chi);
  require(std::isfinite(numberDensity) && numberDensity > 0,
          "linear law: reference number density must be a positive finite value in 1/m^3, got ",
          numberDensity);
  MagnetizationLaw<double> law;
  law.kind = LawKind::Linear;
  law.chiPerDensity = chi / numberDensity;
  return law;
}

MagneticMaterial langevinMaterial(double moment, double temperature, double numberDensity) {
  require(std::isfinite(numberDensity) && numberDensity > 0,
          "Langevin material: number density must be a positive finite value in 1/m^3, got ",
          numberDensity);
  return {langevinLaw(moment, temperature), numberDensity};
}

MagneticMaterial linearMaterial(double chi, double numberDensity) {
  return {linearLaw(chi, numberDensity), numberDensity};
}

MagneticMaterial linearized(const MagneticMaterial& material) {
  if (material.law.kind != LawKind::Langevin) return material;
  return linearMaterial(material.lowFieldSusceptibility(), material.numberDensity);
}

MagneticMaterial nonMagneticMaterial() { return {}; }

MagneticMaterial paperMaterial() {
  const double dx = 7.8e-3;  // m
  return langevinMaterial(1.09e-19, 300.0, 3.6e17 / (dx * dx * dx));
}

double magnetizationFromRemanence(double remanence) {
  require(std::isfinite(remanence), "remanence must be finite (in T), got ", remanence);
  return remanence / kMu0;
}

std::string MagneticMaterial::describe() const {
  switch (law.kind) {
    case LawKind::Langevin:
      // Six significant digits: k2, Ms and chi0 are derived (a person reads them).
      return concat("Langevin: m = ", numberText(law.moment, 6), " A*m^2, k2 = ", numberText(law.k2, 6),
                    " m/A, n0 = ", numberText(numberDensity, 6), " 1/m^3, Ms = ", numberText(saturation(), 6),
                    " A/m, chi0 = ", numberText(lowFieldSusceptibility(), 6));
    case LawKind::Linear:
      return concat("linear: chi = ", numberText(lowFieldSusceptibility(), 6), " at n0 = ", numberText(numberDensity, 6),
                    " 1/m^3");
    default:
      return "non-magnetic";
  }
}

}  // namespace field
}  // namespace lodestone
