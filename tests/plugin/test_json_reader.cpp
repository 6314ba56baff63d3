// Strict JSON reading for scene files: parse errors located at
// file:line:column (computed from nlohmann's byte offset, counted by hand
// here), duplicate keys, and the JsonReader's messages (path, expectation,
// found value), ranges, defaults, unknown keys with suggestions.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "lodestone/plugin/json_reader.h"
#include "lodestone/core/base/error.h"

using namespace lodestone;
using namespace lodestone::plugin;
using nlohmann::json;

namespace {

// The message of the InvalidArgument thrown by f, or "" (a test failure) if none.
template <typename F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "unexpected exception type: " << e.what();
    return "";
  }
  ADD_FAILURE() << "no exception thrown";
  return "";
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

const char* kScene = R"({
  "dt": 1e-4,
  "frames": 1e2,
  "law": "langevin",
  "gravity": [0, 0, -9.81],
  "bodies": [
    {"name": "a", "material": {"density": 1200}},
    {"name": "b", "material": {"density": 1300, "youngs": 5e4}},
    {"name": "c", "material": {"densty": 1400}}
  ]
})";

}  // namespace

// ---- parse errors

TEST(JsonParse, SyntaxErrorNamesFileLineAndColumn) {
  // The extra '}' is byte 9 of line 1.
  EXPECT_EQ(errorOf([] { parseJsonText("{\"a\": 1}}", "s.json"); }),
            "s.json:1:9: syntax error while parsing value - unexpected '}'; expected end of input");
  // Missing comma: nlohmann stops after the string token "b" (line 2, columns 2-4).
  const std::string m = errorOf([] { parseJsonText("{\"a\": 1\n \"b\": 2}", "s.json"); });
  EXPECT_EQ(m.rfind("s.json:2:4: ", 0), 0u) << m;
  // Trailing comma in an array, third line.
  const std::string t = errorOf([] { parseJsonText("{\n\n  \"a\": [1, 2,]}", "scene.json"); });
  EXPECT_EQ(t.rfind("scene.json:3:14: ", 0), 0u) << t;
  EXPECT_TRUE(contains(t, "unexpected ']'")) << t;
}

TEST(JsonParse, ColumnsCountUtf8Characters) {
  // {"é": tru}  -- the '}' that ends the bad literal is the 10th character
  // (the 11th byte: é is two bytes).
  const std::string m = errorOf([] { parseJsonText("{\"\xc3\xa9\": tru}", "u.json"); });
  EXPECT_EQ(m.rfind("u.json:1:10: ", 0), 0u) << m;
  // A byte-order mark does not count.
  const std::string b = errorOf([] { parseJsonText("\xef\xbb\xbf{\"a\": 1}}", "b.json"); });
  EXPECT_EQ(b.rfind("b.json:1:9: ", 0), 0u) << b;
}

TEST(JsonParse, EmptyInputAndCommentsAreErrors) {
  EXPECT_EQ(errorOf([] { parseJsonText("", "e.json"); }).rfind("e.json:1:1: ", 0), 0u);
  const std::string c = errorOf([] { parseJsonText("{\"a\": 1, // note\n}", "c.json"); });
  EXPECT_EQ(c.rfind("c.json:1:10: ", 0), 0u) << c;
}

TEST(JsonParse, NumberOverflowIsLocated) {
  EXPECT_EQ(errorOf([] { parseJsonText("{\n \"a\": 1,\n \"b\": 1e999}", "o.json"); }),
            "o.json:3:7: number overflow parsing '1e999'");
}

TEST(JsonParse, DuplicateKeysNameTheirObject) {
  EXPECT_EQ(errorOf([] { parseJsonText(R"({"b": [{"m": 1}, {"m": 1, "m": 2}]})", "d.json"); }),
            "d.json: b[1]: duplicate key 'm'");
  EXPECT_EQ(errorOf([] { parseJsonText(R"({"b": [[{}, {"x": {"k": 1, "k": 2}}]]})", "d.json"); }),
            "d.json: b[0][1].x: duplicate key 'k'");
  EXPECT_EQ(errorOf([] { parseJsonText(R"({"k": 1, "k": 2})", "d.json"); }), "d.json: top level: duplicate key 'k'");
  // The same key in sibling objects is fine.
  EXPECT_NO_THROW(parseJsonText(R"({"a": {"k": 1}, "b": {"k": 2}, "c": [{"k": 1}, {"k": 2}]})", "d.json"));
}

TEST(JsonParse, FileErrorsNameThePath) {
  const std::string missing = (std::filesystem::temp_directory_path() / "lodestone_no_such_file.json").string();
  EXPECT_TRUE(contains(errorOf([&] { parseJsonFile(missing); }), missing));

  const auto path =
      std::filesystem::temp_directory_path() / ("lodestone_test_json_reader_" + std::to_string(::getpid()) + ".json");
  {
    std::ofstream out(path);
    out << "{\n  \"a\": [1,\n        2\n  \"b\": 3\n}\n";
  }
  const std::string m = errorOf([&] { parseJsonFile(path.string()); });
  EXPECT_EQ(m.rfind(path.string() + ":4:5: ", 0), 0u) << m;
  {
    std::ofstream out(path);
    out << kScene;
  }
  EXPECT_EQ(parseJsonFile(path.string())["bodies"].size(), 3u);
  std::filesystem::remove(path);
}

// ---- helpers

TEST(JsonReaderHelpers, EditDistanceAndSuggestions) {
  EXPECT_EQ(editDistance("kitten", "sitting"), 3);
  EXPECT_EQ(editDistance("density", "densty"), 1);
  EXPECT_EQ(editDistance("radius", "raidus"), 1);  // adjacent swap
  EXPECT_EQ(editDistance("", "abc"), 3);
  EXPECT_EQ(closestMatch("densty", {"youngs", "density", "poisson"}), "density");
  EXPECT_EQ(closestMatch("Density", {"density"}), "density");
  EXPECT_EQ(closestMatch("colour", {"density", "radius"}), "");
  EXPECT_EQ(closestMatch("x", {"y"}), "");  // single letters are not typos of each other
  EXPECT_EQ(closestMatch("dx", {"dt"}), "dt");
}

TEST(JsonReaderHelpers, RangeDescriptions) {
  EXPECT_EQ(Range::positive().describe(), "> 0");
  EXPECT_EQ(Range::atLeast(1).describe(), ">= 1");
  EXPECT_EQ(Range::below(2.5).describe(), "< 2.5");
  EXPECT_EQ(Range::closed(0, 0.1).describe(), "in [0, 0.1]");
  EXPECT_EQ((Range{0, 1, true, false}).describe(), "in (0, 1]");
  EXPECT_EQ(Range::any().describe(), "");
  EXPECT_FALSE(Range::positive().contains(0));
  EXPECT_TRUE(Range::nonNegative().contains(0));
  EXPECT_FALSE(Range::any().contains(std::nan("")));
}

// ---- JsonReader

TEST(JsonReader, ReadsValidScene) {
  const json doc = parseJsonText(kScene, "scene.json");
  JsonReader scene(doc, "", "scene.json");
  EXPECT_EQ(scene.number("dt", "s", Range::positive()), 1e-4);
  EXPECT_EQ(scene.integer("frames", 1, 100000), 100);  // 1e2 written as a float
  EXPECT_EQ(scene.string("law", {"linear", "langevin"}), "langevin");
  const Vec3d g = scene.vec3("gravity", "m/s^2");
  EXPECT_EQ(g.z, -9.81);
  EXPECT_EQ(scene.number("end_time", "s", Range::positive(), 2.5), 2.5);  // absent: default
  EXPECT_TRUE(scene.boolean("preview", true));
  std::vector<JsonReader> bodies = scene.array("bodies", 1);
  ASSERT_EQ(bodies.size(), 3u);
  EXPECT_EQ(bodies[1].path(), "bodies[1]");
  JsonReader material = bodies[1].object("material");
  EXPECT_EQ(material.path(), "bodies[1].material");
  EXPECT_EQ(material.number("density", "kg/m^3", Range::positive()), 1300);
  EXPECT_EQ(material.number("youngs", "Pa", Range::positive(), 1e5), 5e4);
  EXPECT_NO_THROW(material.finish());
  EXPECT_EQ(bodies[1].string("name"), "b");
  EXPECT_NO_THROW(bodies[1].finish());
}

TEST(JsonReader, UnknownKeyIsNamedWithSuggestion) {
  const json doc = parseJsonText(kScene, "scene.json");
  JsonReader scene(doc, "", "scene.json");
  std::vector<JsonReader> bodies = scene.array("bodies");
  JsonReader material = bodies[2].object("material");
  EXPECT_EQ(material.number("density", "kg/m^3", Range::positive(), 1000.0), 1000.0);  // absent
  EXPECT_EQ(errorOf([&] { material.finish(); }),
            "scene.json: bodies[2].material: unknown key 'densty'; did you mean 'density'?");
  // Without a close known key, the known keys are listed; extra unknown keys are counted.
  JsonReader root(doc, "", "scene.json");
  root.number("dt", "s", Range::positive());
  const std::string m = errorOf([&] { root.finish(); });
  EXPECT_EQ(m,
            "scene.json: top level: unknown key 'bodies' (known keys: 'dt') (and 3 more: 'frames', 'gravity' and "
            "'law')");
}

TEST(JsonReader, NumberErrorsSayWhereWhatAndFound) {
  const json doc = json::parse(R"({"m": {"density": -5, "radius": "big", "poisson": 0.5, "count": 2.5,
                                        "big": 3000000000, "flag": 1, "g": [0, "x", 1], "v": [1, 2]}})");
  JsonReader root(doc, "", "s.json");
  JsonReader m = root.object("m");
  EXPECT_EQ(errorOf([&] { m.number("density", "kg/m^3", Range::positive()); }),
            "s.json: m.density: expected a number in kg/m^3 > 0, found number -5");
  EXPECT_EQ(errorOf([&] { m.number("radius", "m", Range::positive()); }),
            "s.json: m.radius: expected a number in m > 0, found string \"big\"");
  EXPECT_EQ(errorOf([&] {
              m.number("poisson", "", Range{-1, 0.5, false, true});
            }),
            "s.json: m.poisson: expected a number in [-1, 0.5), found number 0.5");
  EXPECT_EQ(errorOf([&] { m.number("missing", "Pa", 0.0, 1e9); }),
            "s.json: m: missing required key 'missing' (a number in Pa in [0, 1e+09])");
  EXPECT_EQ(errorOf([&] { m.integer("count", 0, 10); }),
            "s.json: m.count: expected an integer in [0, 10], found the non-integer number 2.5");
  EXPECT_EQ(errorOf([&] { m.integer("big", 0, std::numeric_limits<int>::max()); }),
            "s.json: m.big: expected an integer in [0, 2147483647], found number 3000000000");
  EXPECT_EQ(m.integer64("big", 0, std::int64_t(1) << 40), 3000000000LL);
  EXPECT_EQ(errorOf([&] { m.boolean("flag"); }), "s.json: m.flag: expected true or false, found number 1");
  EXPECT_EQ(errorOf([&] { m.vec3("g", "m/s^2"); }), "s.json: m.g[1]: expected a number in m/s^2, found string \"x\"");
  EXPECT_EQ(errorOf([&] { m.vec3("v", "m/s"); }),
            "s.json: m.v: expected an array of 3 numbers [x, y, z] in m/s, found an array of 2 elements");
}

TEST(JsonReader, NonFiniteNumbersAreRejected) {
  // Parsing rejects 1e999 already; documents built in code can hold inf/NaN.
  json doc = json::object();
  doc["a"] = std::numeric_limits<double>::infinity();
  doc["b"] = json::array({0.0, std::nan(""), 0.0});
  doc["c"] = -std::numeric_limits<double>::infinity();
  JsonReader r(doc, "", "s.json");
  EXPECT_EQ(errorOf([&] { r.number("a", "m", Range::any()); }),
            "s.json: a: expected a number in m, found a non-finite number (inf)");
  EXPECT_EQ(errorOf([&] { r.vec3("b", "m"); }),
            "s.json: b[1]: expected a number in m, found a non-finite number (nan)");
  EXPECT_EQ(errorOf([&] { r.integer("c", 0, 5); }),
            "s.json: c: expected an integer in [0, 5], found a non-finite number (-inf)");
}

TEST(JsonReader, StringsAndDirections) {
  const json doc = json::parse(R"({"law": "lagevin", "n": 3, "axis": [0, 0, 2], "zero": [0, 0, 0]})");
  JsonReader r(doc, "", "s.json");
  EXPECT_EQ(errorOf([&] {
              r.string("law", {"linear", "langevin"});
            }),
            "s.json: law: expected one of 'linear' or 'langevin', found 'lagevin'; did you mean 'langevin'?");
  EXPECT_EQ(errorOf([&] { r.string("n"); }), "s.json: n: expected a string, found number 3");
  EXPECT_EQ(r.string("mode", {"a", "b", "c"}, "b"), "b");
  const Vec3d axis = r.direction("axis");
  EXPECT_EQ(axis.z, 1.0);
  EXPECT_EQ(errorOf([&] { r.direction("zero"); }),
            "s.json: zero: expected a non-zero direction vector [x, y, z], found [0, 0, 0]");
}

TEST(JsonReader, ArraysAndObjects) {
  const json doc = json::parse(R"({"bodies": [{"a": 1}, 3], "list": [1, 2, -3], "obj": [], "few": []})");
  JsonReader r(doc, "", "s.json");
  EXPECT_EQ(errorOf([&] { r.array("bodies"); }), "s.json: bodies[1]: expected an object, found number 3");
  EXPECT_EQ(errorOf([&] { r.numbers("list", "m", Range::nonNegative()); }),
            "s.json: list[2]: expected a number in m >= 0, found number -3");
  EXPECT_EQ(r.numbers("list", "m").size(), 3u);
  EXPECT_EQ(errorOf([&] { r.numbers("list", "", Range::any(), 4, 4); }),
            "s.json: list: expected an array of 4 numbers, found an array of 3 elements");
  EXPECT_EQ(errorOf([&] { r.object("obj"); }), "s.json: obj: expected an object, found an empty array");
  EXPECT_EQ(errorOf([&] { r.array("few", 1); }),
            "s.json: few: expected an array of at least 1 objects, found an empty array");
  EXPECT_EQ(errorOf([&] { r.array("none"); }), "s.json: top level: missing required key 'none' (an array of objects)");
  const json top = json::array({1, 2});
  EXPECT_EQ(errorOf([&] { JsonReader bad(top, "", "s.json"); }),
            "s.json: top level: expected an object, found an array of 2 elements");
}

TEST(JsonReader, HasRawIgnoreAndFail) {
  const json doc = json::parse(R"({"comment": "hi", "custom": {"k": 1}, "x": 1})");
  JsonReader r(doc, "", "s.json");
  EXPECT_TRUE(r.has("x"));
  EXPECT_FALSE(r.has("y"));
  r.ignore("comment");
  EXPECT_EQ(r.raw("custom")["k"], 1);
  // has() alone does not consume the key.
  EXPECT_EQ(errorOf([&] { r.finish(); }),
            "s.json: top level: unknown key 'x' (known keys: 'comment', 'custom' and 'y')");
  EXPECT_EQ(r.number("x", "", Range::any()), 1.0);
  EXPECT_NO_THROW(r.finish());
  EXPECT_EQ(errorOf([&] { r.failAt("x", "must be smaller than y"); }), "s.json: x: must be smaller than y");
}
