// JSON report helpers: unit suffixes in keys, null for non-finite values, no
// silent overwrites, stage timings, and an atomic write read back through the
// strict parser.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/json_reader.h"
#include "lodestone/plugin/output/stats_json.h"

using namespace lodestone;
using namespace lodestone::output;
using lodestone::plugin::parseJsonFile;
using nlohmann::json;

TEST(StatsJson, UnitSuffixes) {
  EXPECT_EQ(unitSuffix("m"), "m");
  EXPECT_EQ(unitSuffix("A/m"), "A_per_m");
  EXPECT_EQ(unitSuffix("N/m^3"), "N_per_m3");
  EXPECT_EQ(unitSuffix("kg/m^3"), "kg_per_m3");
  EXPECT_EQ(unitSuffix("A m^2"), "A_m2");
  EXPECT_EQ(unitSuffix("N*m"), "N_m");
  EXPECT_EQ(unitSuffix(""), "");
  EXPECT_THROW(unitSuffix("m^-1"), InvalidArgument);
  EXPECT_EQ(quantityKey("radius", "m"), "radius_m");
  EXPECT_EQ(quantityKey("solve", "s"), "solve_s");
  EXPECT_EQ(quantityKey("relative_residual", ""), "relative_residual");
}

TEST(StatsJson, BuildsReports) {
  json report;  // null becomes an object
  putQuantity(report, "radius", 0.025, "m");
  putQuantity(report, "total_force", Vec3d{0, 0.5, -1.25}, "N");
  putQuantity(report, "residual", std::numeric_limits<double>::infinity(), "");
  putCount(report, "newton_iterations", 7);
  EXPECT_EQ(report.dump(),
            R"({"newton_iterations":7,"radius_m":0.025,"residual":null,"total_force_N":[0.0,0.5,-1.25]})");
  EXPECT_THROW(putQuantity(report, "radius", 1.0, "m"), InvalidArgument);  // already present
  EXPECT_THROW(putCount(report, "bad name", 1), InvalidArgument);
  json notObject = json::array();
  EXPECT_THROW(putCount(notObject, "n", 1), InvalidArgument);
  EXPECT_EQ(jsonVec3({1, std::nan(""), 3}).dump(), "[1.0,null,3.0]");

  StageTimes t;
  t.add("p2g", 0.25);
  t.add("solve", 0.5);
  EXPECT_EQ(stageTimesJson(t).dump(), R"({"p2g_s":0.25,"solve_s":0.5,"total_s":0.75})");
}

TEST(StatsJson, WritesAtomicallyAndReadsBack) {
  const auto path =
      std::filesystem::temp_directory_path() / ("lodestone_test_stats_json_" + std::to_string(::getpid()) + ".json");
  json report;
  putQuantity(report, "elapsed", 12.5, "s");
  putCount(report, "frames", 240);
  report["name"] = "ball \xff";  // invalid UTF-8 is replaced, not an exception
  writeJsonFile(path.string(), report);
  const json back = parseJsonFile(path.string());
  EXPECT_EQ(back["elapsed_s"], 12.5);
  EXPECT_EQ(back["frames"], 240);
  EXPECT_EQ(back["name"], "ball \xef\xbf\xbd");
  std::filesystem::remove(path);
  EXPECT_THROW(writeJsonFile((path.parent_path() / "no_such_dir_lodestone" / "x.json").string(), report), Error);
}
