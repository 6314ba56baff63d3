// Langevin kernels and magnetization laws: reference values, series limits,
// bounds over the whole argument range, float and double, and derivative
// consistency (Jacobian vs finite differences of M, dW/dH vs M).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/field/langevin.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/core/field/material.h"

using namespace lodestone;

namespace {

// Arguments from 0 through the series/exponential crossover to 1e300.
std::vector<double> sampleArguments() {
  std::vector<double> a = {0.0, 1e-300, 1e-200, 1e-20, 1e-10, 1e-8, 1e-5, 1e-3, 0.01, 0.1, 0.5,
                           0.9, 0.999999, 1.0, 1.000001, 1.5, 2.0, 5.0, 10.0, 20.0, 30.0, 50.0,
                           88.0, 89.0, 100.0, 300.0, 700.0, 710.0, 1e3, 1e5, 1e10, 1e100, 1e300};
  return a;
}

// Reference: long double with the textbook formula where it is accurate
// (a >= 0.5), else the Taylor series to many terms.
long double refL(long double a) {
  if (std::fabs(a) < 0.5L) {
    // a/3 - a^3/45 + 2a^5/945 - a^7/4725 + 2a^9/93555 - 1382a^11/638512875
    const long double x = a * a;
    return a * (1.0L / 3 - x / 45 + 2 * x * x / 945 - x * x * x / 4725 + 2 * x * x * x * x / 93555 -
                1382 * x * x * x * x * x / 638512875.0L);
  }
  if (a > 40) return 1.0L - 1.0L / a;
  return 1.0L / std::tanh(a) - 1.0L / a;
}

}  // namespace

TEST(Langevin, ReferenceValues) {
  // PHYSICS.md reference values.
  EXPECT_NEAR(langevin(1.0), 0.3130352854993313, 2e-16);
  EXPECT_NEAR(langevinDerivative(1.0), 0.27593833903368953, 2e-16);
  EXPECT_NEAR(langevin(2.0), 0.5373147207275481, 2e-16);
  EXPECT_NEAR(langevin(1.0f), 0.3130352854993313f, 1e-7f);
  EXPECT_NEAR(langevinDerivative(1.0f), 0.27593833903368953f, 1e-7f);
  EXPECT_NEAR(langevin(2.0f), 0.5373147207275481f, 1e-7f);
}

TEST(Langevin, MatchesReferenceAcrossRange) {
  for (double a : sampleArguments()) {
    if (a > 1e4) continue;
    const long double ref = refL(a);
    const double got = langevin(a);
    EXPECT_NEAR(got, double(ref), 4e-16 * std::fabs(double(ref)) + 1e-300) << "a = " << a;
  }
}

TEST(Langevin, SeriesLimitsNearZero) {
  for (double a : {1e-300, 1e-100, 1e-10, 1e-6}) {
    EXPECT_DOUBLE_EQ(langevin(a), a / 3.0 - a * a * a / 45) << a;
    EXPECT_DOUBLE_EQ(langevinOverArg(a), 1.0 / 3.0 - a * a / 45) << a;
    EXPECT_DOUBLE_EQ(langevinDerivative(a), 1.0 / 3.0 - a * a / 15) << a;
    EXPECT_NEAR(logSinhOverArg(a), a * a / 6.0 - a * a * a * a / 180, 1e-15 * a * a) << a;
  }
  EXPECT_EQ(langevin(0.0), 0.0);
  EXPECT_EQ(langevinOverArg(0.0), 1.0 / 3.0);
  EXPECT_EQ(langevinDerivative(0.0), 1.0 / 3.0);
  EXPECT_EQ(logSinhOverArg(0.0), 0.0);
  // Three-term expansions: L(a)/a = 1/3 - a^2/45 + 2a^4/945,
  // L'(a) = 1/3 - a^2/15 + 2a^4/189; the next terms are O(a^6) ~ 1e-18 here.
  const double a = 1e-3, a2 = a * a;
  EXPECT_NEAR(langevinOverArg(a), 1.0 / 3 - a2 / 45 + 2 * a2 * a2 / 945, 1e-16);
  EXPECT_NEAR(langevinDerivative(a), 1.0 / 3 - a2 / 15 + 2 * a2 * a2 / 189, 1e-16);
}

TEST(Langevin, LargeArgumentLimits) {
  for (double a : {1e3, 1e10, 1e100, 1e300}) {
    EXPECT_DOUBLE_EQ(langevin(a), 1.0 - 1.0 / a);
    EXPECT_DOUBLE_EQ(langevinDerivative(a), 1.0 / (a * a));
    EXPECT_NEAR(logSinhOverArg(a), a - std::log(2.0 * (a > 1e300 ? 1.0 : a)) - (a > 1e300 ? std::log(a) : 0), 1e-12 * a);
  }
  EXPECT_EQ(langevin(std::numeric_limits<double>::infinity()), 1.0);
  EXPECT_EQ(langevinDerivative(std::numeric_limits<double>::infinity()), 0.0);
}

template <typename T>
void checkBoundsAndSymmetry() {
  const T eps = std::numeric_limits<T>::epsilon();
  for (double ad : sampleArguments()) {
    if (ad > double(std::numeric_limits<T>::max())) continue;
    const T a = T(ad);
    const T L = langevin(a), g = langevinOverArg(a), dL = langevinDerivative(a), W = logSinhOverArg(a);
    ASSERT_TRUE(std::isfinite(L) && std::isfinite(g) && std::isfinite(dL) && std::isfinite(W)) << ad;
    EXPECT_GE(L, T(0)) << ad;
    EXPECT_LE(L, T(1)) << ad;
    EXPECT_GE(dL, T(0)) << ad;
    EXPECT_LE(dL, T(1) / 3 * (1 + 4 * eps)) << ad;
    EXPECT_LE(g, T(1) / 3 * (1 + 4 * eps)) << ad;
    EXPECT_GE(g, T(0)) << ad;
    EXPECT_GE(W, T(0)) << ad;
    // Odd / even symmetry.
    EXPECT_EQ(langevin(-a), -L) << ad;
    EXPECT_EQ(langevinDerivative(-a), dL) << ad;
    EXPECT_EQ(langevinOverArg(-a), g) << ad;
    EXPECT_EQ(logSinhOverArg(-a), W) << ad;
    // L' <= g (the secant slope of a concave increasing function on a > 0).
    EXPECT_LE(dL, g * (1 + 8 * eps)) << ad;
  }
}

TEST(Langevin, BoundsAndSymmetryDouble) { checkBoundsAndSymmetry<double>(); }
TEST(Langevin, BoundsAndSymmetryFloat) { checkBoundsAndSymmetry<float>(); }

TEST(Langevin, FloatAgreesWithDouble) {
  for (double a : sampleArguments()) {
    if (a > 1e30) continue;
    const float af = float(a);
    const double ad = double(af);
    EXPECT_NEAR(langevin(af), langevin(ad), 4e-7 * std::fabs(langevin(ad)) + 1e-37) << a;
    EXPECT_NEAR(langevinDerivative(af), langevinDerivative(ad), 1e-6 * langevinDerivative(ad) + 1e-37) << a;
    EXPECT_NEAR(logSinhOverArg(af), logSinhOverArg(ad), 1e-6 * logSinhOverArg(ad) + 1e-37) << a;
  }
}

TEST(Langevin, DerivativeAndAntiderivativeConsistent) {
  // Across the crossover at a = 1 the branches must agree: compare L' with a
  // central difference of L, and L with a central difference of ln(sinh a/a).
  for (double a : {0.05, 0.3, 0.7, 0.95, 0.999, 1.0, 1.001, 1.05, 1.5, 3.0, 8.0, 25.0}) {
    const double h = 1e-5 * std::max(1.0, a);
    const double fdL = (langevin(a + h) - langevin(a - h)) / (2 * h);
    EXPECT_NEAR(langevinDerivative(a), fdL, 1e-9) << a;
    const double fdW = (logSinhOverArg(a + h) - logSinhOverArg(a - h)) / (2 * h);
    EXPECT_NEAR(langevin(a), fdW, 1e-9) << a;
  }
  // Continuity at the branch switch.
  const double below = std::nextafter(1.0, 0.0);
  EXPECT_NEAR(langevin(below), langevin(1.0), 1e-15);
  EXPECT_NEAR(langevinDerivative(below), langevinDerivative(1.0), 1e-15);
  EXPECT_NEAR(logSinhOverArg(below), logSinhOverArg(1.0), 1e-15);
  EXPECT_NEAR(langevinOverArg(below), langevinOverArg(1.0), 1e-15);
}

TEST(MagnetizationLaw, PaperMaterialConstants) {
  const MagneticMaterial mat = paperMaterial();
  EXPECT_NEAR(mat.law.k2, 3.307e-5, 0.001e-5);
  EXPECT_NEAR(mat.saturation(), 8.27e4, 0.01e4);
  EXPECT_NEAR(mat.lowFieldSusceptibility(), 0.91, 0.005);
  const MagneticMaterial lin = linearized(mat);
  EXPECT_EQ(lin.law.kind, LawKind::Linear);
  EXPECT_DOUBLE_EQ(lin.lowFieldSusceptibility(), mat.lowFieldSusceptibility());
}

TEST(MagnetizationLaw, FactoriesRejectBadValues) {
  EXPECT_THROW(langevinLaw(-1e-19, 300), InvalidArgument);
  EXPECT_THROW(langevinLaw(1e-19, 0), InvalidArgument);
  EXPECT_THROW(langevinLaw(std::nan(""), 300), InvalidArgument);
  EXPECT_THROW(langevinMaterial(1e-19, 300, -1), InvalidArgument);
  EXPECT_THROW(linearMaterial(-0.5, 1e23), InvalidArgument);
  EXPECT_THROW(linearMaterial(1.0, 0), InvalidArgument);
  try {
    langevinLaw(1e-19, -3);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("-3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("K"), std::string::npos) << e.what();
  }
}

namespace {

void checkLawDerivatives(const MagnetizationLaw<double>& law, double n, const Vec3d& H) {
  const MagnetizationResponse<double> r = respond(law, n, H);
  const Vec3d M = magnetization(law, n, H);
  EXPECT_NEAR(norm(r.M - M), 0.0, 1e-14 * (norm(M) + 1e-300));
  EXPECT_NEAR(r.W, coEnergy(law, n, H), 1e-14 * std::fabs(r.W) + 1e-300);
  const double Hn = norm(H);
  const double h = 1e-6 * std::max(Hn, 1.0);
  const double mscale = std::max(norm(M), 1e-300);
  for (int b = 0; b < 3; ++b) {
    Vec3d Hp = H, Hm = H;
    Hp[b] += h;
    Hm[b] -= h;
    const Vec3d dM = (magnetization(law, n, Hp) - magnetization(law, n, Hm)) / (2 * h);
    const Vec3d col = r.dMdH * Vec3d{b == 0 ? 1.0 : 0.0, b == 1 ? 1.0 : 0.0, b == 2 ? 1.0 : 0.0};
    // Jacobian vs finite differences of M, relative to chi0.
    const double chi0 = law.lowFieldSusceptibility(n);
    EXPECT_NEAR(norm(col - dM), 0.0, 1e-6 * chi0) << "H = " << Hn << ", column " << b;
    // dW/dH = M
    const double dW = (coEnergy(law, n, Hp) - coEnergy(law, n, Hm)) / (2 * h);
    EXPECT_NEAR(dW, M[b], 1e-6 * mscale + 1e-9 * std::fabs(r.W) / std::max(Hn, 1.0)) << "H = " << Hn << ", component " << b;
  }
  // Symmetric positive semi-definite: check quadratic forms on random-ish vectors.
  for (const Vec3d& v : {Vec3d{1, 0, 0}, Vec3d{0.3, -0.7, 0.2}, H, cross(H, Vec3d{0.1, 0.2, 0.9})}) {
    EXPECT_GE(dot(v, r.dMdH * v), -1e-15 * norm2(v) * law.lowFieldSusceptibility(n));
  }
}

}  // namespace

TEST(MagnetizationLaw, LangevinJacobianAndCoEnergyMatchFiniteDifferences) {
  const MagneticMaterial mat = paperMaterial();
  const double n = mat.numberDensity;
  for (double Hm : {1.0, 1e2, 1e3, 1e4, 3e4, 1e5, 1e6, 1e7}) {
    checkLawDerivatives(mat.law, n, Vec3d{0.6, -0.48, 0.64} * Hm);
    checkLawDerivatives(mat.law, n, Vec3d{0, 0, 1} * Hm);
  }
}

TEST(MagnetizationLaw, LinearJacobianAndCoEnergy) {
  const MagneticMaterial mat = linearMaterial(2.5, 1e23);
  for (double Hm : {1.0, 1e4, 1e7}) checkLawDerivatives(mat.law, 1e23, Vec3d{0.6, -0.48, 0.64} * Hm);
  const auto r = respond(mat.law, 1e23, Vec3d{1, 2, 3});
  EXPECT_DOUBLE_EQ(r.dMdH.xx, 2.5);
  EXPECT_DOUBLE_EQ(r.dMdH.xy, 0.0);
}

TEST(MagnetizationLaw, ZeroFieldLimitIsChi0Identity) {
  const MagneticMaterial mat = paperMaterial();
  const double chi0 = mat.lowFieldSusceptibility();
  for (const Vec3d H : {Vec3d{0, 0, 0}, Vec3d{1e-200, 0, 0}, Vec3d{0, 1e-3, -1e-3}}) {
    const auto r = respond(mat.law, mat.numberDensity, H);
    EXPECT_NEAR(r.dMdH.xx, chi0, 1e-12);
    EXPECT_NEAR(r.dMdH.yy, chi0, 1e-12);
    EXPECT_NEAR(r.dMdH.zz, chi0, 1e-12);
    EXPECT_NEAR(r.dMdH.xy, 0.0, 1e-12);
    EXPECT_TRUE(isFinite(r.M));
    EXPECT_TRUE(std::isfinite(r.W));
  }
}

TEST(MagnetizationLaw, SaturatesAtStrongField) {
  const MagneticMaterial mat = paperMaterial();
  const double Ms = mat.saturation();
  for (double Hm : {1e8, 1e12, 1e30, 1e300}) {
    const auto r = respond(mat.law, mat.numberDensity, Vec3d{0, Hm, 0});
    ASSERT_TRUE(isFinite(r.M)) << Hm;
    EXPECT_NEAR(r.M.y, Ms, 1e-3 * Ms) << Hm;
    EXPECT_LE(r.M.y, Ms * (1 + 4e-16));
    EXPECT_GE(r.dMdH.yy, 0.0);
    EXPECT_TRUE(std::isfinite(r.W)) << Hm;
  }
  // Linear and Langevin differ by more than a factor of two at 1e5 A/m (PHYSICS.md).
  const double H = 1e5;
  const double Mlin = mat.lowFieldSusceptibility() * H;
  const double Mlan = magnetization(mat.law, mat.numberDensity, Vec3d{H, 0, 0}).x;
  EXPECT_GT(Mlin / Mlan, 1.3);
  EXPECT_GT(mat.lowFieldSusceptibility() * 1e6 / magnetization(mat.law, mat.numberDensity, Vec3d{1e6, 0, 0}).x, 10.0);
}

TEST(MagnetizationLaw, FloatEvaluationFinite) {
  MagnetizationLaw<float> law;
  const MagneticMaterial mat = paperMaterial();
  law.kind = LawKind::Langevin;
  law.moment = float(mat.law.moment);
  law.k2 = float(mat.law.k2);
  // n*moment in float: n ~ 7.6e23 fits float range (max 3.4e38).
  const float n = float(mat.numberDensity);
  for (float Hm : {0.f, 1e-3f, 1.f, 1e4f, 1e5f, 3e6f, 1e7f, 1e30f}) {
    const auto r = respond(law, n, Vec3f{Hm, 0, 0});
    EXPECT_TRUE(isFinite(r.M)) << Hm;
    EXPECT_TRUE(std::isfinite(r.dMdH.xx)) << Hm;
    EXPECT_TRUE(std::isfinite(r.W)) << Hm;
    const double Md = magnetization(mat.law, mat.numberDensity, Vec3d{double(Hm), 0, 0}).x;
    EXPECT_NEAR(r.M.x, Md, 1e-5 * std::fabs(Md) + 1e-30) << Hm;
  }
}

TEST(Langevin, TripleMatchesTheSeparateKernels) {
  for (double a : {0.0, 1e-300, 1e-8, 0.3, 0.999999, 1.0, 1.000001, 2.0, 17.5, 354.0, 710.0, 1e3, 1e30, 1e300, -0.5, -3.0}) {
    const auto t = lodestone::langevinTriple(a);
    EXPECT_NEAR(t.overArg, lodestone::langevinOverArg(a), 4e-16 * std::fabs(lodestone::langevinOverArg(a)) + 1e-300) << a;
    EXPECT_NEAR(t.derivative, lodestone::langevinDerivative(a), 4e-15 * std::fabs(lodestone::langevinDerivative(a)) + 1e-300) << a;
    EXPECT_NEAR(t.logSinhc, lodestone::logSinhOverArg(a), 4e-16 * std::fabs(lodestone::logSinhOverArg(a)) + 1e-300) << a;
  }
  // Against long double references on the exponential branch, where the
  // triple shares reciprocals and one logarithm instead of calling the
  // separate kernels' forms.
  for (double a : sampleArguments()) {
    if (a < 1.0 || a > 1e4) continue;
    const long double al = a, e = std::exp(-2.0L * al);
    const long double ref = refL(al);
    const long double dref = 1.0L / (al * al) - 4.0L * e / ((1.0L - e) * (1.0L - e));
    const long double wref = al - std::log(2.0L) - std::log(al) + std::log1p(-e);
    const auto t = lodestone::langevinTriple(a);
    EXPECT_NEAR(t.overArg, double(ref / al), 1e-15 * double(ref / al)) << a;
    EXPECT_NEAR(t.derivative, double(dref), 2e-15 * double(dref)) << a;
    EXPECT_NEAR(t.logSinhc, double(wref), 1e-15 * double(wref)) << a;
  }
  for (float a : {0.0f, 0.5f, 1.0f, 20.0f, 1e30f}) {
    const auto t = lodestone::langevinTriple(a);
    EXPECT_TRUE(std::isfinite(t.overArg) && std::isfinite(t.derivative) && std::isfinite(t.logSinhc)) << a;
    EXPECT_NEAR(t.overArg, lodestone::langevinOverArg(a), 4e-7f * std::fabs(lodestone::langevinOverArg(a)) + 1e-30f) << a;
  }
}
