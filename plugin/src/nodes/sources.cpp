// Nodes of materials, particles, magnets, applied fields and colliders.
#include <algorithm>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/plugin/errors.h"
#include "lodestone/plugin/node_builders.h"

#include "library.h"

namespace lodestone::plugin::nodes {

namespace {

void addBoundaryParams(std::vector<ParamDecl>& params, const std::string& def) {
  params.push_back(choiceParam("boundary", "Boundary", kBoundaryModes, def,
                               "Velocity condition where material meets it: sticky (no relative motion), slip "
                               "(no normal motion), separate (may leave)."));
  params.push_back(
      range(floatParam("friction", "Friction", 0.0, "", "Coulomb friction coefficient (slip, separate)."), 0, 10));
}

void addMotionParams(std::vector<ParamDecl>& params) {
  params.push_back(vec3Param("motion.velocity", "Velocity", {}, "m/s", "Constant linear velocity of the body."));
  params.push_back(vec3Param("motion.angular_velocity", "Angular velocity", {}, "rad/s",
                             "Constant angular velocity about the body origin (world frame)."));
}

/// `dynamic` and the rigid-body parameters (mpm/rigid_body.h) of a collider or magnet.
void addRigidBodyParams(std::vector<ParamDecl>& params, double density) {
  params.push_back(boolParam("dynamic", "Dynamic", false,
                             "A free rigid body, two-way coupled: moved by the material, gravity, contacts and (a "
                             "magnet) magnetic forces; motion.velocity and motion.angular_velocity are its initial "
                             "velocities, keyframes its starting pose."));
  params.push_back(range(floatParam("density", "Density", density, "kg/m^3",
                                    "Density of a dynamic body; its mass and inertia follow from the shape."),
                         1e-3, 1e6));
  params.push_back(range(floatParam("mass", "Mass", 0.0, "kg",
                                    "Mass of a dynamic body; > 0 replaces the density's (inertia scaled with it)."),
                         0, 1e6));
  params.push_back(range(floatParam("restitution", "Restitution", 0.2, "",
                                    "Bounce of a dynamic body's contacts with bodies, colliders and walls (0..1)."),
                         0, 1));
  params.push_back(range(floatParam("contact_friction", "Contact friction", 0.4, "",
                                    "Coulomb coefficient of a dynamic body's contacts with bodies, colliders and "
                                    "walls (the material's friction on it is `friction`)."),
                         0, 10));
}

void addShapeParams(std::vector<ParamDecl>& q, const std::vector<std::string>& shapes, const std::string& def) {
  const bool fileShapes = std::find(shapes.begin(), shapes.end(), "level_set") != shapes.end();
  q.push_back(
      required(choiceParam("shape", "Shape", shapes, def,
                           fileShapes ? "Shape of the body; level_set and mesh are read from a file (need OpenVDB)."
                                      : "Shape of the body.")));
}

// The help of `center`, which scene files also read for the file shapes.
constexpr const char* kFileShapeCenterHelp =
    "Centre of the shape. Scene files: also for level_set and mesh, where the file's origin is placed (default the "
    "world origin).";

void addFileShapeParams(std::vector<ParamDecl>& q) {
  q.push_back(when(required(stringParam("file", "File", "shape.vdb",
                                        "VDB level set (level_set) or OBJ mesh (mesh); in scene files relative "
                                        "to the scene file. Placed in its own frame (scene files: center, axis).")),
                   "shape", {"level_set", "mesh"}));
  q.push_back(when(stringParam("grid", "Grid", "surface", "Name of the level-set grid."), "shape", {"level_set"}));
  q.push_back(when(nonNegative(floatParam("voxel_size", "Voxel size", 0.0, "m",
                                          "Voxel size the mesh is sampled at; 0: the MPM grid spacing.")),
                   "shape", {"mesh"}));
}

// The sizes of a box, sphere or cylinder (particle_source, particle_emitter,
// collider), each `size` m by default.
void addSizeParams(std::vector<ParamDecl>& q, double size) {
  q.push_back(when(required(positive(vec3Param("half_size", "Half size", {size, size, size}, "m", "Box half-sizes."))),
                   "shape", {"box"}));
  q.push_back(when(required(positive(floatParam("radius", "Radius", size, "m", "Sphere or cylinder radius."))), "shape",
                   {"sphere", "cylinder"}));
  q.push_back(when(required(positive(floatParam("half_length", "Half length", size, "m", "Cylinder half-length."))),
                   "shape", {"cylinder"}));
}

// The emitter lattice (particle_source, particle_emitter).
void addLatticeParams(std::vector<ParamDecl>& q) {
  q.push_back(
      positive(floatParam("cell_size", "Cell size", 0.01, "m",
                          "MPM grid spacing dx the lattice is fitted to (scene files: domain.dx, not a key).")));
  q.push_back(intParam("particles_per_cell", "Particles per cell", 8, 1, 1000, "Lattice points per MPM cell."));
  q.push_back(
      range(floatParam("jitter", "Jitter", 0.0, "", "Random offset as a fraction of the lattice spacing."), 0, 1));
  q.push_back(intParam("seed", "Seed", 1, 0, std::int64_t(1) << 62, "Jitter seed."));
}

}  // namespace

// ---- material ------------------------------------------------------------
NodeDecl materialNode() {
  NodeDecl d = declareNode(
      "material", "Material", "material",
      "An MPM material (Neo-Hookean solid, viscous or viscoplastic fluid, or damped elastoplastic solid) with an "
      "optional magnetization law.");
  auto& q = d.params;
  q.push_back(required(stringParam("name", "Name", "material", "Name by which bodies refer to the material.")));
  q.push_back(
      required(choiceParam("model", "Model", {"solid", "fluid", "viscoplastic_fluid", "elastoplastic_solid"}, "solid",
                           "Constitutive model: Neo-Hookean solid, viscous (J-based) fluid, "
                           "viscoplastic (Herschel-Bulkley / Bingham, J-based) fluid, or damped elastoplastic "
                           "solid (Hencky elasticity, von Mises yield, Kelvin-Voigt damping; deforms and "
                           "stays, like clay; CPU only).")));
  q.push_back(required(positive(floatParam("density", "Density", 1000.0, "kg/m^3", "Rest mass density."))));
  q.push_back(
      when(required(positive(floatParam("youngs_modulus", "Young's modulus", 1e5, "Pa", "Stiffness of the solid."))),
           "model", {"solid", "elastoplastic_solid"}));
  q.push_back(
      when(range(floatParam("poisson_ratio", "Poisson's ratio", 0.3, "", "Compressibility of the solid."), 0, 0.49),
           "model", {"solid", "elastoplastic_solid"}));
  q.push_back(when(required(nonNegative(floatParam(
                       "viscosity", "Viscosity", 1.0, "Pa*s",
                       "Dynamic viscosity of the fluid; for the elastoplastic solid the Kelvin-Voigt damping "
                       "viscosity eta (stress 2 eta D_dev): a shear vibration of wavenumber k loses amplitude at the "
                       "rate eta k^2 / (2 rho) (1/s), and the viscous time step dx^2 rho / (6 eta) caps the "
                       "substep."))),
                   "model", {"fluid", "elastoplastic_solid"}));
  q.push_back(
      when(required(positive(floatParam("bulk_modulus", "Bulk modulus", 1e5, "Pa", "Bulk modulus of the fluid."))),
           "model", {"fluid", "viscoplastic_fluid"}));
  q.push_back(when(required(nonNegative(floatParam(
                       "yield_stress", "Yield stress", 100.0, "Pa",
                       "Viscoplastic fluid: Herschel-Bulkley shear yield stress tau_y, below which the fluid "
                       "does not flow (it creeps at a strain rate ~ stress / max_viscosity). Elastoplastic solid: "
                       "von Mises (uniaxial) yield stress sigma_y, beyond which it deforms permanently (0: yields "
                       "at once, keeping only its volume elasticity)."))),
                   "model", {"viscoplastic_fluid", "elastoplastic_solid"}));
  q.push_back(when(required(nonNegative(floatParam("consistency", "Consistency", 1.0, "Pa*s^n",
                                                   "Herschel-Bulkley consistency k: stress above yield is "
                                                   "tau_y + k gamma_dot^n."))),
                   "model", {"viscoplastic_fluid"}));
  q.push_back(when(range(floatParam("flow_index", "Flow index", 1.0, "",
                                    "Herschel-Bulkley flow index n (1: Bingham plastic, < 1 shear thinning, "
                                    "> 1 shear thickening)."),
                         0.01, 2),
                   "model", {"viscoplastic_fluid"}));
  q.push_back(when(required(positive(floatParam(
                       "max_viscosity", "Max viscosity", 1000.0, "Pa*s",
                       "Cap mu_max of the effective viscosity tau_y / gamma_dot + k gamma_dot^(n-1) (the "
                       "regularization of the yield). Larger is closer to a true yield (slower creep) but the "
                       "viscous time step dx^2 rho / (6 mu_max) shrinks in proportion: substeps grow linearly "
                       "with mu_max."))),
                   "model", {"viscoplastic_fluid"}));
  q.push_back(when(range(floatParam("surface_tension", "Surface tension", 0.0, "N/m",
                                    "Surface tension coefficient sigma of the fluid (0: none; water 0.072, a "
                                    "ferrofluid about 0.03): a capillary stress on the fluid's surface (Laplace "
                                    "pressure 2 sigma / R in a drop of radius R). Adds a substep limit sqrt(rho "
                                    "dx^3 / (2 pi sigma)) and one scatter and one gather per substep; the surface is "
                                    "smoothed over about two cells, walls and colliders have no contact angle."),
                         0, kMaxSurfaceTension),
                   "model", {"fluid", "viscoplastic_fluid"}));
  q.push_back(required(choiceParam("magnetic.law", "Magnetization law",
                                   {"none", "paper", "paper-linear", "langevin", "linear"}, "none",
                                   "none; paper (Langevin, Table 2 of Sun et al. 2021); paper-linear (its low-field "
                                   "linearisation); langevin (moment, temperature); linear (chi).")));
  q.push_back(when(
      required(positive(floatParam("magnetic.moment", "Moment", 1.09e-19, "A*m^2", "Moment of one micro-particle."))),
      "magnetic.law", {"langevin"}));
  q.push_back(when(positive(floatParam("magnetic.temperature", "Temperature", 300.0, "K", "Temperature.")),
                   "magnetic.law", {"langevin"}));
  q.push_back(
      when(required(range(
               floatParam("magnetic.chi", "Susceptibility", 0.91, "", "Susceptibility of the bulk material."), 0, 1e4)),
           "magnetic.law", {"linear"}));
  q.push_back(when(positive(floatParam("magnetic.number_density", "Number density", paperMaterial().numberDensity,
                                       "1/m^3", "Micro-particles per m^3 of bulk material (default: the paper's).")),
                   "magnetic.law", {"langevin", "linear"}));
  q.push_back(when(positive(floatParam("magnetic.per_cell", "Per cell", 3.6e17, "micro-particles",
                                       "Micro-particles per filled cell of size cell_size; with cell_size, "
                                       "replaces number_density.")),
                   "magnetic.law", {"langevin", "linear"}));
  q.back().replaces = "magnetic.number_density";
  q.push_back(when(positive(floatParam("magnetic.cell_size", "Cell size", 7.8e-3, "m", "Cell size of per_cell.")),
                   "magnetic.law", {"langevin", "linear"}));
  d.outputs = {{"material", PortType::Material, "The material."}};
  d.cook = [](const CookContext& c) {
    MaterialData m;
    m.name = c.params().getString("name");
    m.material = materialFrom(c.params());
    return CookOutputs{{"material", value(std::move(m))}};
  };
  return d;
}

NodeDecl particleSourceNode() {
  NodeDecl d =
      declareNode("particle_source", "Particle Source", "particles",
                  "Fills a shape with material points on a lattice (particles per cell of the MPM grid), each with its "
                  "volume, mass and micro-particle count n_p = n0 V_p.");
  auto& q = d.params;
  q.push_back(stringParam("name", "Name", "body", "Name of the body."));
  addShapeParams(q, {"box", "sphere", "cylinder", "level_set", "mesh"}, "box");
  q.push_back(when(required(vec3Param("center", "Center", {}, "m", kFileShapeCenterHelp)), "shape",
                   {"box", "sphere", "cylinder"}));
  q.push_back(directionParam("axis", "Axis", {0, 0, 1},
                             "Body z axis (the cylinder's axis); a file shape's z axis is turned onto it."));
  addFileShapeParams(q);
  addSizeParams(q, 0.02);
  addLatticeParams(q);
  q.push_back(vec3Param("velocity", "Velocity", {}, "m/s", "Initial velocity."));
  d.inputs = {{"material", PortType::Material, "The body's material (default: a non-magnetic solid).", true, false}};
  d.outputs = {{"particles", PortType::Particles, "The material points."}};
  d.cook = [](const CookContext& c) {
    const ParamSet& p = c.params();
    ParticlesData out;
    ParticlesData::Body body;
    body.name = p.getString("name");
    const auto material = c.input<MaterialData>("material");
    body.material = material ? *material : MaterialData{"default", neoHookeanSolid(1e5, 0.3, 1000.0)};
    body.shape = shapeFrom(p);
    body.emit = emitterSettingsFrom(p);
    const double none[3] = {0, 0, 0};
    requireFitsInMemory(body.name, none, 0,
                        estimatedParticles(body.shape.volume(), body.emit.cellSize, body.emit.particlesPerCell));
    emitParticles(out.particles, body.shape, body.material.material, 0, body.emit);
    out.materials.push_back(body.material.material);
    out.bodies.push_back(std::move(body));
    return CookOutputs{{"particles", value(std::move(out))}};
  };
  return d;
}

// ---- particle emitter ---------------------------------------------------------
NodeDecl particleEmitterNode() {
  NodeDecl d = declareNode(
      "particle_emitter", "Particle Emitter", "particles",
      "Emits material over time from a shape (a nozzle is a cylinder along its axis) that may move: whole "
      "lattice fills of the shape (chunks) at a rate, while the time line is on, each placed where the shape was "
      "at its birth and moved on by the emission velocity since; points where material already is are left out "
      "(docs/scenes.md, Emitters).");
  auto& q = d.params;
  q.push_back(stringParam("name", "Name", "emitter", "Name of the emitter."));
  addShapeParams(q, {"box", "sphere", "cylinder"}, "cylinder");
  q.push_back(required(vec3Param("center", "Center", {}, "m", "Centre of the shape at rest (time 0).")));
  q.push_back(directionParam("axis", "Axis", {0, 0, 1},
                             "Body z axis: the nozzle's axis, along which `speed` emits and along which a stream's "
                             "chunks follow each other."));
  addSizeParams(q, 0.02);
  addLatticeParams(q);
  q.push_back(choiceParam("rate", "Rate", {"volume", "particles", "stream"}, "volume",
                          "volume: volume_rate; particles: particle_rate; stream: as fast as the material leaves the "
                          "shape at `speed` (a continuous jet, lattice layers one spacing apart)."));
  q.push_back(when(required(positive(
                       floatParam("volume_rate", "Volume rate", 1e-5, "m^3/s", "Volume emitted per second while on."))),
                   "rate", {"volume"}));
  q.push_back(when(required(positive(floatParam("particle_rate", "Particle rate", 1e4, "1/s",
                                                "Material points emitted per second while on."))),
                   "rate", {"particles"}));
  q.push_back(vec3Param("velocity", "Velocity", {}, "m/s", "Emission velocity in the world frame."));
  q.push_back(positive(floatParam("speed", "Speed", 1.0, "m/s",
                                  "Emission speed along the axis (turns with a moving emitter); when given, "
                                  "replaces velocity. Needed by rate stream.")));
  q.back().replaces = "velocity";
  q.push_back(boolParam("inherit_motion", "Inherit motion", false,
                        "Add the emitter's own velocity (motion) to the emitted material; off: material is laid "
                        "along the emitter's path."));
  q.push_back(nonNegative(floatParam("start", "Start", 0.0, "s", "Time the emitter switches on.")));
  q.push_back(nonNegative(floatParam("end", "End", 0.0, "s", "Time it switches off (after start); not given: never.")));
  q.push_back(nonNegative(floatListParam("intervals", "Intervals", {}, "s", 0, 2000,
                                         "On/off times [on, off, on, off, ...], increasing; replaces start and end.")));
  addMotionParams(q);
  d.inputs = {{"material", PortType::Material, "The emitted material (default: a non-magnetic solid).", true, false}};
  d.outputs = {{"particles", PortType::Particles, "No points yet: the emitter, which the MPM solver runs."}};
  d.cook = [](const CookContext& c) {
    const ParamSet& p = c.params();
    const auto material = c.input<MaterialData>("material");
    const MpmMaterial m = material ? material->material : neoHookeanSolid(1e5, 0.3, 1000.0);
    ParticlesData::Emitter e;
    e.name = p.getString("name");
    e.shape = shapeFrom(p);
    e.settings = rateEmitterSettingsFrom(p, motionFrom(p, e.shape.pose));
    const double none[3] = {0, 0, 0};
    requireFitsInMemory(
        e.name, none, 0,
        estimatedParticles(e.shape.volume(), e.settings.lattice.cellSize, e.settings.lattice.particlesPerCell));
    RateEmitter(e.shape, e.settings, m, 0);  // the lattice and the rate, checked now
    ParticlesData out;
    out.materials.push_back(m);
    out.emitters.push_back(std::move(e));
    return CookOutputs{{"particles", value(std::move(out))}};
  };
  return d;
}

// ---- host particles ---------------------------------------------------------
NodeDecl hostParticlesNode() {
  NodeDecl d = declareNode(
      "host_particles", "Host Particles", "particles",
      "A host's own material points: positions and micro-particle counts n_p (C ABI: network_set_particles), "
      "each with the volume n_p / n0 of its material (or the given volumes) and the mass rho V_p.");
  auto& q = d.params;
  q.push_back(floatListParam("positions", "Positions", {}, "m", 0, std::numeric_limits<std::size_t>::max(),
                             "x, y, z of each point, one after the other (3 numbers a point)."));
  q.push_back(
      nonNegative(floatListParam("counts", "Counts", {}, "micro-particles", 0, std::numeric_limits<std::size_t>::max(),
                                 "Micro-particles n_p of each point.")));
  q.push_back(nonNegative(floatListParam("volumes", "Volumes", {}, "m^3", 0, std::numeric_limits<std::size_t>::max(),
                                         "Volume V_p of each point; empty: n_p / n0 of a magnetic material.")));
  q.push_back(stringParam("name", "Name", "host", "Name of the body."));
  d.inputs = {{"material", PortType::Material, "The points' material (default: a non-magnetic solid).", true, false}};
  d.outputs = {{"particles", PortType::Particles, "The host's points."}};
  d.cook = [](const CookContext& c) {
    const ParamSet& p = c.params();
    const std::vector<double>& x = p.getFloats("positions");
    const std::vector<double>& n = p.getFloats("counts");
    const std::vector<double>& v = p.getFloats("volumes");
    require(x.size() == 3 * n.size(), "positions holds ", x.size(), " numbers, 3 for each of the ", n.size(),
            " counts are needed");
    require(v.empty() || v.size() == n.size(), "volumes holds ", v.size(), " numbers, one for each of the ", n.size(),
            " counts is needed");
    const auto material = c.input<MaterialData>("material");
    ParticlesData out;
    ParticlesData::Body body;
    body.name = p.getString("name");
    body.material = material ? *material : MaterialData{"default", neoHookeanSolid(1e5, 0.3, 1000.0)};
    const MpmMaterial& m = body.material.material;
    const double n0 = m.isMagnetic() ? m.magnetic.numberDensity : 0.0;
    require(!v.empty() || n0 > 0 || n.empty(), "volumes are needed for a non-magnetic material (no n0 to divide by)");
    for (std::size_t k = 0; k < n.size(); ++k) {
      const double volume = v.empty() ? n[k] / n0 : v[k];
      out.particles.add({x[3 * k], x[3 * k + 1], x[3 * k + 2]}, {}, m.density * volume, volume, n[k], 0);
    }
    out.materials.push_back(m);
    out.bodies.push_back(std::move(body));
    return CookOutputs{{"particles", value(std::move(out))}};
  };
  return d;
}

// ---- magnet -----------------------------------------------------------------
NodeDecl magnetNode() {
  NodeDecl d =
      declareNode("magnet", "Magnet", "sources",
                  "A uniformly magnetized permanent magnet (sphere, box or cylinder) with a closed-form field; "
                  "optionally also a collider of the MPM.");
  auto& q = d.params;
  addShapeParams(q, {"sphere", "box", "cylinder"}, "cylinder");
  q.push_back(required(vec3Param("center", "Center", {0, 0, -0.05}, "m", "Centre of the magnet.")));
  q.push_back(directionParam("axis", "Axis", {0, 0, 1}, "Magnetization direction (the body z axis)."));
  q.push_back(
      range(floatParam("magnetization", "Magnetization", 1e6, "A/m", "Magnetization along the axis."), -3e6, 3e6));
  q.push_back(range(floatParam("remanence", "Remanence", 1.2, "T",
                               "Remanent induction Br; when given, replaces magnetization (M = Br/mu0)."),
                    -3, 3));
  q.back().replaces = "magnetization";
  q.push_back(when(required(positive(floatParam("radius", "Radius", 0.02, "m", "Sphere or cylinder radius."))), "shape",
                   {"sphere", "cylinder"}));
  q.push_back(when(required(positive(vec3Param("half_size", "Half size", {0.02, 0.02, 0.02}, "m", "Box half-sizes."))),
                   "shape", {"box"}));
  q.push_back(when(required(positive(floatParam("half_length", "Half length", 0.01, "m", "Cylinder half-length."))),
                   "shape", {"cylinder"}));
  q.push_back(boolParam("collider", "Collider", true, "Also an obstacle for the material."));
  addBoundaryParams(q, "sticky");
  addMotionParams(q);
  addRigidBodyParams(q, 7500);
  d.inputs = {{"sources", PortType::Sources, "Sources to add this magnet to.", true, true}};
  d.outputs = {{"sources", PortType::Sources, "The input sources plus this magnet."}};
  d.cook = [](const CookContext& c) {
    const ParamSet& p = c.params();
    SourcesData out = mergeSources(c.inputs("sources"));
    out.magnets.push_back(magnetFrom(p));
    return CookOutputs{{"sources", value(std::move(out))}};
  };
  return d;
}

// ---- applied field ---------------------------------------------------------
NodeDecl appliedFieldNode() {
  NodeDecl d =
      declareNode("applied_field", "Applied Field", "sources",
                  "An applied field H_ext: uniform, a point dipole, or a vector grid of a VDB file (needs OpenVDB); "
                  "optionally switched on by a linear ramp.");
  auto& q = d.params;
  q.push_back(required(choiceParam("type", "Type", {"uniform", "dipole", "vdb"}, "uniform", "Kind of field.")));
  q.push_back(when(required(range(vec3Param("H", "Field", {0, 0, 1e4}, "A/m", "Uniform field."), -1e8, 1e8)), "type",
                   {"uniform"}));
  q.push_back(
      when(required(vec3Param("position", "Position", {0, 0, -0.1}, "m", "Dipole position.")), "type", {"dipole"}));
  q.push_back(when(required(vec3Param("moment", "Moment", {0, 0, 1}, "A*m^2", "Dipole moment.")), "type", {"dipole"}));
  q.push_back(when(required(stringParam("file", "File", "field.vdb", "VDB file holding the field.")), "type", {"vdb"}));
  q.push_back(when(stringParam("grid", "Grid", "H", "Name of the vector grid (A/m)."), "type", {"vdb"}));
  q.push_back(nonNegative(floatListParam("ramp", "Ramp", {0.0, 0.0}, "s", 2, 2,
                                         "[t0, t1]: the field is off before t0 and on after t1, linear between.")));
  d.inputs = {{"sources", PortType::Sources, "Sources to add this field to.", true, true}};
  d.outputs = {{"sources", PortType::Sources, "The input sources plus this field."}};
  d.cook = [](const CookContext& c) {
    const ParamSet& p = c.params();
    SourcesData out = mergeSources(c.inputs("sources"));
    out.fields.add(appliedFieldFrom(p));
    return CookOutputs{{"sources", value(std::move(out))}};
  };
  return d;
}

// ---- collider ------------------------------------------------------------------
NodeDecl colliderNode() {
  NodeDecl d = declareNode(
      "collider", "Collider", "mpm",
      "An obstacle of the MPM (plane, box, sphere, cylinder, level set or mesh; inverted for containers): static, "
      "moving as scripted, or a dynamic rigid body that the material and contacts move.");
  auto& q = d.params;
  addShapeParams(q, {"plane", "box", "sphere", "cylinder", "level_set", "mesh"}, "plane");
  q.push_back(
      when(required(vec3Param("point", "Point", {0, 0, -0.08}, "m", "A point of the plane.")), "shape", {"plane"}));
  q.push_back(when(required(directionParam("normal", "Normal", {0, 0, 1}, "Plane normal (into the free side).")),
                   "shape", {"plane"}));
  q.push_back(when(required(vec3Param("center", "Center", {}, "m", kFileShapeCenterHelp)), "shape",
                   {"box", "sphere", "cylinder"}));
  q.push_back(when(directionParam("axis", "Axis", {0, 0, 1},
                                  "Body z axis. Scene files: also for level_set and mesh, the direction the file's z "
                                  "axis is turned onto."),
                   "shape", {"box", "sphere", "cylinder"}));
  addFileShapeParams(q);
  addSizeParams(q, 0.05);
  q.push_back(when(boolParam("inverted", "Inverted", false, "Solid outside the shape (a container)."), "shape",
                   {"box", "sphere", "cylinder", "level_set", "mesh"}));
  addBoundaryParams(q, "sticky");
  addMotionParams(q);
  addRigidBodyParams(q, 1000);
  d.inputs = {{"colliders", PortType::Colliders, "Colliders to add this one to.", true, true}};
  d.outputs = {{"colliders", PortType::Colliders, "The input colliders plus this one."}};
  d.cook = [](const CookContext& c) {
    const ParamSet& p = c.params();
    CollidersData out = mergeColliders(c.inputs("colliders"));
    Pose pose;
    const ColliderShape cs = colliderShapeFrom(p, pose);
    out.colliders.emplace_back(cs, motionFrom(p, pose), boundaryFrom(p));
    if (const std::optional<RigidBodySettings> body = rigidBodyFrom(p)) out.colliders.back().setDynamics(*body);
    return CookOutputs{{"colliders", value(std::move(out))}};
  };
  return d;
}

}  // namespace lodestone::plugin::nodes
