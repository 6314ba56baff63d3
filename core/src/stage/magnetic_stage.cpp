#include "lodestone/core/stage/magnetic_stage.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <sstream>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/kept_capacity.h"
#include "lodestone/core/base/stopwatch.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/field/magnetostatic_problem.h"
#include "lodestone/core/stage/nodal_field.h"
#include "lodestone/core/base/parallel.h"

namespace lodestone {
inline namespace stage {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

AppliedFieldFunction appliedFieldOf(const FieldSource& sources, double time) {
  return [&sources, time](const Vec3d* x, std::size_t count, Vec3d* H) {
    for (std::size_t m = 0; m < count; ++m) H[m] = sources.exteriorContinuation(x[m], time);
    sources.accumulateField(x, count, time, H);
  };
}

void MagneticStageSettings::validate() const {
  solve.validate();
  require(forceMaskDilation >= 0 && forceMaskDilation <= 8,
          "magnetic stage: forceMaskDilation must be 0..8 nodes, got ", forceMaskDilation);
}

std::string MagneticStageReport::summary() const {
  std::ostringstream os;
  os.precision(4);
  if (transfer.particles > 0)
    os << "transfer: " << transfer.particles << " particles (" << transfer.skipped << " skipped), "
       << secondsTransfer << " s\n";
  os << "field solve: " << toString(solve.status) << ", " << solve.newtonIterations << " Newton / "
     << solve.cgIterations << " CG iterations (" << solve.preconditioner << "), relative residual "
     << solve.relativeResidual << ", " << solve.materialCells << " material cells, " << secondsSolve << " s\n";
  if (!solve.message.empty()) os << "  " << solve.message << "\n";
  os << "applied field " << secondsAppliedField << " s";
  if (appliedFieldReused)
    os << " (nodes reused: sources unchanged; Gauss points of " << appliedFieldCellsEvaluated << " of "
       << solve.materialCells << " material cells evaluated)";
  os << ", nodal fields " << secondsFields << " s, force " << secondsForce << " s, total " << secondsTotal << " s\n";
  os << "total force (" << totalForce.x << ", " << totalForce.y << ", " << totalForce.z << ") N\n";
  for (const auto& w : warnings) os << "warning: " << w << "\n";
  return os.str();
}

MagneticForceStage::MagneticForceStage(const GridSpec& grid, const MagneticMaterial& material,
                                       const MagneticStageSettings& settings)
    : grid_(grid), material_(material), settings_(settings) {
  grid_.validate("magnetic stage grid");
  settings_.validate();
  n_.reset(grid_, 0.0);
  assignKeepingCapacity(phi_, grid_.nodeCount(), 0.0);
  hext_.reset(grid_);
  h_.reset(grid_);
  m_.reset(grid_);
  b_.reset(grid_);
  t_.reset(grid_);
  f_.reset(grid_);
}

void MagneticForceStage::resetWarmStart() { std::fill(phi_.begin(), phi_.end(), 0.0); }

void MagneticForceStage::setSettings(const MagneticStageSettings& settings) {
  settings.validate();
  if (settings.boundary != settings_.boundary) {
    resetWarmStart();
    problem_.reset();
  }
  settings_ = settings;
}

void MagneticForceStage::setMaterial(const MagneticMaterial& material) {
  if (material.law != material_.law) problem_.reset();  // the law lives in the problem
  material_ = material;
}

MagneticStageReport MagneticForceStage::run(const ParticleView& particles, const FieldSource& sources, double time) {
  const auto t0 = Clock::now();
  MagneticStageReport rep;
  rep.transfer = depositNumberDensity(particles, n_.view(), settings_.outOfGrid, binning_);
  lastParticles_ = fingerprint(particles);
  rep.secondsTransfer = secondsSince(t0);
  if (rep.transfer.skipped > 0)
    rep.warnings.push_back(concat(rep.transfer.skipped, " of ", rep.transfer.particles,
                                  " particles lie outside the grid and were skipped"));
  rep = solveAndForce(sources, time, rep);
  rep.secondsTotal = secondsSince(t0);
  return rep;
}

MagneticStageReport MagneticForceStage::runOnDensity(GridView<const double> density, const FieldSource& sources,
                                                     double time) {
  const auto t0 = Clock::now();
  require(density.spec == grid_, "magnetic stage: the density grid does not match the stage grid");
  std::copy(density.data, density.data + grid_.nodeCount(), n_.data());
  lastParticles_.reset();  // the host's particles are not known
  MagneticStageReport rep = solveAndForce(sources, time, MagneticStageReport{});
  rep.secondsTotal = secondsSince(t0);
  return rep;
}

MagneticStageReport MagneticForceStage::runOnPotential(GridView<const double> density, GridView<const double> phi,
                                                       const FieldSolveReport& solve, const FieldSource& sources,
                                                       double time) {
  const auto t0 = Clock::now();
  require(density.spec == grid_, "magnetic stage: the density grid does not match the stage grid");
  require(phi.spec == grid_, "magnetic stage: the potential grid does not match the stage grid");
  std::copy(density.data, density.data + grid_.nodeCount(), n_.data());
  lastParticles_.reset();
  MagneticStageReport rep = solveAndForce(sources, time, MagneticStageReport{}, &phi, &solve);
  rep.secondsTotal = secondsSince(t0);
  return rep;
}

MagneticStageReport MagneticForceStage::solveAndForce(const FieldSource& sources, double time,
                                                      MagneticStageReport rep, const GridView<const double>* givenPhi,
                                                      const FieldSolveReport* givenSolve) {
  require(std::isfinite(time), "magnetic stage: time must be finite, got ", time, " s");
  time_ = time;
  const AppliedFieldFunction applied = appliedFieldOf(sources, time);

  // Applied field at the nodes (kept when the sources are unchanged: a
  // static magnet is evaluated once) and the material Gauss points.
  auto t = Clock::now();
  const std::size_t count = grid_.nodeCount();
  std::vector<double> signature;
  const bool signed_ = sources.appendFieldSignature(time, signature);
  rep.appliedFieldReused = signed_ && !hextSignature_.empty() && signature.size() == hextSignature_.size() &&
                           std::memcmp(signature.data(), hextSignature_.data(), signature.size() * sizeof(double)) == 0;
  if (!rep.appliedFieldReused) {
    hextSignature_.clear();  // hext_ is being overwritten: an exception below leaves nothing to reuse
    tbb::parallel_for(0, grid_.dims.k, [&](int k) {
      std::vector<Vec3d> x(std::size_t(grid_.dims.i));
      for (int j = 0; j < grid_.dims.j; ++j) {
        for (int i = 0; i < grid_.dims.i; ++i) x[std::size_t(i)] = grid_.nodePosition(i, j, k);
        applied(x.data(), x.size(), &hext_(0, j, k));
      }
    });
    if (signed_) hextSignature_ = std::move(signature);
  }
  if (!problem_) problem_ = std::make_unique<MagnetostaticProblem>(grid_, material_.law, settings_.boundary);
  if (!workspace_) workspace_ = std::make_unique<FieldSolveWorkspace>();
  MagnetostaticProblem& problem = *problem_;
  problem.setMaterial(n_.view(), applied, rep.appliedFieldReused);
  rep.appliedFieldCellsEvaluated = problem.appliedFieldCellsEvaluated();
  rep.secondsAppliedField = secondsSince(t);
  rep.totalCount = problem.totalCount();
  if (settings_.boundary == BoundaryKind::Open && problem.materialCellCount() > 0 &&
      problem.materialWallClearance() < 2)
    rep.warnings.push_back(concat("magnetic material lies ", problem.materialWallClearance(),
                                  " cell(s) from the grid wall; the open (far-field) boundary assumes a margin of a "
                                  "few cells and loses accuracy there"));

  // Field solve.
  t = Clock::now();
  if (!settings_.warmStart || settings_.appliedFieldOnly) resetWarmStart();
  if (givenPhi) {
    std::copy(givenPhi->data, givenPhi->data + count, phi_.begin());
    rep.solve = *givenSolve;
  } else if (settings_.appliedFieldOnly) {
    rep.solve = FieldSolveReport{};
    rep.solve.status = SolveStatus::Trivial;
    rep.solve.materialCells = problem.materialCellCount();
    rep.solve.message = "skipped (applied field only): phi = 0, H = H_ext";
  } else {
    rep.solve = solveField(problem, phi_, settings_.solve, progress_, workspace_.get());
  }
  rep.secondsSolve = secondsSince(t);
  if (!rep.solve.converged()) rep.warnings.push_back("field solve: " + rep.solve.message);

  // Nodal fields.
  t = Clock::now();
  recoverNodalFields(GridView<const double>{phi_.data(), grid_}, hext_.view(), n_.view(), material_.law, h_.view(),
                     m_.view(), b_.view(), &scratch_);
  rep.secondsFields = secondsSince(t);

  // Force.
  t = Clock::now();
  stressDivergence(h_.view(), b_.view(), hext_.view(), n_.view(), settings_.forceMask, t_.view(),
                   settings_.forceMaskDilation, &sources, time, &scratch_);
  spreadForce(t_.view(), f_.view(), &scratch_);
  rep.totalForce = deterministicSum<Vec3d>(count, [&](std::size_t m) { return f_[m]; });
  rep.secondsForce = secondsSince(t);

  // Inside magnets, after the force (which takes the material's M in the
  // field the material sees): H becomes the true field (the continuation
  // removed) and the magnets' own magnetization joins M and B, so that
  // B = mu0 (H + M) holds at every node and B's normal component is
  // continuous across a magnet's faces.
  tbb::parallel_for(0, grid_.dims.k, [&](int k) {
    for (int j = 0; j < grid_.dims.j; ++j)
      for (int i = 0; i < grid_.dims.i; ++i) {
        const Vec3d x = grid_.nodePosition(i, j, k);
        const Vec3d Ms = sources.magnetization(x, time), c = sources.exteriorContinuation(x, time);
        if (Ms == Vec3d{} && c == Vec3d{}) continue;
        const std::size_t m = grid_.index(i, j, k);
        h_[m] -= c;
        m_[m] += Ms;
        b_[m] += kMu0 * (Ms - c);
      }
  });
  return rep;
}

std::vector<Multipole> MagneticForceStage::materialMultipoles() {
  if (!problem_) return {};
  std::vector<double> residual(grid_.nodeCount());
  return problem_->evaluate(phi_.data(), residual.data(), false).multipoles;
}

MagnetWrench MagneticForceStage::reactionOn(const FieldSource& source, const FieldSource& allSources,
                                            const Vec3d& centre, double time) const {
  DenseGrid<Vec3d> material(grid_);
  tbb::parallel_for(0, grid_.dims.k, [&](int k) {
    for (int j = 0; j < grid_.dims.j; ++j)
      for (int i = 0; i < grid_.dims.i; ++i) {
        const std::size_t m = grid_.index(i, j, k);
        if (m_[m] == Vec3d{}) continue;
        // n = 0: no material (a magnet's own M only).
        material[m] = n_[m] > 0 ? m_[m] - allSources.magnetization(grid_.nodePosition(i, j, k), time) : Vec3d{};
      }
  });
  return sourceReaction(material.view(), source, centre, time);
}

TransferReport MagneticForceStage::sampleForceDensity(const Vec3d* positions, std::size_t count, Vec3d* out) const {
  TransferReport r = sampleToParticles(f_.view(), positions, count, out, settings_.outOfGrid);
  const double inv = 1.0 / grid_.cellVolume();
  tbb::parallel_for(std::size_t(0), count, [&](std::size_t p) { out[p] *= inv; });
  return r;
}

MagneticForceStage::ParticleFingerprint MagneticForceStage::fingerprint(const ParticleView& particles) {
  // Up to 4096 particles, evenly spaced and the last one included: their
  // positions' and counts' bits mixed (splitmix64) with their index.
  ParticleFingerprint f;
  f.count = particles.size;
  const std::size_t stride = std::max<std::size_t>(1, particles.size / 4096);
  const auto mix = [](std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  };
  const auto bits = [](double v) {
    std::uint64_t u;
    std::memcpy(&u, &v, sizeof u);
    return u;
  };
  std::uint64_t h = 0x9e3779b97f4a7c15ULL;
  const auto add = [&](std::size_t p) {
    const Vec3d& x = particles.positions[p];
    for (const double v : {x.x, x.y, x.z, particles.counts[p]}) h = mix(h ^ bits(v)) + std::uint64_t(p);
  };
  for (std::size_t p = 0; p < particles.size; p += stride) add(p);
  if (particles.size > 0) add(particles.size - 1);
  f.hash = h;
  return f;
}

TransferReport MagneticForceStage::particleForces(const ParticleView& particles, Vec3d* out) const {
  if (lastParticles_) {
    const ParticleFingerprint f = fingerprint(particles);
    if (f.count != lastParticles_->count)
      throw InvalidArgument(concat("magnetic stage: particleForces got ", f.count,
                                   " particles, but the last run() deposited ", lastParticles_->count,
                                   "; the forces are those of the last run's particles: run() with these first"));
    if (f.hash != lastParticles_->hash)
      throw InvalidArgument(concat("magnetic stage: particleForces got ", f.count,
                                   " particles that are not the last run()'s (their positions or micro-particle",
                                   " counts changed); the forces are those of the last run's particles: run() with",
                                   " these first"));
  }
  // gatherToSupport writes every node: the kept grid needs no clearing.
  if (!(onSupport_.spec() == grid_) || onSupport_.size() != grid_.nodeCount()) onSupport_.reset(grid_);
  DenseGrid<Vec3d>& onSupport = onSupport_;
  gatherToSupport(f_.view(), n_.view(), onSupport.view());
  // g_i = f_i / (n_i dx^3): force per micro-particle at node i.
  const double inv = 1.0 / grid_.cellVolume();
  tbb::parallel_for(std::size_t(0), grid_.nodeCount(), [&](std::size_t m) {
    onSupport[m] = n_[m] > 0 ? onSupport[m] * (inv / n_[m]) : Vec3d{};
  });
  TransferReport r = sampleToParticles(onSupport.view(), particles.positions, particles.size, out, settings_.outOfGrid);
  tbb::parallel_for(std::size_t(0), particles.size, [&](std::size_t p) { out[p] *= particles.counts[p]; });
  return r;
}

TransferReport MagneticForceStage::sampleField(const Vec3d* positions, std::size_t count, Vec3d* out) const {
  return sampleToParticles(h_.view(), positions, count, out, settings_.outOfGrid);
}

}  // namespace stage
}  // namespace lodestone
