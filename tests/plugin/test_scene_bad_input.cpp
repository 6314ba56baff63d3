// Bad scene input, beyond test_scene.cpp's cases: every malformed or
// non-physical scene is refused with an InvalidArgument naming the file, the
// entry and what was expected (line:column for syntax errors, the nearest
// valid key for a misspelt one, GiB and node counts for a grid too large),
// never a crash, a silent default or an int overflow.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>

#include <string>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/errors.h"
#include "lodestone/plugin/node_builders.h"
#include "lodestone/plugin/scene.h"

using namespace lodestone;
using namespace lodestone::plugin;

namespace {

const char* kScene = R"({
  "name": "bad-input",
  "domain": { "min": [0, 0, 0], "max": [0.2, 0.2, 0.2], "dx": 0.02 },
  "time": { "frames": 2, "fps": 100 },
  "materials": [ { "name": "ferro", "model": "fluid", "density": 1000, "viscosity": 1, "bulk_modulus": 1e5,
                   "magnetic": { "law": "paper" } } ],
  "bodies": [ { "material": "ferro", "shape": "sphere", "center": [0.1, 0.1, 0.1], "radius": 0.03 } ],
  "fields": [ { "type": "uniform", "H": [0, 0, 1e4] } ]
})";

std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? s : s.replace(at, from.size(), to);
}

// The message of the InvalidArgument parseScene throws ("" when it does not).
std::string errorOf(const std::string& text) {
  try {
    parseScene(text, "bad.json");
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

struct Case {
  const char* what;
  std::string from, to;
  std::vector<std::string> expected;  // every one must appear in the message
};

}  // namespace

TEST(SceneBadInput, TheUnchangedSceneIsValid) { EXPECT_EQ(errorOf(kScene), ""); }

TEST(SceneBadInput, SurfaceTensionOnAFluidIsAccepted) {
  EXPECT_EQ(errorOf(replaced(kScene, "\"viscosity\": 1", "\"viscosity\": 1, \"surface_tension\": 0.03")), "");
}

TEST(SceneBadInput, EachIsRefusedWithWhereAndWhat) {
  const Case cases[] = {
      // Syntax: line and column.
      {"trailing comma", "\"fps\": 100 }", "\"fps\": 100, }", {"bad.json:4:"}},
      {"NaN literal", "\"density\": 1000", "\"density\": NaN", {"bad.json:5:"}},
      {"unterminated string", "\"name\": \"bad-input\"", "\"name\": \"bad-input", {"bad.json:"}},
      // Unknown keys: the nearest valid name.
      {"misspelt top-level key", "\"fields\"", "\"feilds\"", {"'feilds'", "did you mean 'fields'"}},
      {"misspelt nested key", "\"bulk_modulus\"", "\"bulk_modulos\"", {"materials[0]", "did you mean 'bulk_modulus'"}},
      // Wrong types.
      {"string for a number", "\"dx\": 0.02", "\"dx\": \"0.02\"", {"domain.dx"}},
      {"string in a vector", "\"max\": [0.2, 0.2, 0.2]", "\"max\": [0.2, \"a\", 0.2]", {"domain.max"}},
      {"object for an array", "\"fields\": [ { \"type\": \"uniform\", \"H\": [0, 0, 1e4] } ]",
       "\"fields\": { \"type\": \"uniform\" }", {"fields"}},
      {"number for a boolean", "\"fields\"", "\"output\": {\"png\": 1}, \"fields\"", {"output.png"}},
      // Missing required values.
      {"missing domain",
       "\"domain\": { \"min\": [0, 0, 0], \"max\": [0.2, 0.2, 0.2], \"dx\": 0.02 },",
       "",
       {"missing required key 'domain'"}},
      {"missing dx", ", \"dx\": 0.02 }", " }", {"domain", "'dx'"}},
      {"missing radius", ", \"radius\": 0.03", "", {"bodies[0]", "'radius'"}},
      // Non-physical values.
      {"negative dx", "\"dx\": 0.02", "\"dx\": -0.02", {"domain.dx", "-0.02"}},
      {"zero dx", "\"dx\": 0.02", "\"dx\": 0", {"domain.dx"}},
      {"zero density", "\"density\": 1000", "\"density\": 0", {"materials[0].density"}},
      {"overflowing number (inf)", "\"density\": 1000", "\"density\": 1e999", {"bad.json:5:", "number overflow"}},
      {"negative viscosity", "\"viscosity\": 1", "\"viscosity\": -1", {"materials[0].viscosity"}},
      {"negative surface tension", "\"viscosity\": 1", "\"viscosity\": 1, \"surface_tension\": -0.07",
       {"materials[0].surface_tension", "-0.07"}},
      {"surface tension too large", "\"viscosity\": 1", "\"viscosity\": 1, \"surface_tension\": 72",
       {"materials[0].surface_tension", "72"}},
      {"surface tension on a solid", "\"model\": \"fluid\", \"density\": 1000, \"viscosity\": 1, \"bulk_modulus\": 1e5",
       "\"model\": \"solid\", \"density\": 1000, \"youngs_modulus\": 1e5, \"surface_tension\": 0.07",
       {"materials[0]", "surface_tension"}},
      {"zero fps", "\"fps\": 100", "\"fps\": 0", {"time.fps"}},
      {"zero frames", "\"frames\": 2", "\"frames\": 0", {"time.frames"}},
      {"start frame 0", "\"frames\": 2", "\"start_frame\": 0, \"frames\": 2", {"time.start_frame", "0"}},
      {"start frame beyond the range", "\"frames\": 2", "\"start_frame\": 1000001, \"frames\": 2",
       {"time.start_frame", "1000001"}},
      {"fractional start frame", "\"frames\": 2", "\"start_frame\": 1.5, \"frames\": 2", {"time.start_frame", "1.5"}},
      {"negative radius", "\"radius\": 0.03", "\"radius\": -0.03", {"bodies[0].radius"}},
      {"empty domain", "\"max\": [0.2, 0.2, 0.2]", "\"max\": [0.2, 0.2, 0]", {"max must exceed min"}},
      {"infinite field", "\"H\": [0, 0, 1e4]", "\"H\": [0, 0, 1e400]", {"bad.json:8:", "number overflow"}},
      {"negative checkpoint interval",
       "\"fields\"",
       "\"output\": {\"checkpoint_every\": -1}, \"fields\"",
       {"output.checkpoint_every"}},
      // Grids too large: refused before any allocation, with GiB and node counts.
      {"grid too large", "\"dx\": 0.02", "\"dx\": 0.0002", {"domain", "1001 x 1001 x 1001 nodes", "GiB"}},
      {"grid beyond int", "\"dx\": 0.02", "\"dx\": 1e-300", {"domain", "nodes", "GiB", "too large"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    const std::string err = errorOf(replaced(kScene, c.from, c.to));
    ASSERT_FALSE(err.empty()) << "accepted: " << c.to;
    for (const std::string& e : c.expected) EXPECT_NE(err.find(e), std::string::npos) << err;
    EXPECT_NE(err.find("bad.json"), std::string::npos) << err;
  }
}

TEST(SceneBadInput, GridEstimateIsInGibibytesAndAcceptsTheLargestThatFits) {
  // Against a limit of 25 GiB (the machine's memory otherwise).
  ASSERT_EQ(setenv("LODESTONE_MEMORY_LIMIT_GIB", "25", 1), 0);
  // 257^3 MPM nodes (1.0 GiB), the field solve's 265^3 (6.2 GiB) and 1.9e6
  // points (1.2 GiB): accepted (nothing is allocated by parsing).
  EXPECT_EQ(errorOf(replaced(kScene, "\"dx\": 0.02", "\"dx\": 0.00078125")), "");
  // 401^3: the run as a whole (the field solve's 409^3 nodes, 22.7 GiB, and
  // the sphere's 0.95M material cells, 1.2 GiB) is refused, by part; the MPM
  // grid counts the pages of the runs the sphere's stencils reach, packed
  // (at most 124^3 nodes, 0.104 GiB with the bins and the rows'
  // bookkeeping), not the domain's 401^3 (3.84 GiB).
  const std::string err = errorOf(replaced(kScene, "\"dx\": 0.02", "\"dx\": 0.0005"));
  EXPECT_NE(err.find("bad.json needs about"), std::string::npos) << err;
  EXPECT_NE(err.find("MPM grid 0.104, field solve 24,"), std::string::npos) << err;
  EXPECT_NE(err.find("more than LODESTONE_MEMORY_LIMIT_GIB = 25 GiB"), std::string::npos) << err;
  // Without magnetism the same grid needs no field solve: accepted.
  const std::string plain = replaced(kScene, ",\n                   \"magnetic\": { \"law\": \"paper\" }", "");
  EXPECT_EQ(errorOf(replaced(plain, "\"dx\": 0.02", "\"dx\": 0.0005")), "");
  // A huge domain with a small body: 1601^3 nodes (4.1e9) would be 244 GiB
  // held whole; the 1 mm sphere's box is what the MPM grid holds: accepted.
  EXPECT_EQ(errorOf(replaced(replaced(plain, "\"dx\": 0.02", "\"dx\": 0.000125"), "\"radius\": 0.03",
                             "\"radius\": 0.001")),
            "");
  // A domain with more stencil bins than the MPM grid's 32-bit binning holds
  // is refused by the domain's guard, naming the node counts.
  const std::string huge = errorOf(replaced(plain, "\"dx\": 0.02", "\"dx\": 0.0001"));
  EXPECT_NE(huge.find("domain: a grid of 2001 x 2001 x 2001 nodes"), std::string::npos) << huge;
  EXPECT_NE(huge.find("stencil bins"), std::string::npos) << huge;
  // A body of too many points is refused too, before it is emitted: the grid
  // fits (201^3 nodes), its 1.1e8 points (70 GiB) do not.
  const std::string dense = errorOf(replaced(replaced(kScene, "\"dx\": 0.02", "\"dx\": 0.001"),
                                             "\"radius\": 0.03", "\"radius\": 0.03, \"particles_per_cell\": 1000"));
  EXPECT_NE(dense.find("particles is too large"), std::string::npos) << dense;
  ASSERT_EQ(unsetenv("LODESTONE_MEMORY_LIMIT_GIB"), 0);
}

// Without an override the limit is 80% of this machine's physical memory, or
// of the process's control group's limit where that is lower.
TEST(SceneBadInput, MemoryLimitIsAtMostThePhysicalMemory) {
  const double bytes = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
  EXPECT_LE(memoryLimitBytes(), kUsableMemoryFraction * bytes);
  EXPECT_GT(memoryLimitBytes(), 64.0 * 1024 * 1024);
  EXPECT_NE(memoryLimitText().find("GiB (80% of this"), std::string::npos) << memoryLimitText();
  ASSERT_EQ(setenv("LODESTONE_MEMORY_LIMIT_GIB", "0.5", 1), 0);
  EXPECT_EQ(memoryLimitBytes(), 0.5 * 1024 * 1024 * 1024);
  EXPECT_EQ(memoryLimitText(), "LODESTONE_MEMORY_LIMIT_GIB = 0.5 GiB");
  ASSERT_EQ(setenv("LODESTONE_MEMORY_LIMIT_GIB", "lots", 1), 0);
  EXPECT_THROW(memoryLimitBytes(), InvalidArgument);
  ASSERT_EQ(unsetenv("LODESTONE_MEMORY_LIMIT_GIB"), 0);
}

// The estimate by part: each count times its documented figure.
TEST(SceneBadInput, MemoryEstimateAddsItsParts) {
  MemoryCounts c;
  c.mpmNodes = 1e6;
  c.fieldNodes = 2e6;
  c.fieldMaterialCells = 4e4;
  c.particles = 3e5;
  c.magneticParticles = 1e5;
  c.capillaryParticles = 0;
  c.previewPixels = 640 * 480;
  const MemoryEstimate e = estimateMemory(c, 5e7);
  EXPECT_DOUBLE_EQ(e.mpmGrid, 1e6 * kMpmNodeBytes);
  EXPECT_DOUBLE_EQ(e.fieldGrid, 2e6 * kFieldNodeBytes + 4e4 * kFieldMaterialCellBytes);
  EXPECT_DOUBLE_EQ(e.particles, 3e5 * kParticleBytes + 1e5 * kMagneticParticleBytes);
  EXPECT_DOUBLE_EQ(e.outputs, 640 * 480 * kPreviewPixelBytes);
  EXPECT_DOUBLE_EQ(e.total(), e.mpmGrid + e.fieldGrid + e.particles + e.outputs + 5e7);
  // Surface tension adds the colour field per node and the stress per particle.
  c.capillaryParticles = 1e5;
  const MemoryEstimate s = estimateMemory(c);
  EXPECT_DOUBLE_EQ(s.mpmGrid, 1e6 * (kMpmNodeBytes + kSurfaceTensionNodeBytes));
  EXPECT_DOUBLE_EQ(s.particles - e.particles, 1e5 * kSurfaceTensionParticleBytes);
  EXPECT_NE(e.describe().find("field solve 0.712"), std::string::npos) << e.describe();
  // A scene over the limit is refused naming its parts and the limit.
  ASSERT_EQ(setenv("LODESTONE_MEMORY_LIMIT_GIB", "0.5", 1), 0);
  try {
    requireFitsInMemory("scene 'big'", e);
    ADD_FAILURE() << "accepted";
  } catch (const TooLarge& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find("scene 'big' needs about 0.946 GiB: MPM grid 0.0596, field solve 0.712"), std::string::npos)
        << what;
    EXPECT_NE(what.find("more than LODESTONE_MEMORY_LIMIT_GIB = 0.5 GiB"), std::string::npos) << what;
  }
  ASSERT_EQ(unsetenv("LODESTONE_MEMORY_LIMIT_GIB"), 0);
}

TEST(SceneBadInput, AGridTooCoarseForTheWallsIsSaidInTheDomainsTerms) {
  // 0.2 m at dx = 0.05 m: 5 nodes, the two 2-node walls need 6.
  const std::string err = errorOf(replaced(kScene, "\"dx\": 0.02", "\"dx\": 0.05"));
  EXPECT_NE(err.find("bad.json: domain: dx = 0.05 m gives 5 nodes"), std::string::npos) << err;
  EXPECT_NE(err.find("use a dx below 0.05 m"), std::string::npos) << err;
  EXPECT_EQ(err.find("wallNodes"), std::string::npos) << err;
  EXPECT_EQ(err.find("MPM settings"), std::string::npos) << err;
  EXPECT_EQ(errorOf(replaced(kScene, "\"dx\": 0.02", "\"dx\": 0.0499")), "");
}

TEST(SceneBadInput, ABodyWhollyOutsideTheDomainIsRefusedByName) {
  const std::string text = replaced(replaced(kScene, "\"center\": [0.1, 0.1, 0.1]", "\"center\": [0.5, 0.5, 0.5]"),
                                    "\"material\": \"ferro\",", "\"material\": \"ferro\", \"name\": \"drop\",");
  const Scene scene = parseScene(text, "bad.json");
  try {
    buildSolver(scene);
    FAIL() << "a body outside the domain was accepted";
  } catch (const InvalidArgument& e) {
    const std::string err = e.what();
    EXPECT_NE(err.find("bad.json: body 'drop' lies wholly outside the domain"), std::string::npos) << err;
  }
  // Partly inside: accepted (the rest is clamped at the first substep).
  const Scene partly = parseScene(replaced(kScene, "\"center\": [0.1, 0.1, 0.1]", "\"center\": [0.18, 0.1, 0.1]"),
                                  "bad.json");
  EXPECT_GT(buildSolver(partly)->particles().size(), 0u);
}

// Emitters: bad rates, time lines and keys are named with the entry; an
// emitter that would add more particles over the run than memory holds is
// refused before anything runs; one outside the domain when it switches on
// is refused by name.
TEST(SceneBadInput, EmittersAreReadStrictly) {
  const std::string scene = replaced(kScene, "\"fields\"", R"("emitters": [ { "name": "tap", "material": "ferro",
      "shape": "cylinder", "center": [0.1, 0.1, 0.15], "axis": [0, 0, -1], "radius": 0.02, "half_length": 0.01,
      "rate": "volume", "volume_rate": 1e-5, "speed": 0.5, "start": 0.1, "end": 0.5 } ],
  "fields")");
  ASSERT_EQ(errorOf(scene), "");
  const Case cases[] = {
      {"negative rate", "\"volume_rate\": 1e-5", "\"volume_rate\": -1e-5", {"emitters[0].volume_rate", "m^3/s", "-1e-05"}},
      {"end before start", "\"end\": 0.5", "\"end\": 0.05", {"emitters[0]", "ends at 0.05 s, not after its start 0.1 s"}},
      {"unknown key", "\"volume_rate\"", "\"volume_rat\"", {"emitters[0]", "'volume_rat'", "did you mean 'volume_rate'"}},
      {"unknown rate", "\"rate\": \"volume\"", "\"rate\": \"litres\"", {"emitters[0].rate", "litres"}},
      {"stream without a speed", "\"rate\": \"volume\", \"volume_rate\": 1e-5, \"speed\": 0.5", "\"rate\": \"stream\"",
       {"emitters[0]", "a stream rate needs `speed`"}},
      {"a rate of particles for a volume", "\"volume_rate\": 1e-5", "\"particle_rate\": 100",
       {"emitters[0]", "missing required key 'volume_rate'"}},
      {"odd intervals", "\"start\": 0.1, \"end\": 0.5", "\"intervals\": [0.1, 0.2, 0.3]", {"emitters[0]", "even count"}},
      {"intervals not increasing", "\"start\": 0.1, \"end\": 0.5", "\"intervals\": [0.1, 0.3, 0.2, 0.4]",
       {"emitters[0]", "interval 1 starts at 0.2 s"}},
      {"unknown material", "\"material\": \"ferro\",\n      \"shape\"", "\"material\": \"iron\",\n      \"shape\"",
       {"emitters[0].material", "iron"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    const std::string err = errorOf(replaced(scene, c.from, c.to));
    ASSERT_FALSE(err.empty()) << "accepted: " << c.to;
    for (const std::string& e : c.expected) EXPECT_NE(err.find(e), std::string::npos) << err;
  }
  // 100 m^3/s for the 0.4 s it is on in a run of 1 s: 3.2e8 particles at dx
  // = 0.01 m (120 GiB); refused by the memory estimate. Within a run of
  // 0.02 s it never switches on: accepted.
  ASSERT_EQ(setenv("LODESTONE_MEMORY_LIMIT_GIB", "25", 1), 0);
  const std::string flooding =
      replaced(replaced(scene, "\"volume_rate\": 1e-5", "\"volume_rate\": 100"), "\"dx\": 0.02", "\"dx\": 0.01");
  const std::string flood = errorOf(replaced(flooding, "\"frames\": 2", "\"frames\": 100"));
  EXPECT_NE(flood.find(" and 3200"), std::string::npos) << flood;  // 3.2e8 and the body
  EXPECT_NE(flood.find("particles is too large"), std::string::npos) << flood;
  EXPECT_EQ(errorOf(flooding), "");
  ASSERT_EQ(unsetenv("LODESTONE_MEMORY_LIMIT_GIB"), 0);
  // Outside the domain when it switches on.
  try {
    buildSolver(parseScene(replaced(scene, "\"center\": [0.1, 0.1, 0.15]", "\"center\": [0.1, 0.1, 0.5]"), "bad.json"));
    FAIL() << "an emitter outside the domain was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("bad.json: emitter 'tap' is centred at (0.1, 0.1, 0.5) m at t = 0.1 s"),
              std::string::npos)
        << e.what();
  }
}

TEST(SceneBadInput, ADirectoryOrADeviceAsTheSceneFileIsRefusedWithWhy) {
  const auto messageOf = [](const std::string& path) {
    try {
      loadScene(path);
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string dir = messageOf(::testing::TempDir());
  EXPECT_NE(dir.find("is a directory, not a JSON file"), std::string::npos) << dir;
  // An endless device stops at the size limit instead of filling memory.
  const std::string zero = messageOf("/dev/zero");
  EXPECT_NE(zero.find("'/dev/zero' is larger than 64 MiB"), std::string::npos) << zero;
}

TEST(SceneBadInput, TheContentHashFollowsTheSceneText) {
  const Scene a = parseScene(kScene, "bad.json"), b = parseScene(kScene, "other.json");
  const Scene c = parseScene(replaced(kScene, "\"density\": 1000", "\"density\": 1001"), "bad.json");
  EXPECT_NE(a.contentHash, 0u);
  EXPECT_EQ(a.contentHash, b.contentHash);
  EXPECT_NE(a.contentHash, c.contentHash);
}

TEST(SceneBadInput, DynamicBodiesAreReadAndTheirBadValuesNamed) {
  // A dynamic box and a free magnet are read into dynamic colliders with the
  // given mass properties and contact parameters.
  const std::string ok = replaced(kScene, "\"fields\"", R"("colliders": [ { "shape": "box", "center": [0.1, 0.1, 0.16],
    "half_size": [0.02, 0.02, 0.01], "dynamic": true, "density": 500, "restitution": 0.5, "contact_friction": 0.3 } ],
  "magnets": [ { "shape": "sphere", "center": [0.1, 0.1, 0.04], "radius": 0.01, "remanence": 1.0,
    "dynamic": true, "mass": 0.05 } ],
  "fields")");
  ASSERT_EQ(errorOf(ok), "");
  const plugin::Scene scene = parseScene(ok, "ok.json");
  ASSERT_EQ(scene.colliders.size(), 1u);
  ASSERT_TRUE(scene.colliders[0].isDynamic());
  EXPECT_NEAR(scene.colliders[0].body().mass.mass, 500 * 0.04 * 0.04 * 0.02, 1e-12);
  EXPECT_EQ(scene.colliders[0].body().settings.restitution, 0.5);
  EXPECT_EQ(scene.colliders[0].body().settings.friction, 0.3);
  ASSERT_EQ(scene.magnets.size(), 1u);
  ASSERT_TRUE(scene.magnets[0].dynamics.has_value());
  EXPECT_EQ(scene.magnets[0].dynamics->mass, 0.05);
  auto solver = buildSolver(scene);
  ASSERT_EQ(solver->colliderCount(), 2u);  // the magnet's collider first
  EXPECT_NEAR(solver->collider(0).body().mass.mass, 0.05, 1e-15);
  EXPECT_TRUE(solver->collider(1).isDynamic());

  const Case cases[] = {
      {"dynamic plane", "\"fields\"", R"("colliders": [ { "shape": "plane", "point": [0, 0, 0.05], "normal": [0, 0, 1], "dynamic": true } ], "fields")",
       {"colliders[0].dynamic", "plane", "infinite mass"}},
      {"dynamic container", "\"fields\"",
       R"("colliders": [ { "shape": "box", "center": [0.1, 0.1, 0.1], "half_size": [0.1, 0.1, 0.1], "inverted": true,
                           "dynamic": true } ], "fields")",
       {"colliders[0].dynamic", "inverted"}},
      {"restitution above 1", "\"fields\"",
       R"("colliders": [ { "shape": "sphere", "center": [0.1, 0.1, 0.1], "radius": 0.01, "dynamic": true,
                           "restitution": 1.5 } ], "fields")",
       {"colliders[0].restitution", "1.5"}},
      {"free magnet that is not a collider", "\"fields\"",
       R"("magnets": [ { "shape": "sphere", "center": [0.1, 0.1, 0.02], "radius": 0.01, "remanence": 1,
                         "dynamic": true, "collider": false } ], "fields")",
       {"magnets[0].dynamic", "collider"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    const std::string message = errorOf(replaced(kScene, c.from, c.to));
    for (const std::string& e : c.expected) EXPECT_NE(message.find(e), std::string::npos) << e << " in: " << message;
  }
}
