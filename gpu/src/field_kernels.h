#pragma once
// The per-node and per-cell formulas of the field solve, written once for the
// host reference backend and the CUDA kernels (LODESTONE_HOSTDEV). They are
// the formulas of core/src/field/magnetostatic_problem.cpp, q1_stencil.cpp and
// multigrid.cpp, rearranged so that every output is gathered by its owner:
//
//  * per material cell: the 8 Gauss points' M, W and dM/dH give the cell's
//    residual contributions local[8], its packed element matrix (36 values),
//    its mean dM/dH (the coarse multigrid coefficient) and its energies;
//  * per node: the vacuum Q1 stencil row plus the contributions of the (up
//    to 8) material cells around the node, looked up through a dense
//    cell -> slot map.
//
// A node-centred gather needs no atomics, so the device results do not depend
// on the thread schedule (they differ from the host reference only by the
// order of additions within a row).
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "lodestone/core/base/hostdev.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/core/base/mat3.h"
#include "lodestone/core/field/q1_axis_weights.h"
#include "lodestone/core/field/q1_element.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
namespace gpu {
namespace kernels {

constexpr int kPacked = 36;  // upper triangle of a symmetric 8x8 element matrix

/// Node grid as plain values (kernels cannot call GridSpec's host members).
struct Dims {
  int nx = 0, ny = 0, nz = 0;
  double dx = 0;  ///< m
  LODESTONE_HOSTDEV std::size_t nodes() const { return std::size_t(nx) * std::size_t(ny) * std::size_t(nz); }
  LODESTONE_HOSTDEV std::size_t cells() const {
    return std::size_t(nx - 1) * std::size_t(ny - 1) * std::size_t(nz - 1);
  }
  LODESTONE_HOSTDEV std::size_t index(int i, int j, int k) const {
    return std::size_t(i) + std::size_t(nx) * (std::size_t(j) + std::size_t(ny) * std::size_t(k));
  }
  LODESTONE_HOSTDEV std::size_t cellIndex(int i, int j, int k) const {
    return std::size_t(i) + std::size_t(nx - 1) * (std::size_t(j) + std::size_t(ny - 1) * std::size_t(k));
  }
  LODESTONE_HOSTDEV void coords(std::size_t m, int& i, int& j, int& k) const {
    i = int(m % std::size_t(nx));
    j = int((m / std::size_t(nx)) % std::size_t(ny));
    k = int(m / (std::size_t(nx) * std::size_t(ny)));
  }
  LODESTONE_HOSTDEV bool isWall(int i, int j, int k) const {
    return i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1;
  }
};

/// Tables of the Q1 element at the 2x2x2 Gauss points (q1_element.h) and the
/// products the kernels need; built once on the host, copied to constant
/// memory on the device.
struct Tables {
  double N[8][8];           ///< shape value of corner c at Gauss point q: N[q][c]
  double dN[8][8][3];       ///< reference gradient of corner c at Gauss point q
  double gram[8][kPacked];  ///< packed dN_qc . dN_qd per Gauss point
  /// Packed unit-cell element matrices of d_a N . d_b N (symmetrized for
  /// a != b), Gauss-integrated: E(D) = dx sum_ab D_ab basis_ab (multigrid.cpp).
  double basis[6][kPacked];  ///< xx, yy, zz, xy, xz, yz
  double abscissa[2];        ///< Gauss abscissae in [0, 1]
};

inline Tables makeTables() {
  Tables t{};
  const q1::Tables q = q1::makeTables();
  for (int g = 0; g < 8; ++g)
    for (int c = 0; c < 8; ++c) {
      t.N[g][c] = q.N[g][c];
      t.dN[g][c][0] = q.dN[g][c].x;
      t.dN[g][c][1] = q.dN[g][c].y;
      t.dN[g][c][2] = q.dN[g][c].z;
    }
  for (int g = 0; g < 8; ++g)
    for (int c = 0, e = 0; c < 8; ++c)
      for (int d = c; d < 8; ++d, ++e) t.gram[g][e] = dot(q.dN[g][c], q.dN[g][d]);
  for (int c = 0, e = 0; c < 8; ++c)
    for (int d = c; d < 8; ++d, ++e) {
      double s[6];
      q1::gradientProducts(q, c, d, s);
      for (int a = 0; a < 6; ++a) t.basis[a][e] = s[a];
    }
  t.abscissa[0] = q1::gaussAbscissa(0);
  t.abscissa[1] = q1::gaussAbscissa(1);
  return t;
}

/// Packed index of (c, d) in the upper triangle, any order.
LODESTONE_HOSTDEV inline int packedIndex(int c, int d) {
  if (c > d) {
    const int t = c;
    c = d;
    d = t;
  }
  return c * (15 - c) / 2 + d;
}

LODESTONE_HOSTDEV inline Vec3d gradientAt(const Tables& T, int q, const double v[8]) {
  Vec3d g{};
  for (int c = 0; c < 8; ++c) g += v[c] * Vec3d{T.dN[q][c][0], T.dN[q][c][1], T.dN[q][c][2]};
  return g;
}
LODESTONE_HOSTDEV inline double dotGradient(const Tables& T, int q, int c, const Vec3d& v) {
  return T.dN[q][c][0] * v.x + T.dN[q][c][1] * v.y + T.dN[q][c][2] * v.z;
}

/// Offsets of a cell's corners from its base node (corner c = a + 2b + 4d).
LODESTONE_HOSTDEV inline std::size_t cornerOffset(const Dims& g, int c) {
  return std::size_t(c & 1) + std::size_t(g.nx) * (std::size_t((c >> 1) & 1) + std::size_t(g.ny) * std::size_t(c >> 2));
}

// ---------------------------------------------------------------------------
// Vacuum Q1 stencil (q1_stencil.cpp).

/// Diagonal of the vacuum stiffness at node (i,j,k), m.
LODESTONE_HOSTDEV inline double laplacianDiagonal(const Dims& g, int i, int j, int k) {
  return q1::laplacianDiagonal(g.nx, g.ny, g.nz, g.dx, i, j, k);
}

/// Row (i,j,k) of the vacuum stiffness times v (any node, walls included).
LODESTONE_HOSTDEV inline double laplacianRow(const Dims& g, int i, int j, int k, const double* v) {
  if (i > 0 && j > 0 && k > 0 && i < g.nx - 1 && j < g.ny - 1 && k < g.nz - 1) {
    // Interior: centre 8/3, faces 0, edges -1/6, corners -1/12 (times dx).
    const std::ptrdiff_t sy = g.nx, sz = std::ptrdiff_t(g.nx) * g.ny;
    const double* c = v + g.index(i, j, k);
    const auto A = [&](const double* p) { return p[sy] + p[-sy] + p[sz] + p[-sz]; };
    const auto D = [&](const double* p) { return p[sy + sz] + p[sy - sz] + p[-sy + sz] + p[-sy - sz]; };
    const double edges = A(c - 1) + A(c + 1) + D(c);
    const double corners = D(c - 1) + D(c + 1);
    const double h = g.dx;
    return h * 8.0 / 3.0 * c[0] + (-h / 6.0) * edges + (-h / 12.0) * corners;
  }
  return q1::laplacianRow(g.nx, g.ny, g.nz, g.dx, i, j, k, v);
}

// ---------------------------------------------------------------------------
// Material cells.

/// What evaluateCell computes for one material cell.
struct CellResult {
  double local[8];                   ///< residual contributions to the cell's corners, A m
  double energy = 0, energyAbs = 0;  ///< sum_q w_q W_q and sum_q w_q |W_q|, A^2 m
  bool finite = true;
};

/// Evaluates the 8 Gauss points of one material cell at corner potentials
/// pc (A): H = H_ext - grad phi, M, W, dM/dH (magnetostatic_problem.cpp,
/// evaluate()). With elem != nullptr also writes the packed element matrix
/// (dx/8) sum_q dN_q^T dM/dH_q dN_q and, with tensor != nullptr, the mean
/// dM/dH of the cell. `atZero` evaluates M(H_ext) with magnetization() only
/// (residualAtZero()).
LODESTONE_HOSTDEV inline CellResult evaluateCell(const Tables& T, const MagnetizationLaw<double>& law, double h,
                                                 const double pc[8], const double* nq, const Vec3d* hext, bool atZero,
                                                 double* elem, SymMat3d* tensor) {
  CellResult cs;
  for (int c = 0; c < 8; ++c) cs.local[c] = 0;
  const double w = h * h * h / 8.0, fScale = h * h / 8.0, jScale = h / 8.0;
  if (elem)
    for (int e = 0; e < kPacked; ++e) elem[e] = 0;
  SymMat3d mean{};
  for (int q = 0; q < 8; ++q) {
    if (atZero) {
      const Vec3d M = magnetization(law, nq[q], hext[q]);
      for (int c = 0; c < 8; ++c) cs.local[c] -= fScale * dotGradient(T, q, c, M);
      continue;
    }
    const Vec3d H = hext[q] - gradientAt(T, q, pc) / h;
    const MagnetizationResponse<double> r = respond(law, nq[q], H);
    SymMat3d jq = r.dMdH;
    jq *= jScale;
    if (elem) {
      SymMat3d m8 = r.dMdH;
      m8 *= 0.125;
      mean += m8;
      const double a = jScale * r.iso, b = jScale * r.rank1;
      const double* G = T.gram[q];
      if (b != 0) {
        double u[8];
        for (int c = 0; c < 8; ++c) u[c] = dotGradient(T, q, c, r.h);
        for (int c = 0, e = 0; c < 8; ++c)
          for (int d = c; d < 8; ++d, ++e) elem[e] += a * G[e] + b * u[c] * u[d];
      } else {
        for (int e = 0; e < kPacked; ++e) elem[e] += a * G[e];
      }
    }
    cs.finite = cs.finite && isFinite(r.M) && std::isfinite(r.W) && std::isfinite(jq.trace());
    cs.energy += w * r.W;
    cs.energyAbs += w * std::fabs(r.W);
    const Vec3d mw = r.M;
    for (int c = 0; c < 8; ++c) cs.local[c] -= fScale * dotGradient(T, q, c, mw);
  }
  if (tensor) *tensor = mean;
  return cs;
}

/// sum_q w_q W at corner potentials pc + lambda dc, and sum_q w_q |W| in *absSum.
LODESTONE_HOSTDEV inline double cellEnergyAlong(const Tables& T, const MagnetizationLaw<double>& law, double h,
                                                const double pc[8], const double dc[8], double lambda, const double* nq,
                                                const Vec3d* hext, double* absSum) {
  const double w = h * h * h / 8.0;
  double s = 0, a = 0;
  for (int q = 0; q < 8; ++q) {
    const Vec3d H = hext[q] - (gradientAt(T, q, pc) + lambda * gradientAt(T, q, dc)) / h;
    const double W = w * coEnergy(law, nq[q], H);
    s += W;
    a += std::fabs(W);
  }
  *absSum = a;
  return s;
}

/// The (up to 8) cells around node (i,j,k): calls fn(cellIndex, corner of
/// the node in that cell, cell base node index) for each existing cell.
template <typename Fn>
LODESTONE_HOSTDEV inline void forCellsAroundNode(const Dims& g, int i, int j, int k, const Fn& fn) {
  for (int d = 0; d < 2; ++d) {
    const int ck = k - 1 + d;
    if (ck < 0 || ck >= g.nz - 1) continue;
    for (int b = 0; b < 2; ++b) {
      const int cj = j - 1 + b;
      if (cj < 0 || cj >= g.ny - 1) continue;
      for (int a = 0; a < 2; ++a) {
        const int ci = i - 1 + a;
        if (ci < 0 || ci >= g.nx - 1) continue;
        const int corner = (1 - a) + 2 * (1 - b) + 4 * (1 - d);
        fn(g.cellIndex(ci, cj, ck), corner, g.index(ci, cj, ck));
      }
    }
  }
}

/// Row `corner` of packed element matrix E times the cell's corner values.
LODESTONE_HOSTDEV inline double elementRow(const Dims& g, const double* E, int corner, std::size_t base,
                                           const double* v) {
  double s = 0;
  for (int d = 0; d < 8; ++d) s += E[packedIndex(corner, d)] * v[base + cornerOffset(g, d)];
  return s;
}

/// Packed coarse element matrix entry e for coefficient D: dx sum_ab D_ab basis_ab.
LODESTONE_HOSTDEV inline double coarseElement(const Tables& T, double h, const double* D, int e) {
  return h * (D[0] * T.basis[0][e] + D[1] * T.basis[1][e] + D[2] * T.basis[2][e] + D[3] * T.basis[3][e] +
              D[4] * T.basis[4][e] + D[5] * T.basis[5][e]);
}
LODESTONE_HOSTDEV inline bool isZeroTensor(const double* D) {
  return D[0] == 0 && D[1] == 0 && D[2] == 0 && D[3] == 0 && D[4] == 0 && D[5] == 0;
}

/// Coarse multigrid coefficient of coarse cell (I,J,K) (multigrid.cpp): the
/// mean of the children's D over the children that exist, when any child
/// carries material (fineD returns nullptr for a child without), else zero.
template <typename FineD>
LODESTONE_HOSTDEV inline void coarseTensor(const Dims& fine, int I, int J, int K, const FineD& fineD, double D[6]) {
  SymMat3d sum{};
  int children = 0;
  bool any = false;
  for (int d = 0; d < 2; ++d)
    for (int b = 0; b < 2; ++b)
      for (int a = 0; a < 2; ++a) {
        const int i = 2 * I + a, j = 2 * J + b, k = 2 * K + d;
        if (i >= fine.nx - 1 || j >= fine.ny - 1 || k >= fine.nz - 1) continue;
        ++children;
        const double* c = fineD(fine.cellIndex(i, j, k));
        if (c) {
          SymMat3d t;
          t.xx = c[0];
          t.yy = c[1];
          t.zz = c[2];
          t.xy = c[3];
          t.xz = c[4];
          t.yz = c[5];
          sum += t;
          any = true;
        }
      }
  if (any) sum *= 1.0 / children;
  D[0] = any ? sum.xx : 0.0;
  D[1] = any ? sum.yy : 0.0;
  D[2] = any ? sum.zz : 0.0;
  D[3] = any ? sum.xy : 0.0;
  D[4] = any ? sum.xz : 0.0;
  D[5] = any ? sum.yz : 0.0;
}

/// Node dims of the next coarser level (dx doubled, fine node 2I = coarse node I).
inline Dims coarser(const Dims& f) {
  Dims c;
  c.nx = f.nx / 2 + 1;
  c.ny = f.ny / 2 + 1;
  c.nz = f.nz / 2 + 1;
  c.dx = 2 * f.dx;
  return c;
}

// ---------------------------------------------------------------------------
// Per-node rows. A view holds raw pointers into one backend's memory.

/// The fine level: material cells through a dense cell -> slot map.
struct FineView {
  Dims g;
  bool shield = true;
  const std::int32_t* slot = nullptr;  ///< per cell: material slot or -1
  const double* local = nullptr;       ///< 8 per slot: residual contributions of the last evaluate
  const double* elem = nullptr;        ///< 36 per slot: packed element matrices
  LODESTONE_HOSTDEV bool fixed(int i, int j, int k) const { return !shield && g.isWall(i, j, k); }
};

/// A coarse level: dense per-cell coefficient D (6 per cell, zero where no material).
struct CoarseView {
  Dims g;
  bool shield = true;
  const double* D = nullptr;
  LODESTONE_HOSTDEV bool fixed(int i, int j, int k) const { return !shield && g.isWall(i, j, k); }
};

/// Vacuum row, 0 on fixed (Open wall) rows.
template <typename View>
LODESTONE_HOSTDEV inline double vacuumNode(const View& V, std::size_t m, const double* v) {
  int i, j, k;
  V.g.coords(m, i, j, k);
  return V.fixed(i, j, k) ? 0.0 : laplacianRow(V.g, i, j, k, v);
}

/// Residual F at node m from the cells' local contributions (phi: the potential evaluated).
LODESTONE_HOSTDEV inline double residualNode(const FineView& V, std::size_t m, const double* phi) {
  int i, j, k;
  V.g.coords(m, i, j, k);
  if (V.fixed(i, j, k)) return 0.0;
  double s = laplacianRow(V.g, i, j, k, phi);
  forCellsAroundNode(V.g, i, j, k, [&](std::size_t cell, int corner, std::size_t) {
    const std::int32_t sl = V.slot[cell];
    if (sl >= 0) s += V.local[std::size_t(sl) * 8 + std::size_t(corner)];
  });
  return s;
}

/// (J v) at node m.
LODESTONE_HOSTDEV inline double jacobianNode(const FineView& V, std::size_t m, const double* v) {
  int i, j, k;
  V.g.coords(m, i, j, k);
  if (V.fixed(i, j, k)) return 0.0;
  double s = laplacianRow(V.g, i, j, k, v);
  forCellsAroundNode(V.g, i, j, k, [&](std::size_t cell, int corner, std::size_t base) {
    const std::int32_t sl = V.slot[cell];
    if (sl >= 0) s += elementRow(V.g, V.elem + std::size_t(sl) * kPacked, corner, base, v);
  });
  return s;
}

/// diag(J) at node m (1 on fixed rows).
LODESTONE_HOSTDEV inline double jacobianDiagonalNode(const FineView& V, std::size_t m) {
  int i, j, k;
  V.g.coords(m, i, j, k);
  if (V.fixed(i, j, k)) return 1.0;
  double s = laplacianDiagonal(V.g, i, j, k);
  forCellsAroundNode(V.g, i, j, k, [&](std::size_t cell, int corner, std::size_t) {
    const std::int32_t sl = V.slot[cell];
    if (sl >= 0) s += V.elem[std::size_t(sl) * kPacked + std::size_t(packedIndex(corner, corner))];
  });
  return s;
}

/// (A_l v) at node m of a coarse level.
LODESTONE_HOSTDEV inline double coarseNode(const Tables& T, const CoarseView& V, std::size_t m, const double* v) {
  int i, j, k;
  V.g.coords(m, i, j, k);
  if (V.fixed(i, j, k)) return 0.0;
  double s = laplacianRow(V.g, i, j, k, v);
  forCellsAroundNode(V.g, i, j, k, [&](std::size_t cell, int corner, std::size_t base) {
    const double* D = V.D + cell * 6;
    if (isZeroTensor(D)) return;
    double r = 0;
    for (int d = 0; d < 8; ++d)
      r += coarseElement(T, V.g.dx, D, packedIndex(corner, d)) * v[base + cornerOffset(V.g, d)];
    s += r;
  });
  return s;
}

/// 1/diag(A_l) at node m of a coarse level, 0 on fixed rows.
LODESTONE_HOSTDEV inline double coarseInverseDiagonalNode(const Tables& T, const CoarseView& V, std::size_t m) {
  int i, j, k;
  V.g.coords(m, i, j, k);
  if (V.fixed(i, j, k)) return 0.0;
  double s = laplacianDiagonal(V.g, i, j, k);
  forCellsAroundNode(V.g, i, j, k, [&](std::size_t cell, int corner, std::size_t) {
    const double* D = V.D + cell * 6;
    if (!isZeroTensor(D)) s += coarseElement(T, V.g.dx, D, packedIndex(corner, corner));
  });
  return 1.0 / s;
}

// ---------------------------------------------------------------------------
// Grid transfers of the V-cycle (multigrid.cpp resampleAxis): fine node 2I is
// coarse node I, fine node 2I+1 the mean of coarse I and I+1; restriction is
// the transpose, applied x, then y, then z.

/// Restriction weight sum along one axis: r(c) = f(2c) + f(2c-1)/2 + f(2c+1)/2.
template <typename Fn>
LODESTONE_HOSTDEV inline double restrictAxis(int c, int fineCount, const Fn& f) {
  double v = 0;
  if (2 * c < fineCount) v += f(2 * c);
  if (2 * c - 1 >= 0 && 2 * c - 1 < fineCount) v += 0.5 * f(2 * c - 1);
  if (2 * c + 1 < fineCount) v += 0.5 * f(2 * c + 1);
  return v;
}
template <typename Fn>
LODESTONE_HOSTDEV inline double prolongAxis(int fIdx, const Fn& c) {
  const int k = fIdx / 2;
  return (fIdx % 2 == 0) ? c(k) : 0.5 * (c(k) + c(k + 1));
}

/// Restricted value at coarse node (I,J,K) of fine vector r.
LODESTONE_HOSTDEV inline double restrictAt(const Dims& f, int I, int J, int K, const double* r) {
  return restrictAxis(K, f.nz, [&](int kk) {
    return restrictAxis(J, f.ny,
                        [&](int jj) { return restrictAxis(I, f.nx, [&](int ii) { return r[f.index(ii, jj, kk)]; }); });
  });
}
/// Prolonged value at fine node (i,j,k) of coarse vector x.
LODESTONE_HOSTDEV inline double prolongAt(const Dims& c, int i, int j, int k, const double* x) {
  return prolongAxis(i, [&](int I) {
    return prolongAxis(j, [&](int J) { return prolongAxis(k, [&](int K) { return x[c.index(I, J, K)]; }); });
  });
}

// ---------------------------------------------------------------------------
// Nodal fields and force (nodal_field.cpp, magnetic_force.cpp).

/// Central difference of s along `axis` at node m (one-sided at the walls), / dx.
LODESTONE_HOSTDEV inline double differenceAt(const Dims& g, const double* s, int i, int j, int k, int axis) {
  const int p = axis == 0 ? i : (axis == 1 ? j : k);
  const int count = axis == 0 ? g.nx : (axis == 1 ? g.ny : g.nz);
  const std::size_t stride = axis == 0 ? 1 : (axis == 1 ? std::size_t(g.nx) : std::size_t(g.nx) * g.ny);
  const std::size_t m = g.index(i, j, k);
  if (p == 0) return (s[m + stride] - s[m]) * (1.0 / g.dx);
  if (p == count - 1) return (s[m] - s[m - stride]) * (1.0 / g.dx);
  return (s[m + stride] - s[m - stride]) * (0.5 / g.dx);
}

/// Lumped-L2 projected gradient of phi at node (i,j,k): the central
/// difference along each axis smoothed by [1/6, 2/3, 1/6] across it
/// ([2/3, 1/3] at the walls), the order of projectedGradient().
LODESTONE_HOSTDEV inline Vec3d projectedGradientAt(const Dims& g, const double* phi, int i, int j, int k) {
  Vec3d out{};
  const int count[3] = {g.nx, g.ny, g.nz};
  for (int axis = 0; axis < 3; ++axis) {
    const int s1 = (axis + 1) % 3, s2 = (axis + 2) % 3;
    // smooth along s2 of (smooth along s1 of (difference along axis)).
    const auto smooth = [&](int along, int p, auto&& valueAtOffset) {
      if (p == 0) return (2.0 / 3) * valueAtOffset(0) + (1.0 / 3) * valueAtOffset(1);
      if (p == count[along] - 1) return (2.0 / 3) * valueAtOffset(0) + (1.0 / 3) * valueAtOffset(-1);
      return (2.0 / 3) * valueAtOffset(0) + (1.0 / 6) * (valueAtOffset(1) + valueAtOffset(-1));
    };
    const int idx[3] = {i, j, k};
    out[axis] = smooth(s2, idx[s2], [&](int o2) {
      int q[3] = {i, j, k};
      q[s2] += o2;
      return smooth(s1, q[s1], [&](int o1) {
        int r[3] = {q[0], q[1], q[2]};
        r[s1] += o1;
        return differenceAt(g, phi, r[0], r[1], r[2], axis);
      });
    });
  }
  return out;
}

/// H = H_ext - grad phi (A/m), B = mu0 (H + M(H; n)) (T) at node m (nodal_field.cpp).
LODESTONE_HOSTDEV inline void nodalFieldsAt(const Dims& g, const MagnetizationLaw<double>& law, const double* phi,
                                            const Vec3d* hext, const double* n, std::size_t m, Vec3d& H, Vec3d& B) {
  constexpr double mu0 = 1.25663706212e-6;  // N/A^2, constants.h
  int i, j, k;
  g.coords(m, i, j, k);
  H = hext[m] - projectedGradientAt(g, phi, i, j, k);
  B = mu0 * (H + magnetization(law, n[m], H));
}

/// t = div T (N/m^3) at node m (magnetic_force.cpp stressDivergence, with
/// (M . grad) H_ext by central differences of the nodal H_ext): the split form
/// div T_self + mu0 (M . grad) H_ext. maskMaterial keeps t only within
/// `dilation` nodes of n > 0.
LODESTONE_HOSTDEV inline Vec3d stressDivergenceAt(const Dims& g, const Vec3d* H, const Vec3d* B, const Vec3d* hext,
                                                  const double* n, bool maskMaterial, int dilation, std::size_t m) {
  constexpr double mu0 = 1.25663706212e-6;
  int i, j, k;
  g.coords(m, i, j, k);
  if (maskMaterial) {
    bool near = false;
    for (int c = (k - dilation > 0 ? k - dilation : 0);
         c <= (k + dilation < g.nz - 1 ? k + dilation : g.nz - 1) && !near; ++c)
      for (int b = (j - dilation > 0 ? j - dilation : 0);
           b <= (j + dilation < g.ny - 1 ? j + dilation : g.ny - 1) && !near; ++b)
        for (int a = (i - dilation > 0 ? i - dilation : 0);
             a <= (i + dilation < g.nx - 1 ? i + dilation : g.nx - 1) && !near; ++a)
          near = n[g.index(a, b, c)] > 0;
    if (!near) return Vec3d{};
  }
  const auto row = [&](std::size_t q, int a) {
    const Vec3d Hd = H[q] - hext[q];
    Vec3d r = (B[q][a] - mu0 * hext[q][a]) * Hd;
    r[a] -= 0.5 * mu0 * norm2(Hd);
    return r;
  };
  const int p[3] = {i, j, k};
  const int dims[3] = {g.nx, g.ny, g.nz};
  const std::size_t stride[3] = {1, std::size_t(g.nx), std::size_t(g.nx) * std::size_t(g.ny)};
  const Vec3d M = B[m] / mu0 - H[m];
  Vec3d div{};
  for (int a = 0; a < 3; ++a) {
    const std::size_t up = p[a] < dims[a] - 1 ? m + stride[a] : m;
    const std::size_t dn = p[a] > 0 ? m - stride[a] : m;
    const double span = g.dx * double((up != m) + (dn != m));
    div += (row(up, a) - row(dn, a)) / span;
    div += (mu0 * M[a] / span) * (hext[up] - hext[dn]);
  }
  return div;
}

/// One axis pass of spreadForce: r0 a_m + r1 (a_{m-1} + a_{m+1}), r0 = 2dx/3, r1 = dx/6.
LODESTONE_HOSTDEV inline Vec3d spreadAxisAt(const Dims& g, const Vec3d* a, int axis, std::size_t m) {
  int i, j, k;
  g.coords(m, i, j, k);
  const int p = axis == 0 ? i : (axis == 1 ? j : k);
  const int count = axis == 0 ? g.nx : (axis == 1 ? g.ny : g.nz);
  const std::size_t stride = axis == 0 ? 1 : (axis == 1 ? std::size_t(g.nx) : std::size_t(g.nx) * std::size_t(g.ny));
  const double r0 = 2.0 * g.dx / 3.0, r1 = g.dx / 6.0;
  Vec3d s = r0 * a[m];
  if (p > 0) s += r1 * a[m - stride];
  if (p < count - 1) s += r1 * a[m + stride];
  return s;
}

}  // namespace kernels
}  // namespace gpu
}  // namespace lodestone
