#include "scene.h"

#include <algorithm>
#include <cmath>

#include "json_schema.h"
#include "lodestone/core/constants.h"
#include "lodestone/core/cuboid_magnet.h"
#include "lodestone/core/cylinder_magnet.h"
#include "lodestone/core/error.h"
#include "lodestone/core/material.h"
#include "lodestone/core/point_dipole.h"
#include "lodestone/core/sphere_magnet.h"
#include "lodestone/core/uniform_field.h"

namespace lodestone::examples {

namespace {

/// A pose at `centre` whose body z axis points along the unit vector `axis`.
Pose poseAlong(const Vec3d& centre, const Vec3d& axis) {
  const Vec3d z{0, 0, 1};
  const Vec3d k = cross(z, axis);
  const double s = norm(k), c = dot(z, axis);
  if (s < 1e-12) return c > 0 ? Pose::at(centre) : Pose::fromAxisAngle(centre, {1, 0, 0}, kPi);
  return Pose::fromAxisAngle(centre, k / s, std::atan2(s, c));
}

BoundaryCondition readBoundary(JsonReader& r, const BoundaryCondition& fallback) {
  BoundaryCondition bc = fallback;
  const std::string mode = r.string("boundary", {"sticky", "slip", "separate"},
                                    fallback.mode == BoundaryMode::Sticky ? "sticky"
                                    : fallback.mode == BoundaryMode::Slip ? "slip"
                                                                          : "separate");
  bc.mode = mode == "sticky" ? BoundaryMode::Sticky : mode == "slip" ? BoundaryMode::Slip : BoundaryMode::Separate;
  bc.friction = r.number("friction", "", Range::closed(0, 10), fallback.friction);
  return bc;
}

MagneticMaterial readMagnetic(JsonReader& r) {
  const std::string law = r.string("law", {"none", "paper", "paper-linear", "langevin", "linear"});
  // n0: bulk micro-particle density, 1/m^3, directly or as a count per cell of a size.
  const auto numberDensity = [&](double fallback) {
    if (r.has("number_density")) return r.number("number_density", "1/m^3", Range::positive());
    if (r.has("per_cell")) {
      const double perCell = r.number("per_cell", "micro-particles", Range::positive());
      const double cell = r.number("cell_size", "m", Range::positive());
      return perCell / (cell * cell * cell);
    }
    return fallback;
  };
  MagneticMaterial m;
  if (law == "none") {
    m = nonMagneticMaterial();
  } else if (law == "paper") {
    m = paperMaterial();
  } else if (law == "paper-linear") {
    m = linearized(paperMaterial());
  } else if (law == "langevin") {
    const double moment = r.number("moment", "A*m^2", Range::positive());
    const double temperature = r.number("temperature", "K", Range::positive(), 300.0);
    m = langevinMaterial(moment, temperature, numberDensity(paperMaterial().numberDensity));
  } else {
    const double chi = r.number("chi", "", Range::closed(0, 1e4));
    m = linearMaterial(chi, numberDensity(paperMaterial().numberDensity));
  }
  r.finish();
  return m;
}

std::unique_ptr<MagnetSource> readMagnet(JsonReader& r, Pose& pose) {
  const std::string shape = r.string("shape", {"sphere", "box", "cylinder"});
  const Vec3d centre = r.vec3("center", "m");
  const Vec3d axis = r.direction("axis", {0, 0, 1});
  pose = poseAlong(centre, axis);
  double M = 0;
  if (r.has("remanence"))
    M = magnetizationFromRemanence(r.number("remanence", "T", Range::closed(-3, 3)));
  else
    M = r.number("magnetization", "A/m", Range::closed(-3e6, 3e6));
  const Vec3d Mbody{0, 0, M};  // along the magnet's axis
  if (shape == "sphere") return std::make_unique<SphereMagnet>(pose, r.number("radius", "m", Range::positive()), Mbody);
  if (shape == "box")
    return std::make_unique<CuboidMagnet>(pose, r.vec3("half_size", "m", Range::positive()), Mbody);
  const double radius = r.number("radius", "m", Range::positive());
  return std::make_unique<CylinderMagnet>(pose, radius, r.number("half_length", "m", Range::positive()), Mbody);
}

ColliderMotion readMotion(JsonReader& r, const Pose& rest) {
  if (!r.has("motion")) return ColliderMotion::fixed(rest);
  JsonReader m = r.object("motion");
  ColliderMotion motion;
  if (m.has("keyframes")) {
    std::vector<double> times;
    std::vector<Pose> poses;
    for (JsonReader& k : m.array("keyframes", 1)) {
      times.push_back(k.number("time", "s", Range::nonNegative()));
      poses.push_back(poseAlong(k.vec3("center", "m"), k.direction("axis", rest.rotation * Vec3d{0, 0, 1})));
      k.finish();
    }
    motion = ColliderMotion::keyframed(std::move(times), std::move(poses));
  } else {
    motion = ColliderMotion::constantVelocity(rest, m.vec3("velocity", "m/s", Range::any(), Vec3d{}),
                                              m.vec3("angular_velocity", "rad/s", Range::any(), Vec3d{}));
  }
  m.finish();
  return motion;
}

EmitterShape readShape(JsonReader& r) {
  const std::string shape = r.string("shape", {"box", "sphere", "cylinder"});
  const Pose pose = poseAlong(r.vec3("center", "m"), r.direction("axis", {0, 0, 1}));
  if (shape == "box") return EmitterShape::box(pose, r.vec3("half_size", "m", Range::positive()));
  if (shape == "sphere") return EmitterShape::sphere(pose, r.number("radius", "m", Range::positive()));
  const double radius = r.number("radius", "m", Range::positive());
  return EmitterShape::cylinder(pose, radius, r.number("half_length", "m", Range::positive()));
}

std::vector<JsonReader> optionalArray(JsonReader& r, const std::string& key) {
  return r.has(key) ? r.array(key) : std::vector<JsonReader>{};
}

}  // namespace

namespace {
Scene sceneFromJson(const nlohmann::json& doc, const std::string& sourceName, const SceneOptions& options) {
  JsonReader root(doc, "", sourceName);
  Scene scene;
  scene.file = sourceName;
  scene.name = root.string("name");
  scene.description = root.has("description") ? root.string("description") : std::string();

  // Domain and grid.
  {
    JsonReader d = root.object("domain");
    const Vec3d lo = d.vec3("min", "m"), hi = d.vec3("max", "m");
    for (int a = 0; a < 3; ++a)
      if (!(hi[a] > lo[a]))
        d.fail(concat("max must exceed min on every axis; axis ", a, " has min ", lo[a], " m and max ", hi[a], " m"));
    double dx = d.number("dx", "m", Range::positive());
    scene.fullDx = d.number("full_dx", "m", Range::nonNegative(), 0.0);
    if (options.full) {
      if (!(scene.fullDx > 0)) d.fail("--full needs domain.full_dx in the scene");
      dx = scene.fullDx;
    }
    if (options.dx > 0) dx = options.dx;
    GridSpec g;
    g.origin = lo;
    g.dx = dx;
    g.dims = {int(std::ceil((hi.x - lo.x) / dx - 1e-9)) + 1, int(std::ceil((hi.y - lo.y) / dx - 1e-9)) + 1,
              int(std::ceil((hi.z - lo.z) / dx - 1e-9)) + 1};
    const double nodes = double(g.dims.i) * g.dims.j * g.dims.k;
    if (nodes > 4.5e7)
      d.fail(concat("a grid of ", g.dims.i, " x ", g.dims.j, " x ", g.dims.k, " nodes at dx = ", dx,
                    " m is too large (needs about ", nodes * 600 / 1e9, " GB)"));
    scene.settings.grid = g;
    scene.settings.walls = readBoundary(d, BoundaryCondition{});
    d.finish();
  }

  // Time stepping.
  {
    JsonReader t = root.object("time");
    scene.frames = t.integer("frames", 1, 100000);
    scene.fps = t.number("fps", "1/s", Range::closed(1, 10000), 24.0);
    scene.settings.fixedDt = t.number("dt", "s", Range::closed(0, 1), 0.0);
    scene.settings.cfl = t.number("cfl", "", Range::closed(0.01, 1), scene.settings.cfl);
    scene.settings.dtMax = t.number("dt_max", "s", Range::positive(), scene.settings.dtMax);
    scene.settings.magneticSolveInterval = t.integer("field_solve_every", 0, 1000000, 0);
    t.finish();
  }
  scene.settings.gravity = root.vec3("gravity", "m/s^2", Range::any(), scene.settings.gravity);

  // Magnetic stage.
  int padding = 4;  // cells of free space around the MPM domain for the field solve
  if (root.has("magnetic")) {
    JsonReader m = root.object("magnetic");
    auto& s = scene.settings.magnetic;
    s.boundary = m.string("boundary", {"open", "shield"}, "open") == "open" ? BoundaryKind::Open : BoundaryKind::Shield;
    s.solve.tolerance = m.number("tolerance", "", Range::closed(1e-14, 1e-1), s.solve.tolerance);
    s.solve.preconditioner = m.string("preconditioner", {"multigrid", "jacobi"}, "multigrid") == "multigrid"
                                 ? PreconditionerKind::Multigrid
                                 : PreconditionerKind::Jacobi;
    s.solve.maxNewtonIterations = m.integer("max_newton_iterations", 1, 1000, s.solve.maxNewtonIterations);
    padding = m.integer("padding", 0, 64, padding);
    m.finish();
  }
  if (padding > 0) {
    // The field solve sees free space beyond the MPM walls: material resting
    // on the floor is not at the magnetic grid's edge.
    GridSpec mg = scene.settings.grid;
    mg.origin = mg.origin - double(padding) * Vec3d{mg.dx, mg.dx, mg.dx};
    mg.dims = {mg.dims.i + 2 * padding, mg.dims.j + 2 * padding, mg.dims.k + 2 * padding};
    scene.settings.magneticGrid = mg;
  }

  // Materials.
  for (JsonReader& m : root.array("materials", 1)) {
    const std::string name = m.string("name");
    if (std::find(scene.materialNames.begin(), scene.materialNames.end(), name) != scene.materialNames.end())
      m.fail(concat("duplicate material name '", name, "'"));
    const std::string model = m.string("model", {"solid", "fluid"});
    const double rho = m.number("density", "kg/m^3", Range::positive());
    MagneticMaterial mag = nonMagneticMaterial();
    if (m.has("magnetic")) {
      JsonReader mr = m.object("magnetic");
      mag = readMagnetic(mr);
    }
    if (model == "solid") {
      const double E = m.number("youngs_modulus", "Pa", Range::positive());
      const double nu = m.number("poisson_ratio", "", Range::closed(0, 0.49), 0.3);
      scene.materials.push_back(neoHookeanSolid(E, nu, rho, mag));
    } else {
      const double mu = m.number("viscosity", "Pa*s", Range::nonNegative());
      const double K = m.number("bulk_modulus", "Pa", Range::positive());
      scene.materials.push_back(viscousFluid(mu, K, rho, mag));
    }
    scene.materialNames.push_back(name);
    m.finish();
  }

  // Bodies.
  for (JsonReader& b : optionalArray(root, "bodies")) {
    SceneBody body;
    body.name = b.has("name") ? b.string("name") : concat("body ", scene.bodies.size());
    const std::string material = b.string("material", scene.materialNames);
    body.material = std::uint32_t(std::find(scene.materialNames.begin(), scene.materialNames.end(), material) -
                                  scene.materialNames.begin());
    body.shape = readShape(b);
    body.emit.particlesPerCell = b.integer("particles_per_cell", 1, 1000, 8);
    body.emit.jitter = b.number("jitter", "", Range::closed(0, 1), 0.0);
    body.emit.seed = std::uint64_t(b.integer64("seed", 0, std::int64_t(1) << 62, 1));
    body.emit.velocity = b.vec3("velocity", "m/s", Range::any(), Vec3d{});
    b.finish();
    scene.bodies.push_back(std::move(body));
  }

  // Permanent magnets (field sources, and colliders unless told otherwise).
  for (JsonReader& m : optionalArray(root, "magnets")) {
    SceneMagnet sm;
    Pose pose;
    sm.magnet = readMagnet(m, pose);
    sm.motion = readMotion(m, pose);
    sm.collider = m.boolean("collider", true);
    sm.boundary = readBoundary(m, BoundaryCondition{BoundaryMode::Sticky, 0.0});
    m.finish();
    scene.magnets.push_back(std::move(sm));
  }

  // Applied fields.
  for (JsonReader& f : optionalArray(root, "fields")) {
    const std::string type = f.string("type", {"uniform", "dipole"});
    TimeProfile profile;
    if (f.has("ramp")) {
      const std::vector<double> ramp = f.numbers("ramp", "s", Range::nonNegative(), 2, 2);
      profile = TimeProfile::ramp(ramp[0], ramp[1]);
    }
    if (type == "uniform")
      scene.fields.add(std::make_unique<UniformField>(f.vec3("H", "A/m", Range::closed(-1e8, 1e8)), profile));
    else
      scene.fields.add(std::make_unique<PointDipole>(f.vec3("position", "m"), f.vec3("moment", "A*m^2"), profile));
    f.finish();
  }

  // Colliders.
  for (JsonReader& c : optionalArray(root, "colliders")) {
    const std::string shape = c.string("shape", {"plane", "box", "sphere", "cylinder"});
    ColliderShape cs;
    Pose pose;
    if (shape == "plane") {
      cs = ColliderShape::plane();
      pose = poseAlong(c.vec3("point", "m"), c.direction("normal"));
    } else {
      pose = poseAlong(c.vec3("center", "m"), c.direction("axis", {0, 0, 1}));
      if (shape == "box") cs = ColliderShape::box(c.vec3("half_size", "m", Range::positive()));
      if (shape == "sphere") cs = ColliderShape::sphere(c.number("radius", "m", Range::positive()));
      if (shape == "cylinder") {
        const double radius = c.number("radius", "m", Range::positive());
        cs = ColliderShape::cylinder(radius, c.number("half_length", "m", Range::positive()));
      }
      if (c.boolean("inverted", false)) cs = cs.invertedShape();
    }
    const ColliderMotion motion = readMotion(c, pose);
    const BoundaryCondition bc = readBoundary(c, BoundaryCondition{BoundaryMode::Sticky, 0.0});
    c.finish();
    scene.colliders.emplace_back(cs, motion, bc);
  }

  // Outputs.
  if (root.has("output")) {
    JsonReader o = root.object("output");
    scene.output.ply = o.boolean("ply", true);
    scene.output.png = o.boolean("png", true);
    scene.output.width = o.integer("width", 16, 4096, 640);
    scene.output.height = o.integer("height", 16, 4096, 480);
    scene.output.fovDegrees = o.number("fov", "degrees", Range::closed(5, 120), 35.0);
    if (o.has("vdb")) {
      const nlohmann::json& list = o.raw("vdb");
      if (!list.is_array()) o.failAt("vdb", "expected an array of grid names (n, phi, H, M, B, force)");
      for (std::size_t k = 0; k < list.size(); ++k) {
        const std::vector<std::string> allowed{"n", "phi", "H", "M", "B", "force"};
        if (!list[k].is_string() || std::find(allowed.begin(), allowed.end(), list[k].get<std::string>()) == allowed.end())
          o.failAt("vdb", concat("element ", k, ": expected one of n, phi, H, M, B, force, found ", list[k].dump()));
        scene.output.vdbFields.push_back(list[k].get<std::string>());
      }
    }
    scene.output.vdbPoints = o.boolean("vdb_points", false);
    if (o.has("camera")) {
      JsonReader cam = o.object("camera");
      scene.output.autoCamera = false;
      scene.output.cameraPosition = cam.vec3("position", "m");
      scene.output.cameraLookAt = cam.vec3("look_at", "m");
      cam.finish();
    }
    o.finish();
  }
  root.finish();
  try {
    scene.settings.validate();
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(concat(sourceName, ": ", e.what()));
  }
  return scene;
}

}  // namespace

Scene parseScene(const std::string& text, const std::string& sourceName, const SceneOptions& options) {
  return sceneFromJson(parseJsonText(text, sourceName), sourceName, options);
}

Scene loadScene(const std::string& path, const SceneOptions& options) {
  return sceneFromJson(parseJsonFile(path), path, options);
}

std::unique_ptr<MpmSolver> buildSolver(const Scene& scene) {
  auto solver = std::make_unique<MpmSolver>(scene.settings);
  for (const MpmMaterial& m : scene.materials) solver->addMaterial(m);
  for (const SceneBody& b : scene.bodies) {
    EmitterSettings s = b.emit;
    s.cellSize = scene.settings.grid.dx;
    solver->emit(b.shape, b.material, s);
  }
  solver->setSources(scene.fields);
  for (const SceneMagnet& m : scene.magnets) {
    if (m.collider)
      solver->addMagnet(*m.magnet, m.motion, m.boundary);
    else
      solver->sources().add(*m.magnet);
  }
  for (const MpmCollider& c : scene.colliders) solver->addCollider(c);
  return solver;
}

}  // namespace lodestone::examples
