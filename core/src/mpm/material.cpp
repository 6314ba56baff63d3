#include "lodestone/core/mpm/material.h"

#include <cmath>

#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace mpm {

const char* toString(MpmModel model) {
  switch (model) {
    case MpmModel::NeoHookeanSolid:
      return "Neo-Hookean solid";
    case MpmModel::ViscousFluid:
      return "viscous fluid";
    case MpmModel::ViscoplasticFluid:
      return "viscoplastic fluid";
    case MpmModel::ElastoplasticSolid:
      return "elastoplastic solid";
  }
  return "unknown";
}

double MpmMaterial::waveSpeed() const {
  if (isFluid()) return std::sqrt(bulkModulus / density);
  return std::sqrt((lambda + 2 * mu) / density);
}

double MpmMaterial::kinematicViscosity() const {
  if (model == MpmModel::ViscousFluid) return viscosity / density;
  if (model == MpmModel::ViscoplasticFluid) return maxViscosity / density;
  if (model == MpmModel::ElastoplasticSolid) return viscosity / density;
  return 0.0;
}

void validateMagneticMaterial(const MagneticMaterial& magnetic, const char* who) {
  const MagnetizationLaw<double>& law = magnetic.law;
  switch (law.kind) {
    case LawKind::None:
      return;
    case LawKind::Linear:
      require(std::isfinite(law.chiPerDensity) && law.chiPerDensity >= 0, who,
              ": linear magnetic law needs a finite susceptibility per density >= 0 (m^3), got ", law.chiPerDensity);
      break;
    case LawKind::Langevin:
      require(std::isfinite(law.moment) && law.moment > 0, who,
              ": Langevin law needs a positive finite micro-particle moment (A*m^2), got ", law.moment);
      require(std::isfinite(law.k2) && law.k2 > 0, who, ": Langevin law needs a positive finite k2 (m/A), got ",
              law.k2);
      break;
    default:
      throw InvalidArgument(concat(who, ": unknown magnetization law kind ", int(law.kind)));
  }
  require(std::isfinite(magnetic.numberDensity) && magnetic.numberDensity > 0, who,
          ": a magnetic material needs a positive finite micro-particle number density n0 (1/m^3), got ",
          magnetic.numberDensity);
}

void MpmMaterial::validate() const {
  require(std::isfinite(density) && density > 0,
          "MPM material: density must be a positive finite value in kg/m^3, got ", density);
  switch (model) {
    case MpmModel::NeoHookeanSolid:
      require(std::isfinite(mu) && mu > 0, "Neo-Hookean solid: shear modulus mu must be positive and finite (Pa), got ",
              mu);
      require(std::isfinite(lambda) && lambda + 2.0 / 3.0 * mu > 0,
              "Neo-Hookean solid: lambda must be finite with bulk modulus lambda + 2 mu / 3 > 0 (Pa), got lambda = ",
              lambda, " Pa, mu = ", mu, " Pa");
      break;
    case MpmModel::ViscousFluid:
      require(std::isfinite(viscosity) && viscosity >= 0,
              "viscous fluid: viscosity mu_N must be finite and >= 0 (Pa*s), got ", viscosity);
      require(std::isfinite(bulkModulus) && bulkModulus > 0,
              "viscous fluid: bulk modulus K must be positive and finite (Pa), got ", bulkModulus);
      break;
    case MpmModel::ViscoplasticFluid:
      require(std::isfinite(yieldStress) && yieldStress >= 0,
              "viscoplastic fluid: yield stress tau_y must be finite and >= 0 (Pa), got ", yieldStress);
      require(std::isfinite(consistency) && consistency >= 0,
              "viscoplastic fluid: consistency k must be finite and >= 0 (Pa*s^n), got ", consistency);
      require(std::isfinite(flowIndex) && flowIndex > 0 && flowIndex <= 2,
              "viscoplastic fluid: flow index n must lie in (0, 2] (dimensionless), got ", flowIndex);
      require(std::isfinite(maxViscosity) && maxViscosity > 0,
              "viscoplastic fluid: maximum viscosity mu_max must be positive and finite (Pa*s), got ", maxViscosity);
      require(std::isfinite(bulkModulus) && bulkModulus > 0,
              "viscoplastic fluid: bulk modulus K must be positive and finite (Pa), got ", bulkModulus);
      break;
    case MpmModel::ElastoplasticSolid:
      require(std::isfinite(mu) && mu > 0,
              "elastoplastic solid: shear modulus mu must be positive and finite (Pa), got ", mu);
      require(std::isfinite(lambda) && lambda + 2.0 / 3.0 * mu > 0,
              "elastoplastic solid: lambda must be finite with bulk modulus lambda + 2 mu / 3 > 0 (Pa), got lambda = ",
              lambda, " Pa, mu = ", mu, " Pa");
      require(std::isfinite(yieldStress) && yieldStress >= 0,
              "elastoplastic solid: yield stress sigma_y must be finite and >= 0 (Pa), got ", yieldStress);
      require(std::isfinite(viscosity) && viscosity >= 0,
              "elastoplastic solid: damping viscosity eta must be finite and >= 0 (Pa*s), got ", viscosity);
      break;
    default:
      throw InvalidArgument(concat("MPM material: unknown model ", int(model)));
  }
  if (isFluid())
    require(std::isfinite(surfaceTension) && surfaceTension >= 0 && surfaceTension <= kMaxSurfaceTension,
            toString(model), ": surface tension sigma must be finite and in [0, ", kMaxSurfaceTension,
            "] (N/m), got ", surfaceTension);
  else
    require(surfaceTension == 0, toString(model), ": surface tension applies only to the fluid models, got sigma = ",
            surfaceTension, " N/m on a solid");
  validateMagneticMaterial(magnetic, "MPM material");
}

std::string MpmMaterial::describe() const {
  std::string s;
  if (model == MpmModel::NeoHookeanSolid)
    s = concat("Neo-Hookean solid: mu = ", mu, " Pa, lambda = ", lambda, " Pa, rho = ", density, " kg/m^3");
  else if (model == MpmModel::ViscoplasticFluid)
    s = concat("viscoplastic fluid: tau_y = ", yieldStress, " Pa, k = ", consistency, " Pa*s^n, n = ", flowIndex,
               ", mu_max = ", maxViscosity, " Pa*s, K = ", bulkModulus, " Pa, rho = ", density, " kg/m^3");
  else if (model == MpmModel::ElastoplasticSolid)
    s = concat("elastoplastic solid: mu = ", mu, " Pa, lambda = ", lambda, " Pa, sigma_y = ", yieldStress,
               " Pa, eta = ", viscosity, " Pa*s, rho = ", density, " kg/m^3");
  else
    s = concat("viscous fluid: mu_N = ", viscosity, " Pa*s, K = ", bulkModulus, " Pa, rho = ", density, " kg/m^3");
  if (surfaceTension > 0) s += concat(", sigma = ", surfaceTension, " N/m");
  return s + "; magnetic: " + magnetic.describe();
}

namespace {

/// A solid of the given model with mu = E / (2 (1 + nu)), lambda = E nu / ((1 + nu)(1 - 2 nu)).
MpmMaterial solidFromYoung(MpmModel model, double youngModulus, double poissonRatio, double density,
                           const MagneticMaterial& magnetic) {
  const char* who = toString(model);
  require(std::isfinite(youngModulus) && youngModulus > 0, who,
          ": Young's modulus E must be a positive finite value in Pa, got ", youngModulus);
  require(std::isfinite(poissonRatio) && poissonRatio > -1 && poissonRatio < 0.5, who,
          ": Poisson's ratio nu must lie in (-1, 0.5) (dimensionless), got ", poissonRatio);
  MpmMaterial m;
  m.model = model;
  m.density = density;
  m.mu = youngModulus / (2 * (1 + poissonRatio));
  m.lambda = youngModulus * poissonRatio / ((1 + poissonRatio) * (1 - 2 * poissonRatio));
  m.magnetic = magnetic;
  return m;
}

}  // namespace

MpmMaterial neoHookeanSolid(double youngModulus, double poissonRatio, double density,
                            const MagneticMaterial& magnetic) {
  MpmMaterial m = solidFromYoung(MpmModel::NeoHookeanSolid, youngModulus, poissonRatio, density, magnetic);
  m.validate();
  return m;
}

MpmMaterial elastoplasticSolid(double youngModulus, double poissonRatio, double yieldStress, double viscosity,
                               double density, const MagneticMaterial& magnetic) {
  MpmMaterial m = solidFromYoung(MpmModel::ElastoplasticSolid, youngModulus, poissonRatio, density, magnetic);
  m.yieldStress = yieldStress;
  m.viscosity = viscosity;
  m.validate();
  return m;
}

MpmMaterial viscousFluid(double viscosity, double bulkModulus, double density, const MagneticMaterial& magnetic) {
  MpmMaterial m;
  m.model = MpmModel::ViscousFluid;
  m.density = density;
  m.viscosity = viscosity;
  m.bulkModulus = bulkModulus;
  m.magnetic = magnetic;
  m.validate();
  return m;
}

MpmMaterial viscoplasticFluid(double yieldStress, double consistency, double flowIndex, double maxViscosity,
                              double bulkModulus, double density, const MagneticMaterial& magnetic) {
  MpmMaterial m;
  m.model = MpmModel::ViscoplasticFluid;
  m.density = density;
  m.yieldStress = yieldStress;
  m.consistency = consistency;
  m.flowIndex = flowIndex;
  m.maxViscosity = maxViscosity;
  m.bulkModulus = bulkModulus;
  m.magnetic = magnetic;
  m.validate();
  return m;
}

}  // namespace mpm
}  // namespace lodestone
