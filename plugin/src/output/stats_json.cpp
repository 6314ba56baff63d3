#include "lodestone/plugin/output/stats_json.h"

#include <cmath>

#include "lodestone/plugin/output/atomic_file.h"
#include "lodestone/core/base/error.h"

namespace lodestone::output {
namespace {

bool isWordChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

void checkNewKey(nlohmann::json& object, const std::string& name, const std::string& key) {
  if (object.is_null()) object = nlohmann::json::object();
  require(object.is_object(), "JSON report: cannot add '", key, "' to a ", object.type_name(), " (not an object)");
  bool ok = !name.empty();
  for (char c : name) ok = ok && isWordChar(c);
  require(ok, "JSON report: key name '", name, "' must be non-empty letters, digits and '_'");
  require(!object.contains(key), "JSON report: key '", key, "' is already present");
}

}  // namespace

std::string unitSuffix(const std::string& unit) {
  std::string r;
  for (char c : unit) {
    if (c == '/') {
      r += "_per_";
    } else if (c == ' ' || c == '*') {
      if (!r.empty() && r.back() != '_') r += '_';
    } else if (c == '^') {
      continue;
    } else {
      require(isWordChar(c), "JSON report: unit '", unit, "' has the character '", c,
              "' (use letters, digits, '/', '^', '*' and spaces; 1/m rather than m^-1)");
      r += c;
    }
  }
  return r;
}

std::string quantityKey(const std::string& name, const std::string& unit) {
  const std::string suffix = unitSuffix(unit);
  return suffix.empty() || suffix == "1" ? name : name + "_" + suffix;
}

nlohmann::json jsonNumber(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(); }

nlohmann::json jsonVec3(const Vec3d& value) {
  return nlohmann::json::array({jsonNumber(value.x), jsonNumber(value.y), jsonNumber(value.z)});
}

void putQuantity(nlohmann::json& object, const std::string& name, double value, const std::string& unit) {
  const std::string key = quantityKey(name, unit);
  checkNewKey(object, name, key);
  object[key] = jsonNumber(value);
}

void putQuantity(nlohmann::json& object, const std::string& name, const Vec3d& value, const std::string& unit) {
  const std::string key = quantityKey(name, unit);
  checkNewKey(object, name, key);
  object[key] = jsonVec3(value);
}

void putCount(nlohmann::json& object, const std::string& name, std::int64_t count) {
  checkNewKey(object, name, name);
  object[name] = count;
}

nlohmann::json stageTimesJson(const StageTimes& times) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& s : times.stages()) putQuantity(j, s.first, s.second, "s");
  putQuantity(j, "total", times.total(), "s");
  return j;
}

void writeJsonFile(const std::string& path, const nlohmann::json& value, int indent) {
  // error_handler_t::replace: invalid UTF-8 in strings becomes U+FFFD instead of throwing.
  writeFileAtomically(path, value.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

}  // namespace lodestone::output
