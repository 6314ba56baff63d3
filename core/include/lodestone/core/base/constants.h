#pragma once
// Physical constants in SI units (CODATA 2018).

namespace lodestone {
inline namespace base {

/// Vacuum permeability mu_0 in N/A^2 (= T*m/A).
inline constexpr double kMu0 = 1.25663706212e-6;
/// Boltzmann constant k_B in J/K.
inline constexpr double kBoltzmann = 1.380649e-23;
inline constexpr double kPi = 3.14159265358979323846;

}  // namespace base
}  // namespace lodestone
