// One format: the entries of scene files are nodes. Every entry of every
// example scene, given to the node of its kind, sets only declared
// parameters and cooks to what the scene reader builds; scene errors name the
// entry's path and suggest declared parameter names.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/network.h"
#include "lodestone/plugin/node_builders.h"
#include "lodestone/plugin/param_json.h"
#include "lodestone/plugin/scene.h"

using namespace lodestone;
using namespace lodestone::plugin;

namespace {

/// The node an entry of `list` is, and the scene-only keys it may carry.
struct Kind {
  const char* list;
  const char* node;
  std::vector<std::string> sceneOnly;
};
const Kind kKinds[] = {{"materials", "material", {}},
                       {"bodies", "particle_source", {"material"}},
                       {"emitters", "particle_emitter", {"material", "motion"}},
                       {"magnets", "magnet", {"motion"}},
                       {"fields", "applied_field", {}},
                       {"colliders", "collider", {"motion"}}};

TEST(SceneNodes, EveryExampleSceneEntryIsANodeThatCooks) {
  int entries = 0;
  for (const auto& file : std::filesystem::directory_iterator(LODESTONE_SCENES_DIR)) {
    if (file.path().extension() != ".json") continue;
    SCOPED_TRACE(file.path().string());
    std::ifstream in(file.path());
    const nlohmann::json doc = nlohmann::json::parse(in);
    const plugin::Scene scene = plugin::loadScene(file.path().string());
    for (const Kind& kind : kKinds) {
      if (!doc.contains(kind.list)) continue;
      for (std::size_t k = 0; k < doc[kind.list].size(); ++k) {
        nlohmann::json entry = doc[kind.list][k];
        for (const std::string& key : kind.sceneOnly) entry.erase(key);
        // A scene's relative file paths are relative to the scene file; a node's to the host's directory.
        if (entry.contains("file") && std::filesystem::path(entry["file"].get<std::string>()).is_relative())
          entry["file"] = (file.path().parent_path() / entry["file"].get<std::string>()).string();
        Network net;
        net.addNode(kind.node, "n");
        if (std::string(kind.node) == "particle_source" || std::string(kind.node) == "particle_emitter")
          net.setParam("n", "cell_size", scene.settings.grid.dx);
        ASSERT_NO_THROW(setParamsFromJson(net, "n", entry, concat(kind.list, "[", k, "]")))
            << kind.list << "[" << k << "]";
        const CookOutputs& out = net.cook("n");
        ++entries;
        // What the node built is what the scene reader built.
        if (std::string(kind.node) == "material") {
          const auto m = std::get<std::shared_ptr<const MaterialData>>(out.at("material"));
          EXPECT_EQ(m->material.describe(), scene.materials[k].describe());
        }
        if (std::string(kind.node) == "particle_source") {
          const auto p = std::get<std::shared_ptr<const ParticlesData>>(out.at("particles"));
          EXPECT_NEAR(p->bodies[0].shape.volume(), scene.bodies[k].shape.volume(), 1e-12);
          EXPECT_EQ(p->bodies[0].emit.particlesPerCell, scene.bodies[k].emit.particlesPerCell);
        }
        if (std::string(kind.node) == "particle_emitter") {
          const auto p = std::get<std::shared_ptr<const ParticlesData>>(out.at("particles"));
          const SceneEmitter &node = p->emitters[0], &read = scene.emitters[k];
          EXPECT_NEAR(node.shape.volume(), read.shape.volume(), 1e-15);
          EXPECT_EQ(node.settings.rateKind, read.settings.rateKind);
          EXPECT_EQ(node.settings.rate, read.settings.rate);
          EXPECT_EQ(node.settings.lattice.velocity, read.settings.lattice.velocity);
          EXPECT_EQ(node.settings.velocityInBodyFrame, read.settings.velocityInBodyFrame);
          EXPECT_EQ(node.settings.schedule.list(), read.settings.schedule.list());
          EXPECT_EQ(p->particles.size(), 0u);  // it emits in the solver, over time
        }
        if (std::string(kind.node) == "magnet") {
          const auto s = std::get<std::shared_ptr<const SourcesData>>(out.at("sources"));
          EXPECT_EQ(s->magnets[0].magnet->describe(), scene.magnets[k].magnet->describe());
          EXPECT_EQ(s->magnets[0].collider, scene.magnets[k].collider);
        }
        if (std::string(kind.node) == "applied_field") {
          const auto s = std::get<std::shared_ptr<const SourcesData>>(out.at("sources"));
          EXPECT_EQ(s->fields.source(0).describe(), scene.fields.source(k).describe());
        }
      }
    }
  }
  EXPECT_GT(entries, 20);
}

std::string errorOf(const std::string& text) {
  try {
    plugin::parseScene(text, "test.json");
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

TEST(SceneNodes, SceneErrorsComeFromTheDeclarations) {
  const std::string base = R"({
    "name": "s",
    "domain": { "min": [0, 0, 0], "max": [0.2, 0.2, 0.2], "dx": 0.02 },
    "time": { "frames": 1 },
    "materials": [ { "name": "ferro", "model": "fluid", "density": 1000, "viscosity": 1, "bulk_modulus": 1e5,
                     "magnetic": { "law": "langevin", "moment": 1e-19 } } ],
    "bodies": [ { "material": "ferro", "shape": "sphere", "center": [0.1, 0.1, 0.1], "radius": 0.03 } ],
    "magnets": [ { "shape": "cylinder", "center": [0.1, 0.1, -0.05], "radius": 0.03, "half_length": 0.01,
                   "remanence": 1.2, "collider": false } ],
    "fields": [ { "type": "uniform", "H": [0, 0, 1000], "ramp": [0, 0.1] } ]
  })";
  ASSERT_EQ(errorOf(base), "");
  struct Case {
    std::string from, to;
    std::vector<std::string> expected;
  };
  const Case cases[] = {
      {"\"radius\": 0.03 }", "\"radis\": 0.03 }", {"test.json: bodies[0]", "'radis'", "did you mean 'radius'"}},
      {"\"moment\": 1e-19", "\"moment\": -1e-19", {"materials[0].magnetic.moment", "A*m^2", "> 0"}},
      {"\"law\": \"langevin\"", "\"law\": \"langevn\"", {"materials[0].magnetic.law", "langevin"}},
      {"\"bulk_modulus\": 1e5",
       "\"bulk_modulus\": 1e5, \"youngs_modulus\": 1",
       {"materials[0]", "unknown key 'youngs_modulus'"}},
      {"\"remanence\": 1.2", "\"remanence\": 4", {"magnets[0].remanence", "T", "[-3, 3]"}},
      {"\"remanence\": 1.2,", "", {"magnets[0]", "magnetization"}},
      {"\"ramp\": [0, 0.1]", "\"ramp\": [0]", {"fields[0].ramp"}},
      {"\"H\": [0, 0, 1000]", "\"H\": [0, 0]", {"fields[0].H"}},
  };
  for (const Case& c : cases) {
    std::string text = base;
    const auto at = text.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.from;
    text.replace(at, c.from.size(), c.to);
    const std::string e = errorOf(text);
    for (const std::string& s : c.expected) EXPECT_NE(e.find(s), std::string::npos) << "'" << s << "' not in: " << e;
  }
}

}  // namespace

namespace {

// A scene's domain, time, gravity and magnetic objects are an mpm_solver
// node's parameters: the scene reader and the node build the same settings
// (one builder, one set of defaults), here from a scene that gives only the
// required keys and from one that gives every key.
TEST(SceneNodes, SceneSettingsAreTheMpmSolverNodesSettings) {
  const std::string materials = R"("materials": [ { "name": "m", "model": "solid", "density": 1000,
                                                   "youngs_modulus": 1e5, "magnetic": { "law": "none" } } ])";
  const std::string settings[] = {
      R"("domain": { "min": [0, 0, 0], "max": [0.2, 0.1, 0.1], "dx": 0.02 }, "time": { "frames": 2 })",
      R"("domain": { "min": [0, 0, 0], "max": [0.2, 0.1, 0.1], "dx": 0.02, "boundary": "slip", "friction": 0.3 },
         "time": { "frames": 2, "fps": 30, "dt": 1e-4, "cfl": 0.3, "dt_max": 2e-4, "field_solve_every": 3 },
         "gravity": [0, -1, 0],
         "magnetic": { "boundary": "shield", "tolerance": 1e-5, "preconditioner": "jacobi",
                       "max_newton_iterations": 7, "padding": 2 })"};
  for (const std::string& s : settings) {
    SCOPED_TRACE(s);
    const nlohmann::json doc = nlohmann::json::parse("{" + s + "}");
    const Scene scene = parseScene("{\"name\": \"s\", " + s + ", " + materials + "}", "test.json");
    Network net;
    net.addNode("mpm_solver", "sim");
    setParamsFromJson(net, "sim", doc, "sim");
    const MpmSettings node = mpmSettingsFrom(net.params("sim"));
    const MpmSettings& read = scene.settings;
    EXPECT_EQ(read.grid.dims.i, node.grid.dims.i);
    EXPECT_EQ(read.grid.dims.j, node.grid.dims.j);
    EXPECT_EQ(read.grid.dx, node.grid.dx);
    EXPECT_EQ(read.walls.mode, node.walls.mode);
    EXPECT_EQ(read.walls.friction, node.walls.friction);
    EXPECT_EQ(read.fixedDt, node.fixedDt);
    EXPECT_EQ(read.cfl, node.cfl);
    EXPECT_EQ(read.dtMax, node.dtMax);
    EXPECT_EQ(read.magneticSolveInterval, node.magneticSolveInterval);
    EXPECT_EQ(read.gravity.y, node.gravity.y);
    EXPECT_EQ(read.gravity.z, node.gravity.z);
    EXPECT_EQ(read.magnetic.boundary, node.magnetic.boundary);
    EXPECT_EQ(read.magnetic.solve.tolerance, node.magnetic.solve.tolerance);
    EXPECT_EQ(read.magnetic.solve.preconditioner, node.magnetic.solve.preconditioner);
    EXPECT_EQ(read.magnetic.solve.maxNewtonIterations, node.magnetic.solve.maxNewtonIterations);
    ASSERT_EQ(read.magneticGrid.has_value(), node.magneticGrid.has_value());
    EXPECT_EQ(read.magneticGrid->dims.i, node.magneticGrid->dims.i);
    EXPECT_EQ(scene.frames, net.params("sim").getInt("time.frames"));
    EXPECT_EQ(scene.fps, net.params("sim").getFloat("time.fps"));
  }
}

namespace {

/// The jet of the emitter tests as a node network: a stream emitter (with
/// `motion`, a JSON member or "") into an mpm_solver with time line `time`.
std::shared_ptr<const SimulationData> cookJet(const std::string& motion, const std::string& time) {
  Network net;
  net.addNode("material", "goo");
  setParamsFromJson(net, "goo", nlohmann::json::parse(R"({"name": "goo", "model": "fluid", "density": 1000,
                    "viscosity": 0.5, "bulk_modulus": 2e4})"), "goo");
  net.addNode("particle_emitter", "jet");
  setParamsFromJson(net, "jet", nlohmann::json::parse(std::string(R"({"shape": "cylinder", "center": [0.05, 0.05, 0.12],
                    "axis": [0, 0, -1], "radius": 0.012, "half_length": 0.005, "rate": "stream", "speed": 0.6,
                    "end": 0.04, "cell_size": 0.01)") + (motion.empty() ? "" : ", " + motion) + "}"), "jet");
  net.addNode("mpm_solver", "sim");
  setParamsFromJson(net, "sim", nlohmann::json::parse(R"({"domain": {"min": [0, 0, 0], "max": [0.16, 0.1, 0.16],
                    "dx": 0.01}, "time": )" + time + "}"), "sim");
  net.connect("goo", "material", "jet", "material");
  net.connect("jet", "particles", "sim", "particles");
  return std::get<std::shared_ptr<const SimulationData>>(net.cook("sim").at("simulation"));
}

}  // namespace

// A particle_emitter node feeding an mpm_solver node emits in the solver as
// the scene's emitter does: the same particles after the same frames.
TEST(SceneNodes, AnEmitterNodeEmitsInTheSolverNodeAsTheSceneDoes) {
  const char* text = R"({
    "name": "jet",
    "domain": { "min": [0, 0, 0], "max": [0.16, 0.1, 0.16], "dx": 0.01 },
    "time": { "frames": 3, "fps": 50 },
    "materials": [ { "name": "goo", "model": "fluid", "density": 1000, "viscosity": 0.5, "bulk_modulus": 2e4 } ],
    "emitters": [ { "material": "goo", "shape": "cylinder", "center": [0.05, 0.05, 0.12], "axis": [0, 0, -1],
                    "radius": 0.012, "half_length": 0.005, "rate": "stream", "speed": 0.6, "end": 0.04,
                    "motion": { "velocity": [0.5, 0, 0] } } ]
  })";
  const Scene scene = parseScene(text, "jet.json");
  const auto solver = buildSolver(scene);
  for (int f = 0; f < scene.frames; ++f) solver->advanceFrame(scene.frameDuration());

  const auto sim = cookJet(R"("motion": {"velocity": [0.5, 0, 0]})", R"({"frames": 3, "fps": 50})");
  const MpmParticles &a = solver->particles(), &b = sim->solver->particles();
  ASSERT_GT(a.size(), 0u);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t q = 0; q < a.size(); ++q) ASSERT_EQ(a.x[q], b.x[q]) << q;
}

// time.start_frame in the mpm_solver node as in a scene: the solver starts at
// scene time (start_frame - 1) / fps, so an emitter that stops at t = 0.04 s
// emits only its last 0.02 s from frame 2 (t0 = 0.02 s at 50 fps).
TEST(SceneNodes, TheSolverNodeStartsAtTheStartFramesTime) {
  const std::string sceneText = R"({
    "name": "jet",
    "domain": { "min": [0, 0, 0], "max": [0.16, 0.1, 0.16], "dx": 0.01 },
    "time": { "start_frame": 2, "frames": 3, "fps": 50 },
    "materials": [ { "name": "goo", "model": "fluid", "density": 1000, "viscosity": 0.5, "bulk_modulus": 2e4 } ],
    "emitters": [ { "material": "goo", "shape": "cylinder", "center": [0.05, 0.05, 0.12], "axis": [0, 0, -1],
                    "radius": 0.012, "half_length": 0.005, "rate": "stream", "speed": 0.6, "end": 0.04 } ]
  })";
  const Scene scene = parseScene(sceneText, "jet.json");
  const auto solver = buildSolver(scene);
  EXPECT_DOUBLE_EQ(solver->time(), 0.02);
  for (int f = 0; f < scene.frames; ++f) solver->advanceFrame(scene.frameDuration());
  Scene fromZero = parseScene(sceneText, "jet.json");
  fromZero.startFrame = 1;
  const auto whole = buildSolver(fromZero);
  for (int f = 0; f < scene.frames; ++f) whole->advanceFrame(scene.frameDuration());

  const auto sim = cookJet("", R"({"start_frame": 2, "frames": 3, "fps": 50})");
  EXPECT_EQ(sim->startFrame, 2);
  ASSERT_EQ(sim->frameTimes.size(), 4u);
  EXPECT_DOUBLE_EQ(sim->frameTimes.front(), 0.02);
  EXPECT_NEAR(sim->frameTimes.back(), 0.08, 1e-12);
  const MpmParticles &a = solver->particles(), &b = sim->solver->particles();
  ASSERT_GT(a.size(), 0u);
  EXPECT_LT(a.size(), whole->particles().size());  // the emitter was on for 0.02 s of the run, not 0.04 s
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t q = 0; q < a.size(); ++q) ASSERT_EQ(a.x[q], b.x[q]) << q;
}

// A grid too large is refused by the one settings builder, before any int
// overflow, with the same message for a scene and a node.
TEST(SceneNodes, ATooLargeGridIsRefusedByTheSettingsBuilder) {
  Network net;
  net.addNode("mpm_solver", "sim");
  setParamsFromJson(net, "sim",
                    nlohmann::json::parse(R"({"domain": {"min": [0, 0, 0], "max": [1, 1, 1], "dx": 1e-300}})"), "sim");
  try {
    mpmSettingsFrom(net.params("sim"));
    FAIL() << "accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("domain: a grid of"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("GiB"), std::string::npos) << e.what();
  }
}

}  // namespace
