// The record behind the planner's field reuse in the MPM solver
// (mpm/field_reuse.h): the motion test says "reuse" up to its distance and
// "solve" beyond it, the applied-field test the same about its tolerance, at
// values worked out by hand; the samples are every max(1, N/256)-th magnetic
// point; the record follows a reordering of the particles.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "lodestone/core/mpm/field_reuse.h"
#include "lodestone/core/sources/time_profile.h"
#include "lodestone/core/sources/uniform_field.h"

using namespace lodestone;

namespace {

// Points 0 and 2 are magnetic, 1 is not.
const auto kMagnetic = [](std::size_t p) { return p != 1; };

std::vector<Vec3d> threePoints() { return {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}; }

}  // namespace

TEST(MpmFieldReuse, MotionTestReusesUpToTheDistanceAndSolvesBeyondIt) {
  const UniformField H(Vec3d{1000, 0, 0});
  FieldReuse reuse;
  reuse.record(threePoints(), {0, 2}, H, 0.0);
  const double d = 0.5;  // m

  std::vector<Vec3d> x = threePoints();
  EXPECT_TRUE(reuse.pointsWithin(x, kMagnetic, d)) << "nothing moved";

  x[2] = {0, 1, 0.5};  // |dx| = 0.5 = d exactly (0.25 <= 0.25): still reuse
  EXPECT_TRUE(reuse.pointsWithin(x, kMagnetic, d));

  x[2] = {0, 1, 0.51};  // |dx|^2 = 0.2601 > 0.25: solve
  EXPECT_FALSE(reuse.pointsWithin(x, kMagnetic, d));

  x[2] = {3, 1, 4};  // |dx| = sqrt(9 + 16) = 5: reuse at 5 m, solve at 4.9 m
  EXPECT_TRUE(reuse.pointsWithin(x, kMagnetic, 5.0));
  EXPECT_FALSE(reuse.pointsWithin(x, kMagnetic, 4.9)) << "25 > 24.01";
  x[2] = {3, 1, 4.1};  // |dx|^2 = 25.81: solve at 5 m, reuse at 5.1 m (26.01)
  EXPECT_FALSE(reuse.pointsWithin(x, kMagnetic, 5.0));
  EXPECT_TRUE(reuse.pointsWithin(x, kMagnetic, 5.1));

  x = threePoints();
  x[1] = {10, 0, 0};  // the non-magnetic point may move freely
  EXPECT_TRUE(reuse.pointsWithin(x, kMagnetic, d));
  x[0] = {-0.6, 0, 0};  // a magnetic point 0.6 > 0.5 away
  EXPECT_FALSE(reuse.pointsWithin(x, kMagnetic, d));
}

TEST(MpmFieldReuse, AChangedParticleSetOrNoRecordSolves) {
  const UniformField H(Vec3d{1000, 0, 0});
  FieldReuse empty;
  EXPECT_FALSE(empty.pointsWithin(threePoints(), kMagnetic, 1.0)) << "no solve recorded";

  FieldReuse reuse;
  reuse.record(threePoints(), {0, 2}, H, 0.0);
  std::vector<Vec3d> x = threePoints();
  x.push_back({0, 0, 1});  // a particle was added
  EXPECT_FALSE(reuse.pointsWithin(x, kMagnetic, 1.0));
  x.resize(2);  // one was removed
  EXPECT_FALSE(reuse.pointsWithin(x, kMagnetic, 1.0));

  FieldReuse noMagnetic;  // a solve without magnetic points leaves no samples
  noMagnetic.record(threePoints(), {}, H, 0.0);
  EXPECT_TRUE(noMagnetic.samples().empty());
  EXPECT_FALSE(noMagnetic.pointsWithin(threePoints(), kMagnetic, 1.0));
}

TEST(MpmFieldReuse, FieldTestReusesUpToTheToleranceAndSolvesBeyondIt) {
  // H(t) = (1000, 0, 0) A/m * s(t), s ramping from 1 at t = 0 to 1.2 at t = 1 s:
  // the relative change since t = 0 is 0.2 t.
  const UniformField H(Vec3d{1000, 0, 0}, TimeProfile::ramp(0.0, 1.0, 1.0, 1.2));
  FieldReuse reuse;
  reuse.record(threePoints(), {0, 2}, H, 0.0);
  ASSERT_EQ(reuse.fields().size(), 2u);
  EXPECT_DOUBLE_EQ(reuse.fields()[0].x, 1000.0);
  const double tolerance = 0.1;
  EXPECT_TRUE(reuse.fieldWithin(H, 0.0, tolerance)) << "unchanged";
  EXPECT_TRUE(reuse.fieldWithin(H, 0.25, tolerance)) << "0.05 <= 0.1";
  EXPECT_TRUE(reuse.fieldWithin(H, 0.45, tolerance)) << "0.09 <= 0.1";
  EXPECT_FALSE(reuse.fieldWithin(H, 0.55, tolerance)) << "0.11 > 0.1";
  EXPECT_FALSE(reuse.fieldWithin(H, 1.0, tolerance)) << "0.2 > 0.1";
  EXPECT_TRUE(reuse.fieldWithin(H, 1.0, 0.25)) << "0.2 <= 0.25";

  // A change of direction: |(1000, 300, 0) - (1000, 0, 0)| / 1000 = 0.3.
  const UniformField turned(Vec3d{1000, 300, 0});
  EXPECT_FALSE(reuse.fieldWithin(turned, 0.0, 0.29));
  EXPECT_TRUE(reuse.fieldWithin(turned, 0.0, 0.31));
}

TEST(MpmFieldReuse, FieldIsSampledWhereThePointsWereAtTheSolve) {
  const UniformField H(Vec3d{0, 0, 500});
  FieldReuse reuse;
  reuse.record(threePoints(), {0, 2}, H, 0.0);
  // The particles moving does not enter the field test (the motion test sees it).
  EXPECT_TRUE(reuse.fieldWithin(H, 0.0, 0.0));
  EXPECT_EQ(reuse.positions(), threePoints());
}

TEST(MpmFieldReuse, SamplesEveryNOver256thMagneticPoint) {
  const UniformField H(Vec3d{1, 2, 3});
  const auto samplesOf = [&](std::size_t magnetic) {
    std::vector<Vec3d> x(magnetic + 1);
    std::vector<std::uint32_t> index;
    for (std::size_t p = 1; p <= magnetic; ++p) index.push_back(std::uint32_t(p));  // point 0 is not magnetic
    FieldReuse reuse;
    reuse.record(x, index, H, 0.0);
    EXPECT_EQ(reuse.fields().size(), reuse.samples().size());
    return reuse.samples();
  };
  EXPECT_EQ(samplesOf(3), (std::vector<std::uint32_t>{1, 2, 3}));
  EXPECT_EQ(samplesOf(511).size(), 511u);                    // stride 1
  const std::vector<std::uint32_t> s1000 = samplesOf(1000);  // stride 3: indices 1, 4, ..., 1000
  ASSERT_EQ(s1000.size(), 334u);
  EXPECT_EQ(s1000.front(), 1u);
  EXPECT_EQ(s1000[1], 4u);
  EXPECT_EQ(s1000.back(), 1000u);
}

TEST(MpmFieldReuse, RecordFollowsAReorderingOfTheParticles) {
  const UniformField H(Vec3d{1000, 0, 0});
  const std::vector<Vec3d> x = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  FieldReuse reuse;
  reuse.record(x, {1, 3}, H, 0.0);
  ASSERT_EQ(reuse.samples(), (std::vector<std::uint32_t>{1, 3}));

  const std::vector<std::uint32_t> order = {3, 0, 2, 1};  // new p = old order[p]
  reuse.permute(order);
  const std::vector<Vec3d> moved = {{3, 0, 0}, {0, 0, 0}, {2, 0, 0}, {1, 0, 0}};
  EXPECT_EQ(reuse.positions(), moved);
  // Old 1 is new 3, old 3 is new 0: each sample still names its particle.
  EXPECT_EQ(reuse.samples(), (std::vector<std::uint32_t>{3, 0}));
  const auto magneticNow = [](std::size_t p) { return p == 0 || p == 3; };
  EXPECT_TRUE(reuse.pointsWithin(moved, magneticNow, 0.0));

  // An order of another size (particles removed since) leaves the record.
  reuse.permute({1, 0});
  EXPECT_EQ(reuse.positions(), moved);
}
