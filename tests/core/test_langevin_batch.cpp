// The batched Gauss-point kernels of the field solve's evaluation: the
// vector (AVX2) Langevin response and element matrix against the
// point-by-point ones, over the whole range of fields (series and
// exponential branches, zero, saturation, non-finite input), and the element
// matrix of an isotropic response against the closed-form Q1 Laplacian.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "lodestone/core/field/element_build.h"
#include "lodestone/core/field/langevin_batch.h"
#include "lodestone/core/field/material.h"

using namespace lodestone;

namespace {

double relDiff(double a, double b) {
  const double scale = std::max(std::fabs(a), std::fabs(b));
  return scale > 0 ? std::fabs(a - b) / scale : 0.0;
}

// Fields whose Langevin argument a = k2 |H| spans 1e-9 .. 1e4 (both
// branches, and 4-lane vectors that mix them), in random directions.
void randomFields(std::mt19937& rng, double k2, Vec3d H[8]) {
  std::uniform_real_distribution<double> U(-1, 1), L(-9, 4);
  for (int q = 0; q < 8; ++q) {
    Vec3d d{U(rng), U(rng), U(rng)};
    const double len = std::sqrt(norm2(d));
    const double a = std::pow(10.0, L(rng));
    H[q] = (a / k2 / len) * d;
  }
}

}  // namespace

TEST(LangevinBatch, VectorResponseMatchesThePointByPointOne) {
  const MagneticMaterial mat = paperMaterial();
  ResponseBatch v, s;
  Vec3d H[8];
  double n[8];
  if (!respondBatchVector(mat.law, n, H, v)) GTEST_SKIP() << "no AVX2/FMA vector path on this CPU or build";
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(0, 1);
  double worst[9] = {}, worstAt[9] = {};
  for (int trial = 0; trial < 20000; ++trial) {
    randomFields(rng, mat.law.k2, H);
    for (double& x : n) x = mat.numberDensity * U(rng);
    if (trial % 7 == 0) H[trial % 8] = Vec3d{};          // H = 0
    if (trial % 11 == 0) H[(trial + 3) % 8] = {0, 0, 1 / mat.law.k2};  // a = 1 exactly
    ASSERT_TRUE(respondBatchVector(mat.law, n, H, v));
    respondBatchScalar(mat.law, n, H, s);
    for (int q = 0; q < 8; ++q) {
      // rank1 = 3 chi0 (L'(a) - L(a)/a) cancels for small a in both paths:
      // it is compared on the scale of dM/dH itself, iso.
      const double rank1 = std::fabs(v.rank1[q] - s.rank1[q]) / std::max(std::fabs(s.iso[q]), 1e-300);
      const double d[] = {relDiff(v.Mx[q], s.Mx[q]), relDiff(v.My[q], s.My[q]), relDiff(v.Mz[q], s.Mz[q]),
                          relDiff(v.iso[q], s.iso[q]), rank1,
                          relDiff(v.hx[q], s.hx[q]),   relDiff(v.hy[q], s.hy[q]),   relDiff(v.hz[q], s.hz[q]),
                          relDiff(v.W[q], s.W[q])};
      for (int i = 0; i < 9; ++i) {
        if (d[i] > worst[i]) worstAt[i] = std::sqrt(norm2(H[q])) * mat.law.k2;
        worst[i] = std::max(worst[i], d[i]);
      }
    }
  }
  // A few ulp: libmvec's exp, log and log1p are within 4 ulp, and FMA
  // contracts some products.
  const char* names[9] = {"Mx", "My", "Mz", "iso", "rank1", "hx", "hy", "hz", "W"};
  for (int i = 0; i < 9; ++i) EXPECT_LT(worst[i], 1e-13) << names[i] << " at a = " << worstAt[i];
}

TEST(LangevinBatch, VectorResponseKeepsNonFiniteInputNonFinite) {
  const MagneticMaterial mat = paperMaterial();
  ResponseBatch v, s;
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  Vec3d H[8] = {{inf, 0, 0}, {nan, 0, 0}, {0, 0, -inf}, {3e4, -2e4, 1e4},
                {1e5, 0, 0}, {0, 1e4, 0}, {1, 1, 1}, {0, 0, 0}};
  double n[8];
  std::fill(n, n + 8, mat.numberDensity);
  if (!respondBatchVector(mat.law, n, H, v)) GTEST_SKIP() << "no AVX2/FMA vector path on this CPU or build";
  respondBatchScalar(mat.law, n, H, s);
  for (int q = 0; q < 8; ++q) {
    const bool fv = std::isfinite(v.Mx[q]) && std::isfinite(v.My[q]) && std::isfinite(v.Mz[q]) && std::isfinite(v.W[q]);
    const bool fs = std::isfinite(s.Mx[q]) && std::isfinite(s.My[q]) && std::isfinite(s.Mz[q]) && std::isfinite(s.W[q]);
    EXPECT_EQ(fv, fs) << "point " << q;
    if (fs) {
      EXPECT_LT(relDiff(v.Mx[q], s.Mx[q]) + relDiff(v.My[q], s.My[q]) + relDiff(v.Mz[q], s.Mz[q]), 1e-13) << q;
      EXPECT_LT(relDiff(v.W[q], s.W[q]), 1e-13) << q;
    }
  }
}

TEST(LangevinBatch, ExtremeMagnitudesTakeThePointByPointPath) {
  // |H|^2 over- or underflows from finite components: norm() rescales, the
  // vector path declines and respondBatch gives respond() exactly.
  const MagneticMaterial mat = paperMaterial();
  Vec3d H[8] = {{1e300, 1e300, 0}, {1e5, 0, 0}, {0, 1e4, 0}, {1e-300, 0, 0},
                {0, 0, 0},         {2e4, 0, 0}, {0, 0, 3e5}, {1, 2, 3}};
  double n[8];
  std::fill(n, n + 8, mat.numberDensity);
  ResponseBatch v, s;
  EXPECT_FALSE(respondBatchVector(mat.law, n, H, v));
  respondBatch(mat.law, n, H, v);
  respondBatchScalar(mat.law, n, H, s);
  for (int q = 0; q < 8; ++q) {
    EXPECT_EQ(v.Mx[q], s.Mx[q]) << q;
    EXPECT_EQ(v.hx[q], s.hx[q]) << q;
    EXPECT_EQ(v.W[q], s.W[q]) << q;
  }
  EXPECT_GT(s.Mx[0], 0.5 * mat.law.saturation(mat.numberDensity));  // saturated along (1, 1, 0), not 0
  EXPECT_NEAR(s.hx[3], 1.0, 1e-15);  // the direction of a tiny field, not 0
}

TEST(LangevinBatch, BatchedResponseIsRespondForTheLinearLaw) {
  const MagneticMaterial mat = linearized(paperMaterial());
  Vec3d H[8];
  double n[8];
  std::mt19937 rng(5);
  randomFields(rng, 1e-5, H);
  std::fill(n, n + 8, mat.numberDensity);
  ResponseBatch b;
  respondBatch(mat.law, n, H, b);  // no vector path for this law: point by point
  for (int q = 0; q < 8; ++q) {
    const MagnetizationResponse<double> r = respond(mat.law, n[q], H[q]);
    EXPECT_EQ(b.Mx[q], r.M.x);
    EXPECT_EQ(b.iso[q], r.iso);
    EXPECT_EQ(b.rank1[q], 0.0);
    EXPECT_EQ(b.W[q], r.W);
  }
}

TEST(ElementBuild, IsotropicResponseGivesTheScaledQ1Laplacian) {
  // iso = c, rank1 = 0: E = c dx K with K of the unit cell: 1/3 on the
  // diagonal, 0 between corners one edge apart, -1/12 two or three apart.
  ResponseBatch r{};
  const double c = 0.73, dx = 0.02;
  for (int q = 0; q < 8; ++q) r.iso[q] = c;
  double Es[36], Ev[36];
  buildElementMatrixScalar(dx, r, Es);
  const bool vector = buildElementMatrixVector(dx, r, Ev);
  for (int a = 0, e = 0; a < 8; ++a)
    for (int b = a; b < 8; ++b, ++e) {
      const int apart = __builtin_popcount(unsigned(a ^ b));
      const double K = apart == 0 ? 1.0 / 3.0 : (apart == 1 ? 0.0 : -1.0 / 12.0);
      EXPECT_NEAR(Es[e], c * dx * K, 1e-15) << a << "," << b;
      if (vector) {
        EXPECT_NEAR(Ev[e], c * dx * K, 1e-15) << a << "," << b;
      }
    }
}

TEST(ElementBuild, VectorMatrixMatchesThePointByPointOne) {
  const MagneticMaterial mat = paperMaterial();
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> U(0, 1);
  double Ev[36], Es[36];
  ResponseBatch r{};
  if (!buildElementMatrixVector(0.01, r, Ev)) GTEST_SKIP() << "no AVX2/FMA vector path on this CPU or build";
  double worst = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Vec3d H[8];
    double n[8];
    randomFields(rng, mat.law.k2, H);
    for (double& x : n) x = mat.numberDensity * U(rng);
    respondBatchScalar(mat.law, n, H, r);
    buildElementMatrixScalar(7.8e-3, r, Es);
    ASSERT_TRUE(buildElementMatrixVector(7.8e-3, r, Ev));
    double num = 0, den = 0;
    for (int e = 0; e < 36; ++e) {
      num += (Ev[e] - Es[e]) * (Ev[e] - Es[e]);
      den += Es[e] * Es[e];
    }
    if (den > 0) worst = std::max(worst, std::sqrt(num / den));
  }
  EXPECT_LT(worst, 1e-14);
}
