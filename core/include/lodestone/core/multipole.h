#pragma once
// Dipole + quadrupole expansion of the scalar potential of a magnetization
// distribution, used as the far-field (open) boundary value of the field solve.
//   phi(x) = 1/(4 pi) [ m.r / r^3 + sum_ij N_ij (3 r_i r_j / r^5 - delta_ij / r^3) ],
//   r = x - centre, m = int M dV (A m^2), N_ij = int M_i (y - centre)_j dV (A m^3),
// so that H = -grad phi is the field of M seen from far away.
#include <cmath>

#include "lodestone/core/constants.h"
#include "lodestone/core/vec3.h"

namespace lodestone {

struct Multipole {
  Vec3d centre;              ///< expansion centre, m
  Vec3d dipole;              ///< m = int M dV, A*m^2
  double quadrupole[3][3]{}; ///< N_ij = int M_i (y - c)_j dV, A*m^3

  /// Scalar potential phi (A) at x (m); 0 at the centre itself.
  double potential(const Vec3d& x) const {
    const Vec3d r = x - centre;
    const double r2 = norm2(r);
    if (!(r2 > 0)) return 0.0;
    const double rn = std::sqrt(r2);
    const double inv3 = 1.0 / (r2 * rn);
    const double inv5 = inv3 / r2;
    double q = 0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        q += quadrupole[i][j] * (3.0 * r[i] * r[j] * inv5 - (i == j ? inv3 : 0.0));
    return (dot(dipole, r) * inv3 + q) / (4.0 * kPi);
  }

  Multipole& operator+=(const Multipole& o) {
    dipole += o.dipole;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) quadrupole[i][j] += o.quadrupole[i][j];
    return *this;
  }
};

}  // namespace lodestone
