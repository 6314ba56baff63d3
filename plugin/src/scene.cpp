#include "lodestone/plugin/scene.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <utility>

#include "lodestone/core/base/error.h"
#include "lodestone/core/base/hash.h"
#include "lodestone/core/planner/accuracy_preset.h"
#include "lodestone/core/planner/effects_planner.h"
#include "lodestone/plugin/json_reader.h"
#include "lodestone/plugin/node_builders.h"
#include "lodestone/plugin/node_registry.h"
#include "lodestone/plugin/param_json.h"

namespace lodestone::plugin {

namespace {

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

/// What shapes stored in files need: the readers, the scene file's directory
/// (relative paths are resolved against it) and the MPM dx (m), the default
/// voxel size of a mesh.
struct FileShapes {
  const ShapeLoaders* loaders = nullptr;
  std::filesystem::path directory;
  double dx = 0;
};

/// Body-frame placement of a file shape: the file's origin goes to `center`
/// (default the world origin) and its z axis along `axis`.
Pose readFilePose(JsonReader& r) {
  return poseAlong(r.vec3("center", "m", Range::any(), Vec3d{}), r.direction("axis", {0, 0, 1}));
}

/// The signed distance of a "level_set" (keys file, grid) or "mesh" (keys
/// file, voxel_size) entry.
std::shared_ptr<const SampledSdf> readFileShape(JsonReader& r, const std::string& shape, const FileShapes& files) {
  std::filesystem::path path(r.string("file"));
  if (path.is_relative()) path = files.directory / path;
  try {
    // The node library's readers (loadShapeFile) unless the host installed its own.
    if (shape == "level_set") {
      const std::string grid = r.has("grid") ? r.string("grid") : std::string("surface");
      if (files.loaders->levelSet) return files.loaders->levelSet(path.string(), grid);
      if (!vdbBuilt()) r.failAt("file", "shape 'level_set' needs a lodestone built with OpenVDB");
      return loadShapeFile(shape, path.string(), grid, 0.0);
    }
    const double voxel = r.number("voxel_size", "m", Range::positive(), files.dx);
    if (files.loaders->mesh) return files.loaders->mesh(path.string(), voxel);
    if (!vdbBuilt()) r.failAt("file", "shape 'mesh' needs a lodestone built with OpenVDB");
    return loadShapeFile(shape, path.string(), std::string(), voxel);
  } catch (const InvalidArgument& e) {
    if (std::string(e.what()).rfind(r.file(), 0) == 0) throw;  // already names the entry
    r.failAt("file", e.what());
  }
}

std::vector<JsonReader> optionalArray(JsonReader& r, const std::string& key) {
  return r.has(key) ? r.array(key) : std::vector<JsonReader>{};
}

Scene sceneFromJson(const nlohmann::json& doc, const std::string& sourceName, const SceneOptions& options) {
  JsonReader root(doc, "", sourceName);
  Scene scene;
  scene.file = sourceName;
  scene.name = root.string("name");
  scene.description = root.has("description") ? root.string("description") : std::string();

  // The simulation's settings: the domain, time, gravity and magnetic objects
  // are the parameters of the mpm_solver node (docs/nodes.md), built by the
  // node's own settings builder; domain.full_dx is the scene's own key. The
  // domain and time objects are required (a missing one is named only after
  // the domain is known to fit in memory).
  if (!root.has("domain")) root.object("domain");  // throws: missing required key
  ParamSet solverParams = readNodeEntry(root, "mpm_solver", {}, [&](const std::string& group, JsonReader& r) {
    if (group == "domain") scene.fullDx = r.number("full_dx", "m", Range::nonNegative(), 0.0);
  });
  if (options.full) {
    if (!(scene.fullDx > 0)) root.failAt("domain", "--full needs domain.full_dx in the scene");
    solverParams.set("domain.dx", scene.fullDx);
  }
  if (options.dx > 0) solverParams.set("domain.dx", options.dx);
  try {
    scene.settings = mpmSettingsFrom(solverParams);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(concat(sourceName, ": ", e.what()));
  }
  if (!root.has("time")) root.object("time");
  scene.startFrame = int(solverParams.getInt("time.start_frame"));
  scene.frames = int(solverParams.getInt("time.frames"));
  scene.fps = solverParams.getFloat("time.fps");

  // Accuracy preset (docs/accuracy_vs_time.md): the defaults of the field
  // solve's tolerance and frequency; explicit keys still win.
  if (root.has("accuracy")) {
    const AccuracyPresetSettings p =
        accuracyPresetSettings(parseAccuracyPreset(root.string("accuracy", {"draft", "preview", "final"})));
    scene.accuracy = p;
    if (!solverParams.given("magnetic.tolerance")) scene.settings.magnetic.solve.tolerance = p.solveTolerance;
    if (!solverParams.given("time.field_solve_every")) scene.settings.magneticSolveInterval = p.solveInterval;
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
    ps.patches = parsePlannerToggle(pl.string("patches", toggles, "auto"));
    pl.finish();
  }

  // Materials: each entry is a `material` node (docs/nodes.md); its keys are
  // the node's parameters, read and checked from the declarations.
  for (JsonReader& m : root.array("materials", 1)) {
    const ParamSet p = readNodeEntry(m, "material");
    const std::string& name = p.getString("name");
    if (std::find(scene.materialNames.begin(), scene.materialNames.end(), name) != scene.materialNames.end())
      m.fail(concat("duplicate material name '", name, "'"));
    scene.materials.push_back(materialFrom(p));
    scene.materialNames.push_back(name);
    m.finish();
  }

  const FileShapes files{&options.loaders, std::filesystem::path(sourceName).parent_path(), scene.settings.grid.dx};

  // Bodies: `particle_source` nodes (the lattice is fitted to domain.dx), plus
  // the scene-only key `material` naming one of the materials above.
  for (JsonReader& b : optionalArray(root, "bodies")) {
    SceneBody body;
    const std::string material = b.string("material", scene.materialNames);
    const ParamSet p = readNodeEntry(b, "particle_source", {"cell_size"});
    body.name = p.given("name") ? p.getString("name") : concat("body ", scene.bodies.size());
    body.material = std::uint32_t(std::find(scene.materialNames.begin(), scene.materialNames.end(), material) -
                                  scene.materialNames.begin());
    const std::string& shape = p.getString("shape");
    if (isFileShape(shape)) {
      const Pose pose = readFilePose(b);
      body.shape = EmitterShape::levelSetShape(pose, readFileShape(b, shape, files));
    } else {
      body.shape = shapeFrom(p);
    }
    body.emit = emitterSettingsFrom(p);
    body.emit.cellSize = scene.settings.grid.dx;
    b.finish();
    scene.bodies.push_back(std::move(body));
  }
  // Emitters: `particle_emitter` nodes (the lattice fitted to domain.dx), plus
  // the scene-only keys `material` and `motion.keyframes`.
  for (JsonReader& e : optionalArray(root, "emitters")) {
    SceneEmitter emitter;
    const std::string material = e.string("material", scene.materialNames);
    const ParamSet p = readNodeEntry(e, "particle_emitter", {"cell_size", "motion."});
    emitter.name = p.given("name") ? p.getString("name") : concat("emitter ", scene.emitters.size());
    emitter.material = std::uint32_t(std::find(scene.materialNames.begin(), scene.materialNames.end(), material) -
                                     scene.materialNames.begin());
    emitter.shape = shapeFrom(p);
    const ColliderMotion motion = readMotion(e, emitter.shape.pose);
    try {
      emitter.settings = rateEmitterSettingsFrom(p, motion);
    } catch (const InvalidArgument& error) {
      e.fail(error.what());
    }
    emitter.settings.lattice.cellSize = scene.settings.grid.dx;
    e.finish();
    scene.emitters.push_back(std::move(emitter));
  }
  // The domain's grid was checked alone above; with the bodies' points too
  // (estimated from their volumes) and those the emitters add over the run,
  // before any is emitted.
  double particles = 0;
  for (const SceneBody& b : scene.bodies)
    particles += estimatedParticles(b.shape.volume(), b.emit.cellSize, b.emit.particlesPerCell);
  for (const SceneEmitter& e : scene.emitters)
    particles += estimatedEmittedParticles(e.shape, e.settings, scene.startTime(), scene.frameTime(scene.lastFrame()));
  try {
    mpmSettingsFrom(solverParams, particles);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(concat(sourceName, ": ", e.what()));
  }

  // Permanent magnets (field sources, and colliders unless told otherwise):
  // `magnet` nodes; `motion` may also hold keyframes.
  for (JsonReader& m : optionalArray(root, "magnets")) {
    const ParamSet p = readNodeEntry(m, "magnet", {"motion."});
    if (p.given("remanence") && p.given("magnetization")) m.fail("give magnetization or remanence, not both");
    if (!p.given("remanence"))  // magnetization is required then (missing: named with its declared unit and range)
      readParam(m, "magnetization", *requireNode("magnet").param("magnetization"));
    if (p.getBool("dynamic") && !p.getBool("collider"))
      m.failAt("dynamic", "a dynamic magnet must be a collider (collider = true): its body is what moves");
    Pose pose;
    SceneMagnet sm = magnetFrom(p, &pose);
    sm.motion = readMotion(m, pose);
    m.finish();
    scene.magnets.push_back(std::move(sm));
  }

  // Applied fields: `applied_field` nodes (a VDB file is relative to the scene file).
  for (JsonReader& f : optionalArray(root, "fields")) {
    ParamSet p = readNodeEntry(f, "applied_field");
    if (p.getString("type") == "vdb") {
      std::filesystem::path path(p.getString("file"));
      if (path.is_relative()) p.set("file", (files.directory / path).string());
    }
    try {
      scene.fields.add(appliedFieldFrom(p));
    } catch (const std::exception& e) {
      f.failAt(p.getString("type") == "vdb" ? "file" : "type", e.what());
    }
    f.finish();
  }

  // Colliders: `collider` nodes; `motion` may also hold keyframes.
  for (JsonReader& c : optionalArray(root, "colliders")) {
    const ParamSet p = readNodeEntry(c, "collider", {"motion."});
    const std::string& shape = p.getString("shape");
    ColliderShape cs;
    Pose pose;
    if (isFileShape(shape)) {
      pose = readFilePose(c);
      cs = ColliderShape::levelSetShape(readFileShape(c, shape, files));
      if (p.getBool("inverted")) cs = cs.invertedShape();
    } else {
      cs = colliderShapeFrom(p, pose);
    }
    const ColliderMotion motion = readMotion(c, pose);
    const BoundaryCondition bc = boundaryFrom(p);
    MpmCollider collider(cs, motion, bc);
    try {
      if (const std::optional<RigidBodySettings> body = rigidBodyFrom(p)) collider.setDynamics(*body);
    } catch (const InvalidArgument& e) {
      c.failAt("dynamic", e.what());
    }
    c.finish();
    scene.colliders.push_back(std::move(collider));
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
      if (!list.is_array()) o.failAt("vdb", "expected an array of grid names (n, phi, H, M, B, force, mass, velocity)");
      for (std::size_t k = 0; k < list.size(); ++k) {
        const std::vector<std::string> allowed{"n", "phi", "H", "M", "B", "force", "mass", "velocity"};
        if (!list[k].is_string() ||
            std::find(allowed.begin(), allowed.end(), list[k].get<std::string>()) == allowed.end())
          o.failAt("vdb", concat("element ", k, ": expected one of n, phi, H, M, B, force, mass, velocity, found ",
                                 list[k].dump()));
        scene.output.vdbFields.push_back(list[k].get<std::string>());
      }
    }
    scene.output.vdbPoints = o.boolean("vdb_points", false);
    scene.output.vdbAliases = o.boolean("vdb_aliases", false);
    scene.output.checkpointEvery = o.integer("checkpoint_every", 0, 1000000, 0);
    if (o.has("surface")) {
      JsonReader surface = o.object("surface");
      scene.output.surface = surfaceSettingsFrom(readNodeEntry(surface, "surface", {"path", "volume_path"}));
      surface.finish();
    }
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
  // The whole run, now that its materials and sources are known (the domain
  // was checked for the MPM grid alone): the field solve's grid too when
  // something magnetic meets a magnet or an applied field.
  requireFitsInMemory(sourceName, estimateMemory(sceneMemory(scene)));
  return scene;
}

}  // namespace

Scene parseScene(const std::string& text, const std::string& sourceName, const SceneOptions& options) {
  Scene scene = sceneFromJson(parseJsonText(text, sourceName), sourceName, options);
  scene.contentHash = fnv1a64(text);
  return scene;
}

Scene loadScene(const std::string& path, const SceneOptions& options) { return parseScene(readJsonFile(path), path, options); }

std::unique_ptr<MpmSolver> buildSolver(const Scene& scene, std::shared_ptr<MpmPartition> partition) {
  auto solver = std::make_unique<MpmSolver>(scene.settings);
  // Split before emitting: each process keeps only its part of every body.
  if (partition) solver->setPartition(partition);
  // Before anything is added: magnets and colliders take their pose at the solver's time.
  solver->setTime(scene.startTime());
  for (const MpmMaterial& m : scene.materials) solver->addMaterial(m);
  const Vec3d lo = solver->domainLower(), hi = solver->domainUpper();
  const auto point = [](const Vec3d& p) {
    char text[96];
    std::snprintf(text, sizeof text, "(%.6g, %.6g, %.6g)", p.x, p.y, p.z);
    return std::string(text);
  };
  for (const SceneBody& b : scene.bodies) {
    EmitterSettings s = b.emit;
    s.cellSize = scene.settings.grid.dx;
    const std::size_t first = solver->particles().size();
    const EmitReport emitted = solver->emit(b.shape, b.material, s);
    // A body with no particle inside the domain would be clamped onto its
    // boundary (or removed) at the first substep: refuse it.
    const std::vector<Vec3d>& x = std::as_const(*solver).particles().x;
    const auto inside = [&](const Vec3d& p) {
      return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
    };
    bool any = std::any_of(x.begin() + std::ptrdiff_t(first), x.end(), inside);
    if (partition) any = partition->maxOverRanks(any ? 1.0 : 0.0) > 0;  // some process holds one
    if (emitted.particles > 0 && !any)
      throw InvalidArgument(concat(scene.file, ": body '", b.name, "' lies wholly outside the domain ", point(lo),
                                   " .. ", point(hi), " m (where material can be); none of its ", emitted.particles,
                                   " particles is inside"));
  }
  for (const SceneEmitter& e : scene.emitters) {
    RateEmitterSettings s = e.settings;
    s.lattice.cellSize = scene.settings.grid.dx;
    try {
      solver->addEmitter(e.shape, e.material, s);
    } catch (const InvalidArgument& error) {
      throw InvalidArgument(concat(scene.file, ": emitter '", e.name, "': ", error.what()));
    }
    // An emitter outside the domain when it switches on would emit nothing.
    const double on = s.schedule.list().front().first;
    const Vec3d c = solver->emitter(solver->emitterCount() - 1).poseAt(on).position;
    if (c.x < lo.x || c.x > hi.x || c.y < lo.y || c.y > hi.y || c.z < lo.z || c.z > hi.z)
      throw InvalidArgument(concat(scene.file, ": emitter '", e.name, "' is centred at ", point(c), " m at t = ", on,
                                   " s, outside the domain ", point(lo), " .. ", point(hi),
                                   " m (where material can be)"));
  }
  addSourcesAndColliders(*solver, scene.fields, scene.magnets, scene.colliders);
  return solver;
}

namespace {

// The MPM grid's runs (mpm/grid.h: per x-row, from the first to the last
// node a stencil reaches) for material in `count` boxes [lo, hi] (m;
// boxOf(b, lo, hi) gives box b, a point's box is the point): the stencil
// bases of each box fill their rows of bins, whose node runs mpmNodeRuns
// gives as the grid takes them. Their nodes, and the bytes the grid's pages
// take for them, packed or (MpmSettings::denseGrid) in the whole grid
// (mpmHeldBytes; with the colour field when `colour`).
struct RunMemory {
  double nodes = 0, bytes = 0;
};
template <typename BoxOf>
RunMemory mpmRunMemory(const GridSpec& g, std::size_t count, bool colour, bool packed, const BoxOf& boxOf) {
  const int bd[3] = {g.dims.i - 2, g.dims.j - 2, g.dims.k - 2};
  const auto base = [&](double x, int a) { return mpmStencilBase(g, x, a); };
  int lo[3] = {bd[0], bd[1], bd[2]}, hi[3] = {-1, -1, -1};
  Vec3d blo, bhi;
  for (std::size_t b = 0; b < count; ++b) {
    boxOf(b, blo, bhi);
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], base(blo[a], a));
      hi[a] = std::max(hi[a], base(bhi[a], a));
    }
  }
  if (hi[0] < lo[0]) return {};
  const int nbj = hi[1] - lo[1] + 1, nbk = hi[2] - lo[2] + 1;
  std::vector<std::uint32_t> first(std::size_t(nbj) * std::size_t(nbk), std::uint32_t(bd[0])), end(first.size(), 0);
  for (std::size_t b = 0; b < count; ++b) {
    boxOf(b, blo, bhi);
    const int i0 = base(blo.x, 0), i1 = base(bhi.x, 0) + 1;
    for (int k = base(blo.z, 2); k <= base(bhi.z, 2); ++k)
      for (int j = base(blo.y, 1); j <= base(bhi.y, 1); ++j) {
        const std::size_t row = std::size_t(j - lo[1]) + std::size_t(nbj) * std::size_t(k - lo[2]);
        first[row] = std::min(first[row], std::uint32_t(i0));
        end[row] = std::max(end[row], std::uint32_t(i1));
      }
  }
  std::vector<std::int32_t> runFirst(std::size_t(nbj + 2) * std::size_t(nbk + 2)), runEnd(runFirst.size());
  mpmNodeRuns(first.data(), end.data(), nbj, nbk, runFirst.data(), runEnd.data());
  RunMemory m;
  for (std::size_t q = 0; q < runFirst.size(); ++q) m.nodes += double(runEnd[q] - runFirst[q]);
  m.bytes = mpmHeldBytes(g, {lo[0], lo[1], lo[2]}, nbj, nbk, first.data(), end.data(), runFirst.data(),
                         runEnd.data(), colour, packed);
  return m;
}

}  // namespace

MemoryCounts sceneMemory(const Scene& scene, const MpmSolver* solver) {
  MemoryCounts c;
  // The MPM grid holds memory for the runs of nodes the material's stencils
  // reach (mpm/grid.h): of the material now (the bodies' boxes, or the
  // solver's particles), the whole grid when emitters will add material.
  const bool emitters = solver ? solver->emitterCount() > 0 : !scene.emitters.empty();
  const GridSpec& grid = scene.settings.grid;
  const bool packed = !scene.settings.denseGrid;  // MpmSolver's grid packs its runs (mpm/grid.h)
  const bool colour = std::any_of(scene.materials.begin(), scene.materials.end(),
                                  [](const MpmMaterial& m) { return m.hasSurfaceTension(); });
  // With a partition: this process's part (its window of the grid, which the
  // sums over the processes write whole, and its particles).
  const MpmPartition* split = solver ? solver->partition() : nullptr;
  RunMemory runs;
  if (emitters) {
    runs.nodes = double(grid.nodeCount());
  } else if (split) {
    const Index3 wlo = split->windowLo(), whi = split->windowHi();
    runs.nodes = double(whi.i - wlo.i) * double(whi.j - wlo.j) * double(whi.k - wlo.k);
  } else if (solver) {
    const std::vector<Vec3d>& x = solver->particles().x;
    runs = mpmRunMemory(grid, x.size(), colour, packed, [&](std::size_t p, Vec3d& lo, Vec3d& hi) { lo = hi = x[p]; });
  } else {
    runs = mpmRunMemory(grid, scene.bodies.size(), colour, packed,
                        [&](std::size_t b, Vec3d& lo, Vec3d& hi) { scene.bodies[b].shape.worldBounds(lo, hi); });
  }
  c.mpmNodes = runs.nodes;
  c.mpmGridBytes = runs.bytes;
  c.previewPixels = double(scene.output.width) * double(scene.output.height);
  bool magnetic = false;
  // `n` points of scene material `material`.
  const auto add = [&](const MpmMaterial& m, double n) {
    magnetic = magnetic || (m.isMagnetic() && n > 0);
    c.particles += n;
    c.magneticParticles += m.isMagnetic() ? n : 0;
    c.capillaryParticles += m.hasSurfaceTension() ? n : 0;
  };
  // The volume (m^3) of the magnetic material emitters add over the run, all
  // processes' (each solves the field of all of it).
  double emittedMagneticVolume = 0;
  const auto emitted = [&](const MpmMaterial& m, double points, const RateEmitterSettings& e) {
    const double cell = e.lattice.cellSize;
    if (m.isMagnetic()) emittedMagneticVolume += points * cell * cell * cell / e.lattice.particlesPerCell;
  };
  if (solver) {
    const std::vector<MpmMaterial>& materials = solver->materials();
    const MpmParticles& p = solver->particles();
    for (std::size_t i = 0; i < p.size(); ++i) add(materials[p.material[i]], 1);
    const double end = solver->time() + scene.frames * scene.frameDuration();
    for (std::size_t e = 0; e < solver->emitterCount(); ++e) {
      const RateEmitter& emitter = solver->emitter(e);
      const MpmMaterial& m = materials[emitter.materialIndex()];
      const double points = emitter.particlesBy(end) - emitter.particlesBy(solver->time());
      add(m, points / (split ? split->ranks() : 1));
      emitted(m, points, emitter.settings());
    }
    // Every process runs the field solve: whether there is one is the scene's.
    for (const SceneBody& b : scene.bodies) magnetic = magnetic || (split && scene.materials[b.material].isMagnetic());
  } else {
    for (const SceneBody& b : scene.bodies)
      add(scene.materials[b.material], estimatedParticles(b.shape.volume(), b.emit.cellSize, b.emit.particlesPerCell));
    for (const SceneEmitter& e : scene.emitters) {
      const double points =
          estimatedEmittedParticles(e.shape, e.settings, scene.startTime(), scene.frameTime(scene.lastFrame()));
      add(scene.materials[e.material], points);
      emitted(scene.materials[e.material], points, e.settings);
    }
  }
  const bool sources = !scene.fields.empty() || !scene.magnets.empty();
  if (magnetic && sources) {
    // The field solve's nodes: the planner's patches or active region around
    // the magnetic material when it would choose them
    // (planner/effects_planner.h), the whole magnetic grid otherwise or when
    // emitters add magnetic material.
    const GridSpec& mg = scene.settings.magneticGrid ? *scene.settings.magneticGrid : scene.settings.grid;
    // Points where the magnetic material is: the particles, or before a run
    // a lattice over each magnetic body's bounds (spacing at most 4 cells
    // where 64 points an axis allow, so that a body stays one group).
    std::vector<Vec3d> at;
    bool magneticEmitters = false;
    if (solver) {
      const MpmParticles& p = solver->particles();
      for (std::size_t i = 0; i < p.size(); ++i)
        if (solver->materials()[p.material[i]].isMagnetic()) at.push_back(p.x[i]);
      for (std::size_t e = 0; e < solver->emitterCount(); ++e)
        magneticEmitters = magneticEmitters || solver->materials()[solver->emitter(e).materialIndex()].isMagnetic();
    } else {
      for (const SceneBody& b : scene.bodies) {
        if (!scene.materials[b.material].isMagnetic()) continue;
        Vec3d blo, bhi;
        b.shape.worldBounds(blo, bhi);
        int n[3];
        for (int k = 0; k < 3; ++k) n[k] = std::clamp(int(std::ceil((bhi[k] - blo[k]) / (4 * mg.dx))), 1, 64);
        for (int k = 0; k <= n[2]; ++k)
          for (int j = 0; j <= n[1]; ++j)
            for (int i = 0; i <= n[0]; ++i) {
              const double u[3] = {double(i) / n[0], double(j) / n[1], double(k) / n[2]};
              at.push_back({blo.x + u[0] * (bhi.x - blo.x), blo.y + u[1] * (bhi.y - blo.y), blo.z + u[2] * (bhi.z - blo.z)});
            }
      }
      for (const SceneEmitter& e : scene.emitters) magneticEmitters = magneticEmitters || scene.materials[e.material].isMagnetic();
    }
    const bool placeKnown = !magneticEmitters && !at.empty() && !split;
    c.fieldNodes = placeKnown ? plannedSolveNodes(scene.settings.planner, mg, at.data(), at.size()) : double(mg.nodeCount());
    // The material cells: of the magnetic particles, or before a run of a
    // lattice of one point per field cell filling each magnetic body; the
    // cells emitted material fills (its volume: how it spreads is not known
    // before the run).
    if (solver) {
      // With a partition every process solves the field of all the material,
      // of which it holds about its share.
      c.fieldMaterialCells = plannedMaterialCells(mg, at.data(), at.size()) * (split ? split->ranks() : 1);
    } else {
      std::vector<Vec3d> cells;
      double halfWidth = 0;
      for (const SceneBody& b : scene.bodies) {
        if (!scene.materials[b.material].isMagnetic()) continue;
        EmitterSettings lattice = b.emit;
        lattice.cellSize = mg.dx;
        lattice.particlesPerCell = 1;
        lattice.jitter = 0;
        const EmitterLattice l = emitterLattice(b.shape, lattice);
        for (const Vec3d& p : l.points) cells.push_back(b.shape.pose.toWorld(p));
        halfWidth = std::max({halfWidth, 0.5 * l.spacing.x, 0.5 * l.spacing.y, 0.5 * l.spacing.z});
      }
      c.fieldMaterialCells = plannedMaterialCells(mg, cells.data(), cells.size(), halfWidth);
    }
    c.fieldMaterialCells += emittedMagneticVolume / (mg.dx * mg.dx * mg.dx);
  } else {
    c.magneticParticles = 0;  // no stage runs: no transfer weights
  }
  return c;
}

}  // namespace lodestone::plugin
