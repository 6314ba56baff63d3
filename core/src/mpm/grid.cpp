// MLS-MPM particle <-> grid transfers. The formulas and the determinism
// argument are in mpm/grid.h; the grid's storage is in grid_storage.cpp.
// Lanes4 (below) never crosses a call out of this file, so GCC's note that
// passing it without AVX changes the ABI does not apply; it comes from
// apic_gather.h's templates too, hence before the includes.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

#include "lodestone/core/mpm/grid.h"

#include "grid_kernels.h"

#include "lodestone/core/mpm/apic_gather.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_scan.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstring>
#if defined(__x86_64__)
#include <immintrin.h>
#endif
#include <functional>
#include <limits>
#include <utility>

#include "lodestone/core/base/bspline.h"
#include "lodestone/core/base/cpu_features.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/constitutive.h"
#include "lodestone/core/mpm/surface_tension.h"

namespace lodestone {
inline namespace mpm {

namespace {

// Four doubles processed lane-wise (GCC/Clang vector extension): a node's
// momentum and mass, or a velocity and a zero lane. Each lane does the scalar
// formula's operations in the same order; the compiler uses the widest vector
// registers the target has, and in the AVX2 variant fuses multiplies and adds
// (grid_kernels.h).
typedef double Lanes4 __attribute__((vector_size(32)));

inline Lanes4 load4(const double* p) {
  Lanes4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

inline void store4(double* p, const Lanes4& v) { std::memcpy(p, &v, sizeof v); }

static_assert(sizeof(MpmNode) == 4 * sizeof(double) && offsetof(MpmNode, mass) == 3 * sizeof(double),
              "MpmNode: momentum x, y, z then mass, packed");

// G2P's write-only outputs (a particle's velocity and C), stored without
// first reading their cache lines: the particles go by in index order, so
// the write-combining buffers fill whole lines, and the next P2G reads them
// from memory either way. The same bits land; fenceStreamed makes them
// visible before the chunk's task ends.
template <int N>
inline void streamDoubles(double* dst, const double* src) {
#if defined(__x86_64__)
  for (int i = 0; i < N; ++i) {
    long long bits;
    std::memcpy(&bits, src + i, sizeof bits);
    _mm_stream_si64(reinterpret_cast<long long*>(dst + i), bits);
  }
#else
  std::memcpy(dst, src, N * sizeof(double));
#endif
}
static_assert(sizeof(Mat3d) == 9 * sizeof(double) && sizeof(Vec3d) == 3 * sizeof(double),
              "Mat3d and Vec3d: packed doubles (streamDoubles)");
inline void fenceStreamed() {
#if defined(__x86_64__)
  _mm_sfence();
#endif
}

}  // namespace

// The gather of G2P (apic_gather.h) in Lanes4: a velocity and a zero lane.
template <>
inline Lanes4 apicLanes<Lanes4>(const Vec3d& v) {
  return Lanes4{v.x, v.y, v.z, 0.0};
}
template <>
inline Vec3d apicVec3<Lanes4>(const Lanes4& lanes) {
  return {lanes[0], lanes[1], lanes[2]};
}
// A line of three nodes is nine consecutive doubles: three overlapping
// 4-wide loads, the last one rotated so that x, y, z come first. The fourth
// lane holds a neighbour's component, which the gather never reads out
// (apicVec3); no load reaches past the line.
template <>
inline void apicLine<Lanes4>(const Vec3d* line, Lanes4& n0, Lanes4& n1, Lanes4& n2) {
  static_assert(sizeof(Vec3d) == 3 * sizeof(double), "Vec3d: x, y, z packed");
  const double* d = &line[0].x;
  n0 = load4(d);
  n1 = load4(d + 3);
  const Lanes4 tail = load4(d + 5);  // n1.z, n2.x, n2.y, n2.z
  n2 = Lanes4{tail[1], tail[2], tail[3], tail[0]};
}

namespace {

using Clock = std::chrono::steady_clock;

/// Where the node arrays keep the runs of the active box (MpmGrid's
/// rowOrigin_): node (i, j, k) at origin[row(j, k)] + i, packed or whole.
struct NodeRows {
  const std::ptrdiff_t* origin = nullptr;
  Index3 lo;           // the active box's first node
  std::size_t nj = 0;  // its rows along j
  std::size_t row(int j, int k) const { return std::size_t(j - lo.j) + nj * std::size_t(k - lo.k); }
  /// The origins of the nine rows of a stencil from base row (bj, bk): row
  /// (bj + b, bk + c) at out[b + 3 c].
  void stencilRows(int bj, int bk, std::ptrdiff_t out[9]) const {
    const std::ptrdiff_t* r = origin + row(bj, bk);
    for (int c = 0; c < 3; ++c)
      for (int b = 0; b < 3; ++b) out[b + 3 * c] = r[std::size_t(b) + nj * std::size_t(c)];
  }
};

/// gatherApicLines' lines of a stencil with base node bi on rows from
/// `origin` (NodeRows::origin at the base row).
template <typename T>
struct NodeRowLines {
  const T* data;
  const std::ptrdiff_t* origin;
  std::size_t nj;
  int bi;
  const T* operator()(int b, int c) const { return data + (origin[std::size_t(b) + nj * std::size_t(c)] + bi); }
};
/// The constants of one material the kernels need.
struct MaterialParams {
  bool fluid = false;
  bool viscoplastic = false;
  bool elastoplastic = false;             // tracks F_E, Hencky + von Mises + Kelvin-Voigt (viscosity = eta)
  bool neoHookean = false;                // a solid of Eq. 18 (none of the above)
  double mu = 0, lambda = 0;              // Pa (solid)
  double viscosity = 0, bulkModulus = 0;  // Pa*s, Pa (fluid)
  double yieldStress = 0, consistency = 0, flowIndex = 1, maxViscosity = 0;  // Pa, Pa*s^n, -, Pa*s
  double surfaceTension = 0;                                                 // N/m (fluid)
};

std::vector<MaterialParams> paramsOf(const std::vector<MpmMaterial>& materials) {
  std::vector<MaterialParams> out(materials.size());
  for (std::size_t m = 0; m < materials.size(); ++m) {
    const MpmMaterial& mat = materials[m];
    out[m].fluid = mat.isFluid();  // tracks J only
    out[m].viscoplastic = mat.model == MpmModel::ViscoplasticFluid;
    out[m].elastoplastic = mat.model == MpmModel::ElastoplasticSolid;
    out[m].neoHookean = !out[m].fluid && !out[m].elastoplastic;
    out[m].yieldStress = mat.yieldStress;
    out[m].consistency = mat.consistency;
    out[m].flowIndex = mat.flowIndex;
    out[m].maxViscosity = mat.maxViscosity;
    out[m].mu = mat.mu;
    out[m].lambda = mat.lambda;
    out[m].viscosity = mat.viscosity;
    out[m].bulkModulus = mat.bulkModulus;
    out[m].surfaceTension = mat.isFluid() ? mat.surfaceTension : 0.0;
  }
  return out;
}

/// What a P2G deposit reads and writes (MpmGrid::particleToGrid sets it up).
struct DepositKernel {
  const MaterialParams* params = nullptr;
  double dx = 0, invDx = 0, stressScaleDx = 0, dt = 0;  // m, 1/m, dt D^-1 dx (s/m), s
  Vec3d o;                                            // grid origin, m
  NodeRows rows;                                      // where the nodes are
  const Vec3d *X = nullptr, *V = nullptr;
  const Mat3d *Cp = nullptr, *Fp = nullptr;
  const double *Jp = nullptr, *M = nullptr, *V0 = nullptr;
  const std::uint32_t* mat = nullptr;
  const Mat3d* capillary = nullptr;       // capillary stress per particle (Pa), or none
  const Vec3d* particleForces = nullptr;  // N per particle, or none
  MpmNode* nodes = nullptr;
  const std::uint32_t *sorted = nullptr, *offsets = nullptr;  // the binning
  const std::uint32_t *rowFirst = nullptr, *rowEnd = nullptr;  // per row of bins of the box
  const std::size_t* rowStart = nullptr;
  Index3 binLo, binDims;

  // Deposits the particles of the bins of row (bj, bk), bins in increasing
  // bi, each in increasing particle index. Inlined into each instruction-set
  // variant below.
  __attribute__((always_inline)) inline void operator()(int bj, int bk) const {
    const std::size_t row = std::size_t(bj - binLo.j) + std::size_t(binDims.j) * std::size_t(bk - binLo.k);
    const int first = int(rowFirst[row]), last = int(rowEnd[row]);
    if (first >= last) return;
    // The row's particles, in the order they are deposited: each one's
    // arrays are asked for kAhead particles early, so that their cache
    // lines arrive while the ones before are deposited.
    const std::uint32_t* rowLast = sorted + offsets[rowStart[row] + std::size_t(last - first)] - 1;
    constexpr std::ptrdiff_t kAhead = 8;
    const auto prefetch = [&](std::size_t q) __attribute__((always_inline)) {
      __builtin_prefetch(&Cp[q]);
      __builtin_prefetch(reinterpret_cast<const char*>(&Cp[q]) + 64);
      __builtin_prefetch(&Fp[q]);
      __builtin_prefetch(reinterpret_cast<const char*>(&Fp[q]) + 64);
      __builtin_prefetch(&X[q]);
      __builtin_prefetch(&V[q]);
      __builtin_prefetch(&Jp[q]);
      __builtin_prefetch(&M[q]);
      __builtin_prefetch(&V0[q]);
      __builtin_prefetch(&mat[q]);
    };
    // The row's first kAhead particles, asked for together: a short row
    // (material thin along x) would otherwise wait on each in turn.
    const std::uint32_t* rowFirstParticle = sorted + offsets[rowStart[row]];
    for (const std::uint32_t* q = rowFirstParticle; q <= rowLast && q - rowFirstParticle < kAhead; ++q) prefetch(*q);
    // ln J of the row's Neo-Hookean solids, kLogs particles at a time in a
    // loop of their own: the logarithm is a call, and inside the deposit it
    // made the particle's live values be saved and reloaded around it.
    constexpr std::ptrdiff_t kLogs = 8;
    double logJ[kLogs];
    // Node (i, bj + b, bk + c) at nodes[origin[b + 3 c] + i].
    std::ptrdiff_t origin[9];
    rows.stencilRows(bj, bk, origin);
    for (int bi = first; bi < last; ++bi) {
      const std::size_t bin = rowStart[row] + std::size_t(bi - first);
      const std::uint32_t* it = sorted + offsets[bin];
      const std::uint32_t* end = sorted + offsets[bin + 1];
      if (it == end) continue;
      for (; it != end; ++it) {
        const std::size_t p = *it;
        const std::ptrdiff_t inRow = it - rowFirstParticle;
        if (inRow % kLogs == 0) {
          const std::ptrdiff_t n = std::min(kLogs, rowLast - it + 1);
          for (std::ptrdiff_t g = 0; g < n; ++g)
            if (params[mat[it[g]]].neoHookean) logJ[g] = std::log(flooredVolumeRatio(Fp[it[g]]));
        }
        prefetch(rowLast - it > kAhead ? it[kAhead] : *rowLast);
        const Vec3d x = X[p];
        const double ux = (x.x - o.x) * invDx, uy = (x.y - o.y) * invDx, uz = (x.z - o.z) * invDx;
        const QuadraticWeights<double> wx = quadraticWeightsAt(ux, bi);
        const QuadraticWeights<double> wy = quadraticWeightsAt(uy, bj);
        const QuadraticWeights<double> wz = quadraticWeightsAt(uz, bk);
        const double fx = ux - bi, fy = uy - bj, fz = uz - bk;  // in [1/2, 3/2)

        const double m = M[p];
        const MaterialParams& mp = params[mat[p]];
        // Kirchhoff stress tau = J sigma (Pa): Eq. 18, Eqs. 19-21, Herschel-Bulkley or damped Hencky.
        Mat3d tau = mp.viscoplastic    ? viscoplasticFluidKirchhoff(Cp[p], Jp[p], mp.yieldStress, mp.consistency,
                                                                    mp.flowIndex, mp.maxViscosity, mp.bulkModulus)
                    : mp.fluid         ? viscousFluidKirchhoff(Cp[p], Jp[p], mp.viscosity, mp.bulkModulus)
                    : mp.elastoplastic ? elastoplasticKirchhoff(Fp[p], Cp[p], mp.mu, mp.lambda, mp.viscosity)
                                       : neoHookeanKirchhoffWithLogJ(Fp[p], mp.mu, mp.lambda, logJ[inRow % kLogs]);
        // The capillary stress T_p (Cauchy, Pa) of the liquids with surface tension: tau += J T_p.
        if (capillary) {
          const Mat3d& Tc = capillary[p];
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) tau(a, b) += Jp[p] * Tc(a, b);
        }
        // A dx = m dx C - dt D^-1 dx V0 tau (kg m/s): the MLS-MPM affine momentum with the stress
        // impulse, A, times dx.
        Mat3d Adx;
        const double mdx = m * dx, s = stressScaleDx * V0[p];
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) Adx(a, b) = mdx * Cp[p](a, b) - s * tau(a, b);
        // Contribution at node offset (a, b, c): m v + dt f + A d with
        // d = ((a - fx) dx, (b - fy) dx, (c - fz) dx) = q0 + a A0 + b A1 + c A2 (A_j: column j of A dx).
        Vec3d q0 = m * V[p] - Adx * Vec3d{fx, fy, fz};
        if (particleForces) q0 += dt * particleForces[p];
        // Node lanes: momentum x, y, z and mass; the mass lane of q is m (A's lane is 0).
        const Lanes4 A0{Adx(0, 0), Adx(1, 0), Adx(2, 0), 0.0};
        const Lanes4 A1{Adx(0, 1), Adx(1, 1), Adx(2, 1), 0.0};
        const Lanes4 A2{Adx(0, 2), Adx(1, 2), Adx(2, 2), 0.0};
        const Lanes4 q0m{q0.x, q0.y, q0.z, m};
        // Node (a, b, c) receives w_a w_b w_c (q0m + a A0 + b A1 + c A2)
        // = w_b w_c (P_a + b U_a + c W_a), with P_a = w_a (q0m + a A0),
        // U_a = w_a A1 and W_a = w_a A2: the terms with b or c zero vanish.
        const Lanes4 P[3] = {wx.w[0] * q0m, wx.w[1] * (q0m + A0), wx.w[2] * (q0m + 2.0 * A0)};
        const Lanes4 U[3] = {wx.w[0] * A1, wx.w[1] * A1, wx.w[2] * A1};
        const Lanes4 W[3] = {wx.w[0] * A2, wx.w[1] * A2, wx.w[2] * A2};
        for (int c = 0; c < 3; ++c) {
          Lanes4 Pc[3];
          for (int a = 0; a < 3; ++a) Pc[a] = c == 0 ? P[a] : P[a] + double(c) * W[a];
          for (int b = 0; b < 3; ++b) {
            const double wbc = wy.w[b] * wz.w[c];
            double* line = reinterpret_cast<double*>(nodes + (origin[b + 3 * c] + bi));
            for (int a = 0; a < 3; ++a) {
              const Lanes4 r = b == 0 ? Pc[a] : Pc[a] + double(b) * U[a];
              store4(line + 4 * a, load4(line + 4 * a) + wbc * r);
            }
          }
        }
      }
    }
  }
};

/// A velocity's |v|^2 (m^2/s^2) in G2P and in MpmGrid::maxSpeed: one
/// expression, so the AVX2 variant contracts it into the same FMAs in both.
__attribute__((always_inline)) inline double speed2(const Vec3d& v) { return norm2(v); }

struct G2PSums {
  double maxSpeed2 = 0;
  std::size_t clamped = 0, outside = 0, nonFinite = 0;
  void join(const G2PSums& o) {
    maxSpeed2 = std::max(maxSpeed2, o.maxSpeed2);
    clamped += o.clamped;
    outside += o.outside;
    nonFinite += o.nonFinite;
  }
};

/// What G2P reads and writes (MpmGrid::gridToParticle sets it up).
struct G2PKernel {
  const MaterialParams* params = nullptr;
  double dt = 0, invDx = 0, cScale = 0;  // s, 1/m, 4/dx (1/m)
  Vec3d o;                               // grid origin, m
  NodeRows rows;                         // where the nodes are
  const Vec3d* vel = nullptr;            // node velocities, m/s
  Vec3d *X = nullptr, *V = nullptr;
  Mat3d *Cp = nullptr, *Fp = nullptr;
  double* Jp = nullptr;
  const std::uint32_t* mat = nullptr;
  bool bounded = false, clamp = false;
  Vec3d lo, hi;  // ParticleBounds, m

  // The gather of particle p: its velocity vp (m/s) and C (1/s).
  __attribute__((always_inline)) inline void gather(std::size_t p, Vec3d& vp, Mat3d& C) const {
    const Vec3d x = X[p];
    const double ux = (x.x - o.x) * invDx, uy = (x.y - o.y) * invDx, uz = (x.z - o.z) * invDx;
    // The same base as the binning: the same arithmetic on the same,
    // unmoved position (range-checked there).
    const int bi = int(quadraticBaseFloor(ux));
    const int bj = int(quadraticBaseFloor(uy));
    const int bk = int(quadraticBaseFloor(uz));
    const double u[3] = {ux, uy, uz};
    const int b3[3] = {bi, bj, bk};
    gatherApicLines<Lanes4>(NodeRowLines<Vec3d>{vel, rows.origin + rows.row(bj, bk), rows.nj, bi}, u, b3, cScale, vp,
                            C);
  }

  // Steps 6-7 of particle p from its gathered vp and C.
  __attribute__((always_inline)) inline void update(std::size_t p, Vec3d vp, const Mat3d& C, G2PSums& acc) const {
    const Vec3d x = X[p];
    // Step 6: MLS update of the deformation (F <- (I + dt C) F, or J alone for fluids);
    // the elastoplastic solid's trial F_E is returned to the yield surface.
    const MaterialParams& mp = params[mat[p]];
    if (mp.fluid) {
      Jp[p] *= 1.0 + dt * trace(C);
    } else {
      Mat3d G = Mat3d::identity();
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) G(a, b) += dt * C(a, b);
      Fp[p] = G * Fp[p];
      if (mp.elastoplastic) Fp[p] = vonMisesReturn(Fp[p], mp.mu, mp.yieldStress);
      Jp[p] = determinant(Fp[p]);
    }
    streamDoubles<9>(&Cp[p](0, 0), &C(0, 0));
    // Step 7: advection.
    Vec3d xn = x + dt * vp;
    if (!(isFinite(xn) && isFinite(vp) && std::isfinite(Jp[p]))) {
      ++acc.nonFinite;
    } else if (bounded && (xn.x < lo.x || xn.x > hi.x || xn.y < lo.y || xn.y > hi.y || xn.z < lo.z || xn.z > hi.z)) {
      if (clamp) {
        for (int a = 0; a < 3; ++a) {
          if (xn[a] < lo[a]) {
            xn[a] = lo[a];
            vp[a] = std::max(vp[a], 0.0);
          } else if (xn[a] > hi[a]) {
            xn[a] = hi[a];
            vp[a] = std::min(vp[a], 0.0);
          }
        }
        ++acc.clamped;
      } else {
        ++acc.outside;
      }
    }
    streamDoubles<3>(&V[p].x, &vp.x);
    X[p] = xn;
    acc.maxSpeed2 = std::max(acc.maxSpeed2, speed2(vp));
  }

  // G2P of particles [begin, end), their counts added to acc. Inlined into
  // each instruction-set variant (runKernel). Two particles' gathers go
  // first, then their updates: the second gather's loads and sums overlap
  // the first's chains of additions. The F and x of the particles 16 ahead
  // are asked for early (a solid's F spans three cache lines).
  __attribute__((always_inline)) inline void operator()(std::size_t begin, std::size_t end, G2PSums& acc) const {
    std::size_t p = begin;
    constexpr std::size_t kAhead = 16;  // particles: F and x asked for this far ahead
    for (; p + 1 < end; p += 2) {
      if (p + kAhead < end) {
        __builtin_prefetch(&Fp[p + kAhead]);
        __builtin_prefetch(reinterpret_cast<const char*>(&Fp[p + kAhead]) + 64);
        __builtin_prefetch(reinterpret_cast<const char*>(&Fp[p + kAhead]) + 128);
        __builtin_prefetch(&X[p + kAhead]);
      }
      Vec3d v0, v1;
      Mat3d C0, C1;
      gather(p, v0, C0);
      gather(p + 1, v1, C1);
      update(p, v0, C0, acc);
      update(p + 1, v1, C1, acc);
    }
    if (p < end) {
      Vec3d vp;
      Mat3d C;
      gather(p, vp, C);
      update(p, vp, C, acc);
    }
    fenceStreamed();
  }
};

/// The largest |v|^2 of velocities [begin, end) (MpmGrid::maxSpeed).
struct SpeedKernel {
  const Vec3d* v = nullptr;
  __attribute__((always_inline)) inline void operator()(std::size_t begin, std::size_t end, G2PSums& acc) const {
    for (std::size_t p = begin; p != end; ++p) acc.maxSpeed2 = std::max(acc.maxSpeed2, speed2(v[p]));
  }
};

}  // namespace

// Nine colours (bj mod 3, bk mod 3) in a fixed order; rows of one colour
// write disjoint nodes and run in parallel.
template <typename RowFn>
void MpmGrid::forEachRow(const RowFn& rowFn) const {
  const int j0 = activeLo_.j, j1 = activeHi_.j - 2, k0 = activeLo_.k, k1 = activeHi_.k - 2;  // base rows [j0, j1)
  for (int ck = 0; ck < 3; ++ck) {
    for (int cj = 0; cj < 3; ++cj) {
      // First row of this colour at or after j0 / k0.
      const int fj = j0 + ((cj - j0 % 3) + 3) % 3;
      const int fk = k0 + ((ck - k0 % 3) + 3) % 3;
      const int nrj = fj < j1 ? (j1 - fj + 2) / 3 : 0;
      const int nrk = fk < k1 ? (k1 - fk + 2) / 3 : 0;
      const std::size_t rows = std::size_t(nrj) * std::size_t(nrk);
      if (rows == 0) continue;
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t row = r.begin(); row != r.end(); ++row) {
          const int bj = fj + 3 * int(row % std::size_t(nrj));
          const int bk = fk + 3 * int(row / std::size_t(nrj));
          rowFn(bj, bk);
        }
      });
    }
  }
}

void MpmGrid::particleToGrid(const MpmParticles& particles, const std::vector<MpmMaterial>& materials, double dt,
                             const Vec3d* particleForces) {
  require(std::isfinite(dt) && dt >= 0, "MPM P2G: time step must be finite and >= 0 (s), got ", dt);
  require(!nodes_.empty(), "MPM P2G: the grid was not set up");
  particles.checkSizes();
  const auto t0 = Clock::now();
  const Index3 prevLo = activeLo_, prevHi = activeHi_;
  const bool wasWhole = wholeGrid_, wasPacked = packed_;
  const std::size_t wasPackedCount = packedCount_;
  wholeGrid_ = false;
  bin(particles, materials.size());
  packed_ = !wholeLayout_;
  placeRuns();
  binningSeconds_ = std::chrono::duration<double>(Clock::now() - t0).count();

  // Zero the new runs and hand back what the previous ones held outside
  // them: every node outside the runs stays zero (or, packed, is not
  // stored), and the memory follows the material. A grid whose caller wrote
  // it whole after the last P2G (a partition's sums) is zeroed whole and
  // keeps its pages.
  if (wasWhole && !packed_) {
    zeroBox({0, 0, 0}, spec_.dims);
  } else {
    if (wasWhole || (packed_ && !wasPacked)) {  // the whole grid given up since (setWholeLayout(false))
      nodes_.clear();
      velocity_.clear();
      colour_.clear();
    } else if (packed_) {
      releasePackedTail(wasPackedCount);
    } else {
      releaseOutsideRuns(prevLo, prevHi, prevRunFirst_, prevRunEnd_);
    }
    zeroRuns();
  }
  if (particles.empty()) {
    // The colour sum is collective: a process without particles adds zeros.
    const bool surfaceTension =
        std::any_of(materials.begin(), materials.end(), [](const MpmMaterial& m) { return m.hasSurfaceTension(); });
    if (colourSum_ && surfaceTension) {
      if (colour_.size() != nodes_.size()) colour_ = PageArray<double>(nodes_.size());
      std::fill(colour_.begin(), colour_.end(), 0.0);
      colourSum_(colour_.data(), colour_.size());
    }
    return;
  }

  const std::vector<MaterialParams> params = paramsOf(materials);
  const double dx = spec_.dx;
  const double invDx = 1.0 / dx;
  const double stressScaleDx = dt * 4.0 * invDx;  // dt D^-1 dx, s/m
  const Vec3d o = spec_.origin;

  const Vec3d* X = particles.x.data();
  const Vec3d* V = particles.v.data();
  const Mat3d* Cp = particles.C.data();
  const Mat3d* Fp = particles.F.data();
  const double* Jp = particles.J.data();
  const double* M = particles.mass.data();
  const double* V0 = particles.volume0.data();
  const std::uint32_t* mat = particles.material.data();
  MpmNode* nodes = nodes_.data();

  // Surface tension (surface_tension.h), only when some material has it: the
  // colour field c_i = sum_p w_ip V_p / dx^3 of the liquids with sigma > 0
  // (V_p = V_p^0 J_p), scattered row by row like the mass (deterministic),
  // then per particle g_p = sum_i c_i grad w_ip, the colour's Hessian and
  // T_p = sigma (|g_p| P + d P H P), P = I - n n^T (particleCapillaryStress).
  std::vector<double> sigma(params.size());
  bool anySurfaceTension = false;
  for (std::size_t m = 0; m < params.size(); ++m) {
    sigma[m] = params[m].surfaceTension;
    anySurfaceTension = anySurfaceTension || sigma[m] > 0;
  }
  const Mat3d* capillary = nullptr;
  if (anySurfaceTension) {
    computeCapillaryStress(particles, sigma);
    capillary = capillary_.data();
  }

  DepositKernel kernel;
  kernel.params = params.data();
  kernel.dx = dx;
  kernel.invDx = invDx;
  kernel.stressScaleDx = stressScaleDx;
  kernel.dt = dt;
  kernel.o = o;
  kernel.rows = NodeRows{rowOrigin_.data(), activeLo_, std::size_t(activeHi_.j - activeLo_.j)};
  kernel.X = X;
  kernel.V = V;
  kernel.Cp = Cp;
  kernel.Fp = Fp;
  kernel.Jp = Jp;
  kernel.M = M;
  kernel.V0 = V0;
  kernel.mat = mat;
  kernel.capillary = capillary;
  kernel.particleForces = particleForces;
  kernel.nodes = nodes;
  kernel.sorted = sorted_.data();
  kernel.offsets = offsets_.data();
  kernel.rowFirst = rowFirst_.data();
  kernel.rowEnd = rowEnd_.data();
  kernel.rowStart = rowStart_.data();
  kernel.binLo = binLo_;
  kernel.binDims = binDims_;
  forEachRow([&](int bj, int bk) { runKernel(kernel, bj, bk); });
}

void MpmGrid::computeCapillaryStress(const MpmParticles& particles, const std::vector<double>& sigmaOf) {
  const std::size_t np = particles.size();
  const double dx = spec_.dx;
  const double invDx = 1.0 / dx;
  const double invCell = invDx * invDx * invDx;  // 1/m^3
  const Vec3d o = spec_.origin;
  const NodeRows rows = NodeRows{rowOrigin_.data(), activeLo_, std::size_t(activeHi_.j - activeLo_.j)};
  const Vec3d* X = particles.x.data();
  const double* Jp = particles.J.data();
  const double* V0 = particles.volume0.data();
  const std::uint32_t* mat = particles.material.data();

  // The colour field on the active box (nodes outside it are never read);
  // with a sum over processes on the whole grid, which the sum reads.
  if (colour_.size() != nodes_.size()) colour_ = PageArray<double>(nodes_.size());
  double* colour = colour_.data();
  if (colourSum_) {
    std::fill(colour_.begin(), colour_.end(), 0.0);
  } else if (packed_) {
    std::fill_n(colour, packedCount_, 0.0);
  } else {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, runFirst_.size(), 16),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t row = r.begin(); row != r.end(); ++row)
                          if (runEnd_[row] > runFirst_[row])
                            std::fill_n(colour + (rowOrigin_[row] + runFirst_[row]), runEnd_[row] - runFirst_[row],
                                        0.0);
                      });
  }
  forEachRow([&](int bj, int bk) {
    const std::size_t row = std::size_t(bj - binLo_.j) + std::size_t(binDims_.j) * std::size_t(bk - binLo_.k);
    const int first = int(rowFirst_[row]), last = int(rowEnd_[row]);
    std::ptrdiff_t origin[9];  // node (i, bj + b, bk + c) at colour[origin[b + 3 c] + i]
    if (first < last) rows.stencilRows(bj, bk, origin);
    for (int bi = first; bi < last; ++bi) {
      const std::size_t bin = rowStart_[row] + std::size_t(bi - first);
      for (std::uint32_t s = offsets_[bin]; s != offsets_[bin + 1]; ++s) {
        const std::size_t p = sorted_[s];
        if (!(sigmaOf[mat[p]] > 0)) continue;
        const Vec3d x = X[p];
        const QuadraticWeights<double> wx = quadraticWeightsAt((x.x - o.x) * invDx, bi);
        const QuadraticWeights<double> wy = quadraticWeightsAt((x.y - o.y) * invDx, bj);
        const QuadraticWeights<double> wz = quadraticWeightsAt((x.z - o.z) * invDx, bk);
        const double fraction = V0[p] * Jp[p] * invCell;  // V_p / dx^3
        for (int c = 0; c < 3; ++c)
          for (int b = 0; b < 3; ++b) {
            double* line = colour + (origin[b + 3 * c] + bi);
            const double wbc = fraction * wy.w[b] * wz.w[c];
            for (int a = 0; a < 3; ++a) line[a] += wx.w[a] * wbc;
          }
      }
    }
  });

  if (colourSum_) colourSum_(colour_.data(), colour_.size());

  // Per particle: the colour's gradient and Hessian and the capillary stress,
  // from the colour of the nodes the Hessian reads, one beyond the stencil
  // each side within the grid (so that the block's faces are the grid's),
  // copied into a block of at most 5^3: colourAt of each, 0 outside the runs
  // (with a sum over processes, whatever the sum left on the whole grid).
  const auto stencilColour = [&](const int base[3], double* block, int n[3], int b[3]) {
    int lo[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max(0, base[a] - 1);
      n[a] = std::min(spec_.dims[a], base[a] + 4) - lo[a];
      b[a] = base[a] - lo[a];
    }
    for (int kk = 0; kk < n[2]; ++kk)
      for (int jj = 0; jj < n[1]; ++jj) {
        const int j = lo[1] + jj, k = lo[2] + kk;
        double* out = block + std::size_t(n[0]) * (std::size_t(jj) + std::size_t(n[1]) * std::size_t(kk));
        int first = 0, end = spec_.dims.i;
        if (!colourSum_) activeRun(j, k, first, end);
        const std::ptrdiff_t origin =
            first < end ? (packed_ ? rowOrigin_[activeRow(j, k)] : std::ptrdiff_t(spec_.index(0, j, k))) : 0;
        for (int ii = 0; ii < n[0]; ++ii) {
          const int i = lo[0] + ii;
          out[ii] = i >= first && i < end ? colour[origin + i] : 0.0;
        }
      }
  };
  capillary_.resize(np);
  Mat3d* T = capillary_.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, np, 2048), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p) {
      const double sigma = sigmaOf[mat[p]];
      if (!(sigma > 0)) {
        T[p] = Mat3d{};
        continue;
      }
      const Vec3d x = X[p];
      const double ux = (x.x - o.x) * invDx, uy = (x.y - o.y) * invDx, uz = (x.z - o.z) * invDx;
      const QuadraticWeights<double> wx = quadraticWeightsAt(ux, int(quadraticBaseFloor(ux)), invDx);
      const QuadraticWeights<double> wy = quadraticWeightsAt(uy, int(quadraticBaseFloor(uy)), invDx);
      const QuadraticWeights<double> wz = quadraticWeightsAt(uz, int(quadraticBaseFloor(uz)), invDx);
      const int base[3] = {wx.base, wy.base, wz.base};
      double block[125];
      int n[3], b[3];
      stencilColour(base, block, n, b);
      T[p] = particleCapillaryStress(block, n[0], n[1], n[2], b[0], b[1], b[2], wx, wy, wz, sigma, invDx);
    }
  });
}

GridToParticleReport MpmGrid::gridToParticle(MpmParticles& particles, const std::vector<MpmMaterial>& materials,
                                             double dt, const ParticleBounds* bounds) const {
  require(std::isfinite(dt) && dt >= 0, "MPM G2P: time step must be finite and >= 0 (s), got ", dt);
  particles.checkSizes();
  require(particles.size() == key_.size(), "MPM G2P: ", particles.size(), " particles, but the last P2G binned ",
          key_.size());
  const std::vector<MaterialParams> params = paramsOf(materials);
  for (std::uint32_t m : particles.material)
    require(m < materials.size(), "MPM G2P: material index ", m, " out of range (", materials.size(), " materials)");
  G2PKernel kernel;
  kernel.params = params.data();
  kernel.dt = dt;
  kernel.invDx = 1.0 / spec_.dx;
  kernel.cScale = 4.0 * kernel.invDx;  // D^-1 dx, 1/m
  kernel.o = spec_.origin;
  kernel.rows = NodeRows{rowOrigin_.data(), activeLo_, std::size_t(activeHi_.j - activeLo_.j)};
  kernel.vel = velocity_.data();
  kernel.X = particles.x.data();
  kernel.V = particles.v.data();
  kernel.Cp = particles.C.data();
  kernel.Fp = particles.F.data();
  kernel.Jp = particles.J.data();
  kernel.mat = particles.material.data();
  kernel.bounded = bounds != nullptr;
  kernel.clamp = kernel.bounded && bounds->clamp;
  if (kernel.bounded) {
    kernel.lo = bounds->lo;
    kernel.hi = bounds->hi;
  }
  const G2PSums sums = reduceKernel<G2PSums>(kernel, particles.size(), 1024);
  GridToParticleReport rep;
  rep.maxSpeed = std::sqrt(sums.maxSpeed2);
  rep.clamped = sums.clamped;
  rep.outside = sums.outside;
  rep.nonFinite = sums.nonFinite;
  return rep;
}

double MpmGrid::maxSpeed(const Vec3d* v, std::size_t count) {
  SpeedKernel kernel;
  kernel.v = v;
  return std::sqrt(reduceKernel<G2PSums>(kernel, count, 8192).maxSpeed2);
}

}  // namespace mpm
}  // namespace lodestone
