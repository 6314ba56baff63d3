#pragma once
// Sample inputs shared by the VDB file tests and the VDB benchmark: random
// particles with every attribute set, and a closed torus mesh. Include only
// from targets that link lodestone::vdb_io (TriangleMesh).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>
#include <utility>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/mpm/particles.h"
#include "lodestone/vdb_io/level_set_file.h"

namespace lodestone::test {

/// n particles in a 0.5 x 0.4 x 0.1 m box around (0.3, -0.1, 0), with random
/// velocities, masses, volumes, n_p (every third 0), materials 0..4, J and F.
inline MpmParticles randomParticles(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  MpmParticles p;
  p.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    p.add({0.3 + 0.25 * u(rng), -0.1 + 0.2 * u(rng), 0.05 * u(rng)}, {u(rng), 3 * u(rng), -2e-3 * u(rng)},
          1e-3 * (1.5 + u(rng)), 1e-6, i % 3 == 0 ? 0.0 : 1e9 * (1.5 + u(rng)), std::uint32_t(rng() % 5));
    p.J[i] = 1 + 0.1 * u(rng);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) p.F[i](a, b) = (a == b ? 1.0 : 0.0) + 0.05 * u(rng);
  }
  return p;
}

/// A closed torus about the z axis through `centre` (major radius R, minor
/// r, m), outward counter-clockwise faces, nu x nv quads split in two.
inline TriangleMesh torusMesh(const Vec3d& centre, double R, double r, int nu, int nv) {
  TriangleMesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * kPi * i / nu, v = 2 * kPi * j / nv;
      m.vertices.push_back(
          centre + Vec3d{(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
    }
  const auto id = [&](int i, int j) { return std::uint32_t((i % nu) * nv + (j % nv)); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  if (m.volume() < 0)
    for (auto& t : m.triangles) std::swap(t[1], t[2]);
  return m;
}

}  // namespace lodestone::test
