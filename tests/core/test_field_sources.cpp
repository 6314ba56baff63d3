// Applied-field sources: elliptic integrals, time profiles, uniform field,
// point dipole, sphere magnet, and the superposition of sources. Closed
// forms are checked against independent computations (source_references.h)
// and reference values of the elliptic integrals (mpmath, 30 digits). The
// cuboid and cylinder magnets have their own files.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/pose.h"
#include "lodestone_test/source_references.h"
#include "lodestone/core/sources/cuboid_magnet.h"
#include "lodestone/core/sources/cylinder_magnet.h"
#include "lodestone/core/sources/elliptic_integral.h"
#include "lodestone/core/sources/field_source_set.h"
#include "lodestone/core/sources/magnet_source.h"
#include "lodestone/core/sources/point_dipole.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone/core/sources/time_profile.h"
#include "lodestone/core/sources/uniform_field.h"

using namespace lodestone;
using namespace lodestone::test;

// -------------------------------------------------------- elliptic integrals --

TEST(EllipticIntegral, KnownValuesOfKAndE) {
  struct Ref {
    double k, K, E;
  };
  // mpmath ellipk(k^2), ellipe(k^2) at 30 digits, at the double nearest each k
  // (near k = 1, K is ill-conditioned: dK/dk ~ 1/(1 - k^2)).
  const Ref refs[] = {{0.0, kPi / 2, kPi / 2},
                      {1 / std::sqrt(2.0), 1.854074677301372, 1.350643881047675},
                      {0.5, 1.6857503548125960, 1.4674622093394272},
                      {0.9, 2.2805491384227702, 1.1716970527816141},
                      {0.999999, 7.9474797735479670, 1.0000074474777244}};
  for (const Ref& r : refs) {
    EXPECT_NEAR(ellipticK(r.k), r.K, 2e-15 * r.K) << "k = " << r.k;
    EXPECT_NEAR(ellipticE(r.k), r.E, 2e-15 * r.E) << "k = " << r.k;
  }
  EXPECT_EQ(ellipticE(1.0), 1.0);
  EXPECT_TRUE(std::isinf(ellipticK(1.0)));
  EXPECT_NEAR(ellipticK(0.5f), 1.6857503548125960f, 1e-6f);
}

TEST(EllipticIntegral, GeneralCelAgainstThirdKindReferences) {
  // cel(kc, p, 1, 1) = Pi(n = 1 - p, k^2 = 1 - kc^2); p < 0 is the Cauchy
  // principal value (the real part of mpmath's ellippi).
  EXPECT_NEAR(cel(0.6, 0.25, 1.0, 1.0), 4.3484234819510508, 4e-15 * 4.35);
  EXPECT_NEAR(cel(0.1, 2.0, 1.0, 1.0), 2.2374901533106621, 4e-15 * 2.24);
  EXPECT_NEAR(cel(0.6, -0.5, 1.0, 1.0), -0.73406841361793653, 4e-15);
  // p = 0 with b = 0 is K(kc) times a (the cylinder at rho = R uses it).
  EXPECT_NEAR(cel(0.6, 0.0, 1.0, 0.0), cel(0.6, 1.0, 1.0, 1.0), 1e-15 * 2);
  EXPECT_TRUE(std::isnan(cel(0.6, 0.0, 1.0, 1.0)));
  EXPECT_TRUE(std::isinf(cel(0.0, 1.0, 1.0, 1.0)));
}

TEST(EllipticIntegral, CelMatchesQuadratureOfItsDefinition) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ukc(0.05, 1.5), up(0.05, 3.0), uab(-2.0, 2.0);
  const Rule q = composite(0, kPi / 2, 64, 16);
  double worst = 0;
  for (int n = 0; n < 200; ++n) {
    const double kc = ukc(rng), p = up(rng), a = uab(rng), b = uab(rng);
    double ref = 0, scale = 0;
    for (std::size_t i = 0; i < q.x.size(); ++i) {
      const double c2 = std::cos(q.x[i]) * std::cos(q.x[i]), s2 = 1 - c2;
      const double term = (a * c2 + b * s2) / ((c2 + p * s2) * std::sqrt(c2 + kc * kc * s2));
      ref += q.w[i] * term;
      scale += q.w[i] * std::fabs(term);
    }
    worst = std::fmax(worst, std::fabs(cel(kc, p, a, b) - ref) / scale);
  }
  EXPECT_LT(worst, 1e-14);
}

// Two integrals of one modulus in one loop give what two calls give, bit
// for bit, on random arguments (p of both signs), the cylinder's pairs and
// the special cases.
TEST(EllipticIntegral, CelPairIsTwoCelsBitForBit) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> ukc(1e-6, 1.5), up(-2.0, 3.0), uab(-2.0, 2.0), ug(-0.99, 0.99);
  const auto same = [](double x, double y) { return (std::isnan(x) && std::isnan(y)) || x == y; };
  int checked = 0;
  for (int n = 0; n < 2000; ++n) {
    const double kc = ukc(rng), g = ug(rng);
    const double args[2][6] = {{up(rng), uab(rng), uab(rng), up(rng), uab(rng), uab(rng)},
                               {1.0, 1.0, -1.0, g * g, 1.0, g}};  // the cylinder's radial and axial integrals
    for (const auto& q : args) {
      double r1 = 0, r2 = 0;
      celPair(kc, q[0], q[1], q[2], q[3], q[4], q[5], r1, r2);
      EXPECT_TRUE(same(r1, cel(kc, q[0], q[1], q[2])) && same(r2, cel(kc, q[3], q[4], q[5])))
          << "kc " << kc << ": " << r1 << " " << r2;
      ++checked;
    }
  }
  double r1 = 0, r2 = 0;
  celPair(0.6, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0, r1, r2);  // the first has no value (p = 0, b != 0)
  EXPECT_TRUE(std::isnan(r1));
  EXPECT_EQ(r2, cel(0.6, 1.0, 1.0, 1.0));
  celPair(0.0, 1.0, 1.0, 1.0, 1.0, 1.0, -1.0, r1, r2);  // kc = 0: both diverge
  EXPECT_TRUE(std::isinf(r1) && std::isinf(r2));
  EXPECT_EQ(checked, 4000);
}

TEST(EllipticIntegral, SmallComplementaryModulusIsAccurateAndFinite) {
  // K ~ ln(4/kc) + (kc^2/4)(ln(4/kc) - 1); E ~ 1 + (kc^2/2)(ln(4/kc) - 1/2).
  for (double kc : {1e-4, 1e-6, 1e-9, 1e-12, 1e-100, 1e-300}) {
    const double L = std::log(4 / kc);
    const double K = L + kc * kc / 4 * (L - 1), E = 1 + kc * kc / 2 * (L - 0.5);
    EXPECT_NEAR(cel(kc, 1.0, 1.0, 1.0), K, 4e-15 * K) << kc;
    EXPECT_NEAR(cel(kc, 1.0, 1.0, kc * kc), E, 4e-15) << kc;
    EXPECT_TRUE(std::isfinite(cel(kc, 1.0, 1.0, -1.0))) << kc;
  }
}

// ------------------------------------------------------------- time profile --

TEST(TimeProfile, ConstantRampSineKeyframes) {
  EXPECT_EQ(TimeProfile()(123.0), 1.0);
  EXPECT_EQ(TimeProfile::constant(2.5)(-7.0), 2.5);

  const TimeProfile ramp = TimeProfile::ramp(1.0, 3.0, 0.5, 2.5);
  EXPECT_EQ(ramp(0.0), 0.5);
  EXPECT_EQ(ramp(1.0), 0.5);
  EXPECT_DOUBLE_EQ(ramp(1.5), 1.0);
  EXPECT_DOUBLE_EQ(ramp(2.0), 1.5);
  EXPECT_EQ(ramp(3.0), 2.5);
  EXPECT_EQ(ramp(10.0), 2.5);
  const TimeProfile step = TimeProfile::ramp(2.0, 2.0);
  EXPECT_EQ(step(1.999), 0.0);
  EXPECT_EQ(step(2.0), 1.0);

  const TimeProfile sine = TimeProfile::sine(3.0, 50.0, 0.25, 1.0);
  for (double t : {0.0, 0.001, 0.0123, 0.5})
    EXPECT_NEAR(sine(t), 1.0 + 3.0 * std::sin(2 * kPi * 50.0 * t + 0.25), 1e-14);

  const TimeProfile kf = TimeProfile::keyframes({0.0, 1.0, 3.0}, {0.0, 2.0, -2.0});
  EXPECT_EQ(kf(-1.0), 0.0);  // clamped before
  EXPECT_DOUBLE_EQ(kf(0.25), 0.5);
  EXPECT_EQ(kf(1.0), 2.0);
  EXPECT_DOUBLE_EQ(kf(2.0), 0.0);
  EXPECT_DOUBLE_EQ(kf(2.5), -1.0);
  EXPECT_EQ(kf(3.0), -2.0);
  EXPECT_EQ(kf(99.0), -2.0);  // clamped after
  EXPECT_EQ(TimeProfile::keyframes({5.0}, {0.7})(0.0), 0.7);
  EXPECT_EQ(kf.kind(), TimeProfile::Kind::Keyframes);
  expectContains(kf.describe(), {"keyframes", "3 s"});
  expectContains(ramp.describe(), {"ramp", "3] s"});
  expectContains(sine.describe(), {"50 Hz"});
}

TEST(TimeProfile, BadInputsThrowNamingTheValue) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expectContains(thrownMessage([] { TimeProfile::ramp(2.0, 1.5); }), {"1.5", "2", " s"});
  expectContains(thrownMessage([&] { TimeProfile::ramp(nan, 1.0); }), {"nan", "(s)"});
  expectContains(thrownMessage([] { TimeProfile::sine(1.0, -3.0); }), {"-3", "Hz"});
  expectContains(
      thrownMessage([] { TimeProfile::sine(1.0, std::numeric_limits<double>::infinity()); }),
      {"inf", "Hz"});
  expectContains(thrownMessage([&] { TimeProfile::constant(nan); }), {"nan"});
  expectContains(thrownMessage([] {
                   TimeProfile::keyframes({0.0, 2.0, 1.25}, {0, 0, 0});
                 }),
                 {"1.25", " s"});
  expectContains(thrownMessage([] {
                   TimeProfile::keyframes({0.0, 1.0}, {0.0});
                 }),
                 {"2", "1 values"});
  expectContains(thrownMessage([] { TimeProfile::keyframes({}, {}); }), {"at least one"});
  expectContains(thrownMessage([&] { TimeProfile::keyframes({0.0}, {nan}); }),
                 {"value [0]", "nan"});
}

// ------------------------------------------------------------ uniform field --

TEST(UniformField, ScaledByProfileEverywhere) {
  const Vec3d H0{1e3, -2e3, 5e2};
  const UniformField ramped(H0, TimeProfile::ramp(0.0, 2.0));
  EXPECT_TRUE(ramped.isUniform());
  EXPECT_EQ(ramped.field({0.3, -1, 2}, -1.0), Vec3d{});
  const Vec3d half = ramped.field({5, 6, 7}, 1.0);
  EXPECT_NEAR(norm(half - H0 * 0.5), 0.0, 1e-12);
  EXPECT_EQ(ramped.field({-5, 0, 1e3}, 4.0), H0);
  EXPECT_EQ(ramped.magnetization({0, 0, 0}, 1.0), Vec3d{});

  const UniformField ac(H0, TimeProfile::sine(1.0, 10.0));
  for (double t : {0.0, 0.01, 0.025, 0.07}) {
    const Vec3d expect = H0 * std::sin(2 * kPi * 10.0 * t);
    EXPECT_NEAR(norm(ac.field({1, 2, 3}, t) - expect), 0.0, 1e-12 * norm(H0)) << t;
  }
  std::vector<Vec3d> x = {{0, 0, 0}, {1, 1, 1}}, out = {{1, 0, 0}, {0, 0, 0}};
  ac.accumulateField(x.data(), x.size(), 0.025, out.data());
  EXPECT_NEAR(norm(out[0] - (Vec3d{1, 0, 0} + H0)), 0.0, 1e-9);
  EXPECT_NEAR(norm(out[1] - H0), 0.0, 1e-9);
  expectContains(ac.describe(), {"A/m", "Hz"});
  expectContains(thrownMessage([] {
                   UniformField({1.0, std::numeric_limits<double>::infinity(), 0.0});
                 }),
                 {"inf", "A/m"});
}

// ------------------------------------------------------------- point dipole --

TEST(PointDipole, MatchesTheDipoleFormulaAndIsZeroAtItsCentre) {
  const Vec3d p{0.1, -0.2, 0.05}, m{0.3, 1.2, -0.7};  // m, A*m^2
  const PointDipole dip(p, m, TimeProfile::constant(2.0));
  std::mt19937 rng(3);
  for (int n = 0; n < 50; ++n) {
    const double r = std::pow(10.0, -3 + 4 * (n / 50.0));
    const Vec3d d = randomUnit(rng) * r;
    const Vec3d ref = dipoleReference(m * 2.0, d);
    EXPECT_LT(relErr(dip.field(p + d, 0.0), ref), 1e-13) << r;
  }
  // On the axis of m: H = 2 m / (4 pi r^3); broadside: -m / (4 pi r^3).
  const Vec3d u = m / norm(m);
  EXPECT_LT(relErr(dipoleField(m, u * 0.5), m * (2 / (4 * kPi * 0.125))), 1e-14);
  const Vec3d side = cross(u, Vec3d{1, 0, 0});
  EXPECT_LT(relErr(dipoleField(m, side / norm(side) * 0.5), m * (-1 / (4 * kPi * 0.125))), 1e-14);
  // Singular point excluded: exactly zero at the centre, finite arbitrarily close.
  EXPECT_EQ(dip.field(p, 0.0), Vec3d{});
  EXPECT_EQ(dipoleField(m, {0, 0, 0}), Vec3d{});
  for (double r : {1e-30, 1e-100, 1e-200, 1e-320})
    EXPECT_TRUE(isFinite(dipoleField(m, {r, 0, 0}))) << r;
  EXPECT_TRUE(isFinite(dipoleField(m, {1e200, -1e200, 1e200})));
  expectContains(dip.describe(), {"A*m^2", " m,"});
  expectContains(thrownMessage([&] { PointDipole(p, {std::nan(""), 0, 0}); }), {"nan", "A*m^2"});
  expectContains(thrownMessage([&] {
                   PointDipole({0, std::numeric_limits<double>::infinity(), 0}, m);
                 }),
                 {"inf", "(m)"});
}

// ---------------------------------------------------------- sphere magnet --

TEST(SphereMagnet, OutsideIsDipoleInsideIsMinusMThird) {
  const double a = 0.02;          // m
  const Vec3d M{2e5, -4e5, 6e5};  // A/m
  const Vec3d c{0.1, 0.2, -0.3};  // m
  const SphereMagnet s(Pose::at(c), a, M);
  const Vec3d m = M * (4.0 / 3.0 * kPi * a * a * a);
  EXPECT_LT(relErr(s.moment(0.0), m), 1e-15);
  std::mt19937 rng(11);
  for (int n = 0; n < 100; ++n) {
    const Vec3d u = randomUnit(rng);
    const double rOut = a * (1.0001 + 10.0 * n / 100.0);
    EXPECT_LT(relErr(s.field(c + u * rOut, 0.0), dipoleReference(m, u * rOut)), 1e-12);
    const double rIn = a * 0.9999 * n / 100.0;
    EXPECT_LT(relErr(s.field(c + u * rIn, 0.0), M * (-1.0 / 3.0)), 1e-15);
    EXPECT_EQ(s.magnetization(c + u * rIn, 0.0), M);
    EXPECT_EQ(s.magnetization(c + u * rOut, 0.0), Vec3d{});
  }
}

TEST(SphereMagnet, NormalBAndTangentialHAreContinuousAtTheSurface) {
  const double a = 0.015;
  const Vec3d M{1e5, 3e5, -2e5};
  const SphereMagnet s(Pose{}, a, M);
  std::mt19937 rng(5);
  for (int n = 0; n < 100; ++n) {
    const Vec3d u = randomUnit(rng);
    const Vec3d Hin = s.field(u * (a * (1 - 1e-9)), 0.0), Hout = s.field(u * (a * (1 + 1e-9)), 0.0);
    const double Bn_in = kMu0 * dot(Hin + M, u), Bn_out = kMu0 * dot(Hout, u);
    EXPECT_NEAR(Bn_in, Bn_out, 1e-8 * kMu0 * norm(M));
    const Vec3d Ht_in = Hin - dot(Hin, u) * u, Ht_out = Hout - dot(Hout, u) * u;
    EXPECT_NEAR(norm(Ht_in - Ht_out), 0.0, 1e-8 * norm(M));
    // The normal H does jump, by M.n, so the test above can fail.
    EXPECT_NEAR(dot(Hout - Hin, u), dot(M, u), 1e-8 * norm(M));
  }
  // Exactly on the surface (points whose norm is exactly a): the mean of the two sides.
  for (const Vec3d& u : {Vec3d{1, 0, 0}, Vec3d{0, -1, 0}, Vec3d{0, 0, 1}}) {
    const Vec3d Hin = s.field(u * (a * (1 - 1e-9)), 0.0), Hout = s.field(u * (a * (1 + 1e-9)), 0.0);
    EXPECT_LT(norm(s.field(u * a, 0.0) - (Hin + Hout) * 0.5), 1e-7 * norm(M));
  }
}


TEST(MagnetSource, ProfileScalesFieldAndMagnetizationAndPoseMoves) {
  SphereMagnet s(Pose{}, 0.01, {0, 0, 1e5}, TimeProfile::ramp(0.0, 1.0));
  EXPECT_EQ(s.field({0, 0, 0.05}, -1.0), Vec3d{});
  EXPECT_EQ(s.magnetization({0, 0, 0}, -1.0), Vec3d{});
  EXPECT_LT(relErr(s.magnetization({0, 0, 0}, 0.25), Vec3d{0, 0, 2.5e4}), 1e-15);
  const Vec3d full = s.field({0, 0, 0.05}, 2.0);
  EXPECT_LT(relErr(s.field({0, 0, 0.05}, 0.5), full * 0.5), 1e-15);
  s.setPose(Pose::at({0, 0, 0.05}));
  EXPECT_LT(relErr(s.field({0, 0, 0.05}, 2.0), Vec3d{0, 0, -1e5 / 3}), 1e-15);
  EXPECT_LT(relErr(s.field({0, 0, 0.0}, 2.0), s.field({0, 0, 0.1}, 2.0)), 1e-15);
}

TEST(FieldSourceSet, SuperpositionEqualsTheSumOfTheParts) {
  const UniformField uni({1e3, 0, -5e2}, TimeProfile::sine(1.0, 2.0, 0.3));
  const PointDipole dip({0.05, 0, 0}, {0, 0.2, 0});
  const SphereMagnet sph(Pose::at({-0.05, 0, 0}), 0.01, {0, 0, 3e5});
  const CuboidMagnet cub(Pose::fromAxisAngle({0, 0.05, 0}, {0, 1, 1}, 0.4), kCuboidHalf, kCuboidM);
  const CylinderMagnet cyl(Pose::at({0, -0.05, 0}), kCylR, kCylL, {0, 0, kCylM});
  FieldSourceSet set;
  EXPECT_TRUE(set.isUniform());
  EXPECT_EQ(set.field({1, 2, 3}, 0.0), Vec3d{});
  set.add(uni);
  EXPECT_TRUE(set.isUniform());
  set.add(std::make_unique<PointDipole>(dip));
  set.add(sph);
  set.add(cub);
  set.add(cyl);
  EXPECT_FALSE(set.isUniform());
  ASSERT_EQ(set.size(), 5u);
  const FieldSource* parts[] = {&uni, &dip, &sph, &cub, &cyl};

  std::mt19937 rng(21);
  std::vector<Vec3d> xs;
  for (int n = 0; n < 40; ++n) xs.push_back(randomUnit(rng) * (0.01 + 0.002 * n));
  xs.push_back({-0.05, 0, 0});  // inside the sphere
  xs.push_back({0, -0.05, 0});  // inside the cylinder
  const double t = 0.1;
  std::vector<Vec3d> acc(xs.size(), Vec3d{1, 1, 1});
  set.accumulateField(xs.data(), xs.size(), t, acc.data());
  for (std::size_t n = 0; n < xs.size(); ++n) {
    Vec3d H, M;
    for (const FieldSource* p : parts) {
      H += p->field(xs[n], t);
      M += p->magnetization(xs[n], t);
    }
    EXPECT_LT(norm(set.field(xs[n], t) - H), 1e-14 * norm(H)) << n;
    EXPECT_LT(norm(acc[n] - Vec3d{1, 1, 1} - H), 1e-12 * norm(H)) << n;
    EXPECT_EQ(set.magnetization(xs[n], t), M) << n;
  }
  EXPECT_EQ(set.magnetization({-0.05, 0, 0}, t), (Vec3d{0, 0, 3e5}));

  // Copies are deep: moving a magnet in the copy leaves the original alone.
  FieldSourceSet copy = set;
  dynamic_cast<MagnetSource&>(copy.source(2)).setPose(Pose::at({1, 1, 1}));
  EXPECT_EQ(set.field(xs[0], t), set.clone()->field(xs[0], t));
  EXPECT_NE(copy.field(xs[0], t), set.field(xs[0], t));

  const std::string d = set.describe();
  expectContains(d, {"5 field sources", "[0] uniform", "[1] point dipole", "[2] sphere",
                     "[3] cuboid", "[4] cylinder"});
  expectContains(thrownMessage([&] { set.add(std::unique_ptr<FieldSource>()); }), {"null"});
  expectContains(thrownMessage([&] { set.source(7); }), {"7", "size 5"});
}

TEST(FieldSourceSet, ConcurrentAccumulationMatchesSerial) {
  FieldSourceSet set;
  set.add(CuboidMagnet(Pose{}, kCuboidHalf, kCuboidM));
  set.add(CylinderMagnet(Pose::at({0.05, 0, 0}), kCylR, kCylL, {0, 0, kCylM}));
  std::vector<Vec3d> xs;
  std::mt19937 rng(31);
  for (int n = 0; n < 4000; ++n) xs.push_back(randomUnit(rng) * (0.03 + 1e-5 * n));
  std::vector<Vec3d> serial(xs.size()), parallel(xs.size());
  set.accumulateField(xs.data(), xs.size(), 0.0, serial.data());
  std::vector<std::thread> threads;
  const std::size_t chunk = xs.size() / 4;
  for (int k = 0; k < 4; ++k)
    threads.emplace_back([&, k] {
      set.accumulateField(xs.data() + k * chunk, chunk, 0.0, parallel.data() + k * chunk);
    });
  for (auto& th : threads) th.join();
  for (std::size_t n = 0; n < xs.size(); ++n) EXPECT_EQ(serial[n], parallel[n]) << n;
}

