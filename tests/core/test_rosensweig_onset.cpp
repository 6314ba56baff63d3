// Onset of the Rosensweig instability (field/rosensweig_onset.h) against
// the closed form of a linear liquid, the low-field limit of a Langevin
// liquid, and the defining equation at a saturated operating point.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/field/rosensweig_onset.h"

using namespace lodestone;

namespace {

constexpr double kRho = 1200, kSigma = 0.025, kG = 9.81;  // a typical ferrofluid, kg/m^3, N/m, m/s^2

double linearCriticalM(double chi) {
  return std::sqrt(2 / kMu0 * (1 + 1 / (1 + chi)) * std::sqrt(kRho * kG * kSigma));
}

}  // namespace

TEST(RosensweigOnset, ALinearLiquidMatchesTheClosedForm) {
  for (const double chi : {0.1, 0.91, 3.0}) {
    const RosensweigOnset o = rosensweigOnset(linearMaterial(chi, 1e24), kRho, kSigma, kG);
    const double Mc = linearCriticalM(chi);
    std::printf("linear chi = %.2f: M_c = %.1f A/m (closed form %.1f), H0_c = %.1f A/m, lambda_c = %.3f mm\n", chi,
                o.M, Mc, o.appliedH, 1e3 * o.wavelength);
    EXPECT_NEAR(o.M / Mc, 1.0, 1e-10);
    EXPECT_NEAR(o.H, Mc / chi, 1e-9 * Mc / chi);
    EXPECT_NEAR(o.appliedH, (1 + chi) * Mc / chi, 1e-9 * (1 + chi) * Mc / chi);  // B continuous: H0 = (1 + chi) H
    EXPECT_NEAR(o.muChord, 1 + chi, 1e-12);
    EXPECT_NEAR(o.muTangent, 1 + chi, 1e-12);
    EXPECT_NEAR(o.wavelength, 2 * kPi * std::sqrt(kSigma / (kRho * kG)), 1e-15);
  }
}

TEST(RosensweigOnset, ALangevinLiquidFarFromSaturationIsItsLinearisation) {
  // Many weak micro-particles: Ms = 1e7 A/m, chi0 = 0.5; the onset field is
  // a tiny fraction of the saturating field 1/k2, so M_c is the linear one
  // at chi0 to the Langevin curvature, (k2 H)^2 / 15 relative.
  const double T = 300, m = 1e-22;
  const double k2 = kMu0 * m / (kBoltzmann * T);
  const double n0 = 3 * 0.5 / (m * k2);
  const MagneticMaterial fluid = langevinMaterial(m, T, n0);
  const RosensweigOnset o = rosensweigOnset(fluid, kRho, kSigma, kG);
  const double a = k2 * o.H;
  std::printf("weak Langevin: chi0 = %.3f, M_c = %.2f A/m (linear %.2f), k2 H = %.2e\n", fluid.lowFieldSusceptibility(),
              o.M, linearCriticalM(0.5), a);
  EXPECT_LT(a, 1e-2);
  EXPECT_NEAR(o.M / linearCriticalM(0.5), 1.0, a * a);
}

TEST(RosensweigOnset, TheSaturatedLangevinOnsetSolvesTheCriterion) {
  // The paper's liquid (Ms = 8.3e4 A/m, chi0 = 0.91; onset at 8% of Ms,
  // nearly linear) and a dilute one saturating at 8000 A/m (onset deep in
  // the curved part): at the returned H the criterion holds with the
  // tangent permeability from a central difference of M(H), and the onset
  // lies above the linearised liquid's (saturation lowers mu_hat, which
  // raises the threshold, and it takes a larger field to reach it).
  for (const MagneticMaterial& fluid : {paperMaterial(), langevinMaterial(1.09e-19, 300, 8000 / 1.09e-19)}) {
    const RosensweigOnset o = rosensweigOnset(fluid, kRho, kSigma, kG);
    const auto M = [&](double H) { return magnetization(fluid.law, fluid.numberDensity, Vec3d{0, 0, H}).z; };
    const double h = 1e-4 * o.H;
    const double tangent = 1 + (M(o.H + h) - M(o.H - h)) / (2 * h);
    const double chord = 1 + M(o.H) / o.H;
    const double rhs = 2 / kMu0 * (1 + 1 / std::sqrt(chord * tangent)) * std::sqrt(kRho * kG * kSigma);
    const RosensweigOnset lin = rosensweigOnset(linearized(fluid), kRho, kSigma, kG);
    std::printf("Ms = %.0f A/m, chi0 = %.3f: M_c = %.1f A/m (M/Ms = %.3f), H = %.1f A/m, H0_c = %.1f A/m, "
                "mu_c = %.3f, mu_t = %.3f; linearised: M_c = %.1f A/m, H0_c = %.1f A/m\n",
                fluid.saturation(), fluid.lowFieldSusceptibility(), o.M, o.M / fluid.saturation(), o.H, o.appliedH,
                o.muChord, o.muTangent, lin.M, lin.appliedH);
    EXPECT_NEAR(o.M * o.M / rhs, 1.0, 1e-7);
    EXPECT_NEAR(o.muTangent / tangent, 1.0, 1e-6);
    EXPECT_NEAR(o.muChord, chord, 1e-12);
    EXPECT_NEAR(o.appliedH, o.H + o.M, 1e-9 * o.appliedH);
    EXPECT_GT(o.M, lin.M);
    EXPECT_GT(o.appliedH, lin.appliedH);
  }
}

TEST(RosensweigOnset, ALiquidThatSaturatesTooLowAndBadValuesAreRefused) {
  const MagneticMaterial weak = langevinMaterial(1.09e-19, 300, 1e21);  // Ms = 109 A/m
  try {
    rosensweigOnset(weak, kRho, kSigma, kG);
    FAIL() << "a liquid saturating at 109 A/m was given an onset";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("saturates at Ms = 109"), std::string::npos) << e.what();
  }
  const MagneticMaterial fluid = paperMaterial();
  EXPECT_THROW(rosensweigOnset(fluid, -1, kSigma, kG), InvalidArgument);
  EXPECT_THROW(rosensweigOnset(fluid, kRho, 0, kG), InvalidArgument);
  EXPECT_THROW(rosensweigOnset(fluid, kRho, std::nan(""), kG), InvalidArgument);
  EXPECT_THROW(rosensweigOnset(nonMagneticMaterial(), kRho, kSigma, kG), InvalidArgument);
}

TEST(RosensweigOnset, AFlatLayerKeepsBContinuous) {
  // Linear: M = chi H0 / (1 + chi) exactly; Langevin (the paper's liquid
  // and the dilute one, near saturation): the field inside, H0 - M, gives
  // back M through the law.
  EXPECT_NEAR(flatLayerMagnetization(linearMaterial(0.91, 1e24), 2e4), 0.91 / 1.91 * 2e4, 1e-9);
  for (const MagneticMaterial& fluid : {paperMaterial(), langevinMaterial(1.09e-19, 300, 8000 / 1.09e-19)})
    for (const double H0 : {0.0, 1e3, 2e4, 5e5}) {
      const double M = flatLayerMagnetization(fluid, H0);
      const double back = magnetization(fluid.law, fluid.numberDensity, Vec3d{0, 0, H0 - M}).z;
      EXPECT_NEAR(M, back, 1e-9 * fluid.saturation()) << "H0 = " << H0;
      EXPECT_LE(M, fluid.saturation());
    }
  EXPECT_THROW(flatLayerMagnetization(paperMaterial(), -1), InvalidArgument);
  EXPECT_THROW(flatLayerMagnetization(paperMaterial(), std::nan("")), InvalidArgument);
}

TEST(RosensweigOnset, AMagnetBelowAddsItsPullToGravity) {
  // A linear liquid (chi = 0.91) at H0 = 2e4 A/m, the field falling by
  // 1e6 A/m per m upward: g + mu0 M |dH0/dz| / rho, M = chi H0 / (1 + chi);
  // the onset rises as g^(1/4) and the wavelength shrinks as g^(-1/2).
  const MagneticMaterial fluid = linearMaterial(0.91, 1e24);
  const double M = 0.91 / 1.91 * 2e4;
  const double g = gravityNearMagnet(fluid, kRho, 2e4, -1e6, kG);
  EXPECT_NEAR(g, kG + kMu0 * M * 1e6 / kRho, 1e-9);
  EXPECT_GT(g, 1.9 * kG);  // 10.0 m/s^2 of pull: about twice gravity
  const RosensweigOnset here = rosensweigOnset(fluid, kRho, kSigma, g), flat = rosensweigOnset(fluid, kRho, kSigma, kG);
  EXPECT_NEAR(here.M / flat.M, std::pow(g / kG, 0.25), 1e-9);
  EXPECT_NEAR(here.wavelength / flat.wavelength, std::pow(g / kG, -0.5), 1e-12);
  // A magnet above lightens the layer; one strong enough lifts it.
  EXPECT_NEAR(gravityNearMagnet(fluid, kRho, 2e4, 5e5, kG), kG - kMu0 * M * 5e5 / kRho, 1e-9);
  try {
    gravityNearMagnet(fluid, kRho, 2e4, 1e7, kG);
    FAIL() << "a layer lifted by the magnet was given a gravity";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("gradient 10000000 A/m^2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(gravityNearMagnet(fluid, kRho, 2e4, std::nan(""), kG), InvalidArgument);
}
