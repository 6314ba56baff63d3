#include "node_entry.h"

#include <algorithm>

#include "lodestone/plugin/node_registry.h"

namespace lodestone::examples {

namespace {

bool skipped(const std::string& name, const std::vector<std::string>& skip) {
  for (const std::string& s : skip)
    if (name == s || (!s.empty() && s.back() == '.' && name.rfind(s, 0) == 0)) return true;
  return false;
}

plugin::ParamValue readValue(JsonReader& r, const std::string& key, const plugin::ParamDecl& p) {
  const Range range{p.min, p.max, p.minOpen, p.maxOpen};
  switch (p.type) {
    case plugin::ParamType::Float:
      return r.number(key, p.unit, range);
    case plugin::ParamType::Int:
      return r.integer64(key, std::int64_t(p.min), std::int64_t(p.max));
    case plugin::ParamType::Bool:
      return r.boolean(key);
    case plugin::ParamType::String:
      return r.string(key);
    case plugin::ParamType::Choice:
      return r.string(key, p.choices);
    case plugin::ParamType::Vec3:
      return r.vec3(key, p.unit, range);
    case plugin::ParamType::Direction:
      return r.direction(key);
    case plugin::ParamType::FloatList:
      return r.numbers(key, p.unit, range, p.minCount, p.maxCount);
  }
  return {};
}

}  // namespace

plugin::ParamSet readNodeEntry(JsonReader& entry, const std::string& nodeType, const std::vector<std::string>& skip) {
  const plugin::NodeDecl& decl = plugin::requireNode(nodeType);
  plugin::ParamSet params(decl.params);
  std::vector<std::pair<std::string, JsonReader>> groups;  // nested objects, in the order first met
  std::vector<std::string> absent;
  for (const plugin::ParamDecl& p : decl.params) {
    if (skipped(p.name, skip) || !plugin::applies(p, params)) continue;
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
    if (!p.required && !r->has(key)) continue;  // the declared default
    params.set(p.name, readValue(*r, key, p));
    params.markGiven(p.name);
  }
  for (auto& g : groups) g.second.finish();
  return params;
}

}  // namespace lodestone::examples
