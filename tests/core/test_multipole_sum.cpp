// The summed block multipoles of the open wall (multipoleSum, on the path
// this CPU takes) against Multipole::potential block by block: random blocks
// around a body, points on a far box, a point at a block's centre, and
// distances outside the fast path's range.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/field/multipole.h"

using namespace lodestone;

namespace {

struct Blocks {
  std::vector<Multipole> list;
  std::vector<double> soa;  // 13 fields x padded
  std::size_t padded = 0;
  MultipoleArrays arrays() const {
    const auto f = [&](int k) { return soa.data() + std::size_t(k) * padded; };
    return {f(0), f(1), f(2), f(3), f(4), f(5), f(6), f(7), f(8), f(9), f(10), f(11), f(12), padded};
  }
};

Blocks randomBlocks(std::size_t count, double scale, unsigned seed) {
  Blocks b;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(-1, 1);
  for (std::size_t i = 0; i < count; ++i) {
    Multipole m;
    m.centre = {scale * U(rng), scale * U(rng), scale * U(rng)};
    m.dipole = {U(rng), U(rng), U(rng)};
    for (auto& row : m.quadrupole)
      for (double& v : row) v = scale * U(rng);
    b.list.push_back(m);
  }
  b.padded = (count + 3) / 4 * 4;
  b.soa.assign(13 * b.padded, 0.0);
  for (std::size_t i = 0; i < count; ++i) {
    const Multipole& m = b.list[i];
    const auto& N = m.quadrupole;
    const double v[13] = {m.centre.x, m.centre.y, m.centre.z, m.dipole.x, m.dipole.y, m.dipole.z,
                          N[0][0],    N[1][1],    N[2][2],    N[0][1] + N[1][0], N[0][2] + N[2][0], N[1][2] + N[2][1],
                          N[0][0] + N[1][1] + N[2][2]};
    for (int f = 0; f < 13; ++f) b.soa[std::size_t(f) * b.padded + i] = v[f];
  }
  return b;
}

double reference(const Blocks& b, const Vec3d& x) {
  double s = 0;
  for (const Multipole& m : b.list) s += m.potential(x);
  return 4.0 * kPi * s;
}

}  // namespace

TEST(MultipoleSum, MatchesTheBlockByBlockPotential) {
  for (double scale : {0.05, 3.0}) {  // cm-sized and metre-sized bodies
    const Blocks b = randomBlocks(37, scale, 3);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> U(-1, 1);
    double worst = 0;
    for (int p = 0; p < 400; ++p) {
      // Points on a box twice the body's size.
      Vec3d x{U(rng), U(rng), U(rng)};
      (&x.x)[p % 3] = p % 2 ? 1.0 : -1.0;
      x = (2.0 * scale) * x;
      const double ref = reference(b, x), got = multipoleSum(b.arrays(), x);
      worst = std::max(worst, std::fabs(got - ref) / std::max(std::fabs(ref), 1e-300));
    }
    EXPECT_LT(worst, 1e-12) << "scale " << scale;
  }
}

TEST(MultipoleSum, APointAtABlockCentreGetsNothingFromIt) {
  const Blocks b = randomBlocks(6, 0.1, 7);
  const Vec3d at = b.list[2].centre;
  Blocks others = b;
  others.list.erase(others.list.begin() + 2);
  const double got = multipoleSum(b.arrays(), at);
  EXPECT_TRUE(std::isfinite(got));
  EXPECT_NEAR(got, reference(others, at), 1e-12 * std::fabs(reference(others, at)));
}

TEST(MultipoleSum, FarAndNearDistancesOutsideTheFastRange) {
  // |r|^2 beyond 1e30 or below 1e-30 m^2 takes the exact division.
  for (double scale : {1e16, 1e-16}) {
    const Blocks b = randomBlocks(8, scale, 9);
    const Vec3d x{2.0 * scale, -1.5 * scale, 1.7 * scale};
    const double ref = reference(b, x), got = multipoleSum(b.arrays(), x);
    EXPECT_NEAR(got, ref, 1e-12 * std::fabs(ref)) << "scale " << scale;
  }
}

TEST(MultipoleField, IsMinusTheGradientOfThePotential) {
  // Central differences of potential() (error ~ h^2 phi''' ~ 1e-9 relative
  // at h = 1e-4 r) against field(), for random blocks with nonsymmetric N.
  const Blocks b = randomBlocks(5, 0.1, 11);
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> U(-1, 1);
  double worst = 0;
  for (const Multipole& m : b.list)
    for (int p = 0; p < 20; ++p) {
      const Vec3d x = m.centre + 0.5 * Vec3d{U(rng), U(rng), U(rng)} + Vec3d{0.3, 0, 0};
      const double h = 1e-4 * norm(x - m.centre);
      Vec3d fd;
      for (int a = 0; a < 3; ++a) {
        Vec3d e;
        e[a] = h;
        fd[a] = -(m.potential(x + e) - m.potential(x - e)) / (2 * h);
      }
      worst = std::max(worst, norm(m.field(x) - fd) / norm(fd));
    }
  EXPECT_LT(worst, 1e-6);
}

TEST(MultipoleField, OfAUniformlyMagnetizedSphereIsItsDipoleField) {
  // Outside a sphere of uniform M the field is exactly that of m = M V
  // (Jackson 5.10); a quadrupole about the centre is zero.
  const double R = 0.02, M = 3e5;
  Multipole m;
  m.centre = {0.1, -0.2, 0.3};
  m.dipole = {0, 0, M * 4.0 / 3.0 * kPi * R * R * R};
  // On the axis at distance d: H = 2 m / (4 pi d^3); on the equator: -m / (4 pi d^3).
  const double d = 0.05;
  EXPECT_NEAR(m.field(m.centre + Vec3d{0, 0, d}).z, 2 * m.dipole.z / (4 * kPi * d * d * d), 1e-12 * M);
  EXPECT_NEAR(m.field(m.centre + Vec3d{d, 0, 0}).z, -m.dipole.z / (4 * kPi * d * d * d), 1e-12 * M);
  EXPECT_NEAR(m.field(m.centre + Vec3d{d, 0, 0}).x, 0.0, 1e-12 * M);
  EXPECT_EQ(norm(m.field(m.centre)), 0.0);
}
