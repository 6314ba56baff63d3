#pragma once
// The magnetic-force stage: the one entry point an MPM host calls per step or
// per frame. Given the magnetic material points (positions, micro-particle
// counts n_p) or a density grid, and the applied-field sources, it
//   1. transfers n_p to the nodal density n_i (quadratic B-splines),
//   2. solves the nonlinear magnetostatic problem for phi (Newton-PCG),
//   3. recovers H, M, B at the nodes and the Einstein-Laub force
//      (force density t_j in N/m^3, spread nodal force f_i in N),
// and can sample the force density back to particle positions for hosts
// whose grid differs from ours. No I/O; nothing MPM-specific beyond the
// particle arrays. The potential is kept between calls as the warm start.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "lodestone/core/field/field_solver.h"
#include "lodestone/core/sources/field_source.h"
#include "lodestone/core/base/grid.h"
#include "lodestone/core/stage/magnetic_force.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/field/multipole.h"
#include "lodestone/core/stage/transfer.h"

namespace lodestone {
inline namespace stage {

struct MagneticStageSettings {
  BoundaryKind boundary = BoundaryKind::Open;     ///< far-field (default) or the paper's shield wall
  FieldSolveSettings solve;                       ///< Newton-PCG tolerances and caps
  ForceMask forceMask = ForceMask::Material;      ///< where the stress divergence may act
  int forceMaskDilation = 2;                      ///< nodes beyond the material kept by ForceMask::Material (0..8)
  OutOfGridPolicy outOfGrid = OutOfGridPolicy::Throw;  ///< particles whose stencil leaves the grid
  bool warmStart = true;                          ///< start each solve from the previous potential
  bool appliedFieldOnly = false;                  ///< skip the solve: phi = 0, H = H_ext (weak magnetization;
                                                  ///< the effects planner decides it from the susceptibility)

  /// Throws InvalidArgument naming the first bad value.
  void validate() const;
};

/// Timings (s) and outcome of one run of the stage.
struct MagneticStageReport {
  TransferReport transfer;     ///< zero when the density was given directly
  FieldSolveReport solve;
  double secondsTransfer = 0;
  double secondsAppliedField = 0;  ///< sources evaluated at nodes and Gauss points
  /// True when H_ext at the nodes was kept from the previous run: the same
  /// sources, unmoved, with the same time factor (FieldSource::appendFieldSignature);
  /// only the material's Gauss points were evaluated, and of those only the
  /// cells that were not material in the previous run.
  bool appliedFieldReused = false;
  std::size_t appliedFieldCellsEvaluated = 0;  ///< material cells whose 8 Gauss points were evaluated
  double secondsSolve = 0;
  double secondsFields = 0;        ///< nodal H, M, B
  double secondsForce = 0;
  double secondsTotal = 0;
  Vec3d totalForce;                ///< sum of nodal forces f_i, N
  double totalCount = 0;           ///< integral of n over the grid (micro-particles)
  std::vector<std::string> warnings;

  bool converged() const { return solve.converged(); }
  /// Multi-line human-readable summary with units.
  std::string summary() const;
};

/// The applied field as material sees it (A/m): inside a magnet's body, the
/// field outside continued through its nearest face
/// (FieldSource::exteriorContinuation), so that nodes and Gauss points that
/// the transfer's spread puts inside a magnet do not see its demagnetizing
/// field (and the force does not jump when a node crosses a face). `sources`
/// must outlive the function.
AppliedFieldFunction appliedFieldOf(const FieldSource& sources, double time);

class MagneticForceStage {
 public:
  /// Throws InvalidArgument on a bad grid or settings.
  MagneticForceStage(const GridSpec& grid, const MagneticMaterial& material,
                     const MagneticStageSettings& settings = {});

  /// Transfer + solve + force for material points at time t (s).
  MagneticStageReport run(const ParticleView& particles, const FieldSource& sources, double time);
  /// Solve + force for a density grid n (1/m^3) the host transferred itself.
  MagneticStageReport runOnDensity(GridView<const double> density, const FieldSource& sources, double time);
  /// Fields and force of density n (1/m^3) with potential phi (A) from a
  /// field solve done elsewhere (dist/'s solve across MPI ranks): no solve
  /// here, `solve` is reported as given; phi becomes the next warm start.
  MagneticStageReport runOnPotential(GridView<const double> density, GridView<const double> phi,
                                     const FieldSolveReport& solve, const FieldSource& sources, double time);

  /// Force on each material point (N), conservative: the nodal forces are
  /// first moved onto the support of n (gatherToSupport), then shared among
  /// the particles in proportion to their B-spline weight times n_p, so
  /// sum_p F_p = sum_i f_i. `particles` must be the ones of the last run():
  /// throws InvalidArgument when their count differs, or when a fingerprint
  /// of their positions and counts (up to 4096 of them, evenly spaced) does.
  /// After runOnDensity, ones whose deposit is the density given (not
  /// checked). Uses a grid kept in the stage: do not call it from two
  /// threads at once.
  TransferReport particleForces(const ParticleView& particles, Vec3d* out) const;
  /// Force density (N/m^3) at arbitrary positions: quadratic B-spline
  /// interpolation of f_i / dx^3. Not conservative near surfaces, where part
  /// of the surface traction sits on nodes outside the particles' reach;
  /// prefer particleForces for material points.
  TransferReport sampleForceDensity(const Vec3d* positions, std::size_t count, Vec3d* out) const;
  /// H (A/m) at particle positions (quadratic B-spline interpolation).
  TransferReport sampleField(const Vec3d* positions, std::size_t count, Vec3d* out) const;

  /// The material's far field after the last run: the block multipoles
  /// (dipole + quadrupole about each block's centre, Multipole::field) of
  /// its magnetization at the last run's potential, the expansion the open
  /// wall's values are summed from. Evaluates the material's Gauss points
  /// once. Empty before the first run.
  std::vector<Multipole> materialMultipoles();

  void setProgress(SolveProgress progress) { progress_ = std::move(progress); }
  /// Forget the warm start (next solve starts from phi = 0).
  void resetWarmStart();
  void setSettings(const MagneticStageSettings& settings);
  void setMaterial(const MagneticMaterial& material);

  const GridSpec& grid() const { return grid_; }
  /// The time (s) of the last run (0 before the first).
  double time() const { return time_; }
  const MagneticMaterial& material() const { return material_; }
  const MagneticStageSettings& settings() const { return settings_; }

  // Fields of the last run (one value per node).
  GridView<const double> density() const { return n_.view(); }            ///< n, 1/m^3
  GridView<const double> potential() const { return {phi_.data(), grid_}; }  ///< phi, A
  /// H_ext (A/m) as the material sees it: inside a magnet's body, the field
  /// outside continued through its nearest face (FieldSource::exteriorContinuation).
  GridView<const Vec3d> appliedField() const { return hext_.view(); }
  GridView<const Vec3d> field() const { return h_.view(); }               ///< H, A/m (true field, inside magnets too)
  /// M, A/m: the material's plus the sources' own (inside permanent magnets).
  GridView<const Vec3d> magnetization() const { return m_.view(); }
  GridView<const Vec3d> inductionField() const { return b_.view(); }      ///< B = mu0 (H + M), T
  GridView<const Vec3d> forceDensity() const { return t_.view(); }        ///< t = div T, N/m^3
  GridView<const Vec3d> nodalForce() const { return f_.view(); }          ///< f = R t, N

  /// The reaction of the material on `source` (sourceReaction): force (N)
  /// and torque (N*m about `centre`) after the last run. `allSources` and
  /// `time` must be those of that run (the magnets' own magnetization,
  /// which magnetization() includes inside them, is taken out with them).
  /// `source` is typically one member of `allSources`, a free magnet. One
  /// directional derivative of `source` per material node.
  MagnetWrench reactionOn(const FieldSource& source, const FieldSource& allSources, const Vec3d& centre,
                          double time) const;

 private:
  /// The stage after the density is in n_; with givenPhi, its potential
  /// (and givenSolve's report) instead of a solve.
  MagneticStageReport solveAndForce(const FieldSource& sources, double time, MagneticStageReport rep,
                                    const GridView<const double>* givenPhi = nullptr,
                                    const FieldSolveReport* givenSolve = nullptr);

  GridSpec grid_;
  MagneticMaterial material_;
  MagneticStageSettings settings_;
  SolveProgress progress_;
  double time_ = 0;  // s, of the last run
  ParticleBinning binning_;
  DenseGrid<double> n_;
  std::vector<double> phi_;
  DenseGrid<Vec3d> hext_, h_, m_, b_, t_, f_;
  // Kept between runs so that a run on the same grid allocates nothing
  // large and the multigrid hierarchy only refreshes its values; rebuilt
  // when the law or the boundary changes.
  std::unique_ptr<MagnetostaticProblem> problem_;
  std::unique_ptr<FieldSolveWorkspace> workspace_;
  // What hext_ holds: the sources' signature at its evaluation (empty: not
  // reusable).
  std::vector<double> hextSignature_;
  GridScratch scratch_;  // temporaries of the nodal fields and the force, kept between runs
  struct ParticleFingerprint {
    std::size_t count = 0;
    std::uint64_t hash = 0;
  };
  static ParticleFingerprint fingerprint(const ParticleView& particles);
  std::optional<ParticleFingerprint> lastParticles_;  // of the last run(); none after runOnDensity
  mutable DenseGrid<Vec3d> onSupport_;  // particleForces' nodal forces moved onto the material
};

}  // namespace stage
}  // namespace lodestone
