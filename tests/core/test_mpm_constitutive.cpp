// Constitutive laws of the MPM (mpm_constitutive.h) and the validated
// material factories (mpm_material.h).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/constitutive.h"
#include "lodestone/core/mpm/material.h"

using namespace lodestone;

namespace {
Mat3d randomF(std::mt19937& rng) {
  std::uniform_real_distribution<double> U(-0.3, 0.3);
  Mat3d F = Mat3d::identity();
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) F(a, b) += U(rng);
  return F;
}
}  // namespace

TEST(MpmConstitutive, NeoHookeanStressIsTheEnergyDerivative) {
  // tau = P F^T with P = dPsi/dF (central differences), and sigma = tau / J.
  const double mu = 3e4, lambda = 5e4;
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    const Mat3d F = randomF(rng);
    ASSERT_GT(determinant(F), 0.1);
    Mat3d P;
    const double e = 1e-6;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        Mat3d Fp = F, Fm = F;
        Fp(a, b) += e;
        Fm(a, b) -= e;
        P(a, b) = (neoHookeanEnergyDensity(Fp, mu, lambda) - neoHookeanEnergyDensity(Fm, mu, lambda)) / (2 * e);
      }
    const Mat3d tauFd = P * F.transposed();
    const Mat3d tau = neoHookeanKirchhoff(F, mu, lambda);
    const Mat3d sigma = neoHookeanCauchy(F, mu, lambda);
    const double J = determinant(F);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        ASSERT_NEAR(tau(a, b), tauFd(a, b), 1e-4 * (mu + lambda)) << a << b;
        ASSERT_NEAR(tau(a, b), tau(b, a), 1e-9 * mu);
        ASSERT_NEAR(sigma(a, b) * J, tau(a, b), 1e-9 * mu);
      }
  }
  // Rest state: no stress, no energy; rotations change neither.
  const Mat3d I = Mat3d::identity();
  EXPECT_EQ(neoHookeanEnergyDensity(I, mu, lambda), 0.0);
  const double c = std::cos(0.7), s = std::sin(0.7);
  Mat3d R = I;
  R(0, 0) = c;
  R(0, 1) = -s;
  R(1, 0) = s;
  R(1, 1) = c;
  EXPECT_NEAR(neoHookeanEnergyDensity(R, mu, lambda), 0.0, 1e-10);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) EXPECT_NEAR(neoHookeanCauchy(R, mu, lambda)(a, b), 0.0, 1e-10);
  // Small uniaxial strain: sigma_xx = (lambda + 2 mu) eps (linear elasticity).
  Mat3d F = I;
  F(0, 0) = 1 + 1e-6;
  EXPECT_NEAR(neoHookeanCauchy(F, mu, lambda)(0, 0), (lambda + 2 * mu) * 1e-6, 1e-5 * (lambda + 2 * mu) * 1e-6);
  EXPECT_NEAR(neoHookeanCauchy(F, mu, lambda)(1, 1), lambda * 1e-6, 1e-4 * lambda * 1e-6);
  // An inverted element stays finite.
  F(0, 0) = -0.5;
  const Mat3d inv = neoHookeanCauchy(F, mu, lambda);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) EXPECT_TRUE(std::isfinite(inv(a, b)));
}

TEST(MpmConstitutive, ViscousFluidStress) {
  const double muN = 2.0, K = 1e5;
  Mat3d C;  // velocity gradient, 1/s
  C(0, 0) = 0.5;
  C(0, 1) = 1.0;
  C(1, 0) = -0.2;
  C(2, 2) = -0.1;
  const double J = 0.99;
  const Mat3d s = viscousFluidCauchy(C, J, muN, K);
  // sigma = mu_N (C + C^T) - K (1 - J) I: pressure K (1 - J) = 1000 Pa.
  EXPECT_NEAR(s(0, 0), 2 * muN * 0.5 - 1000, 1e-9);
  EXPECT_NEAR(s(0, 1), muN * 0.8, 1e-12);
  EXPECT_NEAR(s(1, 0), s(0, 1), 0);
  EXPECT_NEAR(s(2, 2), -2 * muN * 0.1 - 1000, 1e-9);
  const Mat3d tau = viscousFluidKirchhoff(C, J, muN, K);
  EXPECT_NEAR(tau(0, 1), J * s(0, 1), 1e-15);
  // Energy K/2 (J - 1)^2 with d/dJ = K (J - 1) = -p.
  const double e = 1e-7;
  EXPECT_NEAR((fluidEnergyDensity(J + e, K) - fluidEnergyDensity(J - e, K)) / (2 * e), -1000.0, 1e-5);
}

TEST(MpmMaterial, FactoriesComputeAndValidateParameters) {
  const MpmMaterial s = neoHookeanSolid(1e5, 0.25, 2500);
  EXPECT_NEAR(s.mu, 1e5 / 2.5, 1e-9);
  EXPECT_NEAR(s.lambda, 1e5 * 0.25 / (1.25 * 0.5), 1e-9);
  EXPECT_NEAR(s.waveSpeed(), std::sqrt((s.lambda + 2 * s.mu) / 2500), 1e-12);
  EXPECT_FALSE(s.isMagnetic());
  const MpmMaterial f = viscousFluid(3, 2e5, 1250, paperMaterial());
  EXPECT_NEAR(f.waveSpeed(), 4e2 / std::sqrt(1250.0) * std::sqrt(1.25), 1e-9);
  EXPECT_NEAR(f.kinematicViscosity(), 3.0 / 1250, 1e-18);
  EXPECT_TRUE(f.isMagnetic());

  auto expectNamed = [](auto&& fn, const char* word) {
    try {
      fn();
      FAIL() << "expected InvalidArgument mentioning " << word;
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  expectNamed([] { neoHookeanSolid(-1, 0.3, 1000); }, "Young");
  expectNamed([] { neoHookeanSolid(1e5, 0.5, 1000); }, "Poisson");
  expectNamed([] { neoHookeanSolid(1e5, 0.3, 0); }, "kg/m^3");
  expectNamed([] { viscousFluid(-1, 1e5, 1000); }, "Pa*s");
  expectNamed([] { viscousFluid(1, 0, 1000); }, "bulk modulus");
  MagneticMaterial bad = paperMaterial();
  bad.numberDensity = 0;
  expectNamed([&] { neoHookeanSolid(1e5, 0.3, 1000, bad); }, "n0");
}
