#pragma once
// Random material points for the reference MPM's tests: every attribute set
// and distinct, positions inside the grid's valid stencil box, and the two
// materials they belong to.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/mpm/material.h"
#include "lodestone/core/mpm/particles.h"

namespace lodestone::test {

/// `count` particles of materials 0 and 1 in turn with random velocities,
/// masses, volumes, affine matrices C, deformations F and J. With
/// `magnetic`, the material-1 particles also carry n_p > 0 and a
/// per-particle magnetic force.
inline MpmParticles randomMpmParticles(const GridSpec& g, std::size_t count, unsigned seed, bool magnetic = false) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0, 1), S(-1, 1);
  MpmParticles p;
  for (std::size_t n = 0; n < count; ++n) {
    const Vec3d u{1.5 + U(rng) * (g.dims.i - 4), 1.5 + U(rng) * (g.dims.j - 4), 1.5 + U(rng) * (g.dims.k - 4)};
    const double vol = std::pow(g.dx / 2, 3) * (0.5 + U(rng));
    const std::uint32_t mat = std::uint32_t(n % 2);
    const bool carriesMoment = magnetic && mat == 1;
    const std::size_t i = p.add(g.origin + g.dx * u, {S(rng), S(rng), S(rng)}, 1000 * vol * (0.5 + U(rng)), vol,
                                carriesMoment ? 1e6 * U(rng) : 0.0, mat);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        p.C[i](a, b) = 5 * S(rng);
        p.F[i](a, b) = (a == b ? 1.0 : 0.0) + 0.1 * S(rng);
      }
    p.J[i] = 1 + 0.05 * S(rng);
    if (carriesMoment) p.magneticForce[i] = {S(rng), S(rng), S(rng)};
  }
  return p;
}

/// Material 0 a Neo-Hookean solid, material 1 a viscous fluid (1000 kg/m^3).
inline std::vector<MpmMaterial> twoMaterials() {
  return {neoHookeanSolid(1e5, 0.3, 1000), viscousFluid(0.5, 1e5, 1000)};
}

}  // namespace lodestone::test
