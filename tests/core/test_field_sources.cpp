// Applied-field sources: time profiles, uniform field, point dipole, sphere,
// cuboid and cylinder magnets, and their superposition. Closed forms are
// checked against independent computations: brute-force quadrature of the
// surface-charge Coulomb integral, the dipole far field, the magnetostatic
// jump conditions across faces, curl H = div H = 0 by central differences,
// and reference values of the elliptic integrals (mpmath, 30 digits).
#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/sources/cuboid_magnet.h"
#include "lodestone/core/sources/cylinder_magnet.h"
#include "lodestone/core/sources/elliptic_integral.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/sources/field_source_set.h"
#include "lodestone/core/sources/magnet_source.h"
#include "lodestone/core/sources/point_dipole.h"
#include "lodestone/core/base/pose.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone/core/sources/time_profile.h"
#include "lodestone/core/sources/uniform_field.h"

using namespace lodestone;

namespace {

// ---------------------------------------------------------------- helpers --

// Message of the InvalidArgument thrown by f, or a marker when none is thrown.
template <typename F>
std::string thrownMessage(F&& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "<no InvalidArgument thrown>";
}

void expectContains(const std::string& msg, std::initializer_list<const char*> parts) {
  for (const char* p : parts)
    EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
}

double relErr(const Vec3d& a, const Vec3d& ref) { return norm(a - ref) / norm(ref); }

// Gauss-Legendre nodes and weights on [-1, 1] (Newton on P_n).
struct Rule {
  std::vector<double> x, w;
};
Rule gaussLegendre(int n) {
  Rule r;
  for (int i = 0; i < n; ++i) {
    double z = std::cos(kPi * (i + 0.75) / (n + 0.5));
    double dp = 0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1, p1 = z;
      for (int j = 2; j <= n; ++j) {
        const double p2 = ((2.0 * j - 1) * z * p1 - (j - 1.0) * p0) / j;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1);
      const double dz = p1 / dp;
      z -= dz;
      if (std::fabs(dz) < 1e-16) break;
    }
    r.x.push_back(z);
    r.w.push_back(2.0 / ((1 - z * z) * dp * dp));
  }
  return r;
}

// Composite Gauss-Legendre rule on [lo, hi]: `panels` panels of `order` points.
Rule composite(double lo, double hi, int panels, int order) {
  const Rule g = gaussLegendre(order);
  Rule r;
  const double h = (hi - lo) / panels;
  for (int p = 0; p < panels; ++p)
    for (int i = 0; i < order; ++i) {
      r.x.push_back(lo + h * (p + 0.5 * (g.x[i] + 1)));
      r.w.push_back(0.5 * h * g.w[i]);
    }
  return r;
}

// Coulomb field (A/m) at x of the rectangle centre + s e1 + t e2 (|s| <= a,
// |t| <= b) carrying surface charge sigma (A/m): sigma/(4 pi) int (x-y)/|x-y|^3 dA.
Vec3d rectangleQuadrature(const Vec3d& x, const Vec3d& centre, const Vec3d& e1, double a,
                          const Vec3d& e2, double b, double sigma) {
  const Rule rs = composite(-a, a, 24, 10), rt = composite(-b, b, 24, 10);
  Vec3d H;
  for (std::size_t i = 0; i < rs.x.size(); ++i)
    for (std::size_t j = 0; j < rt.x.size(); ++j) {
      const Vec3d d = x - (centre + rs.x[i] * e1 + rt.x[j] * e2);
      const double r = norm(d);
      H += d * (rs.w[i] * rt.w[j] / (r * r * r));
    }
  return H * (sigma / (4 * kPi));
}

// Field of a cuboid (half-sizes h, body magnetization M) placed with rotation
// R (columns = body axes in world) at p: the six charged faces, sigma = M.n.
Vec3d cuboidQuadrature(const Vec3d& h, const Vec3d& M, const Mat3d& R, const Vec3d& p,
                       const Vec3d& x) {
  Vec3d axis[3];
  for (int k = 0; k < 3; ++k) axis[k] = {R(0, k), R(1, k), R(2, k)};
  Vec3d H;
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    for (int s = -1; s <= 1; s += 2)
      H += rectangleQuadrature(x, p + (s * h[k]) * axis[k], axis[i], h[i], axis[j], h[j], s * M[k]);
  }
  return H;
}

// Field of a disc of radius a in the plane z = zc (axis e_z) with charge sigma.
Vec3d discQuadrature(const Vec3d& x, double zc, double a, double sigma) {
  const Rule rr = composite(0, a, 16, 8);
  const int nphi = 512;  // trapezoid: spectrally accurate for the periodic angle
  Vec3d H;
  for (std::size_t i = 0; i < rr.x.size(); ++i)
    for (int k = 0; k < nphi; ++k) {
      const double phi = 2 * kPi * k / nphi;
      const Vec3d y{rr.x[i] * std::cos(phi), rr.x[i] * std::sin(phi), zc};
      const Vec3d d = x - y;
      const double r = norm(d);
      H += d * (rr.w[i] * rr.x[i] * (2 * kPi / nphi) / (r * r * r));
    }
  return H * (sigma / (4 * kPi));
}

// Axial cylinder: charges +M on z = +L and -M on z = -L.
Vec3d cylinderQuadrature(double R, double L, double M, const Vec3d& x) {
  return discQuadrature(x, L, R, M) + discQuadrature(x, -L, R, -M);
}

// Independent dipole formula (no unit vector): 3 (m.r) r / r^5 - m / r^3, / 4 pi.
Vec3d dipoleReference(const Vec3d& m, const Vec3d& r) {
  const double d2 = norm2(r), d = std::sqrt(d2);
  return (r * (3 * dot(m, r) / (d2 * d2 * d)) - m / (d2 * d)) / (4 * kPi);
}

// Rodrigues rotation matrix about a unit axis.
Mat3d rotation(Vec3d axis, double angle) {
  axis = axis / norm(axis);
  const double c = std::cos(angle), s = std::sin(angle);
  Mat3d K;
  K(0, 1) = -axis.z;
  K(0, 2) = axis.y;
  K(1, 0) = axis.z;
  K(1, 2) = -axis.x;
  K(2, 0) = -axis.y;
  K(2, 1) = axis.x;
  Mat3d R = Mat3d::identity();
  const Mat3d K2 = K * K;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R(i, j) += s * K(i, j) + (1 - c) * K2(i, j);
  return R;
}

// Central-difference divergence and curl of a field at x with step s (m).
struct DivCurl {
  double div;
  Vec3d curl;
};
template <typename F>
DivCurl divCurl(F&& H, const Vec3d& x, double s) {
  Vec3d d[3];  // d[j] = dH/dx_j
  for (int j = 0; j < 3; ++j) {
    Vec3d e;
    e[j] = s;
    d[j] = (H(x + e) - H(x - e)) / (2 * s);
  }
  return {d[0].x + d[1].y + d[2].z, {d[1].z - d[2].y, d[2].x - d[0].z, d[0].y - d[1].x}};
}

Vec3d randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> g;
  Vec3d v{g(rng), g(rng), g(rng)};
  return v / norm(v);
}

// Signed distance from x to the surface of an axis-aligned box of half-sizes
// h: positive outside, negative inside.
double boxSurfaceDistance(const Vec3d& x, const Vec3d& h) {
  Vec3d out;
  double inside = 1e300;
  for (int k = 0; k < 3; ++k) {
    const double q = std::fabs(x[k]) - h[k];
    out[k] = std::fmax(q, 0.0);
    inside = std::fmin(inside, -q);
  }
  const double o = norm(out);
  return o > 0 ? o : -inside;
}

const Vec3d kCuboidHalf{0.01, 0.015, 0.006};  // m
const Vec3d kCuboidM{3.0e5, -1.2e5, 8.0e5};   // A/m, body frame

}  // namespace

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

// ---------------------------------------------------------- cuboid magnet --

TEST(CuboidMagnet, MatchesQuadratureOfTheSurfaceChargeIntegral) {
  const CuboidMagnet cub(Pose{}, kCuboidHalf, kCuboidM);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> U(-1, 1);
  double worst = 0;
  int outside = 0, inside = 0;
  while (outside < 40 || inside < 20) {
    const Vec3d x{2.5 * kCuboidHalf.x * U(rng), 2.5 * kCuboidHalf.y * U(rng),
                  2.5 * kCuboidHalf.z * U(rng)};
    // Keep away from the faces so that the quadrature converges.
    const double d = boxSurfaceDistance(x, kCuboidHalf);
    if (std::fabs(d) < 0.25 * kCuboidHalf.z) continue;
    int& count = d > 0 ? outside : inside;
    if (count >= (d > 0 ? 40 : 20)) continue;
    ++count;
    const Vec3d ref = cuboidQuadrature(kCuboidHalf, kCuboidM, Mat3d::identity(), {}, x);
    worst = std::fmax(worst, relErr(cub.field(x, 0.0), ref));
  }
  EXPECT_GT(inside, 3);
  EXPECT_GT(outside, 3);
  EXPECT_LT(worst, 1e-11);
  RecordProperty("cuboid_vs_quadrature_max_rel_error", std::to_string(worst));
  std::printf("cuboid vs quadrature: max rel error %.3e over %d inside, %d outside points\n", worst,
              inside, outside);
}

TEST(CuboidMagnet, RotatedAndTranslatedPoseMatchesQuadrature) {
  const Mat3d R = rotation({1, -2, 0.5}, 0.7);
  const Vec3d p{0.05, -0.02, 0.1};
  const CuboidMagnet cub(Pose{p, R}, kCuboidHalf, kCuboidM);
  std::mt19937 rng(2);
  double worst = 0;
  for (int n = 0; n < 20; ++n) {
    const Vec3d x = p + randomUnit(rng) * (norm(kCuboidHalf) * (1.3 + n * 0.2));
    const Vec3d ref = cuboidQuadrature(kCuboidHalf, kCuboidM, R, p, x);
    worst = std::fmax(worst, relErr(cub.field(x, 0.0), ref));
  }
  EXPECT_LT(worst, 1e-11);
  // Magnetization and moment are rotated into the world frame.
  EXPECT_LT(relErr(cub.magnetization(p, 0.0), R * kCuboidM), 1e-15);
  EXPECT_LT(relErr(cub.moment(0.0), R * kCuboidM * cub.volume()), 1e-15);
  EXPECT_EQ(cub.magnetization(p + R * (kCuboidHalf * 1.01), 0.0), Vec3d{});
}

TEST(CuboidMagnet, QuarterTurnEqualsTheSwappedBox) {
  // Rotating by 90 degrees about z maps body x to world y: the same magnet as an
  // axis-aligned box with half-sizes (hy, hx, hz) and M = (-My, Mx, Mz).
  const Vec3d h = kCuboidHalf, M = kCuboidM;
  const CuboidMagnet turned(Pose::fromAxisAngle({0.01, 0.02, 0.03}, {0, 0, 1}, kPi / 2), h, M);
  const CuboidMagnet swapped(Pose::at({0.01, 0.02, 0.03}), {h.y, h.x, h.z}, {-M.y, M.x, M.z});
  std::mt19937 rng(4);
  for (int n = 0; n < 50; ++n) {
    const Vec3d x = Vec3d{0.01, 0.02, 0.03} + randomUnit(rng) * (0.005 + 0.001 * n);
    EXPECT_LT(relErr(turned.field(x, 0.0), swapped.field(x, 0.0)), 1e-12) << n;
  }
}

TEST(CuboidMagnet, CentreFieldIsTheTwoFaceClosedForm) {
  // A cube: -M/3 exactly by symmetry, for any direction of M.
  const CuboidMagnet cube(Pose{}, {0.01, 0.01, 0.01}, kCuboidM);
  EXPECT_LT(relErr(cube.field({0, 0, 0}, 0.0), kCuboidM * (-1.0 / 3.0)), 1e-14);
  // A cuboid: H_k(0) = -(2 M_k / pi) atan(h_i h_j / (h_k |h|)).
  const CuboidMagnet cub(Pose{}, kCuboidHalf, kCuboidM);
  const Vec3d h = kCuboidHalf;
  Vec3d ref;
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    ref[k] = -2 * kCuboidM[k] / kPi * std::atan(h[i] * h[j] / (h[k] * norm(h)));
  }
  EXPECT_LT(relErr(cub.field({0, 0, 0}, 0.0), ref), 1e-14);
}

TEST(CuboidMagnet, FarFieldTendsToTheDipoleAsSizeOverDistanceSquared) {
  const CuboidMagnet cub(Pose{}, kCuboidHalf, kCuboidM);
  const Vec3d m = kCuboidM * cub.volume();
  const double s = norm(kCuboidHalf);
  const Vec3d u = Vec3d{0.3, -0.5, 0.8} / norm(Vec3d{0.3, -0.5, 0.8});
  double previous = 0;
  for (double ratio : {5.0, 10.0, 20.0, 40.0, 80.0}) {
    const double e = relErr(cub.field(u * (ratio * s), 0.0), dipoleReference(m, u * (ratio * s)));
    EXPECT_LT(e, 2.0 / (ratio * ratio)) << ratio;
    if (previous > 0) {
      EXPECT_GT(previous / e, 3.5) << ratio;  // second order: ~4 per doubling
      EXPECT_LT(previous / e, 4.5) << ratio;
    }
    previous = e;
  }
}

TEST(CuboidMagnet, FarFieldExpansionJoinsTheClosedFormAndStaysFinite) {
  const CuboidMagnet cub(Pose{}, kCuboidHalf, kCuboidM);
  const double r0 = CuboidMagnet::kFarFieldRadii * norm(kCuboidHalf);
  std::mt19937 rng(9);
  for (int n = 0; n < 50; ++n) {
    const Vec3d u = randomUnit(rng);
    const Vec3d below = cub.field(u * (r0 * (1 - 1e-12)), 0.0),
                above = cub.field(u * (r0 * (1 + 1e-12)), 0.0);
    EXPECT_LT(relErr(below, above), 1e-8) << n;
  }
  for (double r : {1e3, 1e10, 1e100, 1e200, 1e300}) {
    const Vec3d H = cub.field(Vec3d{1, 2, -3} * r, 0.0);
    EXPECT_TRUE(isFinite(H)) << r;
  }
  const Vec3d far{0, 0, 1e3};
  EXPECT_LT(relErr(cub.field(far, 0.0), dipoleReference(kCuboidM * cub.volume(), far)), 1e-9);
}

TEST(CuboidMagnet, JumpConditionsAcrossEveryFace) {
  const CuboidMagnet cub(Pose{}, kCuboidHalf, kCuboidM);
  const Vec3d& h = kCuboidHalf;
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> U(-0.9, 0.9);
  const double tol = 1e-6 * norm(kCuboidM);
  for (int k = 0; k < 3; ++k)
    for (int s = -1; s <= 1; s += 2)
      for (int n = 0; n < 10; ++n) {
        Vec3d nrm;
        nrm[k] = s;
        Vec3d x{h.x * U(rng), h.y * U(rng), h.z * U(rng)};
        x[k] = s * h[k];
        Vec3d xin = x, xout = x;
        xin[k] -= s * 1e-9 * h[k];
        xout[k] += s * 1e-9 * h[k];
        const Vec3d Hin = cub.field(xin, 0.0), Hout = cub.field(xout, 0.0);
        EXPECT_NEAR(dot(Hin + kCuboidM, nrm), dot(Hout, nrm), tol);  // normal B
        EXPECT_NEAR(dot(Hout - Hin, nrm), dot(kCuboidM, nrm), tol);  // normal H jumps by M.n
        const Vec3d dt = (Hout - Hin) - dot(Hout - Hin, nrm) * nrm;  // tangential H
        EXPECT_LT(norm(dt), tol);
        // Exactly on the face: the mean of the two sides.
        EXPECT_LT(norm(cub.field(x, 0.0) - (Hin + Hout) * 0.5), tol);
        EXPECT_EQ(cub.magnetization(xin, 0.0), kCuboidM);
        EXPECT_EQ(cub.magnetization(xout, 0.0), Vec3d{});
      }
}

TEST(CuboidMagnet, CurlAndDivergenceVanishAwayFromTheFaces) {
  const CuboidMagnet cub(Pose::fromAxisAngle({0.002, 0, -0.001}, {1, 1, 0}, 0.3), kCuboidHalf,
                         kCuboidM);
  auto H = [&](const Vec3d& x) { return cub.field(x, 0.0); };
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> U(-3, 3);
  int checked = 0;
  double worst = 0;
  while (checked < 60) {
    const Vec3d xb{kCuboidHalf.x * U(rng), kCuboidHalf.y * U(rng), kCuboidHalf.z * U(rng)};
    const double d = std::fabs(boxSurfaceDistance(xb, kCuboidHalf));
    if (d < 0.3 * kCuboidHalf.z) continue;
    ++checked;
    const Vec3d x = cub.pose().toWorld(xb);
    const DivCurl dc = divCurl(H, x, 2e-4 * d);
    const double scale = norm(H(x)) / d + norm(kCuboidM) * 1e-3 / d;
    worst = std::fmax(worst, std::fmax(std::fabs(dc.div), norm(dc.curl)) / scale);
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(CuboidMagnet, FiniteOnEdgesCornersAndFaces) {
  const CuboidMagnet cub(Pose{}, kCuboidHalf, kCuboidM);
  const Vec3d& h = kCuboidHalf;
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j)
      for (int k = -2; k <= 2; ++k) {
        // Every combination of centre, half-way, face, and beyond: covers the
        // centre, face centres, edges, corners and their extensions.
        const Vec3d x{0.5 * i * h.x, 0.5 * j * h.y, 0.5 * k * h.z};
        for (const Vec3d& y : {x, x * (1 + 1e-15), x * (1 - 1e-15)}) {
          const Vec3d H = cub.field(y, 0.0);
          EXPECT_TRUE(isFinite(H)) << i << j << k;
        }
      }
  // Approaching an edge the field grows only logarithmically.
  const Vec3d edge{h.x, h.y, 0};
  const double near = norm(cub.field(edge * (1 + 1e-6), 0.0));
  const double nearer = norm(cub.field(edge * (1 + 1e-12), 0.0));
  EXPECT_GT(nearer, near);
  EXPECT_LT(nearer, 10 * norm(kCuboidM));
}

TEST(CuboidMagnet, BadInputsThrowNamingTheValue) {
  expectContains(thrownMessage([] {
                   CuboidMagnet(Pose{}, {0.01, -0.02, 0.01}, {0, 0, 1});
                 }),
                 {"-0.02", "in m", "along y"});
  expectContains(thrownMessage([] {
                   CuboidMagnet(Pose{}, {0.01, 0.02, 0.0}, {0, 0, 1});
                 }),
                 {"got 0", "along z"});
  expectContains(
      thrownMessage([] {
        CuboidMagnet(Pose{}, {0.01, 0.01, 0.01}, {0, -std::numeric_limits<double>::infinity(), 1});
      }),
      {"inf", "A/m"});
  Pose skew;
  skew.rotation(0, 1) = 0.5;
  expectContains(thrownMessage([&] {
                   CuboidMagnet(skew, {0.01, 0.01, 0.01}, {0, 0, 1});
                 }),
                 {"orthonormal", "0.5"});
  Pose mirror;
  mirror.rotation(2, 2) = -1;
  expectContains(thrownMessage([&] {
                   CuboidMagnet(mirror, {0.01, 0.01, 0.01}, {0, 0, 1});
                 }),
                 {"det", "-1"});
  CuboidMagnet ok(Pose{}, {0.01, 0.01, 0.01}, {0, 0, 1});
  expectContains(thrownMessage([&] {
                   ok.setPose(Pose::at({0, std::nan(""), 0}));
                 }),
                 {"nan", "(m)"});
  expectContains(ok.describe(), {"cuboid", "0.01", " m", "A/m"});
}

// -------------------------------------------------------- cylinder magnet --

namespace {
const double kCylR = 0.01, kCylL = 0.015, kCylM = 9e5;  // m, m, A/m

double onAxisHz(double z) {
  const double zp = z + kCylL, zm = z - kCylL;
  const double B = 0.5 * kCylM * (zp / std::hypot(zp, kCylR) - zm / std::hypot(zm, kCylR));
  return std::fabs(z) < kCylL ? B - kCylM : B;
}
}  // namespace

TEST(CylinderMagnet, OnAxisClosedFormAndContinuityOffAxis) {
  const CylinderMagnet cyl(Pose{}, kCylR, kCylL, {0, 0, kCylM});
  for (double z : {0.0, 0.3 * kCylL, -0.9 * kCylL, 1.2 * kCylL, -3 * kCylL, 40 * kCylL}) {
    const Vec3d H = cyl.field({0, 0, z}, 0.0);
    EXPECT_EQ(H.x, 0.0);
    EXPECT_EQ(H.y, 0.0);
    EXPECT_NEAR(H.z, onAxisHz(z), 1e-13 * kCylM) << z;
    // Next to the axis the general (elliptic) formula takes over smoothly.
    const Vec3d Hn = cyl.field({1e-9 * kCylR, -2e-9 * kCylR, z}, 0.0);
    EXPECT_NEAR(Hn.z, onAxisHz(z), 1e-12 * kCylM) << z;
    EXPECT_LT(std::hypot(Hn.x, Hn.y), 1e-7 * kCylM) << z;
  }
  // The centre: demagnetizing field M (L / sqrt(L^2 + R^2) - 1).
  EXPECT_NEAR(cyl.field({0, 0, 0}, 0.0).z, kCylM * (kCylL / std::hypot(kCylL, kCylR) - 1),
              1e-13 * kCylM);
}

TEST(CylinderMagnet, MatchesQuadratureOfTheEndCapCharges) {
  const CylinderMagnet cyl(Pose{}, kCylR, kCylL, {0, 0, kCylM});
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> U(-1, 1);
  double worst = 0;
  int inside = 0, outside = 0;
  while (inside < 20 || outside < 40) {
    const Vec3d x{2.5 * kCylR * U(rng), 2.5 * kCylR * U(rng), 2.5 * kCylL * U(rng)};
    const double rho = std::hypot(x.x, x.y);
    // The charges sit on the caps only; keep away from the cap planes.
    if (std::fabs(std::fabs(x.z) - kCylL) < 0.25 * kCylR) continue;
    const bool in = rho < kCylR && std::fabs(x.z) < kCylL;
    int& count = in ? inside : outside;
    if (count >= (in ? 20 : 40)) continue;
    ++count;
    const Vec3d ref = cylinderQuadrature(kCylR, kCylL, kCylM, x);
    worst = std::fmax(worst, relErr(cyl.field(x, 0.0), ref));
  }
  EXPECT_GT(inside, 3);
  EXPECT_GT(outside, 3);
  EXPECT_LT(worst, 1e-12);
  RecordProperty("cylinder_vs_quadrature_max_rel_error", std::to_string(worst));
  std::printf("cylinder vs quadrature: max rel error %.3e over %d inside, %d outside points\n",
              worst, inside, outside);
}

TEST(CylinderMagnet, FarFieldTendsToTheDipole) {
  const CylinderMagnet cyl(Pose::at({0.1, 0.2, 0.3}), kCylR, kCylL, {0, 0, kCylM});
  const Vec3d m{0, 0, kCylM * kPi * kCylR * kCylR * 2 * kCylL};
  EXPECT_LT(relErr(cyl.moment(0.0), m), 1e-15);
  const double s = std::hypot(kCylR, kCylL);
  const Vec3d u = Vec3d{0.6, 0.2, -0.5} / norm(Vec3d{0.6, 0.2, -0.5});
  double previous = 0;
  for (double ratio : {5.0, 10.0, 20.0, 40.0, 80.0}) {
    const Vec3d d = u * (ratio * s);
    const double e = relErr(cyl.field(Vec3d{0.1, 0.2, 0.3} + d, 0.0), dipoleReference(m, d));
    EXPECT_LT(e, 2.0 / (ratio * ratio)) << ratio;
    if (previous > 0) {
      EXPECT_GT(previous / e, 3.5) << ratio;
      EXPECT_LT(previous / e, 4.5) << ratio;
    }
    previous = e;
  }
  // Across the switch to the far-field expansion, and at absurd distances.
  const double r0 = CylinderMagnet::kFarFieldRadii * s;
  EXPECT_LT(relErr(cyl.bodyField(u * (r0 * (1 - 1e-12))), cyl.bodyField(u * (r0 * (1 + 1e-12)))),
            1e-8);
  for (double r : {1e10, 1e100, 1e300}) EXPECT_TRUE(isFinite(cyl.field(u * r, 0.0))) << r;
}

TEST(CylinderMagnet, JumpConditionsAtSideWallAndEndCaps) {
  const CylinderMagnet cyl(Pose{}, kCylR, kCylL, {0, 0, kCylM});
  const double tol = 1e-6 * kCylM;
  const Vec3d M{0, 0, kCylM};
  for (double phi : {0.0, 0.7, 2.0, 4.0}) {
    const Vec3d er{std::cos(phi), std::sin(phi), 0};
    // Side wall, away from the rims: M.n = 0, so H is continuous and B_z jumps by mu0 M.
    for (double z : {0.0, 0.5 * kCylL, -0.8 * kCylL}) {
      const Vec3d Hin = cyl.field(er * (kCylR * (1 - 1e-9)) + Vec3d{0, 0, z}, 0.0);
      const Vec3d Hout = cyl.field(er * (kCylR * (1 + 1e-9)) + Vec3d{0, 0, z}, 0.0);
      EXPECT_LT(norm(Hin - Hout), tol) << phi << " " << z;
      EXPECT_NEAR(kMu0 * (Hin.z + kCylM) - kMu0 * Hout.z, kMu0 * kCylM, kMu0 * tol);
      const Vec3d Hon = cyl.field(er * kCylR + Vec3d{0, 0, z}, 0.0);  // exactly on the wall
      EXPECT_LT(norm(Hon - (Hin + Hout) * 0.5), tol);
    }
    // End caps: B_z continuous, H_z jumps by M.n, tangential H continuous.
    for (double rho : {0.0, 0.3 * kCylR, 0.9 * kCylR})
      for (int s = -1; s <= 1; s += 2) {
        const Vec3d base = er * rho;
        const Vec3d Hin = cyl.field(base + Vec3d{0, 0, s * kCylL * (1 - 1e-9)}, 0.0);
        const Vec3d Hout = cyl.field(base + Vec3d{0, 0, s * kCylL * (1 + 1e-9)}, 0.0);
        EXPECT_NEAR(Hin.z + kCylM, Hout.z, tol) << rho << " " << s;
        EXPECT_NEAR(s * (Hout.z - Hin.z), s * kCylM, tol);
        EXPECT_LT(std::hypot(Hout.x - Hin.x, Hout.y - Hin.y), tol);
        const Vec3d Hon = cyl.field(base + Vec3d{0, 0, s * kCylL}, 0.0);
        EXPECT_LT(norm(Hon - (Hin + Hout) * 0.5), tol);
        EXPECT_EQ(cyl.magnetization(base + Vec3d{0, 0, s * kCylL * (1 - 1e-9)}, 0.0), M);
        EXPECT_EQ(cyl.magnetization(base + Vec3d{0, 0, s * kCylL * (1 + 1e-9)}, 0.0), Vec3d{});
      }
  }
}

TEST(CylinderMagnet, CurlAndDivergenceVanishAwayFromTheSurface) {
  const CylinderMagnet cyl(Pose{}, kCylR, kCylL, {0, 0, kCylM});
  auto H = [&](const Vec3d& x) { return cyl.field(x, 0.0); };
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> U(-3, 3);
  int checked = 0;
  double worst = 0;
  while (checked < 60) {
    const Vec3d x{kCylR * U(rng), kCylR * U(rng), kCylL * U(rng)};
    const double dr = std::fabs(std::hypot(x.x, x.y) - kCylR),
                 dz = std::fabs(std::fabs(x.z) - kCylL);
    const double d = std::fmin(dr, dz);
    if (d < 0.2 * kCylR) continue;
    ++checked;
    const DivCurl dc = divCurl(H, x, 2e-4 * d);
    const double scale = norm(H(x)) / d + kCylM * 1e-3 / d;
    worst = std::fmax(worst, std::fmax(std::fabs(dc.div), norm(dc.curl)) / scale);
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(CylinderMagnet, TiltedAxisEqualsTheRotatedField) {
  // Axis along world x (a quarter turn about y maps body z to world x).
  const Vec3d c{0.01, -0.02, 0.005};
  const CylinderMagnet tilted(Pose::fromAxisAngle(c, {0, 1, 0}, kPi / 2), kCylR, kCylL,
                              {0, 0, kCylM});
  const CylinderMagnet upright(Pose{}, kCylR, kCylL, {0, 0, kCylM});
  std::mt19937 rng(14);
  for (int n = 0; n < 30; ++n) {
    const Vec3d d = randomUnit(rng) * (0.004 + 0.002 * n);
    const Vec3d Hb = upright.field({-d.z, d.y, d.x}, 0.0);  // body coordinates of c + d
    const Vec3d ref{Hb.z, Hb.y, -Hb.x};
    EXPECT_LT(norm(tilted.field(c + d, 0.0) - ref), 1e-12 * kCylM) << n;
  }
}

TEST(CylinderMagnet, FiniteOnAxisRimCentreAndWalls) {
  const CylinderMagnet cyl(Pose{}, kCylR, kCylL, {0, 0, kCylM});
  const double rs[] = {
      0.0, 1e-300, 0.5 * kCylR, kCylR * (1 - 1e-16), kCylR, kCylR * (1 + 1e-16), 2 * kCylR};
  const double zs[] = {0.0,   0.5 * kCylL,         kCylL * (1 - 1e-16),
                       kCylL, kCylL * (1 + 1e-16), 2 * kCylL};
  for (double rho : rs)
    for (double z : zs)
      for (int s = -1; s <= 1; s += 2) {
        const Vec3d H = cyl.field({rho * std::cos(1.0), rho * std::sin(1.0), s * z}, 0.0);
        EXPECT_TRUE(isFinite(H)) << rho << " " << z;
      }
  // Near the rim the field grows only logarithmically.
  const double nearer = norm(cyl.field({kCylR * (1 + 1e-12), 0, kCylL}, 0.0));
  EXPECT_GT(nearer, norm(cyl.field({kCylR * (1 + 1e-6), 0, kCylL}, 0.0)));
  EXPECT_LT(nearer, 10 * kCylM);
}

TEST(CylinderMagnet, BadInputsThrowNamingTheValue) {
  expectContains(thrownMessage([] {
                   CylinderMagnet(Pose{}, -0.5, 0.01, {0, 0, 1});
                 }),
                 {"-0.5", "radius", "in m"});
  expectContains(thrownMessage([] {
                   CylinderMagnet(Pose{}, 0.01, 0.0, {0, 0, 1});
                 }),
                 {"half-length", "got 0"});
  expectContains(thrownMessage([] {
                   CylinderMagnet(Pose{}, 0.01, 0.01, {250.0, 0, 1});
                 }),
                 {"transverse", "250", "A/m"});
  expectContains(thrownMessage([] {
                   CylinderMagnet(Pose{}, 0.01, 0.01, {0, 0, std::nan("")});
                 }),
                 {"nan", "A/m"});
}

// ----------------------------------------------- time scaling, superposition --

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
