// Wedges without Slurm: JSON paths into a scene, --vary values, the
// cartesian product and its names, the manifest (JSON and CSV), the local
// process pool and the Slurm batch script's text.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "farm_jobs.h"
#include "lodestone/core/base/error.h"
#include "wedge.h"

#include "lodestone_test/scratch_dir.h"

namespace fs = std::filesystem;
using namespace lodestone;
using namespace lodestone::examples;
using nlohmann::json;

namespace {

json scene() {
  return json::parse(R"({
    "name": "s",
    "time": { "frames": 4, "fps": 200 },
    "materials": [ { "name": "ferro", "viscosity": 5 }, { "name": "water", "viscosity": 1 } ],
    "magnets": [ { "magnetization": 1e6, "center": [0, 0, 1] } ]
  })");
}

// The message of the InvalidArgument `f` throws ("" when it throws none).
template <class F>
std::string errorOf(F f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

TEST(WedgePath, ParsesKeysPositionsAndNames) {
  const std::vector<JsonPathStep> p = parseJsonPath("magnets[0].center[2]");
  ASSERT_EQ(p.size(), 4u);
  EXPECT_EQ(p[0].key, "magnets");
  EXPECT_EQ(p[1].index, 0);
  EXPECT_EQ(p[2].key, "center");
  EXPECT_EQ(p[3].index, 2);
  EXPECT_EQ(parseJsonPath("materials.ferro.mu").size(), 3u);
}

TEST(WedgePath, RefusesMalformedPaths) {
  EXPECT_NE(errorOf([] { parseJsonPath("magnets[x]"); }).find("'[x]' is not an array position"), std::string::npos);
  EXPECT_NE(errorOf([] { parseJsonPath("a..b"); }).find("key 'a..b': empty key"), std::string::npos);
  EXPECT_NE(errorOf([] { parseJsonPath("a."); }).find("ends with '.'"), std::string::npos);
  EXPECT_NE(errorOf([] { parseJsonPath("magnets[0"); }).find("unclosed"), std::string::npos);
  EXPECT_NE(errorOf([] { parseJsonPath(""); }).find("empty"), std::string::npos);
}

TEST(WedgePath, SetsByPositionAndByName) {
  json s = scene();
  setJsonPath(s, "magnets[0].magnetization", 2e5);
  setJsonPath(s, "materials.water.viscosity", 3);
  setJsonPath(s, "magnets[0].center[2]", 0.5);
  setJsonPath(s, "time.dt", 1e-4);  // a new last key: the scene validator judges it
  EXPECT_EQ(s["magnets"][0]["magnetization"], 2e5);
  EXPECT_EQ(s["materials"][1]["viscosity"], 3);
  EXPECT_EQ(s["materials"][0]["viscosity"], 5);
  EXPECT_EQ(s["magnets"][0]["center"][2], 0.5);
  EXPECT_EQ(s["time"]["dt"], 1e-4);
}

TEST(WedgePath, NamesTheStepThatDoesNotExist) {
  json s = scene();
  EXPECT_EQ(errorOf([&] { setJsonPath(s, "magnets[3].magnetization", 1); }),
            "key 'magnets[3].magnetization': 'magnets' has 1 elements, so [3] does not exist");
  EXPECT_EQ(errorOf([&] { setJsonPath(s, "materials.oil.viscosity", 1); }),
            "key 'materials.oil.viscosity': 'materials' has no element named 'oil' (names: ferro, water)");
  EXPECT_EQ(errorOf([&] { setJsonPath(s, "domain.dx", 1); }), "key 'domain.dx': the scene has no key 'domain'");
  EXPECT_EQ(errorOf([&] { setJsonPath(s, "time.fps.x", 1); }),
            "key 'time.fps.x': 'time.fps' is a value, not an object, so 'x' does not exist");
  EXPECT_EQ(errorOf([&] { setJsonPath(s, "time[0]", 1); }),
            "key 'time[0]': 'time' is not an array, so [0] does not exist");
  EXPECT_EQ(s, scene());  // nothing changed
}

TEST(WedgeVary, SplitsValuesOutsideBrackets) {
  const WedgeAxis a = parseVary("magnets[0].center=[0,0,1],[0,0,2]");
  EXPECT_EQ(a.key, "magnets[0].center");
  ASSERT_EQ(a.values.size(), 2u);
  EXPECT_EQ(a.values[1], json::parse("[0,0,2]"));
  const WedgeAxis b = parseVary("materials.ferro.model=fluid,solid,1e5,true");
  ASSERT_EQ(b.values.size(), 4u);
  EXPECT_EQ(b.values[0], "fluid");  // not JSON: a string
  EXPECT_EQ(b.values[2], 1e5);
  EXPECT_EQ(b.values[3], true);
  EXPECT_EQ(b.texts[2], "1e5");
}

TEST(WedgeVary, RefusesMissingPartsNamingTheArgument) {
  EXPECT_EQ(errorOf([] { parseVary("magnetization"); }), "--vary 'magnetization': expected KEY=V1,V2,...");
  EXPECT_EQ(errorOf([] { parseVary("=1,2"); }), "--vary '=1,2': no key before '='");
  EXPECT_NE(errorOf([] { parseVary("a.b=1,,2"); }).find("--vary 'a.b=1,,2': an empty value"), std::string::npos);
  EXPECT_NE(errorOf([] { parseVary("a.b="); }).find("an empty value"), std::string::npos);
  EXPECT_NE(errorOf([] { parseVary("a[=1"); }).find("key 'a['"), std::string::npos);
}

TEST(WedgeExpand, CartesianProductFirstAxisSlowest) {
  const std::vector<WedgeAxis> axes = {parseVary("magnets[0].magnetization=1e5,2e5,4e5"),
                                       parseVary("materials.ferro.viscosity=1,5")};
  const std::vector<Wedge> w = expandWedges(scene(), axes);
  ASSERT_EQ(w.size(), 6u);
  const double m[6] = {1e5, 1e5, 2e5, 2e5, 4e5, 4e5};
  const int mu[6] = {1, 5, 1, 5, 1, 5};
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(w[std::size_t(i)].index, i);
    EXPECT_EQ(w[std::size_t(i)].scene["magnets"][0]["magnetization"], m[i]) << i;
    EXPECT_EQ(w[std::size_t(i)].scene["materials"][0]["viscosity"], mu[i]) << i;
    EXPECT_EQ(w[std::size_t(i)].scene["materials"][1]["viscosity"], 1) << i;  // the other material untouched
  }
  EXPECT_EQ(w[0].name, "w00_magnetization-1e5_viscosity-1");
  EXPECT_EQ(w[5].name, "w05_magnetization-4e5_viscosity-5");
  EXPECT_EQ(wedgeSceneFile(w[3]), "w03_magnetization-2e5_viscosity-5/scene.json");
  EXPECT_EQ(wedgeOutDir(w[3]), "w03_magnetization-2e5_viscosity-5/out");
}

TEST(WedgeExpand, NamesAreFileSafeAndDistinguishSharedKeys) {
  const std::vector<WedgeAxis> axes = {parseVary("materials.ferro.viscosity=1"),
                                       parseVary("materials.water.viscosity=2"),
                                       parseVary("magnets[0].center=[0,0,1]")};
  const std::vector<Wedge> w = expandWedges(scene(), axes);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].name, "w00_materials.ferro.viscosity-1_materials.water.viscosity-2_center-_0_0_1_");
  EXPECT_EQ(fileSafe("a/b c*1e+5"), "a_b_c_1e+5");
}

TEST(WedgeExpand, RefusesBadAxes) {
  EXPECT_NE(errorOf([] { expandWedges(scene(), {}); }).find("no --vary"), std::string::npos);
  EXPECT_EQ(errorOf([] {
              expandWedges(scene(), {parseVary("materials.ferro.viscosity=1"), parseVary("materials.ferro.viscosity=2")});
            }),
            "key 'materials.ferro.viscosity' is varied twice");
  EXPECT_EQ(errorOf([] { expandWedges(scene(), {parseVary("magnets[1].magnetization=1,2")}); }),
            "key 'magnets[1].magnetization': 'magnets' has 1 elements, so [1] does not exist");
  EXPECT_NE(errorOf([] {
              expandWedges(scene(), {parseVary("time.fps=1,2,3,4"), parseVary("time.frames=1,2,3")}, 10);
            }).find("more than 10 wedges"),
            std::string::npos);
}

TEST(WedgeManifest, ListsEachWedgeInJsonAndCsv) {
  const std::vector<WedgeAxis> axes = {parseVary("magnets[0].magnetization=1e5,2e5"),
                                       parseVary("materials.ferro.model=fluid,solid")};
  const std::vector<Wedge> w = expandWedges(scene(), axes);
  const json m = wedgeManifest("/scenes/s.json", axes, w);
  EXPECT_EQ(m["source_scene"], "/scenes/s.json");
  ASSERT_EQ(m["wedges"].size(), 4u);
  EXPECT_EQ(m["wedges"][2]["name"], "w02_magnetization-2e5_model-fluid");
  EXPECT_EQ(m["wedges"][2]["out"], "w02_magnetization-2e5_model-fluid/out");
  EXPECT_EQ(m["wedges"][2]["values"]["magnets[0].magnetization"], 2e5);
  EXPECT_EQ(m["wedges"][2]["values"]["materials.ferro.model"], "fluid");
  EXPECT_EQ(m["axes"][1]["values"], json::parse(R"(["fluid", "solid"])"));
  const std::string csv = wedgeManifestCsv(m);
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "index,name,scene,out,magnets[0].magnetization,materials.ferro.model");
  EXPECT_NE(csv.find("\n3,w03_magnetization-2e5_model-solid,w03_magnetization-2e5_model-solid/scene.json,"
                     "w03_magnetization-2e5_model-solid/out,200000.0,solid\n"),
            std::string::npos)
      << csv;
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 5);
}

fs::path scratch(const std::string& name) { return lodestone::test::scratchDir("farm", name); }

std::string readFile(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

TEST(FarmPool, RunsEveryJobAndReportsEachStatus) {
  const fs::path dir = scratch("pool");
  std::vector<FarmJob> jobs;
  for (int i = 0; i < 5; ++i)
    jobs.push_back({{"/bin/sh", "-c", "echo job " + std::to_string(i) + "; exit " + std::to_string(i % 3)},
                    (dir / ("log" + std::to_string(i))).string()});
  jobs.push_back({{"/bin/sh", "-c", "kill -9 $$"}, ""});
  jobs.push_back({{(dir / "no_such_program").string()}, ""});
  std::vector<std::size_t> order;
  const std::vector<int> status = runPool(jobs, 3, [&](std::size_t i, int) { order.push_back(i); });
  EXPECT_EQ(status, (std::vector<int>{0, 1, 2, 0, 1, 128 + 9, 127}));
  EXPECT_EQ(order.size(), jobs.size());
  for (int i = 0; i < 5; ++i) EXPECT_EQ(readFile(dir / ("log" + std::to_string(i))), "job " + std::to_string(i) + "\n");
}

TEST(FarmPool, RunsAtMostNAtATime) {
  // Each job adds a line to a shared file when it starts and when it ends;
  // the number running never exceeds the limit, and with 2 jobs of 0.3 s at
  // a time 4 jobs take at least 0.6 s.
  const fs::path dir = scratch("pool_limit");
  const std::string events = (dir / "events").string();
  std::vector<FarmJob> jobs;
  for (int i = 0; i < 4; ++i)
    jobs.push_back({{"/bin/sh", "-c", "echo + >> " + events + "; sleep 0.3; echo - >> " + events}, ""});
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<int> status = runPool(jobs, 2);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(status, std::vector<int>(4, 0));
  int running = 0, most = 0;
  for (const char c : readFile(events)) {
    if (c == '+') most = std::max(most, ++running);
    if (c == '-') --running;
  }
  EXPECT_EQ(running, 0);
  EXPECT_EQ(most, 2);
  EXPECT_GE(seconds, 0.6);
  EXPECT_NE(errorOf([] { runPool({}, 0); }).find("at least one"), std::string::npos);
}

TEST(FarmPool, CapturesOutput) {
  std::string out;
  EXPECT_EQ(runCapture({"/bin/sh", "-c", "printf '42;cluster\\n'; exit 3"}, &out), 3);
  EXPECT_EQ(out, "42;cluster\n");
}

TEST(FarmSlurmScript, OneTaskPerLineRequeuedAndAppending) {
  ArrayJob job{"wedge", "/farm/logs", {"exec run a", "exec run 'b c'", "exec run d"}, "gpu", {"--account=fx"}};
  const std::string s = arrayScript(job);
  EXPECT_EQ(s.rfind("#!/bin/bash\n", 0), 0u);
  for (const char* line : {"#SBATCH --array=0-2\n", "#SBATCH --requeue\n", "#SBATCH --open-mode=append\n",
                           "#SBATCH --output=/farm/logs/wedge_%a.log\n", "#SBATCH --partition=gpu\n",
                           "#SBATCH --account=fx\n",
                           "  0) exec run a ;;\n", "  1) exec run 'b c' ;;\n", "  2) exec run d ;;\n"})
    EXPECT_NE(s.find(line), std::string::npos) << line << " not in\n" << s;
  job.sbatchArgs = {"fx"};
  EXPECT_NE(errorOf([&] { arrayScript(job); }).find("--sbatch-args 'fx': give each sbatch option as one argument"),
            std::string::npos);
  job.sbatchArgs.clear();
  job.partition.clear();
  EXPECT_EQ(arrayScript(job).find("--partition"), std::string::npos);
  job.taskCommands.clear();
  EXPECT_NE(errorOf([&] { arrayScript(job); }).find("no tasks"), std::string::npos);
}

}  // namespace
