#include "lodestone/core/stage/magnetic_patches.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <sstream>

#include "lodestone/core/base/error.h"
#include "lodestone/core/base/stopwatch.h"
#include "lodestone/core/field/open_wall_sum.h"
#include "lodestone/core/stage/far_field.h"

namespace lodestone {
inline namespace stage {

namespace {
using Clock = std::chrono::steady_clock;

/// `blocks` merged into clusters of edge `edge` (m): each cluster's moments
/// about the mean of its blocks' centres (N_ij + m_i (c_b - c)_j), clusters
/// in the order of their cells.
std::vector<Multipole> clustered(const std::vector<Multipole>& blocks, double edge) {
  std::map<std::array<long, 3>, std::vector<const Multipole*>> cells;
  for (const Multipole& m : blocks)
    if (!m.empty())
      cells[{long(std::floor(m.centre.x / edge)), long(std::floor(m.centre.y / edge)), long(std::floor(m.centre.z / edge))}]
          .push_back(&m);
  std::vector<Multipole> out;
  for (const auto& [cell, members] : cells) out.push_back(mergedMultipole(members.data(), members.size()));
  return out;
}

/// What patch `self` (grid g) sees of the others: each other patch's
/// blocks, merged into clusters of edge d/8 when that exceeds 16 cells (d
/// the distance from g to the patch's blocks). The expansion left out (the
/// octupole) is (s/d)^2 of a cluster's dipole field at distance d from a
/// cluster of half-diagonal s <= 0.11 d: at most 1.2%, while a distant
/// patch costs a handful of expansions instead of one per block.
std::vector<Multipole> farBlocks(const std::vector<std::vector<Multipole>>& moments, std::size_t self,
                                 const GridSpec& g) {
  std::vector<Multipole> out;
  for (std::size_t q = 0; q < moments.size(); ++q) {
    if (q == self) continue;
    const double edge = distanceToBlocks(g, moments[q]) / 8;
    if (edge > 16 * g.dx) {
      const std::vector<Multipole> c = clustered(moments[q], edge);
      out.insert(out.end(), c.begin(), c.end());
    } else {
      for (const Multipole& m : moments[q])
        if (!m.empty()) out.push_back(m);
    }
  }
  return out;
}

/// The scene's sources plus the far field of the other patches: what one
/// patch's stage takes as its applied field. The other patches lie outside
/// this patch's grid, so their field is smooth on it; inside magnets the
/// base's continuation and magnetization are passed on unchanged.
class CoupledSource final : public FieldSource {
 public:
  CoupledSource(const FieldSource& base, std::vector<Multipole> far, const GridSpec& grid, std::size_t others)
      : base_(base), far_(std::make_shared<const SampledFarField>(std::move(far), grid)), others_(others) {}
  Vec3d field(const Vec3d& x, double t) const override { return base_.field(x, t) + far_->at(x); }
  Vec3d magnetization(const Vec3d& x, double t) const override { return base_.magnetization(x, t); }
  Vec3d exteriorContinuation(const Vec3d& x, double t) const override { return base_.exteriorContinuation(x, t); }
  void accumulateField(const Vec3d* x, std::size_t count, double t, Vec3d* out) const override {
    base_.accumulateField(x, count, t, out);
    for (std::size_t n = 0; n < count; ++n) out[n] += far_->at(x[n]);
  }
  std::string describe() const override {
    return concat(base_.describe(), " + the far field of ", others_, " other patch(es) of material");
  }
  std::unique_ptr<FieldSource> clone() const override { return std::make_unique<CoupledSource>(*this); }

 private:
  const FieldSource& base_;
  std::shared_ptr<const SampledFarField> far_;
  std::size_t others_;
};

}  // namespace

void MagneticPatchSettings::validate() const {
  require(couplingTolerance > 0 && couplingTolerance < 1,
          "magnetic patches: couplingTolerance must be in (0, 1), got ", couplingTolerance);
  require(maxRounds >= 1 && maxRounds <= 100, "magnetic patches: maxRounds must be 1..100, got ", maxRounds);
}

bool MagneticPatchReport::converged() const {
  if (!couplingConverged) return false;
  for (const MagneticStageReport& r : patches)
    if (!r.converged()) return false;
  return true;
}

MagneticStageReport MagneticPatchReport::combined() const {
  MagneticStageReport c;
  c.solve.status = SolveStatus::Trivial;
  for (std::size_t p = 0; p < patches.size(); ++p) {
    const MagneticStageReport& r = patches[p];
    c.transfer.particles += r.transfer.particles;
    c.transfer.skipped += r.transfer.skipped;
    c.transfer.totalCount += r.transfer.totalCount;
    c.transfer.seconds += r.transfer.seconds;
    c.totalCount += r.totalCount;
    c.totalForce += r.totalForce;
    c.secondsTransfer += r.secondsTransfer;
    c.secondsAppliedField += r.secondsAppliedField;
    c.secondsSolve += r.secondsSolve;
    c.secondsFields += r.secondsFields;
    c.secondsForce += r.secondsForce;
    c.appliedFieldReused = p == 0 ? r.appliedFieldReused : c.appliedFieldReused && r.appliedFieldReused;
    c.appliedFieldCellsEvaluated += r.appliedFieldCellsEvaluated;
    FieldSolveReport& s = c.solve;
    if (s.converged() && (!r.solve.converged() || s.status == SolveStatus::Trivial)) {
      s.status = r.solve.status;
      s.message = r.solve.message;
      s.preconditioner = r.solve.preconditioner;
      s.backend = r.solve.backend;
    }
    s.newtonIterations += r.solve.newtonIterations;
    s.cgIterations += r.solve.cgIterations;
    s.lineSearchCuts += r.solve.lineSearchCuts;
    s.relativeResidual = std::max(s.relativeResidual, r.solve.relativeResidual);
    s.materialEnergy += r.solve.materialEnergy;
    s.seconds += r.solve.seconds;
    s.materialCells += r.solve.materialCells;
    s.multigridLevels = std::max(s.multigridLevels, r.solve.multigridLevels);
    for (const std::string& w : r.warnings) c.warnings.push_back(concat("patch ", p, ": ", w));
  }
  if (!couplingConverged && c.solve.converged()) c.solve.status = SolveStatus::IterationCap;  // the rounds' cap
  c.solve.message = concat(patches.size(), " patches, ", rounds, " round(s), far-field change ", couplingChange,
                           c.solve.message.empty() ? "" : "; ", c.solve.message);
  c.secondsTotal = secondsTotal;
  return c;
}

std::string MagneticPatchReport::summary() const {
  std::ostringstream os;
  os.precision(4);
  os << patches.size() << " patches, " << rounds << " round(s), far-field change " << couplingChange
     << (couplingConverged ? " (converged)" : " (NOT converged)") << ", coupling " << secondsCoupling << " s, total "
     << secondsTotal << " s\n";
  for (std::size_t p = 0; p < patches.size(); ++p) os << "patch " << p << ":\n" << patches[p].summary();
  return os.str();
}

MagneticPatches::MagneticPatches(std::vector<GridSpec> grids, const MagneticMaterial& material,
                                 const MagneticStageSettings& settings, const MagneticPatchSettings& patchSettings)
    : patchSettings_(patchSettings) {
  patchSettings_.validate();
  require(!grids.empty(), "magnetic patches: no patch grid given");
  require(settings.boundary == BoundaryKind::Open,
          "magnetic patches: the boundary must be open (far field); the shield wall is one box around everything");
  for (std::size_t p = 0; p < grids.size(); ++p) {
    grids[p].validate("magnetic patch grid");
    require(grids[p].dx == grids[0].dx, "magnetic patches: patch ", p, " has dx = ", grids[p].dx,
            " m, patch 0 has ", grids[0].dx, " m");
    for (std::size_t q = 0; q < p; ++q)
      require(!grids[q].meets(grids[p]), "magnetic patches: patches ", q, " and ", p,
              " overlap (patches must lie apart)");
  }
  for (const GridSpec& g : grids) stages_.push_back(std::make_unique<MagneticForceStage>(g, material, settings));
}

MagneticPatchReport MagneticPatches::run(const std::vector<ParticleView>& points, const FieldSource& sources,
                                         double time) {
  const auto t0 = Clock::now();
  require(points.size() == stages_.size(), "magnetic patches: ", points.size(), " point sets for ", stages_.size(),
          " patches");
  const std::size_t n = stages_.size();
  MagneticPatchReport rep;
  rep.patches.resize(n);
  if (moments_.size() != n) moments_.assign(n, {});
  std::vector<std::vector<double>> density(n);
  for (int round = 1; round <= patchSettings_.maxRounds; ++round) {
    rep.rounds = round;
    for (std::size_t p = 0; p < n; ++p) {
      const CoupledSource coupled(sources, farBlocks(moments_, p, stages_[p]->grid()), stages_[p]->grid(), n - 1);
      MagneticForceStage& stage = *stages_[p];
      if (round == 1) {
        rep.patches[p] = stage.run(points[p], coupled, time);
        const GridView<const double> d = stage.density();
        density[p].assign(d.data, d.data + stage.grid().nodeCount());
      } else {
        const MagneticStageReport transfer = rep.patches[p];
        rep.patches[p] = stage.runOnDensity({density[p].data(), stage.grid()}, coupled, time);
        rep.patches[p].transfer = transfer.transfer;
        rep.patches[p].secondsTransfer = transfer.secondsTransfer;
      }
    }
    if (n == 1) {
      rep.couplingConverged = true;
      moments_[0] = stages_[0]->materialMultipoles();
      break;
    }
    // The new far fields, compared with those the round used at the centres
    // of each patch's own material blocks.
    const auto tc = Clock::now();
    std::vector<std::vector<Multipole>> next(n);
    for (std::size_t p = 0; p < n; ++p) next[p] = stages_[p]->materialMultipoles();
    double change = 0;
    for (std::size_t p = 0; p < n; ++p) {
      double diff = 0, scale = 0;
      const GridSpec& g = stages_[p]->grid();
      const std::vector<Multipole> farBefore = farBlocks(moments_, p, g), farAfter = farBlocks(next, p, g);
      for (const Multipole& own : next[p]) {
        if (own.empty()) continue;
        const Vec3d before = farFieldOf(farBefore, own.centre), after = farFieldOf(farAfter, own.centre);
        diff = std::max(diff, norm(after - before));
        scale = std::max(scale, norm(sources.field(own.centre, time) + after));
      }
      if (diff > 0) change = std::max(change, scale > 0 ? diff / scale : 1.0);
    }
    moments_ = std::move(next);
    rep.secondsCoupling += secondsSince(tc);
    rep.couplingChange = change;
    if (change <= patchSettings_.couplingTolerance) {
      rep.couplingConverged = true;
      break;
    }
  }
  for (const MagneticStageReport& r : rep.patches) rep.totalForce += r.totalForce;
  if (!rep.couplingConverged)
    for (MagneticStageReport& r : rep.patches)
      r.warnings.push_back(concat("patch coupling: the far fields still changed by ", rep.couplingChange,
                                  " (relative) after ", rep.rounds, " rounds"));
  rep.secondsTotal = secondsSince(t0);
  return rep;
}

Vec3d MagneticPatches::farField(std::size_t p, const Vec3d& x) const {
  require(p < stages_.size(), "magnetic patches: no patch ", p, " (", stages_.size(), " patches)");
  return moments_.size() == stages_.size() ? farFieldOf(farBlocks(moments_, p, stages_[p]->grid()), x) : Vec3d{};
}

TransferReport MagneticPatches::particleForces(std::size_t p, const ParticleView& points, Vec3d* out) const {
  require(p < stages_.size(), "magnetic patches: no patch ", p, " (", stages_.size(), " patches)");
  return stages_[p]->particleForces(points, out);
}

MagnetWrench MagneticPatches::reactionOn(const FieldSource& source, const FieldSource& allSources,
                                         const Vec3d& centre, double time) const {
  MagnetWrench sum;
  for (const auto& stage : stages_) {
    const MagnetWrench w = stage->reactionOn(source, allSources, centre, time);
    sum.force += w.force;
    sum.torque += w.torque;
  }
  return sum;
}

void MagneticPatches::setSettings(const MagneticStageSettings& settings) {
  require(settings.boundary == BoundaryKind::Open,
          "magnetic patches: the boundary must be open (far field); the shield wall is one box around everything");
  for (const auto& stage : stages_) stage->setSettings(settings);
}

void MagneticPatches::setMaterial(const MagneticMaterial& material) {
  for (const auto& stage : stages_) stage->setMaterial(material);
}

void MagneticPatches::setProgress(SolveProgress progress) {
  for (const auto& stage : stages_) stage->setProgress(progress);
}

}  // namespace stage
}  // namespace lodestone
