// Checkpoints of the reference MLS-MPM (mpm_checkpoint.h): a solver restored
// from a checkpoint continues bit for bit like the one that saved it (after
// resetMagneticWarmStart, as the command does), including a magnetic force
// cached between field solves and a sort by cell pending after an emission;
// truncated, corrupted or foreign bytes are
// refused with a message and leave the solver unchanged.
#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/mpm/checkpoint.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/sources/point_dipole.h"
#include "lodestone/core/sources/uniform_field.h"

using namespace lodestone;

namespace {

std::unique_ptr<MpmSolver> makeSolver(int solveInterval, int nodes = 16) {
  MpmSettings st;
  st.grid = GridSpec{{0, 0, 0}, 0.01, {nodes, nodes, nodes}};
  st.magneticSolveInterval = solveInterval;
  auto s = std::make_unique<MpmSolver>(st);
  const std::uint32_t fluid = s->addMaterial(viscousFluid(1.0, 2e5, 2500, paperMaterial()));
  const std::uint32_t solid = s->addMaterial(neoHookeanSolid(1e5, 0.3, 1000, paperMaterial()));
  EmitterSettings e;
  e.particlesPerCell = 8;
  e.jitter = 0.5;
  s->emit(EmitterShape::sphere(Pose::at({0.07, 0.07, 0.06}), 0.025), fluid, e);
  e.velocity = {0.2, 0, 0};
  s->emit(EmitterShape::box(Pose::at({0.07, 0.07, 0.1}), {0.02, 0.02, 0.01}), solid, e);
  s->sources().add(PointDipole({0.075, 0.075, -0.02}, {0, 0, 2.0}));
  return s;
}

void expectSameState(const MpmSolver& a, const MpmSolver& b) {
  const MpmParticles &p = a.particles(), &q = b.particles();
  ASSERT_EQ(p.size(), q.size());
  EXPECT_EQ(a.time(), b.time());
  for (std::size_t i = 0; i < p.size(); ++i) {
    ASSERT_EQ(std::memcmp(&p.x[i], &q.x[i], sizeof(Vec3d)), 0) << "x of particle " << i;
    ASSERT_EQ(std::memcmp(&p.v[i], &q.v[i], sizeof(Vec3d)), 0) << "v of particle " << i;
    ASSERT_EQ(std::memcmp(&p.F[i], &q.F[i], sizeof(Mat3d)), 0) << "F of particle " << i;
    ASSERT_EQ(std::memcmp(&p.C[i], &q.C[i], sizeof(Mat3d)), 0) << "C of particle " << i;
    ASSERT_EQ(p.J[i], q.J[i]);
    ASSERT_EQ(p.id[i], q.id[i]);
  }
}

}  // namespace

TEST(MpmCheckpoint, RestoredSolverContinuesBitForBit) {
  for (const int interval : {0, 7}) {  // once per frame; every 7 substeps (force cached across frames)
    SCOPED_TRACE(interval);
    auto a = makeSolver(interval);
    for (int f = 0; f < 2; ++f) a->advanceFrame(0.004);
    const std::vector<std::uint8_t> bytes = saveMpmCheckpoint(*a, 2, "test scene");
    a->resetMagneticWarmStart();
    auto b = makeSolver(interval);
    const MpmCheckpointInfo info = restoreMpmCheckpoint(*b, bytes.data(), bytes.size(), "test scene");
    EXPECT_EQ(info.frame, 2);
    EXPECT_EQ(info.particles, a->particles().size());
    EXPECT_EQ(info.time, a->time());
    expectSameState(*a, *b);
    for (int f = 0; f < 2; ++f) {
      const MpmFrameReport ra = a->advanceFrame(0.004), rb = b->advanceFrame(0.004);
      EXPECT_EQ(ra.substeps, rb.substeps);
      EXPECT_EQ(ra.magneticReports.size(), rb.magneticReports.size());
    }
    expectSameState(*a, *b);
    // And the next checkpoints are identical bytes.
    EXPECT_TRUE(saveMpmCheckpoint(*a, 4, "t") == saveMpmCheckpoint(*b, 4, "t"));
  }
}

TEST(MpmCheckpoint, ASortPendingAfterAnEmissionIsRestoredWithIt) {
  // A body emitted between frames: the saving solver sorts at its next
  // substep, and so must the restored one, whose own last sort is done.
  auto a = makeSolver(0);
  a->advanceFrame(0.004);
  a->emit(EmitterShape::box(Pose::at({0.1, 0.1, 0.04}), {0.012, 0.012, 0.008}), 1, EmitterSettings{});
  const std::vector<std::uint8_t> bytes = saveMpmCheckpoint(*a, 1, "t");
  a->resetMagneticWarmStart();
  auto b = makeSolver(0);
  b->advanceFrame(0.004);
  restoreMpmCheckpoint(*b, bytes.data(), bytes.size(), "t");
  expectSameState(*a, *b);
  const std::vector<std::uint64_t> saved = a->particles().id;
  a->step(1e-4);  // s; one substep: the order is compared before the interval's sort could align it
  b->step(1e-4);
  ASSERT_NE(a->particles().id, saved) << "no sort happened: the test would be vacuous";
  expectSameState(*a, *b);
}

TEST(MpmCheckpoint, BadBytesAreRefusedAndLeaveTheSolverUnchanged) {
  auto a = makeSolver(0);
  a->advanceFrame(0.004);
  const std::vector<std::uint8_t> good = saveMpmCheckpoint(*a, 1, "scene");
  auto b = makeSolver(0);
  const std::size_t before = b->particles().size();
  const auto refused = [&](std::vector<std::uint8_t> bytes, const std::string& expected, const std::string& tag = "") {
    try {
      restoreMpmCheckpoint(*b, bytes.data(), bytes.size(), tag);
      ADD_FAILURE() << "accepted; expected " << expected;
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
    EXPECT_EQ(b->particles().size(), before);
    EXPECT_EQ(b->time(), 0.0);
  };
  refused({}, "shorter than");
  refused(std::vector<std::uint8_t>(good.begin(), good.begin() + 20), "shorter than");
  refused(std::vector<std::uint8_t>(good.begin(), good.end() - 1), "truncated");
  std::vector<std::uint8_t> flipped = good;
  flipped[flipped.size() / 2] ^= 0x01;
  refused(flipped, "checksum mismatch");
  std::vector<std::uint8_t> magic = good;
  magic[0] = 'X';
  refused(magic, "bad magic");
  std::vector<std::uint8_t> version = good;
  version[8] = 99;
  refused(version, "format version 99");
  refused(good, "not for 'other'", "other");
  // A solver of another grid.
  auto c = makeSolver(0, 20);
  EXPECT_THROW(restoreMpmCheckpoint(*c, good.data(), good.size()), InvalidArgument);
  // The info reader agrees with the file.
  const MpmCheckpointInfo info = readMpmCheckpointInfo(good.data(), good.size());
  EXPECT_EQ(info.frame, 1);
  EXPECT_EQ(info.tag, "scene");
  EXPECT_EQ(info.particles, a->particles().size());
}
