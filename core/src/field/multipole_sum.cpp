#include "lodestone/core/field/multipole.h"

#include <cmath>

#include "lodestone/core/base/cpu_features.h"

#if defined(LODESTONE_X86_AVX2)
#include <immintrin.h>
#endif

namespace lodestone {
inline namespace field {

namespace {

double sumPortable(const MultipoleArrays& B, const Vec3d& x) {
  double acc[4] = {0, 0, 0, 0};
  for (std::size_t b = 0; b < B.count; b += 4)
    for (std::size_t l = 0; l < 4; ++l) {
      const std::size_t q = b + l;
      const double rx = x.x - B.cx[q], ry = x.y - B.cy[q], rz = x.z - B.cz[q];
      const double r2 = rx * rx + ry * ry + rz * rz;
      const double inv2 = r2 > 0 ? 1.0 / r2 : 0.0;  // a node at a block centre: no contribution
      const double inv3 = inv2 * std::sqrt(inv2), inv5 = inv3 * inv2;
      const double quad = B.nxx[q] * rx * rx + B.nyy[q] * ry * ry + B.nzz[q] * rz * rz + B.nxy[q] * rx * ry +
                          B.nxz[q] * rx * rz + B.nyz[q] * ry * rz;
      acc[l] += inv3 * (B.mx[q] * rx + B.my[q] * ry + B.mz[q] * rz - B.tr[q]) + 3.0 * inv5 * quad;
    }
  return (acc[0] + acc[1]) + (acc[2] + acc[3]);
}

#if defined(LODESTONE_X86_AVX2)
__attribute__((target("avx2,fma"))) double sumAvx2(const MultipoleArrays& B, const Vec3d& x) {
  const __m256d px = _mm256_set1_pd(x.x), py = _mm256_set1_pd(x.y), pz = _mm256_set1_pd(x.z);
  const __m256d half = _mm256_set1_pd(0.5), threeHalves = _mm256_set1_pd(1.5), three = _mm256_set1_pd(3.0);
  // Where the single-precision estimate is valid (and r2 > 0).
  const __m256d lo = _mm256_set1_pd(1e-30), hi = _mm256_set1_pd(1e30);
  __m256d acc = _mm256_setzero_pd();
  for (std::size_t b = 0; b < B.count; b += 4) {
    const __m256d rx = _mm256_sub_pd(px, _mm256_loadu_pd(B.cx + b));
    const __m256d ry = _mm256_sub_pd(py, _mm256_loadu_pd(B.cy + b));
    const __m256d rz = _mm256_sub_pd(pz, _mm256_loadu_pd(B.cz + b));
    const __m256d r2 = _mm256_fmadd_pd(rz, rz, _mm256_fmadd_pd(ry, ry, _mm256_mul_pd(rx, rx)));
    const __m256d inRange = _mm256_and_pd(_mm256_cmp_pd(r2, lo, _CMP_GT_OQ), _mm256_cmp_pd(r2, hi, _CMP_LT_OQ));
    __m256d inv1;
    if (_mm256_movemask_pd(inRange) == 0xF) {
      inv1 = _mm256_cvtps_pd(_mm_rsqrt_ps(_mm256_cvtpd_ps(r2)));
      for (int step = 0; step < 3; ++step)  // y <- y (3/2 - r2 y^2 / 2)
        inv1 = _mm256_mul_pd(inv1, _mm256_fnmadd_pd(_mm256_mul_pd(half, r2), _mm256_mul_pd(inv1, inv1), threeHalves));
    } else {
      const __m256d positive = _mm256_cmp_pd(r2, _mm256_setzero_pd(), _CMP_GT_OQ);
      inv1 = _mm256_and_pd(positive, _mm256_div_pd(_mm256_set1_pd(1.0), _mm256_sqrt_pd(r2)));
    }
    const __m256d inv2 = _mm256_mul_pd(inv1, inv1), inv3 = _mm256_mul_pd(inv2, inv1), inv5 = _mm256_mul_pd(inv3, inv2);
    __m256d quad = _mm256_mul_pd(_mm256_loadu_pd(B.nxx + b), _mm256_mul_pd(rx, rx));
    quad = _mm256_fmadd_pd(_mm256_loadu_pd(B.nyy + b), _mm256_mul_pd(ry, ry), quad);
    quad = _mm256_fmadd_pd(_mm256_loadu_pd(B.nzz + b), _mm256_mul_pd(rz, rz), quad);
    quad = _mm256_fmadd_pd(_mm256_loadu_pd(B.nxy + b), _mm256_mul_pd(rx, ry), quad);
    quad = _mm256_fmadd_pd(_mm256_loadu_pd(B.nxz + b), _mm256_mul_pd(rx, rz), quad);
    quad = _mm256_fmadd_pd(_mm256_loadu_pd(B.nyz + b), _mm256_mul_pd(ry, rz), quad);
    __m256d dip = _mm256_mul_pd(_mm256_loadu_pd(B.mx + b), rx);
    dip = _mm256_fmadd_pd(_mm256_loadu_pd(B.my + b), ry, dip);
    dip = _mm256_fmadd_pd(_mm256_loadu_pd(B.mz + b), rz, dip);
    dip = _mm256_sub_pd(dip, _mm256_loadu_pd(B.tr + b));
    acc = _mm256_add_pd(acc, _mm256_fmadd_pd(inv3, dip, _mm256_mul_pd(_mm256_mul_pd(three, inv5), quad)));
  }
  alignas(32) double lanes[4];
  _mm256_store_pd(lanes, acc);
  return (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
}
#endif

}  // namespace

PackedMultipoles::PackedMultipoles(const std::vector<Multipole>& blocks) {
  enum { kCx, kCy, kCz, kMx, kMy, kMz, kNxx, kNyy, kNzz, kNxy, kNxz, kNyz, kTr, kFields };
  const std::size_t nb = blocks.size(), padded = (nb + 3) / 4 * 4;
  soa_.assign(std::size_t(kFields) * padded, 0.0);
  for (std::size_t b = 0; b < nb; ++b) {
    const Multipole& mp = blocks[b];
    const auto& N = mp.quadrupole;
    const double v[kFields] = {mp.centre.x, mp.centre.y, mp.centre.z, mp.dipole.x, mp.dipole.y, mp.dipole.z,
                               N[0][0], N[1][1], N[2][2], N[0][1] + N[1][0], N[0][2] + N[2][0], N[1][2] + N[2][1],
                               N[0][0] + N[1][1] + N[2][2]};
    for (int f = 0; f < kFields; ++f) soa_[std::size_t(f) * padded + b] = v[f];
  }
  const auto field = [&](int f) { return soa_.data() + std::size_t(f) * padded; };
  arrays_ = {field(kCx),  field(kCy),  field(kCz),  field(kMx),  field(kMy),  field(kMz), field(kNxx),
             field(kNyy), field(kNzz), field(kNxy), field(kNxz), field(kNyz), field(kTr), padded};
}

double multipoleSum(const MultipoleArrays& blocks, const Vec3d& x) {
#if defined(LODESTONE_X86_AVX2)
  if (cpuHasAvx2Fma()) return sumAvx2(blocks, x);
#endif
  return sumPortable(blocks, x);
}

}  // namespace field
}  // namespace lodestone
