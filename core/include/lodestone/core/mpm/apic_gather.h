#pragma once
// Grid-to-particle gather of MLS-MPM with APIC (Hu et al. 2018, eq. 8-10;
// Section 4.3 of Sun et al. 2021): the particle's velocity
//   v_p = sum_i w_ip v_i
// and affine velocity
//   C_p = D_p^-1 sum_i w_ip v_i (x_i - x_p)^T,  D_p = dx^2 / 4 I
// (quadratic B-splines), over the 3x3x3 nodes from the stencil's base node.
// Host and device: the reference MPM and the CUDA backend call it alike.
#include <cstddef>

#include "lodestone/core/base/bspline.h"
#include "lodestone/core/base/hostdev.h"
#include "lodestone/core/base/mat3.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace mpm {

/// A node velocity in the lanes of the arithmetic type L the gather sums in
/// (gatherApic): Vec3d itself here; a host vector type (x, y, z and lanes the
/// gather ignores) specialises these two.
template <typename L>
LODESTONE_HOSTDEV inline L apicLanes(const Vec3d& v);
template <typename L>
LODESTONE_HOSTDEV inline Vec3d apicVec3(const L& lanes);
template <>
LODESTONE_HOSTDEV inline Vec3d apicLanes<Vec3d>(const Vec3d& v) {
  return v;
}
template <>
LODESTONE_HOSTDEV inline Vec3d apicVec3<Vec3d>(const Vec3d& lanes) {
  return lanes;
}

/// The three node velocities line[0..2] (consecutive in x) in lanes of L;
/// a host vector type may specialise it to load the nine doubles at once.
template <typename L>
LODESTONE_HOSTDEV inline void apicLine(const Vec3d* line, L& n0, L& n1, L& n2) {
  n0 = apicLanes<L>(line[0]);
  n1 = apicLanes<L>(line[1]);
  n2 = apicLanes<L>(line[2]);
}

/// The node lines of a stencil in an array with strides sj and sk along j
/// and k (x fastest): line (b, c) starts at corner + b sj + c sk.
struct ApicStridedLines {
  const Vec3d* corner;
  std::size_t sj, sk;
  LODESTONE_HOSTDEV const Vec3d* operator()(int b, int c) const {
    return corner + std::size_t(b) * sj + std::size_t(c) * sk;
  }
};

/// `lines(b, c)`: the nodal velocities (m/s) of the stencil's line of three
/// nodes (b3[0] .. b3[0] + 2, b3[1] + b, b3[2] + c), consecutive in x; u: the
/// particle's grid coordinates (cells, (x - origin) / dx) and b3 the
/// stencil's base node (from the same u); cScale = 4/dx (1/m). Sets vp (m/s)
/// and C (1/s). The sums run in L lane by lane (component-wise the same
/// operations for any L, so the same bits where the compiler fuses the
/// same multiplies and adds), in the same order whatever the lines'
/// storage.
template <typename L, typename Lines>
LODESTONE_HOSTDEV inline void gatherApicLines(const Lines& lines, const double u[3], const int b3[3], double cScale,
                                              Vec3d& vp, Mat3d& C) {
  const QuadraticWeights<double> wx = quadraticWeightsAt(u[0], b3[0]);
  const QuadraticWeights<double> wy = quadraticWeightsAt(u[1], b3[1]);
  const QuadraticWeights<double> wz = quadraticWeightsAt(u[2], b3[2]);
  const double f[3] = {u[0] - b3[0], u[1] - b3[1], u[2] - b3[2]};
  // v_p = sum w v_i; S_a = sum w v_i (node offset index along a). Each
  // plane c sums its three lines first (P, P0, P1), then the planes are
  // summed: two short chains of additions instead of one of nine.
  L S0{}, S1{}, S2{}, v{};
  for (int c = 0; c < 3; ++c) {
    L P{}, P0{}, P1{};
    for (int b = 0; b < 3; ++b) {
      L n0, n1, n2;
      apicLine<L>(lines(b, c), n0, n1, n2);
      const L l1 = wx.w[1] * n1, l2 = wx.w[2] * n2;
      const L s0 = wx.w[0] * n0 + l1 + l2;
      const L s1 = l1 + 2.0 * l2;
      P += wy.w[b] * s0;
      P0 += wy.w[b] * s1;
      if (b != 0) P1 += (double(b) * wy.w[b]) * s0;  // the line of offset 0 adds nothing to S1
    }
    v += wz.w[c] * P;
    S0 += wz.w[c] * P0;
    S1 += wz.w[c] * P1;
    if (c != 0) S2 += (double(c) * wz.w[c]) * P;
  }
  vp = apicVec3(v);
  // d_i = (index - f) dx: column a of C is (4/dx)(S_a - v_p f_a).
  const Vec3d col[3] = {cScale * (apicVec3(S0) - f[0] * vp), cScale * (apicVec3(S1) - f[1] * vp),
                        cScale * (apicVec3(S2) - f[2] * vp)};
  for (int a = 0; a < 3; ++a) {
    C(0, a) = col[a].x;
    C(1, a) = col[a].y;
    C(2, a) = col[a].z;
  }
}

/// gatherApicLines with `corner`, the nodal velocity of the stencil's base
/// node in an array with strides sj and sk along j and k (x fastest).
template <typename L = Vec3d>
LODESTONE_HOSTDEV inline void gatherApicAt(const Vec3d* corner, std::size_t sj, std::size_t sk, const double u[3],
                                           const int b3[3], double cScale, Vec3d& vp, Mat3d& C) {
  gatherApicLines<L>(ApicStridedLines{corner, sj, sk}, u, b3, cScale, vp, C);
}

/// gatherApicAt on `vel`, the nodal velocities (m/s) of a whole grid of
/// nx x ny x (any) nodes, x fastest.
template <typename L = Vec3d>
LODESTONE_HOSTDEV inline void gatherApic(const Vec3d* vel, std::size_t nx, std::size_t ny, const double u[3],
                                         const int b3[3], double cScale, Vec3d& vp, Mat3d& C) {
  const Vec3d* corner = vel + (std::size_t(b3[0]) + nx * (std::size_t(b3[1]) + ny * std::size_t(b3[2])));
  gatherApicAt<L>(corner, nx, nx * ny, u, b3, cScale, vp, C);
}

}  // namespace mpm
}  // namespace lodestone
