#include "lodestone/plugin/param_json.h"

#include <algorithm>
#include <utility>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/node_registry.h"

namespace lodestone::plugin {

ParamValue readParam(JsonReader& entry, const std::string& key, const ParamDecl& p) {
  const Range range{p.min, p.max, p.minOpen, p.maxOpen};
  switch (p.type) {
    case ParamType::Float:
      return entry.number(key, p.unit, range);
    case ParamType::Int:
      return entry.integer64(key, std::int64_t(p.min), std::int64_t(p.max));
    case ParamType::Bool:
      return entry.boolean(key);
    case ParamType::String:
      return entry.string(key);
    case ParamType::Choice:
      return entry.string(key, p.choices);
    case ParamType::Vec3:
      return entry.vec3(key, p.unit, range);
    case ParamType::Direction:
      return entry.nonZeroVec3(key);
    case ParamType::FloatList:
      return entry.numbers(key, p.unit, range, p.minCount, p.maxCount);
  }
  return {};
}

namespace {

bool skipped(const std::string& name, const std::vector<std::string>& skip) {
  for (const std::string& s : skip)
    if (name == s || (!s.empty() && s.back() == '.' && name.rfind(s, 0) == 0)) return true;
  return false;
}

/// Which declared parameters a walk reads: a scene entry's (those that apply,
/// required ones necessarily) or an update's (those present, any condition).
enum class Walk { Entry, Update };

/// Reads the declared parameters of `decl` from `entry` and hands each value
/// read to `set`; `values` holds the values so far (for the conditions).
void walkParams(JsonReader& entry, const NodeDecl& decl, const ParamSet& values, Walk walk,
                const std::vector<std::string>& skip, const EntryGroupHook& groupHook,
                const std::function<void(const ParamDecl&, ParamValue)>& set) {
  std::vector<std::pair<std::string, JsonReader>> groups;  // nested objects, in the order first met
  std::vector<std::string> absent;
  for (const ParamDecl& p : decl.params) {
    if (skipped(p.name, skip) || (walk == Walk::Entry && !applies(p, values))) continue;
    JsonReader* r = &entry;
    std::string key = p.name;
    const std::size_t dot = p.name.find('.');
    if (dot != std::string::npos) {
      const std::string group = p.name.substr(0, dot);
      key = p.name.substr(dot + 1);
      if (std::find(absent.begin(), absent.end(), group) != absent.end()) continue;
      auto it = std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == group; });
      if (it == groups.end()) {
        if (!entry.has(group)) {
          absent.push_back(group);
          continue;
        }
        groups.emplace_back(group, entry.object(group));
        it = groups.end() - 1;
      }
      r = &it->second;
    }
    if ((walk == Walk::Update || !p.required) && !r->has(key)) continue;  // the declared default
    set(p, readParam(*r, key, p));
  }
  for (auto& g : groups) {
    if (groupHook) groupHook(g.first, g.second);
    g.second.finish();
  }
}

}  // namespace

ParamSet readNodeEntry(JsonReader& entry, const std::string& nodeType, const std::vector<std::string>& skip,
                       const EntryGroupHook& groupHook) {
  const NodeDecl& decl = requireNode(nodeType);
  ParamSet params(decl.params);
  const std::string where = entry.path().empty() ? entry.file() : concat(entry.file(), ": ", entry.path());
  walkParams(entry, decl, params, Walk::Entry, skip, groupHook, [&](const ParamDecl& p, ParamValue v) {
    params.set(p.name, p.check(v, where));
    params.markGiven(p.name);
  });
  return params;
}

void setParamsFromJson(Network& network, const std::string& node, const nlohmann::json& params,
                       const std::string& where) {
  const NodeDecl& decl = network.declOf(node);
  JsonReader entry(params, "", where);
  std::vector<std::pair<std::string, ParamValue>> read;
  walkParams(entry, decl, ParamSet(decl.params), Walk::Update, {}, {},
             [&](const ParamDecl& p, ParamValue v) { read.emplace_back(p.name, std::move(v)); });
  entry.finish();
  for (const auto& [name, value] : read) network.setParam(node, name, value);
}

}  // namespace lodestone::plugin
