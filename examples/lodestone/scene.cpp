#include "scene.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "json_schema.h"
#include "node_entry.h"
#include "lodestone/core/planner/accuracy_preset.h"
#include "lodestone/core/base/constants.h"
#include "lodestone/core/sources/cuboid_magnet.h"
#include "lodestone/core/sources/cylinder_magnet.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/sources/point_dipole.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/plugin/node_builders.h"

namespace lodestone::examples {

namespace {

// Memory the simulation needs per grid node, bytes: the MPM grid (mass,
// momentum, velocity, binning) and the magnetic stage's padded grid (n, phi,
// H_ext, H, M, B, t, f, the solver's vectors and multigrid hierarchy), about
// 600 B together; the estimate refuses grids that cannot fit before any
// allocation.
constexpr double kBytesPerNode = 600;
constexpr double kMaxGridGiB = 25;

double gridMemoryGiB(double ni, double nj, double nk) {
  return ni * nj * nk * kBytesPerNode / (1024.0 * 1024.0 * 1024.0);
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

ColliderMotion readMotion(JsonReader& r, const Pose& rest) {
  if (!r.has("motion")) return ColliderMotion::fixed(rest);
  JsonReader m = r.object("motion");
  ColliderMotion motion;
  if (m.has("keyframes")) {
    std::vector<double> times;
    std::vector<Pose> poses;
    for (JsonReader& k : m.array("keyframes", 1)) {
      times.push_back(k.number("time", "s", Range::nonNegative()));
      poses.push_back(plugin::poseAlong(k.vec3("center", "m"), k.direction("axis", rest.rotation * Vec3d{0, 0, 1})));
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

/// What shapes stored in files need: the readers, the scene file's directory
/// (relative paths are resolved against it) and the MPM dx (m), the default
/// voxel size of a mesh.
struct FileShapes {
  const ShapeLoaders* loaders = nullptr;
  std::filesystem::path directory;
  double dx = 0;
};

bool isFileShape(const std::string& shape) { return shape == "level_set" || shape == "mesh"; }

/// Body-frame placement of a file shape: the file's origin goes to `center`
/// (default the world origin) and its z axis along `axis`.
Pose readFilePose(JsonReader& r) {
  return plugin::poseAlong(r.vec3("center", "m", Range::any(), Vec3d{}), r.direction("axis", {0, 0, 1}));
}

/// The signed distance of a "level_set" (keys file, grid) or "mesh" (keys
/// file, voxel_size) entry.
std::shared_ptr<const SampledSdf> readFileShape(JsonReader& r, const std::string& shape, const FileShapes& files) {
  std::filesystem::path path(r.string("file"));
  if (path.is_relative()) path = files.directory / path;
  try {
    if (shape == "level_set") {
      const std::string grid = r.has("grid") ? r.string("grid") : std::string("surface");
      if (!files.loaders->levelSet) r.failAt("file", "shape 'level_set' needs a lodestone built with OpenVDB");
      return files.loaders->levelSet(path.string(), grid);
    }
    const double voxel = r.number("voxel_size", "m", Range::positive(), files.dx);
    if (!files.loaders->mesh) r.failAt("file", "shape 'mesh' needs a lodestone built with OpenVDB");
    return files.loaders->mesh(path.string(), voxel);
  } catch (const InvalidArgument& e) {
    if (std::string(e.what()).rfind(r.file(), 0) == 0) throw;  // already names the entry
    r.failAt("file", e.what());
  }
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
    // Node counts in double first: a tiny dx must be refused, not overflow an int.
    double n[3];
    for (int a = 0; a < 3; ++a) n[a] = std::ceil((hi[a] - lo[a]) / dx - 1e-9) + 1;
    const double gib = gridMemoryGiB(n[0], n[1], n[2]);
    if (!(gib <= kMaxGridGiB) || !(std::max(n[0], std::max(n[1], n[2])) <= 1 << 20))
      d.fail(concat("a grid of ", n[0], " x ", n[1], " x ", n[2], " nodes at dx = ", dx, " m is too large (needs about ",
                    gib, " GiB, limit ", kMaxGridGiB, " GiB)"));
    g.dims = {int(n[0]), int(n[1]), int(n[2])};
    scene.settings.grid = g;
    scene.settings.walls = readBoundary(d, BoundaryCondition{});
    d.finish();
  }

  // Accuracy preset (docs/accuracy_vs_time.md): the defaults of the field
  // solve's tolerance and frequency; explicit keys below still win.
  if (root.has("accuracy")) {
    const AccuracyPresetSettings p =
        accuracyPresetSettings(parseAccuracyPreset(root.string("accuracy", {"draft", "preview", "final"})));
    scene.accuracy = p;
    scene.settings.magnetic.solve.tolerance = p.solveTolerance;
    scene.settings.magneticSolveInterval = p.solveInterval;
    scene.settings.planner.enabled = true;  // a preset is also the planner's budget
    scene.settings.planner.budget = p.bound;
  }
  // Effects planner (docs/planner.md): which magnetic stages run, within a budget.
  if (root.has("planner")) {
    JsonReader pl = root.object("planner");
    PlannerSettings& ps = scene.settings.planner;
    ps.enabled = pl.boolean("enabled", true);
    ps.budget = pl.number("budget", "", Range{0, 1, true, true}, ps.budget);
    const std::vector<std::string> toggles{"auto", "off", "on"};
    ps.linearLaw = parsePlannerToggle(pl.string("linear_law", toggles, "auto"));
    ps.appliedFieldOnly = parsePlannerToggle(pl.string("applied_field_only", toggles, "auto"));
    ps.fieldReuse = parsePlannerToggle(pl.string("field_reuse", toggles, "auto"));
    ps.activeRegion = parsePlannerToggle(pl.string("active_region", toggles, "auto"));
    pl.finish();
  }

  // Time stepping.
  {
    JsonReader t = root.object("time");
    scene.frames = t.integer("frames", 1, 100000);
    scene.fps = t.number("fps", "1/s", Range::closed(1, 10000), 24.0);
    scene.settings.fixedDt = t.number("dt", "s", Range::closed(0, 1), 0.0);
    scene.settings.cfl = t.number("cfl", "", Range::closed(0.01, 1), scene.settings.cfl);
    scene.settings.dtMax = t.number("dt_max", "s", Range::positive(), scene.settings.dtMax);
    scene.settings.magneticSolveInterval =
        t.integer("field_solve_every", 0, 1000000, scene.settings.magneticSolveInterval);
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

  // Materials: each entry is a `material` node (docs/nodes.md); its keys are
  // the node's parameters, read and checked from the declarations.
  for (JsonReader& m : root.array("materials", 1)) {
    const plugin::ParamSet p = readNodeEntry(m, "material");
    const std::string& name = p.getString("name");
    if (std::find(scene.materialNames.begin(), scene.materialNames.end(), name) != scene.materialNames.end())
      m.fail(concat("duplicate material name '", name, "'"));
    scene.materials.push_back(plugin::materialFrom(p));
    scene.materialNames.push_back(name);
    m.finish();
  }

  const FileShapes files{&options.loaders, std::filesystem::path(sourceName).parent_path(), scene.settings.grid.dx};

  // Bodies: `particle_source` nodes (the lattice is fitted to domain.dx), plus
  // the scene-only key `material` naming one of the materials above.
  for (JsonReader& b : optionalArray(root, "bodies")) {
    SceneBody body;
    const std::string material = b.string("material", scene.materialNames);
    const plugin::ParamSet p = readNodeEntry(b, "particle_source", {"cell_size"});
    body.name = p.given("name") ? p.getString("name") : concat("body ", scene.bodies.size());
    body.material = std::uint32_t(std::find(scene.materialNames.begin(), scene.materialNames.end(), material) -
                                  scene.materialNames.begin());
    const std::string& shape = p.getString("shape");
    if (isFileShape(shape)) {
      const Pose pose = readFilePose(b);
      body.shape = EmitterShape::levelSetShape(pose, readFileShape(b, shape, files));
    } else {
      body.shape = plugin::shapeFrom(p);
    }
    body.emit.particlesPerCell = int(p.getInt("particles_per_cell"));
    body.emit.jitter = p.getFloat("jitter");
    body.emit.seed = std::uint64_t(p.getInt("seed"));
    body.emit.velocity = p.getVec3("velocity");
    b.finish();
    scene.bodies.push_back(std::move(body));
  }

  // Permanent magnets (field sources, and colliders unless told otherwise):
  // `magnet` nodes; `motion` may also hold keyframes.
  for (JsonReader& m : optionalArray(root, "magnets")) {
    SceneMagnet sm;
    const plugin::ParamSet p = readNodeEntry(m, "magnet", {"motion."});
    if (p.given("remanence") && p.given("magnetization")) m.fail("give magnetization or remanence, not both");
    if (!p.given("remanence")) m.number("magnetization", "A/m", Range::closed(-3e6, 3e6));  // required then
    const Pose pose = plugin::poseAlong(p.getVec3("center"), p.getVec3("axis"));
    sm.magnet = plugin::makeMagnet(p, pose);
    sm.motion = readMotion(m, pose);
    sm.collider = p.getBool("collider");
    sm.boundary = plugin::boundaryFrom(p);
    m.finish();
    scene.magnets.push_back(std::move(sm));
  }

  // Applied fields: `applied_field` nodes (a VDB file is relative to the scene file).
  for (JsonReader& f : optionalArray(root, "fields")) {
    plugin::ParamSet p = readNodeEntry(f, "applied_field");
    if (p.getString("type") == "vdb") {
      std::filesystem::path path(p.getString("file"));
      if (path.is_relative()) p.set("file", (files.directory / path).string());
    }
    try {
      scene.fields.add(plugin::appliedFieldFrom(p));
    } catch (const std::exception& e) {
      f.failAt(p.getString("type") == "vdb" ? "file" : "type", e.what());
    }
    f.finish();
  }

  // Colliders: `collider` nodes; `motion` may also hold keyframes.
  for (JsonReader& c : optionalArray(root, "colliders")) {
    const plugin::ParamSet p = readNodeEntry(c, "collider", {"motion."});
    const std::string& shape = p.getString("shape");
    ColliderShape cs;
    Pose pose;
    if (isFileShape(shape)) {
      pose = readFilePose(c);
      cs = ColliderShape::levelSetShape(readFileShape(c, shape, files));
      if (p.getBool("inverted")) cs = cs.invertedShape();
    } else {
      cs = plugin::colliderShapeFrom(p, pose);
    }
    const ColliderMotion motion = readMotion(c, pose);
    const BoundaryCondition bc = plugin::boundaryFrom(p);
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
      if (!list.is_array())
        o.failAt("vdb", "expected an array of grid names (n, phi, H, M, B, force, mass, velocity)");
      for (std::size_t k = 0; k < list.size(); ++k) {
        const std::vector<std::string> allowed{"n", "phi", "H", "M", "B", "force", "mass", "velocity"};
        if (!list[k].is_string() || std::find(allowed.begin(), allowed.end(), list[k].get<std::string>()) == allowed.end())
          o.failAt("vdb", concat("element ", k, ": expected one of n, phi, H, M, B, force, mass, velocity, found ",
                                 list[k].dump()));
        scene.output.vdbFields.push_back(list[k].get<std::string>());
      }
    }
    scene.output.vdbPoints = o.boolean("vdb_points", false);
    scene.output.vdbAliases = o.boolean("vdb_aliases", false);
    scene.output.checkpointEvery = o.integer("checkpoint_every", 0, 1000000, 0);
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
