// Scene files: every example scene validates and builds; malformed scenes
// are rejected with the path of the bad entry and what was expected.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/scene.h"

using namespace lodestone;
using namespace lodestone::plugin;

namespace {

const char* kMinimal = R"({
  "name": "minimal",
  "domain": { "min": [0, 0, 0], "max": [0.2, 0.2, 0.2], "dx": 0.02 },
  "time": { "frames": 2, "fps": 100, "dt": 1e-4 },
  "materials": [ { "name": "jelly", "model": "solid", "density": 1000, "youngs_modulus": 1e4 } ],
  "bodies": [ { "material": "jelly", "shape": "box", "center": [0.1, 0.1, 0.1], "half_size": [0.03, 0.03, 0.03] } ]
})";

std::string errorOf(const std::string& text) {
  try {
    parseScene(text, "test.json");
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return s.replace(at, from.size(), to);
}

}  // namespace

TEST(Scene, EveryExampleSceneValidatesAndBuilds) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(LODESTONE_SCENES_DIR)) {
    if (entry.path().extension() != ".json") continue;
    ++count;
    SCOPED_TRACE(entry.path().string());
    const Scene scene = loadScene(entry.path().string());
    EXPECT_FALSE(scene.description.empty());
    EXPECT_GT(scene.fullDx, 0.0) << "every paper scene has a full-resolution variant";
    EXPECT_LT(scene.fullDx, scene.settings.grid.dx);
    const auto solver = buildSolver(scene);
    // The bodies' particles, and those the emitters add over the run.
    double particles = double(solver->particles().size());
    for (std::size_t e = 0; e < solver->emitterCount(); ++e)
      particles += solver->emitter(e).particlesBy(scene.frames * scene.frameDuration());
    EXPECT_GT(particles, 1000);
    bool magnetic = false;
    for (const auto& m : solver->materials()) magnetic = magnetic || m.isMagnetic();
    EXPECT_TRUE(magnetic);
  }
  EXPECT_GE(count, 8);
}

TEST(Scene, MinimalSceneReadsUnitsAndDefaults) {
  const Scene s = parseScene(kMinimal, "minimal.json");
  EXPECT_EQ(s.settings.grid.dims.i, 11);
  EXPECT_DOUBLE_EQ(s.settings.grid.dx, 0.02);
  EXPECT_DOUBLE_EQ(s.settings.fixedDt, 1e-4);
  EXPECT_EQ(s.frames, 2);
  EXPECT_DOUBLE_EQ(s.frameDuration(), 0.01);
  EXPECT_EQ(s.bodies.size(), 1u);
  EXPECT_EQ(s.bodies[0].emit.particlesPerCell, 8);
  EXPECT_DOUBLE_EQ(s.settings.gravity.z, -9.81);
  SceneOptions o;
  o.dx = 0.01;
  EXPECT_EQ(parseScene(kMinimal, "minimal.json", o).settings.grid.dims.i, 21);
  o = {};
  o.full = true;
  EXPECT_EQ(errorOf(kMinimal), "");
  try {
    parseScene(kMinimal, "minimal.json", o);
    FAIL() << "--full without full_dx was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("full_dx"), std::string::npos) << e.what();
  }
}

TEST(Scene, MalformedScenesNameThePathAndTheExpectation) {
  struct Case {
    std::string from, to, expected;
  };
  const Case cases[] = {
      {"\"density\": 1000", "\"densty\": 1000", "did you mean 'density'"},
      {"\"density\": 1000", "\"density\": -5", "materials[0].density"},
      {"\"dx\": 0.02", "\"dx\": \"fine\"", "domain.dx"},
      {"\"frames\": 2", "\"frames\": 2.5", "time.frames"},
      {"\"material\": \"jelly\"", "\"material\": \"jely\"", "bodies[0].material"},
      {"\"shape\": \"box\"", "\"shape\": \"cone\"", "bodies[0].shape"},
      {"\"max\": [0.2, 0.2, 0.2]", "\"max\": [0.2, -0.2, 0.2]", "max must exceed min"},
      {"\"dx\": 0.02", "\"dx\": 0.00001", "too large"},
      {"\"half_size\": [0.03, 0.03, 0.03]", "\"half_size\": [0.03, 0.03]", "bodies[0].half_size"},
      {"\"name\": \"minimal\",", "", "missing required key 'name'"},
      {"\"fps\": 100", "\"fps\": 100,", "test.json:"},  // syntax error: line and column
      {"\"bodies\"", "\"output\": { \"vdb\": [\"H\", \"X\"] }, \"bodies\"", "output.vdb"},
      {"\"bodies\"", "\"output\": { \"vdb_points\": 1 }, \"bodies\"", "output.vdb_points"},
  };
  for (const Case& c : cases) {
    const std::string err = errorOf(replaced(kMinimal, c.from, c.to));
    EXPECT_NE(err.find(c.expected), std::string::npos) << c.to << " -> " << err;
    EXPECT_NE(err.find("test.json"), std::string::npos) << err;
  }
}

TEST(Scene, VdbPointsOutputDefaultsToFalse) {
  EXPECT_FALSE(parseScene(kMinimal, "test.json").output.vdbPoints);
  const Scene on =
      parseScene(replaced(kMinimal, "\"bodies\"", "\"output\": { \"vdb_points\": true }, \"bodies\""), "test.json");
  EXPECT_TRUE(on.output.vdbPoints);
}

// output.surface: the surface node's parameters, checked by its declarations.
TEST(Scene, OutputSurfaceReadsTheSurfaceNodesParameters) {
  const Scene plain = parseScene(kMinimal, "test.json");
  EXPECT_EQ(plain.output.surface.method, "density");
  EXPECT_DOUBLE_EQ(plain.output.surface.kernelWidth, 1.5);
  const Scene splat = parseScene(
      replaced(kMinimal, "\"bodies\"",
               "\"output\": { \"surface\": { \"method\": \"splat\", \"voxel_size\": 0.004, \"radius_scale\": 1.2, "
               "\"closing\": 2 } }, \"bodies\""),
      "test.json");
  EXPECT_EQ(splat.output.surface.method, "splat");
  EXPECT_DOUBLE_EQ(splat.output.surface.voxelSize, 0.004);
  EXPECT_DOUBLE_EQ(splat.output.surface.radiusScale, 1.2);
  EXPECT_EQ(splat.output.surface.closing, 2);
  const std::string bad = errorOf(
      replaced(kMinimal, "\"bodies\"", "\"output\": { \"surface\": { \"kernel_width\": 9 } }, \"bodies\""));
  EXPECT_NE(bad.find("output.surface.kernel_width"), std::string::npos) << bad;
  const std::string unknown = errorOf(
      replaced(kMinimal, "\"bodies\"", "\"output\": { \"surface\": { \"metod\": \"splat\" } }, \"bodies\""));
  EXPECT_NE(unknown.find("did you mean 'method'"), std::string::npos) << unknown;
}

TEST(Scene, MissingFileIsNamed) {
  try {
    loadScene("/nonexistent/scene.json");
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scene.json"), std::string::npos) << e.what();
  }
}

// A scene's emitter pours at its stream rate while on: the particles are
// those emitted (counted in the frame reports), their volume is the rate
// times the on-time within one chunk, and none comes after it switches off.
TEST(Scene, EmitterPoursAtItsRateWhileOn) {
  // A one-layer box (4 x 4 points of 1e-6 m^3 at dx = 0.02 m) pouring
  // 2e-3 m^3/s from 0.01 s to 0.05 s: a chunk every 8 ms, carried off at
  // 1.25 m/s (one layer per chunk period), over a run of 0.1 s.
  std::string text = replaced(kMinimal, R"("bodies": [ { "material": "jelly", "shape": "box", "center": [0.1, 0.1, 0.1], "half_size": [0.03, 0.03, 0.03] } ])",
                              R"("emitters": [ { "name": "tap", "material": "jelly", "shape": "box",
      "center": [0.1, 0.1, 0.15], "axis": [0, 0, -1], "half_size": [0.02, 0.02, 0.005], "rate": "volume",
      "volume_rate": 2e-3, "speed": 1.25, "start": 0.01, "end": 0.05 } ])");
  text = replaced(text, R"("frames": 2)", R"("frames": 10)");
  const Scene scene = parseScene(text, "test.json");
  ASSERT_EQ(scene.emitters.size(), 1u);
  EXPECT_EQ(scene.emitters[0].name, "tap");
  const auto solver = buildSolver(scene);
  ASSERT_EQ(solver->emitterCount(), 1u);
  EXPECT_EQ(solver->particles().size(), 0u);
  const double chunk = solver->emitter(0).chunkVolume();
  ASSERT_NEAR(chunk, 1.6e-5, 1e-12);
  std::size_t emitted = 0, blocked = 0;
  for (int f = 0; f < scene.frames; ++f) {
    const MpmFrameReport r = solver->advanceFrame(scene.frameDuration());
    emitted += r.emitted.particles;
    blocked += r.emitted.blocked + r.emitted.outside;
    if (solver->time() <= 0.01 + 1e-12 || solver->time() - scene.frameDuration() >= 0.05) {
      EXPECT_EQ(r.emitted.particles, 0u) << "frame " << f;  // off
    }
  }
  EXPECT_EQ(blocked, 0u);
  EXPECT_EQ(solver->particles().size(), emitted);
  double volume = 0;
  for (double v : solver->particles().volume0) volume += v;
  // Q a = 8e-5 m^3 (5 chunks) within one chunk.
  EXPECT_GE(volume, 2e-3 * 0.04 - 1e-15);
  EXPECT_LT(volume, 2e-3 * 0.04 + chunk);
  EXPECT_EQ(double(solver->particles().size()), solver->emitter(0).particlesBy(0.1));
}

TEST(Scene, MagnetThatIsNotAColliderKeepsItsMotion) {
  // "collider": false dropped the magnet's keyframes: it became a static
  // field source ("0 magnets, 0 colliders").
  const std::string text = replaced(kMinimal, R"("bodies")", R"("magnets": [ { "shape": "sphere", "center": [0.1, 0.1, 0.02],
      "radius": 0.01, "remanence": 1.2, "collider": false,
      "motion": { "keyframes": [ { "time": 0, "center": [0.1, 0.1, 0.02] },
                                 { "time": 1, "center": [0.1, 0.1, 0.12] } ] } } ],
  "bodies")");
  const auto solver = buildSolver(parseScene(
      replaced(text, R"("youngs_modulus": 1e4 })", R"("youngs_modulus": 1e4, "magnetic": { "law": "linear", "chi": 0.5 } })"),
      "test.json"));
  ASSERT_EQ(solver->magnetCount(), 1u);
  EXPECT_EQ(solver->colliderCount(), 0u);
  EXPECT_EQ(solver->sources().size(), 0u);
  solver->advanceFrame(0.01);
  solver->advanceFrame(0.01);
  // Posed at the last solve, in the second frame (0.01 s <= t < 0.02 s): the
  // keyframes move it 0.1 m/s up.
  EXPECT_GE(solver->magnet(0).pose().position.z, 0.02 + 0.1 * 0.01 - 1e-9);
  EXPECT_LT(solver->magnet(0).pose().position.z, 0.02 + 0.1 * 0.02);
}

// time.start_frame: frame f ends at scene time f / fps; the initial state is
// frame start_frame - 1, where the solver starts.
TEST(SceneStartFrame, TheTimeLineStartsAtTheInitialFrame) {
  const Scene first = parseScene(kMinimal, "test.json");
  EXPECT_EQ(first.startFrame, 1);
  EXPECT_EQ(first.initialFrame(), 0);
  EXPECT_EQ(first.lastFrame(), 2);
  EXPECT_EQ(first.startTime(), 0.0);
  EXPECT_EQ(buildSolver(first)->time(), 0.0);

  const Scene later = parseScene(replaced(kMinimal, R"("frames": 2)", R"("start_frame": 1001, "frames": 2)"), "test.json");
  EXPECT_EQ(later.startFrame, 1001);
  EXPECT_EQ(later.initialFrame(), 1000);
  EXPECT_EQ(later.lastFrame(), 1002);
  EXPECT_DOUBLE_EQ(later.startTime(), 10.0);  // 1000 frames at 100 fps
  EXPECT_DOUBLE_EQ(later.frameTime(later.lastFrame()), 10.02);
  EXPECT_DOUBLE_EQ(buildSolver(later)->time(), 10.0);
}

// Nothing in the minimal scene depends on the time: the same frames from
// any start frame. The frame duration and substep are powers of two (1/64 s,
// 1/1024 s) so that the times add up exactly from either start.
TEST(SceneStartFrame, ATimeIndependentSceneGivesTheSameFramesFromAnyStart) {
  const std::string exact = replaced(kMinimal, R"("fps": 100, "dt": 1e-4)", R"("fps": 64, "dt": 0.0009765625)");
  const Scene a = parseScene(exact, "test.json");
  const Scene b = parseScene(replaced(exact, R"("frames": 2)", R"("start_frame": 1001, "frames": 2)"), "test.json");
  const auto sa = buildSolver(a), sb = buildSolver(b);
  ASSERT_GT(sa->particles().size(), 0u);
  const double z0 = sa->particles().x[0].z;
  for (int f = 0; f < 2; ++f) {
    sa->advanceFrame(a.frameDuration());
    sb->advanceFrame(b.frameDuration());
  }
  EXPECT_DOUBLE_EQ(sb->time(), b.frameTime(1002));
  ASSERT_EQ(sa->particles().size(), sb->particles().size());
  for (std::size_t p = 0; p < sa->particles().size(); ++p) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(sa->particles().x[p][c], sb->particles().x[p][c]) << "particle " << p;
      EXPECT_EQ(sa->particles().v[p][c], sb->particles().v[p][c]) << "particle " << p;
    }
  }
  EXPECT_LT(sa->particles().x[0].z, z0);  // it did move (gravity)
}

// Keyframe times are scene seconds: a magnet keyed to move from t = 1 s to
// t = 1.5 s rests at its first key for a run from frame 1, and a run from
// frame 151 (t0 = 1.5 s at 100 fps) starts with it at its last key.
TEST(SceneStartFrame, KeyframesAreInSceneSeconds) {
  const std::string text = replaced(replaced(kMinimal, R"("bodies")", R"("magnets": [ { "shape": "sphere", "center": [0.1, 0.1, 0.02],
      "radius": 0.01, "remanence": 1.2, "collider": false,
      "motion": { "keyframes": [ { "time": 1, "center": [0.1, 0.1, 0.02] },
                                 { "time": 1.5, "center": [0.1, 0.1, 0.12] } ] } } ],
  "bodies")"), R"("youngs_modulus": 1e4 })", R"("youngs_modulus": 1e4, "magnetic": { "law": "linear", "chi": 0.5 } })");
  const auto early = buildSolver(parseScene(text, "test.json"));
  early->advanceFrame(0.01);
  early->advanceFrame(0.01);
  EXPECT_EQ(early->magnet(0).pose().position.z, 0.02);
  const Scene lateScene = parseScene(replaced(text, R"("frames": 2)", R"("start_frame": 151, "frames": 2)"), "test.json");
  const auto late = buildSolver(lateScene);
  EXPECT_NEAR(late->magnet(0).pose().position.z, 0.12, 1e-12);
  // From frame 126 (t0 = 1.25 s): half way, and moving up over the frames.
  const auto middle =
      buildSolver(parseScene(replaced(text, R"("frames": 2)", R"("start_frame": 126, "frames": 2)"), "test.json"));
  EXPECT_NEAR(middle->magnet(0).pose().position.z, 0.07, 1e-9);
  middle->advanceFrame(0.01);
  middle->advanceFrame(0.01);
  EXPECT_GT(middle->magnet(0).pose().position.z, 0.07 + 0.2 * 0.01 - 1e-9);
}
