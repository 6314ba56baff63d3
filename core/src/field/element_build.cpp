#include "lodestone/core/field/element_build.h"

#include "lodestone/core/base/cpu_features.h"
#include "lodestone/core/field/q1_element.h"

#if defined(LODESTONE_X86_AVX2)
#include <immintrin.h>
#endif

namespace lodestone {
inline namespace field {

namespace {
constexpr q1::Tables kQ1 = q1::makeTables();

// Packed upper triangles of dN_qc . dN_qd for each Gauss point q.
struct PackedGram {
  double g[8][36];
};
constexpr PackedGram makePackedGram() {
  PackedGram t{};
  for (int q = 0; q < 8; ++q)
    for (int c = 0, e = 0; c < 8; ++c)
      for (int d = c; d < 8; ++d, ++e) t.g[q][e] = dot(kQ1.dN[q][c], kQ1.dN[q][d]);
  return t;
}
constexpr PackedGram kPackedGram = makePackedGram();
}  // namespace

void buildElementMatrixScalar(double dx, const ResponseBatch& r, double E[36]) {
  const double jScale = dx / 8.0;
  for (int e = 0; e < 36; ++e) E[e] = 0.0;
  for (int q = 0; q < 8; ++q) {
    const double a = jScale * r.iso[q], b = jScale * r.rank1[q];
    const double* G = kPackedGram.g[q];
    if (b != 0) {
      const Vec3d h{r.hx[q], r.hy[q], r.hz[q]};
      double u[8];
      for (int c = 0; c < 8; ++c) u[c] = dot(kQ1.dN[q][c], h);
      for (int c = 0, e = 0; c < 8; ++c) {
        const double bu = b * u[c];
        for (int d = c; d < 8; ++d, ++e) E[e] += a * G[e] + bu * u[d];
      }
    } else {
      for (int e = 0; e < 36; ++e) E[e] += a * G[e];
    }
  }
}

#if defined(LODESTONE_X86_AVX2)
namespace {
// Full rows of dN_qc . dN_qd and the shape gradients by component, per q.
struct FullTables {
  alignas(32) double gram[8][8][8];  // [q][c][d]
  alignas(32) double dNx[8][8], dNy[8][8], dNz[8][8];  // [q][c]
};
constexpr FullTables makeFullTables() {
  FullTables t{};
  for (int q = 0; q < 8; ++q)
    for (int c = 0; c < 8; ++c) {
      t.dNx[q][c] = kQ1.dN[q][c].x;
      t.dNy[q][c] = kQ1.dN[q][c].y;
      t.dNz[q][c] = kQ1.dN[q][c].z;
      for (int d = 0; d < 8; ++d) t.gram[q][c][d] = dot(kQ1.dN[q][c], kQ1.dN[q][d]);
    }
  return t;
}
constexpr FullTables kFull = makeFullTables();


__attribute__((target("avx2,fma"))) void buildAvx2(double dx, const ResponseBatch& r, double E[36]) {
  const double jScale = dx / 8.0;
  __m256d acc[8][2];
  for (int c = 0; c < 8; ++c) acc[c][0] = acc[c][1] = _mm256_setzero_pd();
  for (int q = 0; q < 8; ++q) {
    const __m256d a = _mm256_set1_pd(jScale * r.iso[q]);
    const double b = jScale * r.rank1[q];
    const __m256d hx = _mm256_set1_pd(r.hx[q]), hy = _mm256_set1_pd(r.hy[q]), hz = _mm256_set1_pd(r.hz[q]);
    // u = dN_q h for the 8 corners, as two vectors.
    __m256d u[2];
    for (int half = 0; half < 2; ++half)
      u[half] = _mm256_fmadd_pd(
          _mm256_load_pd(&kFull.dNz[q][4 * half]), hz,
          _mm256_fmadd_pd(_mm256_load_pd(&kFull.dNy[q][4 * half]), hy,
                          _mm256_mul_pd(_mm256_load_pd(&kFull.dNx[q][4 * half]), hx)));
    alignas(32) double us[8];
    _mm256_store_pd(us, u[0]);
    _mm256_store_pd(us + 4, u[1]);
    // Only the blocks that hold the upper triangle: rows 4..7 need columns 4..7 alone.
    for (int c = 0; c < 8; ++c) {
      const __m256d bu = _mm256_set1_pd(b * us[c]);
      for (int half = c < 4 ? 0 : 1; half < 2; ++half)
        acc[c][half] = _mm256_fmadd_pd(bu, u[half],
                                       _mm256_fmadd_pd(a, _mm256_load_pd(&kFull.gram[q][c][4 * half]), acc[c][half]));
    }
  }
  alignas(32) double full[8][8];
  for (int c = 0; c < 8; ++c) {
    _mm256_store_pd(&full[c][0], acc[c][0]);
    _mm256_store_pd(&full[c][4], acc[c][1]);
  }
  for (int c = 0, e = 0; c < 8; ++c)
    for (int d = c; d < 8; ++d, ++e) E[e] = full[c][d];
}
}  // namespace

bool buildElementMatrixVector(double dx, const ResponseBatch& r, double E[36]) {
  if (!cpuHasAvx2Fma()) return false;
  buildAvx2(dx, r, E);
  return true;
}
#else
bool buildElementMatrixVector(double, const ResponseBatch&, double*) { return false; }
#endif

void buildElementMatrix(double dx, const ResponseBatch& r, double E[36]) {
  if (!buildElementMatrixVector(dx, r, E)) buildElementMatrixScalar(dx, r, E);
}

}  // namespace field
}  // namespace lodestone
