#pragma once
// Dipole + quadrupole expansion of the scalar potential of a magnetization
// distribution, used as the far-field (open) boundary value of the field solve
// and as the field one patch of material applies to another (magnetic_patches.h).
//   phi(x) = 1/(4 pi) [ m.r / r^3 + sum_ij N_ij (3 r_i r_j / r^5 - delta_ij / r^3) ],
//   r = x - centre, m = int M dV (A m^2), N_ij = int M_i (y - centre)_j dV (A m^3),
// so that H = -grad phi is the field of M seen from far away.
#include <cmath>
#include <cstddef>
#include <vector>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace field {

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

  /// Field H = -grad phi (A/m) at x (m); 0 at the centre itself:
  ///   4 pi H = 3 r (m.r) / r^5 - m / r^3
  ///          - 3 (N + N^T) r / r^5 + 15 (r^T N r) r / r^7 - 3 tr(N) r / r^5.
  Vec3d field(const Vec3d& x) const {
    const Vec3d r = x - centre;
    const double r2 = norm2(r);
    if (!(r2 > 0)) return {};
    const double inv2 = 1.0 / r2, inv3 = inv2 / std::sqrt(r2), inv5 = inv3 * inv2, inv7 = inv5 * inv2;
    Vec3d sym;  // (N + N^T) r
    double rNr = 0, trace = 0;
    for (int i = 0; i < 3; ++i) {
      trace += quadrupole[i][i];
      for (int j = 0; j < 3; ++j) {
        sym[i] += (quadrupole[i][j] + quadrupole[j][i]) * r[j];
        rNr += r[i] * quadrupole[i][j] * r[j];
      }
    }
    const Vec3d h = (3.0 * dot(dipole, r) * inv5 + 15.0 * rNr * inv7 - 3.0 * trace * inv5) * r - inv3 * dipole -
                    (3.0 * inv5) * sym;
    return h / (4.0 * kPi);
  }

  /// No dipole and no quadrupole moment: a block without magnetization.
  bool empty() const {
    if (!(dipole == Vec3d{})) return false;
    for (const auto& row : quadrupole)
      for (double v : row)
        if (v != 0) return false;
    return true;
  }

  Multipole& operator+=(const Multipole& o) {
    dipole += o.dipole;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) quadrupole[i][j] += o.quadrupole[i][j];
    return *this;
  }
};

/// Many blocks' expansions as arrays, one per field (count a multiple of 4,
/// padded with empty blocks: zero moments), for summing at many points.
/// The quadrupole enters as its diagonal, its symmetrized off-diagonal sums
/// (nxy = N_xy + N_yx, ...) and its trace.
struct MultipoleArrays {
  const double *cx, *cy, *cz, *mx, *my, *mz, *nxx, *nyy, *nzz, *nxy, *nxz, *nyz, *tr;
  std::size_t count;
};

/// Expansions packed as MultipoleArrays (the storage they point into),
/// padded to a multiple of 4 with empty blocks.
class PackedMultipoles {
 public:
  explicit PackedMultipoles(const std::vector<Multipole>& blocks);
  const MultipoleArrays& arrays() const { return arrays_; }

 private:
  std::vector<double> soa_;
  MultipoleArrays arrays_{};
};

/// 4 pi times the summed potential of all blocks at x (a point at a block's
/// centre gets nothing from it): with r = x - c,
///   4 pi phi = (m.r - tr N) / r^3 + 3 r^T N r / r^5,
/// summed in 4 lanes in a fixed order. On CPUs with AVX2 and FMA (chosen at
/// run time) 1/|r| comes from the single-precision reciprocal square root and
/// three Newton steps (relative error below 1e-15) instead of a division and
/// a square root; elsewhere the portable loop runs.
double multipoleSum(const MultipoleArrays& blocks, const Vec3d& x);

}  // namespace field
}  // namespace lodestone
