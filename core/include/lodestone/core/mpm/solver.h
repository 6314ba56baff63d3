#pragma once
// The reference MLS-MPM with nonlinear magnetism (Section 4.3 of the paper,
// PHYSICS.md section 5). One substep, top to bottom:
//
//   0. particles handed out through particles() or added by emit() since the
//      last substep are checked: outside the domain they are clamped back or
//      removed, non-finite ones removed (all counted);
//   1. P2G: mass and APIC momentum with the MLS stress impulse (mpm/grid.h);
//   2-3. the magnetic force: every `magneticSolveInterval` substeps (or once
//      per frame) the magnetic points (their positions at the start of the
//      substep, as P2G sees them) are handed to MagneticForceStage::run
//      exactly as an external host would, and its nodal force is kept and
//      reused until the next solve; with the planner on, a due solve is
//      skipped while the last one still holds (mpm/field_reuse.h). It is
//      computed before P2G, which deposits the per-particle forces;
//   4. grid update: v_i = (m v_i + dt f_i) / m_i + dt g, then the colliders'
//      and the domain walls' boundary conditions;
//   5-7. G2P (APIC), MLS update of F or J, advection (mpm/grid.h); advected
//      particles leaving the domain are clamped or removed, non-finite ones
//      removed, and counted in the report; particles that ended deeper
//      inside a collider than its allowance are pushed back (colliderProjection).
//      Every `reorderInterval` substeps, and after the first substep that
//      follows an emit(), the particles are then sorted by cell
//      (mpm/particle_order.h).
//
// Coupling to the magnetic stage. When the stage grid equals the MPM grid
// (the default), the stage's nodal force f_i (N) is first moved onto the
// support of the micro-particle density with gatherToSupport (conserving its
// sum): ForceMask::Material keeps force up to two nodes beyond the material,
// where the MPM has no mass and a force would be lost; on the support every
// node has mass, because mass and n are deposited by the same particles with
// the same weights. It is then added to the grid momentum (f_i dt). When the
// stage grid differs, MagneticForceStage::particleForces gives a
// conservative force per particle (N), kept in MpmParticles::magneticForce
// and deposited in P2G (w_ip F_p dt). Either way the total impulse is
// dt * (the stage's total force) up to force the stage drops.
//
// The domain: nodes within `wallNodes` (W) of a grid face are walls with the
// `walls` boundary condition (normal pointing into the domain); material is
// stopped about W - 1/2 nodes from the face (domainLower / domainUpper: a
// block placed with its bottom there rests without sinking, one placed at
// node W sinks into the last half cell). Particles are kept where their
// stencil fits: (x - origin)/dx in [1, dims - 2] per axis (a half-cell margin
// inside the valid range [1/2, dims - 3/2)); leaving that box counts as
// leaving the domain.
//
// Time stepping: a fixed dt, or dt = min(cfl dx / (max|v_p| + c), cfl dx^2 /
// (3 nu), 2 cfl t_sigma, cfl h_c / (max|v_p| + collider speed), dtMax) floored at dtMin,
// with c the largest elastic wave speed of the materials (sqrt((lambda + 2
// mu)/rho) or sqrt(K/rho)), nu the largest kinematic viscosity (the explicit
// diffusion limit dx^2/(6 nu) at cfl = 1/2) and h_c the thinnest collider
// half-thickness (colliderCrossingDt), t_sigma = min sqrt(rho dx^3 / (2 pi
// sigma)) over the liquids with surface tension (Brackbill et al. 1992; the
// capillary limit, mpm/surface_tension.h).
// A fixed dt above the stability bound (stabilityLimitDt) is shortened by
// advanceFrame, with a warning, rather than taken and blown up.
//
// Known limitations of the scheme (measured in tests/core/test_mpm_*.cpp):
// APIC transfers damp elastic vibration at the grid scale (an 8-cell block
// loses about 90% of its breathing-mode energy in 14 periods); the J-only fluid on a
// collocated grid carries pressure modes the grid cannot see (alternating J
// within a cell, nodal checkerboard), so its per-particle pressure is noisy
// after violent flow though its grid-visible mean is hydrostatic; fluids seep
// up to about half a cell into separate/slip wall layers; particle density
// drifts from 1/J in fluids (particles cluster without a pressure response).
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "lodestone/core/planner/effects_planner.h"
#include "lodestone/core/sources/field_source_set.h"
#include "lodestone/core/base/grid.h"
#include "lodestone/core/sources/magnet_source.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/core/stage/magnetic_patches.h"
#include "lodestone/core/mpm/collider.h"
#include "lodestone/core/mpm/emitter.h"
#include "lodestone/core/mpm/field_reuse.h"
#include "lodestone/core/mpm/grid.h"
#include "lodestone/core/mpm/material.h"
#include "lodestone/core/mpm/particles.h"
#include "lodestone/core/mpm/partition.h"
#include "lodestone/core/mpm/rate_emitter.h"
#include "lodestone/core/mpm/rigid_body.h"
#include "lodestone/core/mpm/rigid_contact.h"
#include "lodestone/core/sources/magnet_interaction.h"

namespace lodestone {
inline namespace mpm {

/// What to do with a particle that leaves the domain (see the header comment).
enum class OutOfDomainPolicy : int {
  Clamp = 0,  ///< move it back to the domain edge and stop its outward motion
  Remove = 1  ///< delete it
};

struct MpmSettings {
  GridSpec grid;                   ///< the MPM grid (at least 4 nodes per axis)
  Vec3d gravity{0.0, 0.0, -9.81};  ///< m/s^2
  BoundaryCondition walls;         ///< domain walls (default: separate, frictionless)
  int wallNodes = 2;               ///< wall layer thickness in nodes (0 = no walls)
  OutOfDomainPolicy outOfDomain = OutOfDomainPolicy::Clamp;

  double fixedDt = 0;   ///< > 0: every substep takes this dt (s); 0: CFL-adaptive
  double cfl = 0.4;     ///< fraction of a cell a wave or particle may cross per substep
  double dtMax = 1e-3;  ///< s
  double dtMin = 1e-7;  ///< s; a smaller CFL step is raised to this (and reported)
  /// Substeps per frame: advanceFrame takes at least minSubsteps (dt <=
  /// frame / minSubsteps, e.g. for smoother collider motion or sub-frame
  /// output), and throws lodestone::Error naming the frame, the substep
  /// count and the step that set it when a frame would need more than
  /// maxSubsteps (0: no limit): a scene that stiffens or speeds up past what
  /// the artist budgeted stops with a message instead of running on for hours.
  int minSubsteps = 1;
  int maxSubsteps = 0;

  int reorderInterval = 20;  ///< substeps between sorts of the particles by grid cell, for memory locality in P2G;
                             ///< the first substep after an emit() also sorts
                             ///< (0 = never: indices stay stable; MpmParticles::id survives either way)
  /// Hold the MPM grid whole: laid out over the whole grid, the grid update
  /// visits every node and P2G zeroes them all, as a process of a partition
  /// does with its window. Off (the default), the grid holds and visits only
  /// the runs of nodes the particles' stencils reach on each x-row, packed
  /// back to back (mpm/grid.h). The particles
  /// are the same bit for bit either way; dense takes the whole grid's
  /// memory and is never faster (docs/benchmarks.md, "The MPM grid against
  /// particle count and domain size"): the reference the sparse grid is
  /// checked against.
  bool denseGrid = false;

  int magneticSolveInterval = 0;         ///< substeps between field solves; 0 = automatic (below)
  /// With magneticSolveInterval == 0: the field is solved at the first
  /// substep of each frame and again as soon as a magnetic point or a
  /// magnet (its centre, or its rotation times its size) has moved this many
  /// magnetic-grid cells since the last solve, so the solve frequency follows
  /// the motion, not the frame rate. 0: exactly once per frame.
  double magneticSolveDistance = 0.25;
  std::optional<GridSpec> magneticGrid;  ///< grid of the magnetic stage; empty = the MPM grid (a grid not covering
                                         ///< every magnetic particle needs magnetic.outOfGrid = Skip)
  MagneticStageSettings magnetic;        ///< settings of the magnetic stage
  PlannerSettings planner;               ///< effects planner (off: every magnetic stage runs as configured)

  /// Scan every substep for NaN/Inf (particles' x, v, C, F, J, magnetic
  /// force; the grid's mass, momentum and velocity on the active runs; the
  /// magnetic nodal force) and throw lodestone::Error naming the quantity, the
  /// substep and the particle (index and id) or node. Off by default: the
  /// solver then removes non-finite particles and counts them. About one
  /// extra pass over the particles and the active grid per substep.
  bool checkFinite = false;

  /// After advection, particles found deeper inside a collider than
  /// colliderAllowance() are pushed back out along the normal to that depth,
  /// with the collider's boundary condition applied to their velocity
  /// (MpmCollider::projectOut), and the substep is limited so that no
  /// particle moves, relative to a collider, more than the rest of the
  /// collider's thinnest half-thickness (ColliderShape::halfThickness) in
  /// one substep: material then cannot cross a wall however thin it is or
  /// however hard it is pushed. The allowance leaves the shallow contact
  /// layer to the grid's boundary condition, so that moving particles
  /// (which does not change their deformation) does not set a pressed
  /// elastic body. Off: only the grid nodes inside a collider see its
  /// boundary condition, which holds for walls a few cells thick and gentle
  /// loads but lets strongly pushed material seep into walls and through
  /// walls thinner than about two cells. One signed-distance evaluation per
  /// particle and collider per substep.
  bool colliderProjection = true;

  /// Throws InvalidArgument naming the first bad value.
  void validate() const;
};

/// Energies of the particle system (J).
struct MpmEnergies {
  double kinetic = 0;        ///< sum 1/2 m_p |v_p|^2
  double gravitational = 0;  ///< -sum m_p g . x_p (zero at the world origin)
  double elastic = 0;        ///< sum V_p^0 Psi (Neo-Hookean, Hencky of F_E, or K/2 (J-1)^2)
  double total() const { return kinetic + gravitational + elastic; }
};

/// Outcome and timings (s) of one substep.
struct MpmStepReport {
  double dt = 0;               ///< s
  double time = 0;             ///< time after the substep, s
  double secondsP2G = 0;       ///< domain check, binning and P2G
  double secondsBinning = 0;   ///< part of secondsP2G
  double secondsMagnetic = 0;  ///< transfer + solve + force (+ coupling), when a solve ran
  double secondsGridUpdate = 0;
  double secondsG2P = 0;  ///< G2P, F/J update, advection, domain check
  double secondsTotal = 0;
  bool magneticSolved = false;   ///< a field solve ran in this substep
  bool magneticReused = false;   ///< a solve was due but the planner reused the last one (nothing moved enough)
  MagneticStageReport magnetic;  ///< its report (when magneticSolved)
  Vec3d magneticImpulse;         ///< dt * magnetic force applied this substep, N*s
  std::size_t particles = 0;     ///< particles after the substep
  std::size_t clamped = 0;       ///< particles clamped back into the domain
  std::size_t removed = 0;       ///< particles removed (out of domain under Remove, or non-finite)
  std::size_t nonFinite = 0;     ///< of the removed, those with a non-finite state
  std::size_t projected = 0;     ///< particles pushed out of a collider (MpmSettings::colliderProjection)
  double maxSpeed = 0;           ///< max |v_p| after G2P, m/s
  RateEmitReport emitted;        ///< what the rate emitters added (8.)
};

/// A dynamic rigid body (MpmCollider::setDynamics) at the end of a frame,
/// with what acted on it during the frame.
struct RigidBodyReport {
  std::size_t collider = 0;       ///< collider index
  long magnet = -1;               ///< magnet index, -1 for a collider that is not a magnet
  Pose pose;                      ///< of the body origin
  Vec3d velocity;                 ///< of the centre of mass, m/s
  Vec3d angularVelocity;          ///< world frame, rad/s
  Vec3d magneticForce;            ///< N, at the last substep (material's reaction + other magnets)
  Vec3d magneticTorque;           ///< N*m about the centre of mass, at the last substep
  Vec3d materialImpulse;          ///< N*s the material exerted over the frame (grid exchange and projection)
  Vec3d contactImpulse;           ///< N*s from contacts with bodies, colliders and walls over the frame
};

/// Outcome of advanceFrame.
struct MpmFrameReport {
  int substeps = 0;
  double time = 0;              ///< time at the end, s
  double minDt = 0, maxDt = 0;  ///< s
  int dtAtMinimum = 0;          ///< substeps whose CFL step was raised to dtMin
  int dtLimitedByCfl = 0;       ///< substeps whose fixed dt exceeded stabilityLimitDt() and was shortened
  double secondsP2G = 0, secondsMagnetic = 0, secondsGridUpdate = 0, secondsG2P = 0, secondsTotal = 0;
  double secondsBinning = 0;  ///< part of secondsP2G: the particle sort by stencil bin
  std::vector<MagneticStageReport> magneticReports;  ///< one per field solve
  int magneticReused = 0;                            ///< due solves the planner skipped (field reused)
  Vec3d magneticImpulse;                             ///< sum over substeps of dt * applied magnetic force, N*s
  std::size_t clamped = 0, removed = 0, nonFinite = 0;
  std::size_t projected = 0;  ///< particle pushes out of colliders, summed over the substeps
  int dtLimitedByColliders = 0;  ///< substeps whose CFL step was set by a collider's thickness
  RateEmitReport emitted;  ///< what the rate emitters added, summed over the substeps
  MpmEnergies energies;    ///< at the end of the frame
  bool cancelled = false;  ///< the progress callback asked to stop
  std::vector<RigidBodyReport> bodies;  ///< the dynamic rigid bodies, in collider order
  std::vector<std::string> warnings;
  /// Multi-line summary with units.
  std::string summary() const;
};

/// Progress of a frame: called after every substep; return false to stop.
struct MpmProgress {
  int substep = 0;
  double time = 0;      ///< s
  double fraction = 0;  ///< of the frame done, 0..1
};
using MpmProgressCallback = std::function<bool(const MpmProgress&)>;

class MpmSolver {
 public:
  /// Throws InvalidArgument on bad settings.
  explicit MpmSolver(const MpmSettings& settings);
  ~MpmSolver();
  MpmSolver(const MpmSolver&) = delete;
  MpmSolver& operator=(const MpmSolver&) = delete;

  const MpmSettings& settings() const { return settings_; }

  /// The particles. Taking them mutably marks them for a domain check (and
  /// clamping or removal) at the start of the next substep.
  MpmParticles& particles() {
    particlesDirty_ = true;
    return particles_;
  }
  const MpmParticles& particles() const { return particles_; }

  /// Adds a material and returns its index. All magnetic materials must share
  /// one magnetization law (they may differ in n0): one stage solves them all.
  std::uint32_t addMaterial(const MpmMaterial& material);
  const std::vector<MpmMaterial>& materials() const { return materials_; }

  /// Fills a shape with particles of material `material` (an index from
  /// addMaterial); a zero settings.cellSize means the MPM grid's dx.
  EmitReport emit(const EmitterShape& shape, std::uint32_t material, EmitterSettings settings);

  /// Adds a source that emits material of `material` over time (mpm/rate_emitter.h);
  /// a zero settings.lattice.cellSize means the MPM grid's dx. Returns its index.
  std::size_t addEmitter(const EmitterShape& shape, std::uint32_t material, RateEmitterSettings settings);
  std::size_t emitterCount() const { return emitters_.size(); }
  const RateEmitter& emitter(std::size_t i) const;

  /// Adds a collider (kinematic, or dynamic after MpmCollider::setDynamics:
  /// see "Rigid bodies" below).
  std::size_t addCollider(const MpmCollider& collider);
  std::size_t colliderCount() const { return colliders_.size(); }
  MpmCollider& collider(std::size_t i);
  const MpmCollider& collider(std::size_t i) const;

  /// The applied-field sources (coils, uniform fields, static magnets).
  /// Magnets added with addMagnet or addNonCollidingMagnet are kept separately.
  FieldSourceSet& sources() { return sources_; }
  const FieldSourceSet& sources() const { return sources_; }
  void setSources(FieldSourceSet sources) { sources_ = std::move(sources); }

  /// A permanent magnet that is both a field source and a collider of its
  /// own shape (SphereMagnet -> sphere, CylinderMagnet -> cylinder,
  /// CuboidMagnet -> box; other kinds throw). The magnet's pose follows
  /// `motion` (before each field solve it is moved to motion.poseAt(t)).
  /// Returns the collider index.
  std::size_t addMagnet(const MagnetSource& magnet, const ColliderMotion& motion,
                        const BoundaryCondition& boundary = BoundaryCondition());
  /// As above, resting at the magnet's current pose.
  std::size_t addMagnet(const MagnetSource& magnet, const BoundaryCondition& boundary = BoundaryCondition());
  /// A permanent magnet that is a field source only (material passes
  /// through it; any MagnetSource). Its pose follows `motion` before each
  /// field solve, as a colliding magnet's does. Returns the magnet index.
  std::size_t addNonCollidingMagnet(const MagnetSource& magnet, const ColliderMotion& motion);
  std::size_t magnetCount() const { return magnets_.size(); }
  const MagnetSource& magnet(std::size_t i) const;

  /// The applied field the stage sees: sources() plus the magnets.
  const FieldSource& appliedField() const;

  /// The substep the solver would take now (s): fixedDt, or the CFL step.
  double suggestedDt() const;
  /// The largest stable substep now (s): dx / (max|v_p| + c), the
  /// explicit viscous limit dx^2 / (6 nu), the capillary limit sqrt(rho dx^3
  /// / (2 pi sigma)) of the liquids with surface tension and, with colliderProjection, the
  /// collider crossing limit colliderCrossingDt(); infinite for an empty or
  /// static inviscid scene. advanceFrame shortens a fixedDt above it to cfl times
  /// it (counted in MpmFrameReport::dtLimitedByCfl, with a warning).
  double stabilityLimitDt() const;
  /// The time (s) in which the fastest particle, relative to a collider's
  /// fastest point, would cross the collider's thinnest half-thickness less
  /// its allowance: min over colliders of (halfThickness - allowance) /
  /// (max|v_p| + |v_c| + |w_c| r),
  /// r the distance from the collider's origin to the farthest domain
  /// corner. Infinite without colliders, with only planes and inverted
  /// analytic shapes, or when nothing moves.
  double colliderCrossingDt() const;
  /// How deep (m) particles may lie inside collider `c` before the
  /// projection moves them: min(dx / 2, halfThickness / 2), the depth the
  /// grid's boundary condition alone lets material seep to.
  double colliderAllowance(std::size_t c) const;
  /// One substep of dt (s, finite, > 0).
  MpmStepReport step(double dt);
  /// Substeps until the time has advanced by frameDuration (s); the last
  /// substep is shortened to land on the frame end. With
  /// magneticSolveInterval == 0 the field is solved at the frame's first substep.
  MpmFrameReport advanceFrame(double frameDuration, const MpmProgressCallback& progress = {});

  double time() const { return time_; }
  void setTime(double t);

  // Rigid bodies. A dynamic collider (MpmCollider::setDynamics; a colliding
  // magnet made dynamic with collider(c).setDynamics) is moved every substep,
  // two-way coupled with the material:
  //   a. its velocity takes gravity and, for a magnet, the magnetic force and
  //      torque (magnetWrench): the reaction of the material it magnetizes
  //      and the pull of the other magnets (magnet_interaction.h);
  //   b. contacts with the other bodies, the kinematic colliders and the
  //      domain walls (rigid_contact.h);
  //   c. in the grid update, the body and the grid nodes with mass inside it
  //      or within one cell of it exchange momentum: the body's velocity
  //      V = (v, w) solves
  //        (M + sum_i m_i J_i^T P_i J_i) V = M V_pred + sum_i m_i J_i^T P_i v_i,
  //      J_i V = v + w x (x_i - x_c) the body's velocity at node i, v_i the
  //      node's velocity, inside the body without the substep's gravity (its
  //      mass is the kernels' reach of material outside the body, whose
  //      weight the material's pressure carries, not the body), P_i = I
  //      (sticky), n n^T (slip, and separate where the node approaches),
  //      which is the momentum balance with the nodes taking the body's
  //      normal velocity; the collider's boundary condition (with friction)
  //      is then applied with that velocity and the body takes exactly the
  //      opposite of the nodes' momentum change, so material + body conserve
  //      linear and angular momentum (without gravity exactly; with it, up
  //      to the weight of the material mass on nodes inside bodies).
  //      Implicit in V: stable for bodies much
  //      lighter than the material around them;
  //   d. its pose advances (rigid_body.h); particles the projection pushes out
  //      of it give it the opposite of their momentum change.

  /// The dynamic bodies now (their last frame's impulses are not kept here:
  /// advanceFrame reports them).
  std::vector<RigidBodyReport> rigidBodies() const;
  /// Force (N) and torque (N*m, about its centre) of the field on magnet m
  /// as last computed (zero unless the magnet is dynamic).
  MagnetWrench magnetWrench(std::size_t m) const;

  MpmEnergies energies() const;
  /// Where the wall layers act, m: a wall made of the nodes below index W
  /// (W = wallNodes) stops material at about W - 1/2 nodes from the face, so
  /// the domain is [origin + (W - 1/2) dx, origin + (dims - 1 - W + 1/2) dx]
  /// per axis; a body resting on the floor has its bottom at domainLower().z.
  Vec3d domainLower() const;
  Vec3d domainUpper() const;
  const MpmGrid& grid() const { return grid_; }
  /// The magnetic stage (null before the first field solve, and while the
  /// planner solves separate patches of material: magneticPatches()).
  const MagneticForceStage* magneticStage() const { return stage_.get(); }
  /// The patches of the last field solve when the planner chose several
  /// (PlannerSettings::patches); null otherwise.
  const MagneticPatches* magneticPatches() const { return patches_.get(); }
  /// Called after each Newton iteration of the field solves this solver
  /// runs: a host's point of cancellation inside a substep (advanceFrame's
  /// callback runs only between substeps). Returning false stops that solve:
  /// the substep goes on with the field reached so far and its report says
  /// so (MagneticStageReport::solve.status Cancelled); the caller then stops
  /// the frame from its advanceFrame callback. Empty (the default): none.
  void setFieldSolveProgress(SolveProgress progress) { fieldSolveProgress_ = std::move(progress); }
  /// The nodal magnetic force (N) applied on the MPM grid until the next
  /// solve; an empty view (null data) before the first field solve on the
  /// MPM grid and when the stage grid differs from the MPM grid.
  GridView<const Vec3d> magneticNodalForce() const { return magneticForce_.view(); }
  /// Force the last solve could not place on the support of the density
  /// (gatherToSupport's dropped part), N.
  Vec3d magneticForceDropped() const { return magneticDropped_; }

  /// Forget the magnetic stage's warm start: the next field solve starts
  /// from phi = 0, as it does in a solver restored from a checkpoint (which
  /// is why the `lodestone` command calls it after writing one: a resumed
  /// run then repeats the uninterrupted one bit for bit).
  void resetMagneticWarmStart();

  /// Substeps taken since construction (or restored from a checkpoint).
  long long substepCount() const { return substeps_; }

  /// Shares this simulation with other processes (mpm/partition.h): every
  /// process builds the same solver (materials, colliders, sources,
  /// particles) and calls this with its part of one partition, before or
  /// after emitting; each keeps only the particles it owns (emit() and the
  /// rate emitters keep only those from then on) and holds the MPM grid on
  /// its window.
  /// From then on step() and advanceFrame() are collective: every process
  /// calls them with the same arguments. Surface tension sums its colour
  /// field over the processes (a second exchange inside P2G); a dynamic rigid
  /// body's momentum exchange gathers its coupling nodes and pushed particles
  /// from every process and each runs the same exchange. Throws
  /// InvalidArgument for a null partition or one whose window does not lie
  /// in the grid or is thinner than 3 nodes.
  /// The field solve runs on every process on the gathered magnetic points
  /// (the same solve, replicated); each applies its window of the force.
  void setPartition(std::shared_ptr<MpmPartition> partition);
  /// The particles of the whole simulation: particles().size(), summed over
  /// the processes with a partition (collective).
  std::size_t totalParticles() const;
  /// The partition, or null when the solver holds the whole simulation.
  const MpmPartition* partition() const { return partition_.get(); }
  /// With a partition: moves every particle to rank 0 (collective) so that
  /// rank 0 holds the whole simulation's particles, e.g. to write a frame;
  /// the next substep hands them back to their owners. Without: nothing.
  void gatherParticlesToRoot();

  /// The effects planner's decisions for the magnetic stages in the current
  /// state (what the next field solve would do), without solving.
  MagneticPlan planMagneticNow() const;
  /// The plan with the material where it is now and the sources (magnets'
  /// motion, time profiles) at time t (s): what a solve at t would do if
  /// the material had not moved. The magnets are posed back afterwards.
  MagneticPlan planMagneticAt(double t) const;
  /// The plan of the last field solve (empty decisions before the first, or
  /// when the planner is off).
  const MagneticPlan& lastMagneticPlan() const { return lastPlan_; }

 private:
  friend struct MpmCheckpointAccess;  // checkpoint.cpp reads and restores the private state
  void checkFiniteParticles(const char* where) const;
  /// The CFL step (or, with `bound`, the stability bound); *byColliders is
  /// set when the collider crossing limit is the one that binds.
  double cflDt(double cfl, bool bound, bool* byColliders = nullptr) const;
  double colliderCrossingDt(double vmax) const;  // with the fastest particle's speed (m/s) given
  void checkFiniteGrid(const char* where) const;
  // Throws naming the first node of `stage` with a non-finite H or nodal
  // force (`nodeKind` says what its index counts) and the solve's outcome.
  void checkFiniteStage(const MagneticForceStage& stage, const char* nodeKind, const FieldSolveReport& solve) const;
  class SceneField;
  std::size_t enforceDomain(std::size_t& removedOut, std::size_t& nonFiniteOut);
  ParticleBounds domainBounds() const;
  bool anyMagneticParticles() const;
  // The substep's phases (step reads as their sequence).
  void enforceDomainOfHandedOut(MpmStepReport& rep);   // 0.
  void updateMagneticForce(MpmStepReport& rep);        // 2-3.: solve when due, unless the last one holds
  void particleToGrid(double dt, MpmStepReport& rep);  // 1.
  void gridUpdate(double dt, MpmStepReport& rep);      // 4.
  bool gridToParticle(double dt, MpmStepReport& rep);  // 5-7.; true when particles were removed after it
  std::size_t projectOutOfColliders(double dt, std::size_t& outside);  // particles pushed out; outside: now beyond the domain
  double maxParticleSpeed() const;                     // m/s
  // Rigid bodies (rigid_coupling.cpp).
  bool anyDynamicBodies() const;
  void predictRigidBodies(double dt);                       // a.-b.
  void exchangeWithRigidBodies(double dt);                  // c. (in the grid update)
  void advanceRigidBodies(double dt);                       // d.
  // The collider projection for dynamic collider c at state s: particles
  // pushed out and their momentum exchanged with the body; returns how many
  // were pushed, adding to `outside` those now beyond `bounds`.
  std::size_t pushOutOfBody(std::size_t c, const ColliderState& s, double allowed, const ParticleBounds& bounds,
                            std::size_t& outside);
  void updateMagnetWrenches();                              // magnetWrench_ of the dynamic magnets
  std::size_t colliderMagnet(std::size_t c) const;          // magnet index of collider c, or magnetCount()
  void solveMagnetic(MpmStepReport& rep);
  void emitFromEmitters(double dt, MpmStepReport& rep);  // 8.
  double maxEmissionSpeed() const;                       // m/s, of the emitters on within the next dtMax
  bool lastSolveHolds();  // the planner's reuse test (field_reuse.h); poses the magnets when it samples the field
  bool isMagneticPoint(std::size_t p) const;    // a particle with n_p > 0 of a magnetic material
  const MagneticMaterial* magneticLaw() const;  // the (shared) law of the magnetic materials, or null
  void poseMagnetsAt(double t) const;
  const ColliderMotion& magnetMotion(std::size_t m) const;
  /// Whether a magnetic point or a magnet moved magneticSolveDistance cells since the last solve.
  bool movedSinceSolve() const;           // move the magnets to their motion's pose at t (s)
  PlannerInputs plannerInputs(const std::vector<Vec3d>& positions, const MagneticMaterial& law) const;
  // The magnetic points of the whole simulation: index (into particles_,
  // or kElsewhere for a point another process holds), position, n_p and id.
  // Without a partition the solver's own, in index order; with one, every
  // process's, gathered and sorted by id (the same on every process).
  struct MagneticPoints {
    static constexpr std::uint32_t kElsewhere = ~std::uint32_t(0);
    std::vector<std::uint32_t> index;
    std::vector<Vec3d> x;
    std::vector<double> count;
    std::vector<std::uint64_t> id;  // with a partition (ascending)
  };
  // Fills `out` with the magnetic points, keeping its storage: a solve every
  // substep refills the same arrays instead of growing new ones.
  void magneticPoints(MagneticPoints& out) const;
  // Whether every magnetic point lies within `distance` (m) of its place at
  // the last solve (FieldReuse::pointsWithin). With a partition each process
  // tests its own points against the record, which every process keeps in
  // id order (solvedIds_), and the answer is agreed (collective).
  bool magneticPointsWithin(double distance) const;
  void keepOwnedParticles(std::size_t from);  // with a partition: drops particles [from, size) owned elsewhere

  MpmSettings settings_;
  GridSpec magneticGrid_;
  bool sameGrid_ = true;
  MpmParticles particles_;
  std::vector<MpmMaterial> materials_;
  std::vector<MpmCollider> colliders_;
  std::vector<RateEmitter> emitters_;
  FieldSourceSet sources_;
  std::vector<std::unique_ptr<MagnetSource>> magnets_;
  static constexpr std::size_t kNoCollider = ~std::size_t(0);
  std::vector<std::size_t> magnetCollider_;  // collider index of each magnet, kNoCollider for none
  std::vector<ColliderMotion> magnetMotion_;  // motion of each magnet without a collider
  std::unique_ptr<SceneField> scene_;
  MpmGrid grid_;
  std::unique_ptr<MagneticForceStage> stage_;
  std::unique_ptr<MagneticPatches> patches_;  // instead of stage_ when the planner chose patches
  // The field solve on the planner's patches (solveMagnetic's part for them).
  void solvePatches(const MagneticPoints& points, const MagneticMaterial& law, MpmStepReport& rep);
  SolveProgress fieldSolveProgress_;  // setFieldSolveProgress
  DenseGrid<Vec3d> magneticForce_;  // on the MPM grid (same-grid coupling)
  // solveMagnetic's points and their forces (N), kept between solves.
  MagneticPoints magneticPoints_;
  std::vector<Vec3d> magneticPointForces_;
  Vec3d magneticDropped_;
  bool haveMagneticForce_ = false;
  bool frameStart_ = false;
  bool particlesDirty_ = true;
  double knownMaxSpeed_ = -1;  // m/s: max |v_p| from the last substep's G2P, when still exact (else < 0)
  bool emittedSinceSort_ = false;  // emit() since the last sort: the next substep sorts (particle_order.h)
  int stepsSinceSolve_ = 0;
  MagneticPlan lastPlan_;
  std::vector<RigidBodyState> rigid_;                 // the substep's body states: one per collider, then the walls
  std::vector<std::vector<Vec3d>> contactSamples_;  // per collider (computed on first use)
  std::vector<MagnetWrench> magnetWrench_;          // per magnet: reaction + other magnets
  std::vector<MagnetWrench> magnetReaction_;        // per magnet: the material's pull at the last field solve
  std::vector<Vec3d> materialImpulse_, contactImpulse_;  // per collider, since the frame started
  std::shared_ptr<MpmPartition> partition_;  // setPartition; null: this solver holds the whole simulation
  std::vector<std::uint64_t> solvedIds_;     // with a partition: ids of reuse_'s positions (ascending)
  FieldReuse reuse_;  // the last solve's record for the planner's reuse test, permuted with the particles
  long long substeps_ = 0;
  double time_ = 0;
};

}  // namespace mpm
}  // namespace lodestone
