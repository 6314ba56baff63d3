#pragma once
// The stability suite's harness (see the criteria at the top of
// test_stability.cpp): small settings, the run loop that checks every
// substep, and the stated bounds (expectStable). Included by each of the
// suite's files.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "lodestone/core/base/bspline.h"
#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/sources/cuboid_magnet.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone/core/sources/uniform_field.h"

using namespace lodestone;

// Inline: each file of the suite uses only some of them.
namespace {

constexpr double kDx = 0.01;  // m
constexpr int kNodes = 16;
constexpr double kRho = 2500;  // kg/m^3

inline double centre() { return 0.5 * (kNodes - 1) * kDx; }

inline MpmSettings smallSettings(int nodes = kNodes) {
  MpmSettings s;
  s.grid = GridSpec{{0, 0, 0}, kDx, {nodes, nodes, nodes}};
  s.checkFinite = true;
  return s;
}

inline MpmMaterial ferrofluid(const MagneticMaterial& mag = paperMaterial(), double K = 2e5) {
  return viscousFluid(1.0, K, kRho, mag);
}

inline EmitterSettings emitSettings(int ppc = 8, Vec3d velocity = {}) {
  EmitterSettings e;
  e.particlesPerCell = ppc;
  e.velocity = velocity;
  return e;
}

struct Outcome {
  int frames = 0, solves = 0, unconverged = 0, dtLimited = 0;
  std::size_t emitted = 0, removed = 0, clamped = 0, nonFinite = 0;
  double maxCellsPerSubstep = 0;  // max |v| dt / dx over substeps
  double energy0 = 0, maxEnergy = -std::numeric_limits<double>::infinity();
  double energyAllowance = 0;  // 1% of m g L, J
  // max over substeps of E(t) - E(0) - B(t) (J; <= energyAllowance), and
  // E(t) - E(0) and B(t) at that substep.
  double energyExcess = -std::numeric_limits<double>::infinity(), growthAtExcess = 0, boundAtExcess = 0;
  double injected = 0;  // mechanical energy the rate emitters brought in (kinetic + gravitational at emission), J
  std::size_t blocked = 0;  // emitter points left out: space full of material or outside the domain
  double impulse = 0;  // sum of |magnetic impulse| over frames, N s
  std::vector<double> frameImpulse;  // |magnetic impulse| of each frame, N s
  std::vector<std::string> messages;
};

// B(t) of the file comment: mu0 sum_p W_p(H_ext(x_p, t)), J. coEnergy(law,
// n, H) is linear in n, so passing the particle's micro-particle count
// gives the particle's co-energy (A^2 m) without its volume.
inline double magneticWorkBound(const MpmSolver& solver, double t) {
  const MpmParticles& p = solver.particles();
  const FieldSource& applied = solver.appliedField();
  double sum = 0;
  for (std::size_t q = 0; q < p.size(); ++q) {
    const MpmMaterial& m = solver.materials()[p.material[q]];
    if (m.isMagnetic() && p.count[q] > 0) sum += coEnergy(m.magnetic.law, p.count[q], applied.field(p.x[q], t));
  }
  return kMu0 * sum;
}

// Runs `frames` frames of `duration` s, checking after every substep.
inline Outcome run(MpmSolver& solver, int frames, double duration) {
  Outcome o;
  const MpmSolver& view = solver;
  o.emitted = view.particles().size();
  o.energy0 = view.energies().total();
  const GridSpec& g = view.settings().grid;
  o.energyAllowance = 0.01 * view.particles().totalMass() * norm(view.settings().gravity) * (g.dims.k - 1) * g.dx;
  std::uint64_t nextId = view.particles().nextId;
  // Energy the emitters bring in with the points they add (ids from nextId on).
  const auto countInjected = [&]() {
    const MpmParticles& p = view.particles();
    for (std::size_t q = 0; q < p.size(); ++q)
      if (p.id[q] >= nextId) o.injected += 0.5 * p.mass[q] * norm2(p.v[q]) - p.mass[q] * dot(view.settings().gravity, p.x[q]);
    nextId = p.nextId;
  };
  const auto checkEnergy = [&](double t) {
    const double growth = view.energies().total() - o.energy0 - o.injected, bound = magneticWorkBound(view, t);
    if (growth - bound > o.energyExcess) {
      o.energyExcess = growth - bound;
      o.growthAtExcess = growth;
      o.boundAtExcess = bound;
    }
  };
  checkEnergy(view.time());
  const double dx = g.dx;
  for (int f = 0; f < frames; ++f) {
    double lastTime = solver.time();
    const MpmFrameReport r = solver.advanceFrame(duration, [&](const MpmProgress& p) {
      const double dt = p.time - lastTime;
      lastTime = p.time;
      double vmax = 0;
      for (const Vec3d& v : view.particles().v) vmax = std::max(vmax, norm(v));
      o.maxCellsPerSubstep = std::max(o.maxCellsPerSubstep, vmax * dt / dx);
      if (view.particles().nextId != nextId) countInjected();
      checkEnergy(p.time);
      return true;
    });
    ++o.frames;
    o.solves += int(r.magneticReports.size());
    for (const MagneticStageReport& m : r.magneticReports)
      if (!m.converged()) {
        ++o.unconverged;
        o.messages.push_back(m.solve.message);
      }
    o.dtLimited += r.dtLimitedByCfl;
    o.removed += r.removed;
    o.clamped += r.clamped;
    o.nonFinite += r.nonFinite;
    o.emitted += r.emitted.particles;
    o.blocked += r.emitted.blocked + r.emitted.outside;
    o.impulse += norm(r.magneticImpulse);
    o.frameImpulse.push_back(norm(r.magneticImpulse));
    o.maxEnergy = std::max(o.maxEnergy, r.energies.total());
    for (const std::string& w : r.warnings) o.messages.push_back(w);
  }
  return o;
}

// The bounds every case must meet (see the file comment).
inline void expectStable(const MpmSolver& solver, const Outcome& o, const std::string& name) {
  SCOPED_TRACE(name);
  EXPECT_EQ(o.unconverged, 0) << (o.messages.empty() ? "" : o.messages.front());
  EXPECT_EQ(o.nonFinite, 0u);
  EXPECT_LE(o.maxCellsPerSubstep, 1.0) << "a particle crossed more than a cell in one substep";
  EXPECT_EQ(solver.particles().size() + o.removed, o.emitted);
  EXPECT_LE(o.energyExcess, o.energyAllowance)
      << "mechanical energy grew by " << o.growthAtExcess << " J, more than the magnetic work bound " << o.boundAtExcess
      << " J plus 1% of m g L (" << o.energyAllowance << " J)";
  const GridSpec& g = solver.settings().grid;
  const Vec3d lo = g.origin + g.dx * Vec3d{1, 1, 1}, hi = g.nodePosition(g.dims.i - 2, g.dims.j - 2, g.dims.k - 2);
  for (const Vec3d& x : solver.particles().x)
    for (int a = 0; a < 3; ++a) {
      ASSERT_GE(x[a], lo[a]);
      ASSERT_LE(x[a], hi[a]);
    }
  std::printf(
      "[stability] %-34s frames %d, solves %d, particles %zu (removed %zu, clamped %zu), max cells/substep "
      "%.3f, energy %.4g -> max %.4g J; worst E(t) - E(0) %.4g J against B(t) %.4g J + %.3g J\n",
      name.c_str(), o.frames, o.solves, solver.particles().size(), o.removed, o.clamped, o.maxCellsPerSubstep,
      o.energy0, o.maxEnergy, o.growthAtExcess, o.boundAtExcess, o.energyAllowance);
}

// A ball of ferrofluid in the middle of the box in a uniform field H (A/m, along z).
inline Outcome fluidBallInField(double H, const MagneticMaterial& mag, int frames, std::unique_ptr<MpmSolver>& out,
                         TimeProfile profile = TimeProfile(), int nodes = kNodes) {
  auto s = std::make_unique<MpmSolver>(smallSettings(nodes));
  const double c = 0.5 * (nodes - 1) * kDx;
  s->emit(EmitterShape::sphere(Pose::at({c, c, c}), 0.03), s->addMaterial(ferrofluid(mag)), emitSettings());
  s->sources().add(std::make_unique<UniformField>(Vec3d{0, 0, H}, profile));
  const Outcome o = run(*s, frames, 0.01);
  out = std::move(s);
  return o;
}

}  // namespace
