#pragma once
// Helpers for the JSON reports of the `lodestone` program (run statistics,
// timings, solver counts). Keys carry their unit as a suffix, the convention
// of the field demo's field_solve.json: "radius_m", "solve_s",
// "magnetization_A_per_m", "force_density_N_per_m3"; counts are plain plural
// names ("newton_iterations", "particles"). JSON has no infinity or NaN, so
// non-finite values are written as null, never as invalid JSON.
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "lodestone/core/base/vec3.h"
#include "lodestone/plugin/output/progress.h"

namespace lodestone::output {

/// Key suffix of a unit: "/" -> "_per_", spaces and '*' -> "_", '^' dropped:
/// "m" -> "m", "A/m" -> "A_per_m", "N/m^3" -> "N_per_m3", "A m^2" -> "A_m2",
/// "" -> "". Throws lodestone::InvalidArgument on other characters.
std::string unitSuffix(const std::string& unit);

/// name + "_" + unitSuffix(unit), or name alone for a dimensionless unit ("").
std::string quantityKey(const std::string& name, const std::string& unit);

/// The number, or null when not finite.
nlohmann::json jsonNumber(double value);
/// [x, y, z] with jsonNumber components.
nlohmann::json jsonVec3(const Vec3d& value);

/// object[quantityKey(name, unit)] = value. Throws InvalidArgument when
/// `object` is not an object (null becomes one), the name is not letters,
/// digits and '_', or the key is already present (no silent overwrite).
void putQuantity(nlohmann::json& object, const std::string& name, double value, const std::string& unit);
void putQuantity(nlohmann::json& object, const std::string& name, const Vec3d& value, const std::string& unit);
/// object[name] = count (same checks).
void putCount(nlohmann::json& object, const std::string& name, std::int64_t count);

/// {"<stage>_s": seconds, ..., "total_s": sum} in the stages' order.
nlohmann::json stageTimesJson(const StageTimes& times);

/// Writes `value` (indented; -1: one line) plus a newline to `path`
/// atomically (atomic_file.h); lodestone::Error names the path on failure.
void writeJsonFile(const std::string& path, const nlohmann::json& value, int indent = 2);

}  // namespace lodestone::output
