#include "lodestone/plugin/node_builders.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <string>

#if __has_include(<unistd.h>)
#include <unistd.h>
#endif

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/number_text.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/mpm/grid.h"
#include "lodestone/core/sources/cuboid_magnet.h"
#include "lodestone/core/sources/cylinder_magnet.h"
#include "lodestone/core/sources/point_dipole.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/plugin/errors.h"
#include "lodestone/plugin/node_registry.h"

#if LODESTONE_PLUGIN_HAVE_VDB
#include "lodestone/vdb_io/field_file.h"
#include "lodestone/vdb_io/level_set_file.h"
#include "lodestone/vdb_io/render_frame.h"
#include "lodestone/plugin/output/mesh_files.h"
#endif

namespace lodestone::plugin {

Pose poseAlong(const Vec3d& centre, const Vec3d& axis) {
  const Vec3d z{0, 0, 1};
  const Vec3d k = cross(z, axis);
  const double s = norm(k), c = dot(z, axis);
  if (s < 1e-12) return c > 0 ? Pose::at(centre) : Pose::fromAxisAngle(centre, {1, 0, 0}, kPi);
  return Pose::fromAxisAngle(centre, k / s, std::atan2(s, c));
}

bool isFileShape(const std::string& shape) { return shape == "level_set" || shape == "mesh"; }

std::shared_ptr<const SampledSdf> loadShapeFile(const std::string& shape, const std::string& path,
                                                const std::string& grid, double voxelSize) {
#if LODESTONE_PLUGIN_HAVE_VDB
  if (shape == "level_set") return std::make_shared<const SampledSdf>(readLevelSetVdb(path, grid));
  return std::make_shared<const SampledSdf>(levelSetFromObj(path, voxelSize));
#else
  (void)grid;
  (void)voxelSize;
  throw NotBuilt(concat("shape '", shape, "' (", path, ") needs OpenVDB, which this build of Lodestone lacks"));
#endif
}

EmitterShape shapeFrom(const ParamSet& p) {
  const std::string& shape = p.getString("shape");
  if (isFileShape(shape)) {
    const double voxel = p.getFloat("voxel_size") > 0 ? p.getFloat("voxel_size") : p.getFloat("cell_size");
    return EmitterShape::levelSetShape(poseAlong({}, p.getVec3("axis")),
                                       loadShapeFile(shape, p.getString("file"), p.getString("grid"), voxel));
  }
  const Pose pose = poseAlong(p.getVec3("center"), p.getVec3("axis"));
  if (shape == "box") return EmitterShape::box(pose, p.getVec3("half_size"));
  if (shape == "sphere") return EmitterShape::sphere(pose, p.getFloat("radius"));
  return EmitterShape::cylinder(pose, p.getFloat("radius"), p.getFloat("half_length"));
}

ColliderMotion motionFrom(const ParamSet& p, const Pose& rest) {
  const Vec3d v = p.getVec3("motion.velocity"), w = p.getVec3("motion.angular_velocity");
  if (norm2(v) == 0 && norm2(w) == 0) return ColliderMotion::fixed(rest);
  return ColliderMotion::constantVelocity(rest, v, w);
}

std::optional<RigidBodySettings> rigidBodyFrom(const ParamSet& p) {
  if (!p.getBool("dynamic")) return std::nullopt;
  RigidBodySettings b;
  b.density = p.getFloat("density");
  b.mass = p.getFloat("mass");
  b.restitution = p.getFloat("restitution");
  b.friction = p.getFloat("contact_friction");
  b.validate("rigid body");
  return b;
}

SourcesData::Magnet magnetFrom(const ParamSet& p, Pose* restPose) {
  SourcesData::Magnet m;
  const Pose pose = poseAlong(p.getVec3("center"), p.getVec3("axis"));
  m.magnet = makeMagnet(p, pose);
  m.motion = motionFrom(p, pose);
  m.collider = p.getBool("collider");
  m.boundary = boundaryFrom(p);
  m.dynamics = rigidBodyFrom(p);
  if (m.dynamics && !m.collider)
    throw InvalidArgument("magnet: a dynamic magnet must be a collider (collider = true): its body is what moves");
  if (restPose) *restPose = pose;
  return m;
}

std::unique_ptr<MagnetSource> makeMagnet(const ParamSet& p, const Pose& pose) {
  const double M =
      p.given("remanence") ? magnetizationFromRemanence(p.getFloat("remanence")) : p.getFloat("magnetization");
  const Vec3d body{0, 0, M};  // along the magnet's axis
  const std::string& shape = p.getString("shape");
  if (shape == "sphere") return std::make_unique<SphereMagnet>(pose, p.getFloat("radius"), body);
  if (shape == "box") return std::make_unique<CuboidMagnet>(pose, p.getVec3("half_size"), body);
  return std::make_unique<CylinderMagnet>(pose, p.getFloat("radius"), p.getFloat("half_length"), body);
}

EmitterSettings emitterSettingsFrom(const ParamSet& p) {
  EmitterSettings e;
  e.cellSize = p.getFloat("cell_size");
  e.particlesPerCell = int(p.getInt("particles_per_cell"));
  e.jitter = p.getFloat("jitter");
  e.seed = std::uint64_t(p.getInt("seed"));
  e.velocity = p.getVec3("velocity");
  return e;
}

RateEmitterSettings rateEmitterSettingsFrom(const ParamSet& p, const ColliderMotion& motion) {
  RateEmitterSettings s;
  s.lattice = emitterSettingsFrom(p);
  if (p.given("speed")) {
    s.lattice.velocity = {0, 0, p.getFloat("speed")};
    s.velocityInBodyFrame = true;
  }
  const std::string& rate = p.getString("rate");
  require(rate != "stream" || p.given("speed"),
          "a stream rate needs `speed`, the emission speed along the axis in m/s (velocity is in the world frame)");
  s.rateKind = rate == "volume"      ? EmissionRateKind::VolumePerSecond
               : rate == "particles" ? EmissionRateKind::ParticlesPerSecond
                                     : EmissionRateKind::Stream;
  if (rate == "volume") s.rate = p.getFloat("volume_rate");
  if (rate == "particles") s.rate = p.getFloat("particle_rate");
  s.inheritMotion = p.getBool("inherit_motion");
  s.motion = motion;
  s.followsMotion = motion.kind() != ColliderMotion::Kind::Static;
  if (p.given("intervals")) {
    require(!p.given("start") && !p.given("end"), "give start and end, or intervals, not both");
    const std::vector<double>& t = p.getFloats("intervals");
    require(t.size() % 2 == 0, "intervals holds ", t.size(), " times; it needs on, off pairs (an even count)");
    std::vector<std::pair<double, double>> onOff;
    for (std::size_t k = 0; k < t.size(); k += 2) onOff.emplace_back(t[k], t[k + 1]);
    s.schedule = EmissionSchedule::intervals(std::move(onOff));
  } else {
    s.schedule = EmissionSchedule::between(p.getFloat("start"),
                                           p.given("end") ? p.getFloat("end") : EmissionSchedule::kForever);
  }
  return s;
}

double estimatedEmittedParticles(const EmitterShape& shape, const RateEmitterSettings& s, double start,
                                 double end) {
  const double cell = s.lattice.cellSize, ppc = s.lattice.particlesPerCell;
  const double pointVolume = cell * cell * cell / ppc;  // m^3
  const double chunk = estimatedParticles(shape.volume(), cell, s.lattice.particlesPerCell);
  double perSecond = 0;
  switch (s.rateKind) {
    case EmissionRateKind::VolumePerSecond:
      perSecond = s.rate / pointVolume;
      break;
    case EmissionRateKind::ParticlesPerSecond:
      perSecond = s.rate;
      break;
    case EmissionRateKind::Stream: {
      // A chunk each time the material has moved the shape's length along its axis.
      const double length = shape.kind == EmitterShapeKind::Box      ? 2 * shape.halfSize.z
                            : shape.kind == EmitterShapeKind::Sphere ? 2 * shape.radius
                                                                     : 2 * shape.halfLength;
      perSecond = s.velocityInBodyFrame && length > 0 ? std::max(0.0, s.lattice.velocity.z) * chunk / length : 0.0;
      break;
    }
  }
  return perSecond * (s.schedule.activeTime(end) - s.schedule.activeTime(start)) + chunk;
}

MpmMaterial materialFrom(const ParamSet& p) {
  const std::string& law = p.getString("magnetic.law");
  const double n0 = p.given("magnetic.per_cell")
                        ? p.getFloat("magnetic.per_cell") / std::pow(p.getFloat("magnetic.cell_size"), 3)
                        : p.getFloat("magnetic.number_density");
  MagneticMaterial mag = nonMagneticMaterial();
  if (law == "paper") mag = paperMaterial();
  if (law == "paper-linear") mag = linearized(paperMaterial());
  if (law == "langevin") mag = langevinMaterial(p.getFloat("magnetic.moment"), p.getFloat("magnetic.temperature"), n0);
  if (law == "linear") mag = linearMaterial(p.getFloat("magnetic.chi"), n0);
  const double rho = p.getFloat("density");
  const std::string model = p.getString("model");
  if (model == "elastoplastic_solid")
    return elastoplasticSolid(p.getFloat("youngs_modulus"), p.getFloat("poisson_ratio"), p.getFloat("yield_stress"),
                              p.getFloat("viscosity"), rho, mag);
  if (model == "solid") return neoHookeanSolid(p.getFloat("youngs_modulus"), p.getFloat("poisson_ratio"), rho, mag);
  MpmMaterial fluid = model == "viscoplastic_fluid"
                          ? viscoplasticFluid(p.getFloat("yield_stress"), p.getFloat("consistency"),
                                              p.getFloat("flow_index"), p.getFloat("max_viscosity"),
                                              p.getFloat("bulk_modulus"), rho, mag)
                          : viscousFluid(p.getFloat("viscosity"), p.getFloat("bulk_modulus"), rho, mag);
  fluid.surfaceTension = p.getFloat("surface_tension");
  fluid.validate();
  return fluid;
}

std::unique_ptr<FieldSource> appliedFieldFrom(const ParamSet& p) {
  TimeProfile profile;
  if (p.given("ramp")) profile = TimeProfile::ramp(p.getFloats("ramp")[0], p.getFloats("ramp")[1]);
  const std::string& type = p.getString("type");
  if (type == "uniform") return std::make_unique<UniformField>(p.getVec3("H"), profile);
  if (type == "dipole") return std::make_unique<PointDipole>(p.getVec3("position"), p.getVec3("moment"), profile);
  require(!p.given("ramp"), "a VDB field takes no ramp");
  FieldSourceSet set;
  addVdbField(set, p.getString("file"), p.getString("grid"));
  return set.source(0).clone();
}

ColliderShape colliderShapeFrom(const ParamSet& p, Pose& pose) {
  const std::string& shape = p.getString("shape");
  ColliderShape cs;
  if (shape == "plane") {
    pose = poseAlong(p.getVec3("point"), p.getVec3("normal"));
    return ColliderShape::plane();
  }
  if (isFileShape(shape)) {
    pose = Pose();
    const double voxel = p.getFloat("voxel_size");
    require(shape != "mesh" || voxel > 0, "a mesh collider needs voxel_size > 0 m");
    cs = ColliderShape::levelSetShape(loadShapeFile(shape, p.getString("file"), p.getString("grid"), voxel));
  } else {
    pose = poseAlong(p.getVec3("center"), p.getVec3("axis"));
    if (shape == "box") cs = ColliderShape::box(p.getVec3("half_size"));
    if (shape == "sphere") cs = ColliderShape::sphere(p.getFloat("radius"));
    if (shape == "cylinder") cs = ColliderShape::cylinder(p.getFloat("radius"), p.getFloat("half_length"));
  }
  if (p.getBool("inverted")) cs = cs.invertedShape();
  return cs;
}

BoundaryCondition boundaryFrom(const ParamSet& p, const std::string& prefix) {
  const std::string& mode = p.getString(prefix + "boundary");
  BoundaryCondition bc;
  bc.mode = mode == "sticky" ? BoundaryMode::Sticky : mode == "slip" ? BoundaryMode::Slip : BoundaryMode::Separate;
  bc.friction = p.getFloat(prefix + "friction");
  return bc;
}

MagneticStageSettings solveSettingsFrom(const ParamSet& p, const std::string& prefix) {
  MagneticStageSettings s;
  s.boundary = p.getString(prefix + "boundary") == "open" ? BoundaryKind::Open : BoundaryKind::Shield;
  s.solve.tolerance = p.getFloat(prefix + "tolerance");
  s.solve.preconditioner = p.getString(prefix + "preconditioner") == "multigrid" ? PreconditionerKind::Multigrid
                                                                                 : PreconditionerKind::Jacobi;
  s.solve.maxNewtonIterations = int(p.getInt(prefix + "max_newton_iterations"));
  return s;
}

namespace {
constexpr double kMaxNodesPerAxis = 1 << 20;
constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;

/// A count as a whole number while doubles hold it exactly (2.14748e+09 says too little).
std::string countText(double n) { return n < 9e15 ? std::to_string(std::int64_t(n)) : concat(n); }
}  // namespace

void requireFitsInMemory(const std::string& what, const double nodes[3], double dx, double particles, GridUse use) {
  const double nodeCount = nodes[0] * nodes[1] * nodes[2];
  MemoryCounts counts;
  // The MPM grid alone reserves address space: its memory is the box the
  // material reaches (mpm/grid.h), counted with the scene (sceneMemory).
  counts.mpmNodes = use == GridUse::MpmAndFieldSolve ? nodeCount : 0;
  counts.fieldNodes = use == GridUse::Mpm ? 0 : nodeCount;
  counts.particles = counts.magneticParticles = particles;
  const double need = estimateMemory(counts).total(), limit = memoryLimitBytes();
  const double nodeBytes =
      (use == GridUse::MpmAndFieldSolve ? kMpmNodeBytes : 0) + (use == GridUse::Mpm ? 0 : kFieldNodeBytes);
  const bool axisTooLong = std::max(nodes[0], std::max(nodes[1], nodes[2])) > kMaxNodesPerAxis;
  // The MPM grid bins particles by the base node of their stencil (dims - 2
  // per axis) with 32-bit offsets.
  const double bins = (nodes[0] - 2) * (nodes[1] - 2) * (nodes[2] - 2);
  const bool tooManyBins = use != GridUse::FieldSolve && bins >= double(kMpmGridCountLimit);
  if (need <= limit && !axisTooLong && !tooManyBins) return;
  std::string subject;
  if (nodeCount > 0)
    subject = concat("a grid of ", countText(nodes[0]), " x ", countText(nodes[1]), " x ", countText(nodes[2]),
                     " nodes at dx = ", dx, " m");
  if (axisTooLong)
    throw TooLarge(concat(what, ": ", subject, " is too large (more than ", kMaxNodesPerAxis,
                          " nodes on an axis; needs about ", numberText(need / kGiB, 3), " GiB)"));
  if (tooManyBins)
    throw TooLarge(concat(what, ": ", subject, " is too large for the MPM grid (", countText(bins),
                          " stencil bins, at most ", countText(double(kMpmGridCountLimit - 1)), ")"));
  if (particles > 0) subject += concat(subject.empty() ? "" : " and ", countText(particles), " particles");
  const std::string perNode = nodeBytes > 0 ? concat(nodeBytes, " B a node and ") : std::string();
  throw TooLarge(concat(what, ": ", subject, nodeCount > 0 ? " is too large" : " are too many",
                        " (needs about ", numberText(need / kGiB, 3), " GiB at ", perNode,
                        kParticleBytes + kMagneticParticleBytes, " B a particle; limit ", memoryLimitText(), ")"));
}

void requireFitsInMemory(const std::string& what, const MemoryEstimate& estimate) {
  if (estimate.total() <= memoryLimitBytes()) return;
  throw TooLarge(concat(what, " needs about ", estimate.describe(), ", more than ", memoryLimitText(),
                        " (docs/benchmarks.md, \"Memory\")"));
}

double estimatedParticles(double volume, double cellSize, int particlesPerCell) {
  return volume / (cellSize * cellSize * cellSize) * particlesPerCell;
}

MpmSettings mpmSettingsFrom(const ParamSet& p, double particles) {
  MpmSettings s;
  const Vec3d lo = p.getVec3("domain.min"), hi = p.getVec3("domain.max");
  for (int a = 0; a < 3; ++a)
    require(hi[a] > lo[a], "domain: max must exceed min on every axis; axis ", a, " has min ", lo[a], " m and max ",
            hi[a], " m");
  const double dx = p.getFloat("domain.dx");
  // Node counts in double first: a tiny dx must be refused, not overflow an int.
  double n[3];
  for (int a = 0; a < 3; ++a) n[a] = std::ceil((hi[a] - lo[a]) / dx - 1e-9) + 1;
  // The MPM grid here; the field solve's grid once the scene's materials
  // and sources are known (sceneFromJson), or when a stage is made.
  requireFitsInMemory("domain", n, dx, particles, GridUse::Mpm);
  GridSpec g;
  g.origin = lo;
  g.dx = dx;
  g.dims = {int(n[0]), int(n[1]), int(n[2])};
  s.grid = g;
  s.walls = boundaryFrom(p, "domain.");
  s.fixedDt = p.getFloat("time.dt");
  s.cfl = p.getFloat("time.cfl");
  s.dtMax = p.getFloat("time.dt_max");
  s.minSubsteps = int(p.getInt("time.min_substeps"));
  s.maxSubsteps = int(p.getInt("time.max_substeps"));
  if (s.maxSubsteps > 0 && s.maxSubsteps < s.minSubsteps)
    throw InvalidArgument(concat("time.max_substeps = ", s.maxSubsteps, " is below time.min_substeps = ",
                                 s.minSubsteps, " (0: no limit)"));
  s.magneticSolveInterval = int(p.getInt("time.field_solve_every"));
  s.magneticSolveDistance = p.getFloat("time.field_solve_distance");
  s.gravity = p.getVec3("gravity");
  s.magnetic = solveSettingsFrom(p, "magnetic.");
  const int padding = int(p.getInt("magnetic.padding"));
  if (padding > 0) {
    // The field solve sees free space beyond the MPM walls: material resting
    // on the floor is not at the magnetic grid's edge.
    GridSpec mg = g;
    mg.origin = mg.origin - double(padding) * Vec3d{dx, dx, dx};
    mg.dims = {mg.dims.i + 2 * padding, mg.dims.j + 2 * padding, mg.dims.k + 2 * padding};
    s.magneticGrid = mg;
  }
  // The walls need 2 W + 2 nodes on every axis: said in the domain's terms
  // before MpmSettings::validate would name its fields.
  const int walls = s.wallNodes, nodes = std::min({g.dims.i, g.dims.j, g.dims.k});
  if (walls > 0 && 2 * walls + 2 > nodes) {
    const double side = std::min({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    char text[256];
    std::snprintf(text, sizeof text,
                  "domain: dx = %.6g m gives %d nodes across the shortest side (%.6g m), too few for the domain's "
                  "walls (%d nodes at each face need %d): use a dx below %.4g m",
                  dx, nodes, side, walls, 2 * walls + 2, side / (2 * walls));
    throw InvalidArgument(text);
  }
  s.validate();
  return s;
}

void addSourcesAndColliders(MpmSolver& solver, const FieldSourceSet& fields,
                            const std::vector<SourcesData::Magnet>& magnets,
                            const std::vector<MpmCollider>& colliders) {
  solver.setSources(fields);
  for (const SourcesData::Magnet& m : magnets) {
    if (m.collider) {
      const std::size_t c = solver.addMagnet(*m.magnet, m.motion, m.boundary);
      if (m.dynamics) solver.collider(c).setDynamics(*m.dynamics);
    } else
      solver.addNonCollidingMagnet(*m.magnet, m.motion);
  }
  for (const MpmCollider& c : colliders) solver.addCollider(c);
}

bool vdbBuilt() { return LODESTONE_PLUGIN_HAVE_VDB != 0; }

void addVdbField(FieldSourceSet& set, const std::string& path, const std::string& gridName) {
#if LODESTONE_PLUGIN_HAVE_VDB
  set.add(std::make_unique<VdbFieldSource>(path, gridName));
#else
  (void)set;
  throw NotBuilt(concat("cannot read grid '", gridName, "' of '", path,
                        "': VDB support is not built into this library (no OpenVDB)"));
#endif
}

void writeStageVdb(const std::string& path, const MagneticForceStage& stage, const std::string& solverSummary,
                   bool doublePrecision) {
#if LODESTONE_PLUGIN_HAVE_VDB
  VdbFrameMetadata meta;
  meta.solverSummary = solverSummary;
  VdbWriteOptions options;
  options.doublePrecision = doublePrecision;
  writeFieldsVdb(path, stage, meta, options);
#else
  (void)stage;
  (void)solverSummary;
  (void)doublePrecision;
  throw NotBuilt(concat("cannot write '", path, "': VDB support is not built into this library (no OpenVDB)"));
#endif
}

void addSurfaceParams(std::vector<ParamDecl>& q) {
  q.push_back(choiceParam("method", "Method", {"density", "splat"}, "density",
                          "density: the 1/2 contour of the particles' smoothed volume fraction (smooth in time); "
                          "splat: spheres of the particles' radius (OpenVDB ParticlesToLevelSet) closed and "
                          "smoothed with LevelSetFilter."));
  q.push_back(range(floatParam("voxel_size", "Voxel size", 0.0, "m",
                               "Voxel size of the surface and volumes; 0: the particle spacing (cube root of the "
                               "mean particle volume, half the MPM dx at 8 particles per cell)."),
                    0, 10));
  q.push_back(when(range(floatParam("kernel_width", "Kernel width", 1.5, "",
                                    "Width of the quadratic B-spline that spreads each particle's volume, in "
                                    "particle spacings (the cube root of its volume): the density method's "
                                    "smoothing."),
                         1, 4),
                   "method", {"density"}));
  q.push_back(when(range(floatParam("radius_scale", "Radius scale", 1.0, "",
                                    "Sphere radius over the particle's radius (of a sphere of its volume)."),
                         0.5, 4),
                   "method", {"splat"}));
  q.push_back(when(intParam("smoothing", "Smoothing", 1, 0, 4,
                            "Width of the Gaussian filter of the spheres' level set, voxels; 0: none."),
                   "method", {"splat"}));
  q.push_back(when(intParam("closing", "Closing", 1, 0, 4,
                            "Dilation, then erosion, of the spheres' level set, voxels: closes gaps between "
                            "particles."),
                   "method", {"splat"}));
}

SurfaceSettings surfaceSettingsFrom(const ParamSet& p) {
  SurfaceSettings s;
  s.method = p.getString("method");
  s.voxelSize = p.getFloat("voxel_size");
  if (s.method == "splat") {
    s.radiusScale = p.getFloat("radius_scale");
    s.smoothing = int(p.getInt("smoothing"));
    s.closing = int(p.getInt("closing"));
  } else {
    s.kernelWidth = p.getFloat("kernel_width");
  }
  return s;
}

RenderOutputCost writeRenderOutputs(const RenderOutputPaths& paths, const MpmParticles& particles,
                                    const std::vector<std::string>& materialNames, const SurfaceSettings& settings,
                                    int frame, double time, const MagnetizationInput& magnetization,
                                    TriangleMesh* meshOut) {
#if LODESTONE_PLUGIN_HAVE_VDB
  using Clock = std::chrono::steady_clock;
  const auto since = [](Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  SurfaceParticles p = surfaceParticles(particles);
  SurfaceOptions o;
  o.method = surfaceMethodFromName(settings.method);
  o.voxelSize = settings.voxelSize > 0 ? settings.voxelSize : particleSpacing(p);
  o.radiusScale = settings.radiusScale;
  o.kernelWidth = settings.kernelWidth;
  o.smoothing = settings.smoothing;
  o.closing = settings.closing;
  RenderOutputCost cost;
  cost.voxelSize = o.voxelSize;
  if (p.size() == 0) return cost;
  RenderFrame render(std::move(p), o, materialNames);
  VdbFrameMetadata meta;
  meta.frame = frame;
  meta.time = time;
  if (!paths.surface.empty()) {
    const auto t0 = Clock::now();
    render.writeSurfaceVdb(paths.surface, meta);
    cost.surface = since(t0);
  }
  if (!paths.meshPly.empty() || !paths.meshObj.empty()) {
    const auto t0 = Clock::now();
    const TriangleMesh& mesh = render.mesh();
    const std::string comment = concat("lodestone ", LODESTONE_VERSION_STRING, " frame ", frame, " time ", time,
                                       " s; units m, m/s");
    if (!paths.meshPly.empty()) output::writeMeshPly(paths.meshPly, mesh, comment);
    if (!paths.meshObj.empty()) output::writeMeshObj(paths.meshObj, mesh, comment);
    cost.mesh = since(t0);
    cost.triangles = mesh.triangles.size();
    if (meshOut) *meshOut = mesh;
  }
  if (!paths.volume.empty()) {
    const auto t0 = Clock::now();
    if (magnetization.grid.data)
      render.setMagnetization(magnetization.grid);
    else if (!magnetization.file.empty())
      render.setMagnetizationFromFile(magnetization.file);
    render.writeVolumeVdb(paths.volume, meta);
    cost.volume = since(t0);
  }
  return cost;
#else
  (void)particles, (void)materialNames, (void)settings, (void)frame, (void)time, (void)magnetization, (void)meshOut;
  throw NotBuilt(concat("cannot write '", paths.surface + paths.volume + paths.meshPly + paths.meshObj,
                        "': VDB support is not built into this library (no OpenVDB)"));
#endif
}

}  // namespace lodestone::plugin
