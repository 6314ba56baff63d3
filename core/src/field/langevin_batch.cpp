#include "lodestone/core/field/langevin_batch.h"

#include <cmath>

#include "lodestone/core/base/cpu_features.h"

#if defined(LODESTONE_HAVE_LIBMVEC) && defined(LODESTONE_X86_AVX2)
#define LODESTONE_BATCH_AVX2 1
#include <immintrin.h>
#endif

namespace lodestone {
inline namespace field {

void respondBatchScalar(const MagnetizationLaw<double>& law, const double n[8], const Vec3d H[8],
                        ResponseBatch& out) {
  for (int q = 0; q < 8; ++q) {
    const MagnetizationResponse<double> r = respond(law, n[q], H[q]);
    out.Mx[q] = r.M.x;
    out.My[q] = r.M.y;
    out.Mz[q] = r.M.z;
    out.iso[q] = r.iso;
    out.rank1[q] = r.rank1;
    out.hx[q] = r.h.x;
    out.hy[q] = r.h.y;
    out.hz[q] = r.h.z;
    out.W[q] = r.W;
  }
}

#if defined(LODESTONE_BATCH_AVX2)
// glibc's AVX2 vector math (libmvec), the variants GCC calls for
// vectorized exp, log and log1p.
extern "C" __attribute__((target("avx2"))) __m256d _ZGVdN4v_exp(__m256d);
extern "C" __attribute__((target("avx2"))) __m256d _ZGVdN4v_log(__m256d);
extern "C" __attribute__((target("avx2"))) __m256d _ZGVdN4v_log1p(__m256d);

namespace {
// The series coefficients of langevin.h (langevin_series::seriesP/Q/S, double).
constexpr double kP[12] = {0.3333333333333333,     0.03333333333333333,    0.0011904761904761906,
                           2.2045855379188714e-05, 2.505210838544172e-07,  1.9270852604185937e-09,
                           1.0706029224547743e-11, 4.498331606952833e-14,  1.4797143443923793e-16,
                           3.9145882126782523e-19, 8.509974375387505e-22,  1.5472680682522736e-24};
constexpr double kQ[12] = {0.16666666666666666,    0.008333333333333333,   0.0001984126984126984,
                           2.7557319223985893e-06, 2.505210838544172e-08,  1.6059043836821613e-10,
                           7.647163731819816e-13,  2.8114572543455206e-15, 8.22063524662433e-18,
                           1.9572941063391263e-20, 3.868170170630684e-23,  6.446950284384474e-26};
constexpr double kS[12] = {0.3333333333333333,     0.044444444444444446,   0.0031746031746031746,
                           0.00014109347442680775, 4.275559831115387e-06,  9.39683479366019e-08,
                           1.5661391322766984e-09, 2.0472406957865337e-11, 2.1549902060910883e-13,
                           1.8657923862260506e-15, 1.3520234682797467e-17, 8.320144420183057e-20};

__attribute__((target("avx2,fma"))) inline __m256d horner12(__m256d x, const double* c) {
  __m256d r = _mm256_set1_pd(c[11]);
  for (int k = 10; k >= 0; --k) r = _mm256_fmadd_pd(r, x, _mm256_set1_pd(c[k]));
  return r;
}

// Four points of respond() for the Langevin law.
__attribute__((target("avx2,fma"))) void langevin4(const MagnetizationLaw<double>& law, const double* n,
                                                   const double* Hx, const double* Hy, const double* Hz,
                                                   ResponseBatch& out, int at) {
  const __m256d one = _mm256_set1_pd(1.0), zero = _mm256_setzero_pd();
  const __m256d hx = _mm256_loadu_pd(Hx), hy = _mm256_loadu_pd(Hy), hz = _mm256_loadu_pd(Hz);
  const __m256d Hn = _mm256_sqrt_pd(_mm256_fmadd_pd(hz, hz, _mm256_fmadd_pd(hy, hy, _mm256_mul_pd(hx, hx))));
  const __m256d k2 = _mm256_set1_pd(law.k2);
  const __m256d b = _mm256_mul_pd(k2, Hn);  // >= 0 (or NaN)
  // Exponential forms (b >= 1; garbage, later discarded, below).
  const __m256d e = _ZGVdN4v_exp(_mm256_mul_pd(_mm256_set1_pd(-2.0), b));
  const __m256d u = _mm256_sub_pd(one, e);
  const __m256d ib = _mm256_div_pd(one, b), iu = _mm256_div_pd(one, u), eu = _mm256_mul_pd(e, iu);
  __m256d over = _mm256_mul_pd(_mm256_fmadd_pd(_mm256_set1_pd(2.0), eu, _mm256_sub_pd(one, ib)), ib);
  __m256d der = _mm256_fnmadd_pd(_mm256_mul_pd(_mm256_set1_pd(4.0), eu), iu, _mm256_mul_pd(ib, ib));
  __m256d lsc = _mm256_add_pd(_mm256_sub_pd(b, _mm256_set1_pd(0.69314718055994530942)),
                              _ZGVdN4v_log(_mm256_mul_pd(u, ib)));
  lsc = _mm256_blendv_pd(lsc, b, _mm256_cmp_pd(b, _mm256_set1_pd(1e30), _CMP_GT_OQ));
  // Series below 1, only when a lane needs it.
  const __m256d small = _mm256_cmp_pd(b, one, _CMP_LT_OQ);
  if (_mm256_movemask_pd(small) != 0) {
    const __m256d bs = _mm256_min_pd(b, one);  // keeps the discarded lanes finite
    const __m256d x = _mm256_mul_pd(bs, bs);
    const __m256d q = _mm256_mul_pd(x, horner12(x, kQ));
    const __m256d sv = horner12(x, kS);
    over = _mm256_blendv_pd(over, _mm256_div_pd(horner12(x, kP), _mm256_add_pd(one, q)), small);
    der = _mm256_blendv_pd(der, _mm256_div_pd(sv, _mm256_fmadd_pd(x, sv, one)), small);
    lsc = _mm256_blendv_pd(lsc, _ZGVdN4v_log1p(q), small);
  }
  const __m256d nv = _mm256_loadu_pd(n);
  const __m256d chi0x3 = _mm256_mul_pd(_mm256_mul_pd(nv, _mm256_set1_pd(law.moment)), k2);
  const __m256d iso = _mm256_mul_pd(chi0x3, over);
  const __m256d inv = _mm256_and_pd(_mm256_cmp_pd(Hn, zero, _CMP_GT_OQ), _mm256_div_pd(one, Hn));
  _mm256_storeu_pd(out.Mx + at, _mm256_mul_pd(iso, hx));
  _mm256_storeu_pd(out.My + at, _mm256_mul_pd(iso, hy));
  _mm256_storeu_pd(out.Mz + at, _mm256_mul_pd(iso, hz));
  _mm256_storeu_pd(out.iso + at, iso);
  _mm256_storeu_pd(out.rank1 + at, _mm256_mul_pd(chi0x3, _mm256_sub_pd(der, over)));
  _mm256_storeu_pd(out.hx + at, _mm256_mul_pd(inv, hx));
  _mm256_storeu_pd(out.hy + at, _mm256_mul_pd(inv, hy));
  _mm256_storeu_pd(out.hz + at, _mm256_mul_pd(inv, hz));
  const __m256d wScale = _mm256_div_pd(_mm256_mul_pd(nv, _mm256_set1_pd(law.moment)), k2);
  _mm256_storeu_pd(out.W + at, _mm256_mul_pd(wScale, lsc));
}

}  // namespace

bool respondBatchVector(const MagnetizationLaw<double>& law, const double n[8], const Vec3d H[8],
                        ResponseBatch& out) {
  if (law.kind != LawKind::Langevin || !cpuHasAvx2Fma()) return false;
  double x[8], y[8], z[8];
  for (int q = 0; q < 8; ++q) {
    x[q] = H[q].x;
    y[q] = H[q].y;
    z[q] = H[q].z;
    // |H|^2 over- or underflowing from finite, non-zero components: norm()
    // rescales, so such points (|H| beyond 1e150 or below 1e-145 A/m) take
    // the scalar path.
    const double s = x[q] * x[q] + y[q] * y[q] + z[q] * z[q];
    const bool finite = std::isfinite(x[q]) && std::isfinite(y[q]) && std::isfinite(z[q]);
    const bool zero = x[q] == 0 && y[q] == 0 && z[q] == 0;
    if (finite && !zero && !(s > 1e-290 && s < 1e300)) return false;
  }
  langevin4(law, n, x, y, z, out, 0);
  langevin4(law, n + 4, x + 4, y + 4, z + 4, out, 4);
  return true;
}


#else

bool respondBatchVector(const MagnetizationLaw<double>&, const double*, const Vec3d*, ResponseBatch&) {
  return false;
}

#endif

void respondBatch(const MagnetizationLaw<double>& law, const double n[8], const Vec3d H[8], ResponseBatch& out) {
  if (!respondBatchVector(law, n, H, out)) respondBatchScalar(law, n, H, out);
}

}  // namespace field
}  // namespace lodestone
