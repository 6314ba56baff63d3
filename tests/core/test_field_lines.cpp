// Field lines against closed forms: a point dipole's lines r = L sin^2(theta),
// a sphere magnet's (exact dipole outside, uniform inside) lines tangent to
// the exact B at every vertex, closing through the magnet or leaving the
// domain, and no two lines closer than a bound.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/sources/cuboid_magnet.h"
#include "lodestone/core/sources/point_dipole.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone/core/stage/field_lines.h"
#include "lodestone/core/stage/induction_field.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/core/field/material.h"

using namespace lodestone;

namespace {

FieldLineSettings boxSettings(double half) {
  FieldLineSettings s;
  s.domainMin = {-half, -half, -half};
  s.domainMax = {half, half, half};
  return s;
}

/// Angle (rad) between the line's tangent at interior vertex i (the
/// second-order three-point derivative over chord length) and `b`.
double tangentError(const std::vector<Vec3d>& p, std::size_t i, const Vec3d& b) {
  const double h1 = norm(p[i] - p[i - 1]), h2 = norm(p[i + 1] - p[i]);
  const Vec3d t = (h2 / (h1 * (h1 + h2))) * (p[i] - p[i - 1]) * 1.0 + (h1 / (h2 * (h1 + h2))) * (p[i + 1] - p[i]);
  // (the three-point formula written as weighted backward and forward chords)
  const double c = dot(t, b) / (norm(t) * norm(b));
  return std::acos(std::clamp(c, -1.0, 1.0));
}

SphereMagnet sphereMagnet() { return SphereMagnet(Pose::at({0, 0, 0}), 0.01, {0, 0, 8e5}); }

}  // namespace

TEST(FieldLines, DipoleLineIsRofLSinSquaredTheta) {
  const PointDipole dipole({0, 0, 0}, {0, 0, 1.0});
  const InductionField B(dipole, 0.0);
  const double L = 0.05;
  FieldLineSettings s = boxSettings(0.1);
  const FieldLine line = traceFieldLine(B, {L * std::cos(0.3), L * std::sin(0.3), 0.0}, s);
  ASSERT_GT(line.points.size(), 50u);
  EXPECT_FALSE(line.closed);
  double worst = 0, worstTangent = 0;
  std::size_t checked = 0;
  // From the seed out both ways until the line reaches the dipole (a point
  // dipole's line goes on through its centre, along the axis).
  const std::size_t seed = std::size_t(std::find(line.points.begin(), line.points.end(), line.seed) - line.points.begin());
  ASSERT_LT(seed, line.points.size());
  for (const int dir : {-1, 1})
    for (std::size_t i = seed; i > 0 && i + 1 < line.points.size(); i += dir) {
      const Vec3d& x = line.points[i];
      const double r = norm(x);
      if (r < 0.05 * L) break;
      const double sinTheta = std::hypot(x.x, x.y) / r;
      worst = std::max(worst, std::fabs(r - L * sinTheta * sinTheta) / L);
      // The line stays in the plane of its seed (azimuth 0.3 rad).
      EXPECT_NEAR(std::atan2(x.y, x.x), 0.3, 1e-6) << i;
      worstTangent = std::max(worstTangent, tangentError(line.points, i, B(x)));
      ++checked;
    }
  std::printf("dipole line: %zu vertices, max |r - L sin^2| / L = %.3g, max tangent error %.3g rad\n", checked, worst,
              worstTangent);
  EXPECT_GT(checked, 50u);
  EXPECT_LT(worst, 1e-6);
  EXPECT_LT(worstTangent, 1e-3);
}

TEST(FieldLines, SphereMagnetLinesFollowBCloseOrLeaveAndDoNotCross) {
  const SphereMagnet magnet = sphereMagnet();
  const InductionField B(magnet, 0.0);
  FieldLineSettings s = boxSettings(0.06);
  const double spacing = std::sqrt(4 * kPi * 0.01 * 0.01 / 40);  // seed spacing on the sphere, m
  s.separation = 0.3 * spacing;
  const std::vector<Vec3d> seeds = magnetSurfaceSeeds(magnet, 40, 2e-4);
  ASSERT_EQ(seeds.size(), 40u);
  const std::vector<FieldLine> lines = traceFieldLines(B, seeds, s);
  ASSERT_GE(lines.size(), 15u);
  std::size_t closed = 0, vertices = 0, kinks = 0;
  double worstTangent = 0;
  for (const FieldLine& line : lines) {
    EXPECT_TRUE(line.endEnd == FieldLineEnd::Closed || line.endEnd == FieldLineEnd::LeftDomain)
        << fieldLineEndName(line.endEnd);
    EXPECT_TRUE(line.startEnd == FieldLineEnd::Closed || line.startEnd == FieldLineEnd::LeftDomain)
        << fieldLineEndName(line.startEnd);
    if (line.closed) {
      ++closed;
      EXPECT_EQ(line.points.front(), line.points.back());
    } else {
      // Both ends on the domain box.
      for (const Vec3d& e : {line.points.front(), line.points.back()})
        EXPECT_NEAR(std::max({std::fabs(e.x), std::fabs(e.y), std::fabs(e.z)}), 0.06, 1e-15);
    }
    const auto& p = line.points;
    for (std::size_t i = 1; i + 1 < p.size(); ++i) {
      // B's direction has a kink on the magnet's surface (its tangential
      // part jumps with M): skip vertices whose stencil touches or straddles it.
      const double r0 = norm(p[i - 1]) - 0.01, r1 = norm(p[i]) - 0.01, r2 = norm(p[i + 1]) - 0.01;
      if (std::min({std::fabs(r0), std::fabs(r1), std::fabs(r2)}) < 1e-6 || r0 * r1 < 0 || r1 * r2 < 0) {
        ++kinks;
        continue;
      }
      worstTangent = std::max(worstTangent, tangentError(p, i, B(p[i])));
      ++vertices;
    }
  }
  EXPECT_GE(closed, lines.size() / 2);
  // Distinct lines' segments: the smallest distance between them.
  double closest = 1e9;
  for (std::size_t a = 0; a < lines.size(); ++a)
    for (std::size_t b = a + 1; b < lines.size(); ++b) {
      const auto &p = lines[a].points, &q = lines[b].points;
      for (std::size_t i = 0; i + 1 < p.size(); ++i) {
        Vec3d lo = p[i], hi = p[i];
        for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], p[i + 1][c]), hi[c] = std::max(hi[c], p[i + 1][c]);
        for (std::size_t j = 0; j + 1 < q.size(); ++j) {
          bool far = false;
          for (int c = 0; c < 3; ++c)
            if (std::min(q[j][c], q[j + 1][c]) > hi[c] + closest || std::max(q[j][c], q[j + 1][c]) < lo[c] - closest)
              far = true;
          if (!far) closest = std::min(closest, segmentDistance(p[i], p[i + 1], q[j], q[j + 1]));
        }
      }
    }
  EXPECT_LT(kinks, vertices / 5);
  std::printf("sphere magnet: %zu lines (%zu closed), %zu vertices (%zu skipped at the surface), max tangent error %.3g rad, closest lines %.3g m "
              "(seed spacing %.3g m)\n",
              lines.size(), closed, vertices, kinks, worstTangent, closest, spacing);
  EXPECT_LT(worstTangent, 1e-3);
  EXPECT_GT(closest, 0.1 * spacing);
  // A seed on a kept line's middle is dropped: its line would coincide.
  std::vector<Vec3d> again = seeds;
  again.push_back(lines[0].points[lines[0].points.size() / 2]);
  EXPECT_EQ(traceFieldLines(B, again, s).size(), lines.size());
  s.separation = 0;
  EXPECT_EQ(traceFieldLines(B, again, s).size(), again.size());
}

TEST(FieldLines, ClosedLineReturnsToItsSeedThroughTheMagnet) {
  // A seed just outside the equator... of a cuboid magnet: the line loops
  // around and back through the body.
  const CuboidMagnet magnet(Pose::at({0, 0, 0}), {0.005, 0.005, 0.01}, {0, 0, 1e6});
  const InductionField B(magnet, 0.0);
  FieldLineSettings s = boxSettings(0.1);
  const FieldLine line = traceFieldLine(B, {0.0051, 0.0, 0.009}, s);
  EXPECT_TRUE(line.closed) << fieldLineEndName(line.endEnd);
  // It passes through the magnet's body (where B points along +z).
  bool through = false;
  for (const Vec3d& x : line.points) through |= std::fabs(x.x) < 0.005 && std::fabs(x.z) < 0.005;
  EXPECT_TRUE(through);
  // A short line cap ends it early instead.
  s.maxLength = 0.005;
  const FieldLine capped = traceFieldLine(B, {0.0051, 0.0, 0.009}, s);
  EXPECT_FALSE(capped.closed);
  EXPECT_EQ(capped.endEnd, FieldLineEnd::LengthCap);
  EXPECT_LT(capped.length(), 2 * 0.005 + 2 * 0.002);
}

TEST(FieldLines, InductionFieldAddsTheInterpolatedMaterialPart) {
  const SphereMagnet magnet = sphereMagnet();
  GridSpec g;
  g.origin = {-0.02, -0.02, -0.02};
  g.dx = 0.005;
  g.dims = {9, 9, 9};
  DenseGrid<Vec3d> part(g);
  for (int k = 0; k < 9; ++k)
    for (int j = 0; j < 9; ++j)
      for (int i = 0; i < 9; ++i) {
        const Vec3d x = g.nodePosition(i, j, k);
        part(i, j, k) = {0.1 * x.y, 2.0 * x.z, -x.x + 0.001};  // linear: trilinear interpolation is exact
      }
  const InductionField B(magnet, 0.0, part);
  const Vec3d x{0.0123, -0.0071, 0.0033};
  const Vec3d expected = Vec3d{0.1 * x.y, 2.0 * x.z, -x.x + 0.001} + kMu0 * magnet.field(x, 0);
  EXPECT_LT(norm(B(x) - expected), 1e-12);
  // Outside the grid only the sources remain; inside the magnet B = mu0 (H + M).
  const Vec3d far{0.03, 0, 0};
  EXPECT_EQ(B(far), kMu0 * magnet.field(far, 0));
  const Vec3d centre{0, 0, 0};
  EXPECT_NEAR(B.sourcesPart(centre).z, kMu0 * (2.0 / 3.0) * 8e5, 1e-9);
}

TEST(FieldLines, StageFieldTakesTheSourcesAtTheSolveTime) {
  // A field ramped from 0 (t = 0) to 1e4 A/m (t = 1 s); the stage solved at
  // t = 0 with no material: at t = 1 s the induction is the sources' alone.
  GridSpec g;
  g.origin = {-0.05, -0.05, -0.05};
  g.dx = 0.01;
  g.dims = {11, 11, 11};
  MagneticForceStage stage(g, paperMaterial());
  const UniformField ramped({0, 0, 1e4}, TimeProfile::ramp(0.0, 1.0));
  DenseGrid<double> empty(g, 0.0);
  stage.runOnDensity(empty.view(), ramped, 0.0);
  EXPECT_EQ(stage.time(), 0.0);
  const InductionField B = InductionField::ofStage(stage, ramped, 1.0);
  EXPECT_NEAR(B({0.012, -0.003, 0.02}).z, kMu0 * 1e4, 1e-12);
  EXPECT_NEAR(norm(B.materialPart({0.012, -0.003, 0.02})), 0.0, 1e-12);
}

TEST(FieldLines, SeedsLieOnTheSurfaceAndSpreadEvenly) {
  const CuboidMagnet magnet(Pose::fromAxisAngle({0.01, 0, 0}, {1, 0, 0}, 0.4), {0.005, 0.01, 0.003}, {0, 0, 1e6});
  const std::vector<Vec3d> seeds = magnetSurfaceSeeds(magnet, 30, 1e-4);
  ASSERT_EQ(seeds.size(), 30u);
  double closest = 1e9;
  for (std::size_t a = 0; a < seeds.size(); ++a) {
    Vec3d n;
    EXPECT_NEAR(magnet.surfaceDepth(magnet.pose().toLocal(seeds[a]), n), -1e-4, 1e-9);
    for (std::size_t b = a + 1; b < seeds.size(); ++b) closest = std::min(closest, norm(seeds[a] - seeds[b]));
  }
  // Area 2 (ab + bc + ca) = 2 (2e-4 + 1.2e-4 + 0.6e-4) m^2 = 7.6e-4 m^2 over 30
  // points: a spacing of about 5 mm; evenly spread points keep well apart.
  EXPECT_GT(closest, 2.5e-3);
  // A ball of material points: boundary seeds lie near its surface.
  std::vector<Vec3d> ball;
  for (int k = -20; k <= 20; ++k)
    for (int j = -20; j <= 20; ++j)
      for (int i = -20; i <= 20; ++i)
        if (i * i + j * j + k * k <= 400) ball.push_back({i * 5e-4, j * 5e-4, k * 5e-4});
  const std::vector<Vec3d> b = pointCloudBoundarySeeds(ball.data(), ball.size(), 1e-3, 20);
  ASSERT_EQ(b.size(), 20u);
  for (const Vec3d& p : b) {
    EXPECT_GT(norm(p), 0.01 - 1.5e-3);
    EXPECT_LT(norm(p), 0.01 + 1e-9);
  }
  EXPECT_THROW(magnetSurfaceSeeds(magnet, 3, -1.0), InvalidArgument);
}

TEST(FieldLines, SettingsAreValidated) {
  const PointDipole dipole({0, 0, 0}, {0, 0, 1.0});
  const InductionField B(dipole, 0.0);
  FieldLineSettings s = boxSettings(0.1);
  EXPECT_THROW(traceFieldLine(B, {0.2, 0, 0}, s), InvalidArgument);  // seed outside
  s.maxTurn = 0;
  EXPECT_THROW(traceFieldLine(B, {0.05, 0, 0}, s), InvalidArgument);
  s = boxSettings(0.1);
  s.domainMax.x = -0.2;
  EXPECT_THROW(traceFieldLine(B, {0.05, 0, 0}, s), InvalidArgument);
}
