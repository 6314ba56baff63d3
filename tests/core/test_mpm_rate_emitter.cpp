// Emission over time (mpm/rate_emitter.h): the emitted volume and mass against
// rate x active time (closed form, within one chunk), nothing while off, a
// moving nozzle laying material along its path, a jet whose particles are
// one lattice spacing apart along the stream at any dt, a resumed run equal
// to an uninterrupted one, full space left alone, and bad input named.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/mpm/checkpoint.h"
#include "lodestone/core/mpm/rate_emitter.h"
#include "lodestone/core/mpm/solver.h"

using namespace lodestone;

namespace {

std::string text(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.4g", v);
  return buffer;
}

constexpr double kDx = 0.01;  // m; lattice h = dx/2 at 8 particles per cell

ParticleBounds everywhere() {
  ParticleBounds b;
  b.lo = {-1e3, -1e3, -1e3};
  b.hi = {1e3, 1e3, 1e3};
  return b;
}

// The points move freely at their velocity over a substep (what the MPM does
// with material in free flight at uniform velocity) before the substep's
// chunks are emitted at its end, so older chunks leave the nozzle.
void drift(MpmParticles& p, double dt) {
  for (std::size_t q = 0; q < p.size(); ++q) p.x[q] += dt * p.v[q];
}

RateEmitterSettings nozzleSettings(double speed) {
  RateEmitterSettings s;
  s.lattice.cellSize = kDx;
  s.lattice.velocity = {0, 0, speed};
  s.velocityInBodyFrame = true;
  return s;
}

// Message of the InvalidArgument `f` throws ("" when it does not).
template <typename F>
std::string messageOf(F&& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(MpmRateEmitter, ScheduleActiveTimeAndItsInverse) {
  const EmissionSchedule s = EmissionSchedule::intervals({{0.1, 0.3}, {0.5, 0.6}, {1.0, EmissionSchedule::kForever}});
  EXPECT_DOUBLE_EQ(s.activeTime(0.05), 0.0);
  EXPECT_DOUBLE_EQ(s.activeTime(0.2), 0.1);
  EXPECT_DOUBLE_EQ(s.activeTime(0.4), 0.2);
  EXPECT_DOUBLE_EQ(s.activeTime(0.55), 0.25);
  EXPECT_DOUBLE_EQ(s.activeTime(2.0), 1.3);
  EXPECT_DOUBLE_EQ(s.timeAtActive(0.0), 0.1);
  EXPECT_DOUBLE_EQ(s.timeAtActive(0.2), 0.5);  // the end of one interval is the start of the next
  EXPECT_DOUBLE_EQ(s.timeAtActive(0.35), 1.05);
  EXPECT_TRUE(s.isOn(0.1));
  EXPECT_FALSE(s.isOn(0.3));
  EXPECT_FALSE(s.onWithin(0.3, 0.5));
  EXPECT_TRUE(s.onWithin(0.3, 0.50001));
}

// V(t) = N(t) V_c with N(t) = ceil(Q a(t) / V_c): Q a <= V < Q a + V_c at
// every substep end, for several dt, and not a chunk while the emitter is
// off; the mass is rho V.
TEST(MpmRateEmitter, EmittedVolumeAndMassAreRateTimesActiveTimeWithinOneChunk) {
  const MpmMaterial fluid = viscousFluid(0.0, 1e4, 1200.0, paperMaterial());
  const double Q = 3e-5;  // m^3/s
  RateEmitterSettings s = nozzleSettings(3.0);
  s.rate = Q;
  s.schedule = EmissionSchedule::intervals({{0.01, 0.04}, {0.07, 0.08}});
  const RateEmitter e(EmitterShape::cylinder(Pose::at({0, 0, 0}), 0.012, 0.0025), s, fluid, 0);
  const double Vc = e.chunkVolume();
  ASSERT_GT(Vc, 0);
  for (double dt : {1e-4, 7e-4, 3.1e-3}) {
    MpmParticles p;
    double t = 0, worst = 0;
    std::size_t blocked = 0;
    while (t < 0.1) {
      const double t1 = t + dt;
      drift(p, dt);
      const std::size_t before = p.size();
      const RateEmitReport r = e.emitBetween(p, t, t1, everywhere());
      blocked += r.blocked + r.outside;
      // Nothing while the emitter is off in the whole substep.
      if (!s.schedule.onWithin(t, t1)) {
        ASSERT_EQ(p.size(), before) << "dt " << dt << " t " << t;
      }
      t = t1;
      double volume = 0, mass = 0;
      for (std::size_t q = 0; q < p.size(); ++q) volume += p.volume0[q], mass += p.mass[q];
      const double expected = Q * s.schedule.activeTime(t);
      ASSERT_GE(volume, expected - 1e-12 * Vc) << "dt " << dt << " t " << t;
      ASSERT_LT(volume, expected + Vc) << "dt " << dt << " t " << t;
      ASSERT_NEAR(mass, 1200.0 * volume, 1e-9 * mass);
      worst = std::max(worst, std::fabs(volume - expected) / Vc);
    }
    EXPECT_EQ(blocked, 0u);
    // All of it: 0.04 s on at 3e-5 m^3/s.
    double total = 0;
    for (double v : p.volume0) total += v;
    EXPECT_NEAR(total, Q * 0.04, Vc) << dt;
    RecordProperty(("worst_fraction_of_a_chunk_dt_" + text(dt)).c_str(), text(worst));
  }
}

// A rate in particles per second is that many points a second (in whole chunks).
TEST(MpmRateEmitter, ParticleRateCountsPoints) {
  RateEmitterSettings s = nozzleSettings(10.0);
  s.rateKind = EmissionRateKind::ParticlesPerSecond;
  s.rate = 20000;  // 1/s
  s.schedule = EmissionSchedule::between(0.0, 0.05);
  const RateEmitter e(EmitterShape::box(Pose::at({0, 0, 0}), {0.01, 0.01, 0.0025}), s, viscousFluid(0, 1e4, 1000), 0);
  MpmParticles p;
  for (double t = 0; t < 0.1; t += 1e-3) {
    drift(p, 1e-3);
    e.emitBetween(p, t, t + 1e-3, everywhere());
  }
  EXPECT_GE(double(p.size()), 20000 * 0.05);
  EXPECT_LT(double(p.size()), 20000 * 0.05 + double(e.chunkParticles()));
}

// A nozzle moved by keyframes lays each chunk where the nozzle was when the
// chunk was born, moved on by the emission velocity since: the centroid of
// chunk k is pose(t_k) + v_e (t - t_k), here with the nozzle turned to point
// down.
TEST(MpmRateEmitter, MovingNozzleLaysMaterialAlongItsPath) {
  const Pose down = Pose::fromAxisAngle({0, 0, 0.3}, {1, 0, 0}, 3.14159265358979323846);
  Pose end = down;
  end.position = {0.4, 0.1, 0.3};
  RateEmitterSettings s = nozzleSettings(1.5);
  s.rateKind = EmissionRateKind::Stream;
  s.motion = ColliderMotion::keyframed({0.0, 0.2}, {down, end});
  s.followsMotion = true;
  const RateEmitter e(EmitterShape::cylinder(down, 0.01, 0.0025), s, viscousFluid(0, 1e4, 1000), 0);
  const std::size_t n = e.chunkParticles();
  MpmParticles p;
  const double dt = 2.3e-3;
  double t = 0;
  for (int k = 0; k < 80; ++k, t += dt) {
    drift(p, dt);
    e.emitBetween(p, t, t + dt, everywhere());
  }
  ASSERT_GT(p.size(), 10 * n);
  ASSERT_EQ(p.size() % n, 0u);
  double worst = 0;
  for (std::size_t c = 0; c < p.size() / n; ++c) {
    Vec3d centroid;
    for (std::size_t q = c * n; q < (c + 1) * n; ++q) centroid += p.x[q] / double(n);
    const double tk = e.birthTime((long long)c);
    const Vec3d expected = s.motion.poseAt(tk).position + (t - tk) * Vec3d{0, 0, -1.5};
    worst = std::max(worst, norm(centroid - expected));
    // The nozzle moved 0.4 m in x over 0.2 s: the path, not one place.
    ASSERT_NEAR(centroid.x, 2.0 * std::min(tk, 0.2), 1e-9) << "chunk " << c;
  }
  EXPECT_LT(worst, 1e-9);
  RecordProperty("worst_centroid_error_m", text(worst));
}

// A jet out of a nozzle along +x in the MPM (no gravity, a fluid at rest
// pressure): the particles on the nozzle's axis are exactly one lattice
// spacing apart along the stream, with no gap and no doubled layer, for a
// dt below and above the chunk period.
TEST(MpmRateEmitter, JetParticlesAreOneLatticeSpacingApartAlongTheStreamAtAnyDt) {
  const double u = 2.0;  // m/s
  for (double dt : {2.9e-4, 1.1e-3, 3.7e-3}) {
    MpmSettings st;
    st.grid = GridSpec{{0, 0, 0}, kDx, {46, 12, 12}};
    st.gravity = {0, 0, 0};
    st.fixedDt = dt;
    MpmSolver solver(st);
    const std::uint32_t m = solver.addMaterial(viscousFluid(0.0, 100.0, 1000.0));
    RateEmitterSettings s = nozzleSettings(u);
    s.rateKind = EmissionRateKind::Stream;
    const Pose alongX = Pose::fromAxisAngle({0.05, 0.055, 0.055}, {0, 1, 0}, 3.14159265358979323846 / 2);
    solver.addEmitter(EmitterShape::cylinder(alongX, 0.012, 0.0025), m, s);
    const double h = solver.emitter(0).spacing().z;
    ASSERT_NEAR(h, kDx / 2, 1e-15);
    std::size_t emitted = 0;
    while (solver.time() < 0.12) emitted += solver.step(dt).emitted.particles;
    EXPECT_EQ(emitted, solver.particles().size());
    std::vector<double> xs;
    for (const Vec3d& x : solver.particles().x)
      if (std::fabs(x.y - 0.0575) < 0.3 * h && std::fabs(x.z - 0.0575) < 0.3 * h) xs.push_back(x.x);
    std::sort(xs.begin(), xs.end());
    ASSERT_GT(xs.size(), 40u) << dt;
    double lo = 1e300, hi = 0;
    for (std::size_t i = 1; i < xs.size(); ++i)
      lo = std::min(lo, xs[i] - xs[i - 1]), hi = std::max(hi, xs[i] - xs[i - 1]);
    EXPECT_NEAR(lo, h, 1e-9) << "dt " << dt;
    EXPECT_NEAR(hi, h, 1e-9) << "dt " << dt;
    RecordProperty(("spacing_minus_h_min_max_dt_" + text(dt)).c_str(), text(lo - h) + " " + text(hi - h));
  }
}

// The emitted state is a function of time: a run saved to a checkpoint and
// resumed by a solver built again equals the uninterrupted run bit for bit
// (moving jittered nozzle, gravity, two on-intervals, a blocking pool).
TEST(MpmRateEmitter, ResumedRunEqualsUninterruptedRun) {
  const auto build = []() {
    MpmSettings st;
    st.grid = GridSpec{{0, 0, 0}, kDx, {16, 16, 16}};
    auto solver = std::make_unique<MpmSolver>(st);
    const std::uint32_t m = solver->addMaterial(viscousFluid(0.5, 2e4, 1000.0, paperMaterial()));
    EmitterSettings pool;
    solver->emit(EmitterShape::box(Pose::at({0.075, 0.075, 0.035}), {0.05, 0.05, 0.012}), m, pool);
    RateEmitterSettings s = nozzleSettings(0.8);
    s.rate = 4e-4;
    s.lattice.jitter = 0.3;
    s.schedule = EmissionSchedule::intervals({{0.0, 0.03}, {0.05, 0.2}});
    const Pose down = Pose::fromAxisAngle({0.05, 0.075, 0.11}, {1, 0, 0}, 3.14159265358979323846);
    Pose end = down;
    end.position = {0.1, 0.075, 0.11};
    s.motion = ColliderMotion::keyframed({0.0, 0.1}, {down, end});
    s.followsMotion = true;
    s.inheritMotion = true;
    solver->addEmitter(EmitterShape::cylinder(down, 0.01, 0.005), m, s);
    return solver;
  };
  const double frame = 1.0 / 48;
  auto whole = build();
  for (int f = 0; f < 4; ++f) whole->advanceFrame(frame);

  auto first = build();
  for (int f = 0; f < 2; ++f) first->advanceFrame(frame);
  const std::vector<std::uint8_t> bytes = saveMpmCheckpoint(*first, 2, "emitter");
  auto resumed = build();
  restoreMpmCheckpoint(*resumed, bytes.data(), bytes.size(), "emitter");
  for (int f = 2; f < 4; ++f) resumed->advanceFrame(frame);

  const MpmParticles &a = whole->particles(), &b = resumed->particles();
  ASSERT_GT(a.size(), first->particles().size());  // it emitted after the checkpoint
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t q = 0; q < a.size(); ++q) {
    ASSERT_EQ(a.id[q], b.id[q]) << q;
    ASSERT_EQ(a.x[q], b.x[q]) << q;
    ASSERT_EQ(a.v[q], b.v[q]) << q;
  }
  RecordProperty("particles_at_checkpoint", std::to_string(first->particles().size()));
  RecordProperty("particles_at_end", std::to_string(a.size()));
}

// An emitter at rest with nothing carrying its material away: the first
// chunk fills the shape, every later point finds material there.
TEST(MpmRateEmitter, FullSpaceIsNotEmittedInto) {
  RateEmitterSettings s;
  s.lattice.cellSize = kDx;
  s.rate = 1e-3;
  const RateEmitter e(EmitterShape::sphere(Pose::at({0, 0, 0}), 0.01), s, viscousFluid(0, 1e4, 1000), 0);
  MpmParticles p;
  RateEmitReport total;
  for (double t = 0; t < 0.05; t += 1e-3) total += e.emitBetween(p, t, t + 1e-3, everywhere());
  EXPECT_EQ(p.size(), e.chunkParticles());
  EXPECT_EQ(total.particles, e.chunkParticles());
  EXPECT_EQ(total.blocked, std::size_t(total.chunks - 1) * e.chunkParticles());
  EXPECT_GT(total.chunks, 5);
}

TEST(MpmRateEmitter, RejectsBadInputNamingIt) {
  const MpmMaterial fluid = viscousFluid(0, 1e4, 1000);
  const EmitterShape nozzle = EmitterShape::cylinder(Pose::at({0, 0, 0}), 0.01, 0.005);
  RateEmitterSettings s = nozzleSettings(1.0);
  s.rate = -2e-5;
  EXPECT_NE(messageOf([&] { RateEmitter(nozzle, s, fluid, 0); }).find("-2e-05"), std::string::npos);
  EXPECT_NE(messageOf([] { EmissionSchedule::between(0.5, 0.1); }).find("ends at 0.1 s, not after its start 0.5 s"),
            std::string::npos);
  EXPECT_NE(messageOf([] {
              EmissionSchedule::intervals({{0.0, 0.2}, {0.1, 0.3}});
            }).find("starts at 0.1 s"),
            std::string::npos);
  EXPECT_NE(messageOf([] { EmissionSchedule::between(-1.0); }).find("-1"), std::string::npos);
  RateEmitterSettings stream = nozzleSettings(-1.0);
  stream.rateKind = EmissionRateKind::Stream;
  EXPECT_NE(messageOf([&] { RateEmitter(nozzle, stream, fluid, 0); }).find("speed"), std::string::npos);
  // A rate far beyond what one substep should add is refused before anything is added.
  RateEmitterSettings huge = nozzleSettings(1.0);
  huge.rate = 1e3;
  const RateEmitter e(nozzle, huge, fluid, 0);
  MpmParticles p;
  EXPECT_NE(messageOf([&] { e.emitBetween(p, 0, 1e-3, everywhere()); }).find("particles are due in one substep"),
            std::string::npos);
  EXPECT_EQ(p.size(), 0u);
}
