// Onset of the Rosensweig instability. See field/rosensweig_onset.h.
#include "lodestone/core/field/rosensweig_onset.h"

#include <cmath>
#include <utility>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace field {

namespace {

struct OperatingPoint {
  double M = 0, chord = 0, tangent = 0;  // A/m; relative permeabilities
};

OperatingPoint at(const MagneticMaterial& m, double H) {
  const MagnetizationResponse<double> r = respond(m.law, m.numberDensity, Vec3d{0, 0, H});
  OperatingPoint p;
  p.M = r.M.z;
  p.tangent = 1 + r.iso + r.rank1 * r.h.z * r.h.z;
  p.chord = H > 0 ? 1 + p.M / H : 1 + m.lowFieldSusceptibility();
  return p;
}

/// Narrows [lo, hi] around the root of an increasing function by bisection,
/// `below(x)` telling whether x lies below it, to 1e-13 of hi (at most 200
/// halvings); returns the final bracket.
template <typename Below>
std::pair<double, double> bisect(double lo, double hi, const Below& below) {
  for (int it = 0; it < 200 && hi - lo > 1e-13 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (below(mid) ? lo : hi) = mid;
  }
  return {lo, hi};
}

}  // namespace

RosensweigOnset rosensweigOnset(const MagneticMaterial& material, double density, double surfaceTension,
                                double gravity) {
  require(std::isfinite(density) && density > 0, "Rosensweig onset: density must be positive and finite, got ",
          density, " kg/m^3");
  require(std::isfinite(surfaceTension) && surfaceTension > 0,
          "Rosensweig onset: surface tension must be positive and finite, got ", surfaceTension, " N/m");
  require(std::isfinite(gravity) && gravity > 0, "Rosensweig onset: gravity must be positive and finite, got ",
          gravity, " m/s^2");
  const double chi0 = material.lowFieldSusceptibility();
  require(material.law.kind != LawKind::None && chi0 > 0,
          "Rosensweig onset: the material is not magnetizable (", material.describe(), ")");
  RosensweigOnset out;
  out.wavelength = 2 * kPi * std::sqrt(surfaceTension / (density * gravity));
  const double capillary = std::sqrt(density * gravity * surfaceTension);  // Pa
  // f(H) = M^2 - (2/mu0) (1 + 1/mu_hat) sqrt(rho g sigma), increasing in H.
  const auto excess = [&](double H, OperatingPoint& p) {
    p = at(material, H);
    return p.M * p.M - 2 / kMu0 * (1 + 1 / std::sqrt(p.chord * p.tangent)) * capillary;
  };
  OperatingPoint p;
  double lo = 0, hi = std::sqrt(4 / kMu0 * capillary) / chi0;  // M(hi) >= the largest right side for a linear law
  int grow = 0;
  while (excess(hi, p) < 0) {
    require(++grow < 200 && std::isfinite(hi), "Rosensweig onset: the material saturates at Ms = ",
            material.saturation(), " A/m, below the onset magnetization (at least ",
            std::sqrt(2 / kMu0 * capillary), " A/m for rho = ", density, " kg/m^3, sigma = ", surfaceTension,
            " N/m): no field makes spikes");
    lo = hi;
    hi *= 2;
  }
  hi = bisect(lo, hi, [&](double H) { return excess(H, p) < 0; }).second;
  excess(hi, p);
  out.H = hi;
  out.M = p.M;
  out.appliedH = hi + p.M;
  out.muChord = p.chord;
  out.muTangent = p.tangent;
  return out;
}

double flatLayerMagnetization(const MagneticMaterial& material, double appliedH) {
  require(std::isfinite(appliedH) && appliedH >= 0, "flat layer: the applied field must be >= 0 and finite, got ",
          appliedH, " A/m");
  // H + M(H) grows with H from 0 and H0 lies between H = 0 and H = H0.
  const auto [lo, hi] = bisect(0.0, appliedH, [&](double H) { return H + at(material, H).M < appliedH; });
  return at(material, 0.5 * (lo + hi)).M;
}

double gravityNearMagnet(const MagneticMaterial& material, double density, double appliedH, double appliedGradient,
                         double gravity) {
  require(std::isfinite(density) && density > 0, "gravity near a magnet: density must be positive and finite, got ",
          density, " kg/m^3");
  require(std::isfinite(appliedGradient), "gravity near a magnet: the field's gradient must be finite, got ",
          appliedGradient, " A/m^2");
  require(std::isfinite(gravity), "gravity near a magnet: gravity must be finite, got ", gravity, " m/s^2");
  const double g = gravity - kMu0 * flatLayerMagnetization(material, appliedH) * appliedGradient / density;
  require(g > 0, "gravity near a magnet: the field's pull (gradient ", appliedGradient, " A/m^2 at H0 = ", appliedH,
          " A/m) exceeds gravity ", gravity, " m/s^2: the layer is lifted, it has no flat state");
  return g;
}

}  // namespace field
}  // namespace lodestone
