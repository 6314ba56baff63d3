#pragma once
// The Rosensweig (normal-field) instability of a flat layer of magnetizable
// liquid: the magnetization at which its surface breaks into spikes, and the
// spacing of the pattern that grows first (Cowley and Rosensweig 1967;
// Rosensweig, Ferrohydrodynamics, 1985, ch. 7). docs/physics.md, "Spikes:
// the Rosensweig instability", derives the nonlinear case.
//
// A deep layer of density rho and surface tension sigma, non-magnetic above,
// in a vertical applied field H0: B is continuous across the flat surface,
// so the liquid sees H with H0 = H + M(H). The surface is unstable when
//   M^2 >= (2/mu0) (1 + mu0/mu_hat) sqrt(rho g sigma),
//   mu_hat = sqrt(mu_c mu_t),  mu_c = B/H = mu0 (1 + M/H),  mu_t = dB/dH = mu0 (1 + dM/dH),
// with the chord and tangent permeabilities at the operating point H; the
// first unstable pattern has the capillary wavelength
//   lambda_c = 2 pi sqrt(sigma / (rho g)).
// For a linear liquid mu_c = mu_t = mu0 (1 + chi) and M_c is explicit; for
// any other law the equation is solved for H (its left side grows with H,
// its right side stays between the linear value at chi0 and (4/mu0)
// sqrt(rho g sigma)).
#include "lodestone/core/field/material.h"

namespace lodestone {
inline namespace field {

struct RosensweigOnset {
  double H = 0;          ///< field in the liquid at onset, A/m
  double M = 0;          ///< critical magnetization M_c, A/m
  double appliedH = 0;   ///< applied vertical field H0 = H + M that brings the flat layer to onset, A/m
  double muChord = 0;    ///< relative chord permeability mu_c / mu0 at onset
  double muTangent = 0;  ///< relative tangent permeability mu_t / mu0 at onset
  double wavelength = 0; ///< capillary wavelength lambda_c, m
};

/// Onset of spikes in a flat layer of `material` (bulk number density as
/// filled) of density `density` (kg/m^3) and surface tension
/// `surfaceTension` (N/m) under gravity `gravity` (m/s^2). Throws
/// InvalidArgument naming a value that is not positive and finite, a
/// material that is not magnetizable, or one that saturates below the
/// onset magnetization (no field makes spikes).
RosensweigOnset rosensweigOnset(const MagneticMaterial& material, double density, double surfaceTension,
                                double gravity = 9.81);

/// Magnetization (A/m) of a flat layer of `material` in a vertical applied
/// field H0 (A/m, >= 0): B is continuous across its surface, so the field
/// inside is the H with H + M(H) = H0. Throws InvalidArgument for an H0
/// that is negative or not finite.
double flatLayerMagnetization(const MagneticMaterial& material, double appliedH);

/// The gravity (m/s^2) a flat layer of `material` (density kg/m^3) feels in
/// a magnet's field: g - mu0 M dH0/dz / rho, with M the layer's
/// magnetization in the applied vertical field H0 (A/m) at its surface and
/// dH0/dz (A/m^2) that field's rate of change upward (negative over a
/// magnet below: the pull adds to gravity; docs/physics.md, "Near a
/// magnet"). The onset and the wavelength of spikes there are
/// rosensweigOnset's with this gravity. Throws InvalidArgument naming a
/// value that is not finite or a result that is not positive (the magnet
/// lifts the layer off its floor).
double gravityNearMagnet(const MagneticMaterial& material, double density, double appliedH, double appliedGradient,
                         double gravity = 9.81);

}  // namespace field
}  // namespace lodestone
