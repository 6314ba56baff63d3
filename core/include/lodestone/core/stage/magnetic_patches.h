#pragma once
// Separate patches of magnetic material, each solved on its own grid (the
// material's box plus the open wall's margin) instead of one grid around
// all of them, coupled through their far fields: patch q's magnetization
// applies to patch p the field of q's block multipoles (dipole + quadrupole
// about each block's centre, Multipole::field), which p's stage takes as
// part of its applied field. The field a patch's own material makes is its
// own solve's (its open wall sums its own blocks), so nothing is counted
// twice.
//
// The patches are solved in rounds: in each, every patch with the far
// fields of the round before (Jacobi order: the result does not depend on
// the patches' order), until the far fields change by less than
// `couplingTolerance` of the field at the material. The first round of a
// run starts from the far fields of the last run (warm, like the
// potentials); later rounds reuse the first's transfer. The expansion left
// out of a block's far field (its octupole) is (s/d)^2 of its dipole field
// at distance d from a block of half-diagonal s: the patches must lie apart
// by at least their margin (material_patches.h keeps their material more
// than twice their margin apart). A patch farther than 128 cells is seen
// through its blocks merged into clusters of an eighth of that distance
// (at most 1.2% of a cluster's field left out).
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/field/multipole.h"
#include "lodestone/core/sources/field_source.h"
#include "lodestone/core/sources/magnet_interaction.h"
#include "lodestone/core/stage/magnetic_stage.h"

namespace lodestone {
inline namespace stage {

struct MagneticPatchSettings {
  double couplingTolerance = 1e-3;  ///< relative change of the far fields that ends the rounds, (0, 1)
  int maxRounds = 8;                ///< rounds at most per run, 1..100

  /// Throws InvalidArgument naming the first bad value.
  void validate() const;
};

/// Outcome of one run of all patches.
struct MagneticPatchReport {
  std::vector<MagneticStageReport> patches;  ///< each patch's last round
  int rounds = 0;                            ///< rounds run (1 for a single patch)
  /// Largest change of a patch's far field in the last round, relative to
  /// the largest applied-plus-far field at its material (A/m over A/m).
  double couplingChange = 0;
  bool couplingConverged = false;  ///< couplingChange <= couplingTolerance (or a single patch)
  double secondsCoupling = 0;      ///< the far fields' moments and their comparison, s
  double secondsTotal = 0;
  Vec3d totalForce;                ///< sum of all patches' nodal forces, N

  /// Every patch's solve converged and so did the coupling.
  bool converged() const;
  /// The patches' last rounds as one stage report: particles, counts,
  /// iterations, material cells, times (all rounds) and forces summed; the
  /// largest relative residual; the first status that is not converged (or
  /// the coupling's failure); each warning prefixed with its patch.
  MagneticStageReport combined() const;
  /// Multi-line summary with units: rounds, coupling change, per-patch solves.
  std::string summary() const;
};

class MagneticPatches {
 public:
  /// One stage per grid (all of spacing `grids[0].dx`). Throws
  /// InvalidArgument when there is no grid, when two grids share a node
  /// (naming both), when their spacings differ, or when the boundary is not
  /// Open (the shield wall is a box around everything).
  MagneticPatches(std::vector<GridSpec> grids, const MagneticMaterial& material,
                  const MagneticStageSettings& settings = {}, const MagneticPatchSettings& patchSettings = {});

  /// Transfer, solve and force of every patch at time t (s): `points[p]`
  /// are the material points of patch p (their stencils on its grid).
  /// Throws InvalidArgument when points.size() != size().
  MagneticPatchReport run(const std::vector<ParticleView>& points, const FieldSource& sources, double time);

  std::size_t size() const { return stages_.size(); }
  const MagneticForceStage& stage(std::size_t p) const { return *stages_.at(p); }
  const GridSpec& grid(std::size_t p) const { return stages_.at(p)->grid(); }
  /// Patch p's block multipoles (its material's far field) of the last
  /// round of the last run; empty before the first run of several patches.
  const std::vector<Multipole>& moments(std::size_t p) const { return moments_.at(p); }
  /// The far field (A/m) the other patches' material applies at x to patch
  /// p, as of the last round of the last run.
  Vec3d farField(std::size_t p, const Vec3d& x) const;

  /// Force on each of patch p's points (N), as MagneticForceStage::particleForces.
  TransferReport particleForces(std::size_t p, const ParticleView& points, Vec3d* out) const;
  /// The reaction of all patches' material on `source`
  /// (MagneticForceStage::reactionOn, summed).
  MagnetWrench reactionOn(const FieldSource& source, const FieldSource& allSources, const Vec3d& centre,
                          double time) const;

  void setSettings(const MagneticStageSettings& settings);
  void setMaterial(const MagneticMaterial& material);
  void setProgress(SolveProgress progress);
  const MagneticPatchSettings& patchSettings() const { return patchSettings_; }

 private:
  std::vector<std::unique_ptr<MagneticForceStage>> stages_;
  MagneticPatchSettings patchSettings_;
  std::vector<std::vector<Multipole>> moments_;  // each patch's block multipoles, of the last round
};

}  // namespace stage
}  // namespace lodestone
