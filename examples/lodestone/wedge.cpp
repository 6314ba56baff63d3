#include "wedge.h"

#include <cctype>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

#include "lodestone/core/base/error.h"

namespace lodestone::examples {

std::vector<JsonPathStep> parseJsonPath(const std::string& path) {
  const auto bad = [&](const std::string& why) {
    return InvalidArgument(concat("key '", path, "': ", why, " (expected a path like magnets[0].magnetization or ",
                                  "materials.ferro.viscosity)"));
  };
  std::vector<JsonPathStep> steps;
  std::size_t i = 0;
  bool expectKey = true;
  while (i < path.size()) {
    if (path[i] == '[') {
      const std::size_t close = path.find(']', i);
      if (close == std::string::npos) throw bad("unclosed '['");
      const std::string digits = path.substr(i + 1, close - i - 1);
      if (digits.empty() || digits.size() > 6 ||
          digits.find_first_not_of("0123456789") != std::string::npos)
        throw bad(concat("'[", digits, "]' is not an array position"));
      steps.push_back({"", std::stoi(digits)});
      i = close + 1;
      expectKey = false;
    } else if (path[i] == '.') {
      if (steps.empty() || expectKey) throw bad(concat("empty key at position ", i));
      ++i;
      expectKey = true;
    } else {
      if (!expectKey) throw bad(concat("'.' or '[' expected at position ", i));
      const std::size_t end = path.find_first_of(".[", i);
      const std::string key = path.substr(i, end == std::string::npos ? std::string::npos : end - i);
      if (key.find(']') != std::string::npos) throw bad("']' without '['");
      steps.push_back({key, -1});
      i = end == std::string::npos ? path.size() : end;
      expectKey = false;
    }
  }
  if (steps.empty()) throw bad("empty");
  if (expectKey) throw bad("it ends with '.'");
  return steps;
}

void setJsonPath(nlohmann::json& doc, const std::string& path, const nlohmann::json& value) {
  const std::vector<JsonPathStep> steps = parseJsonPath(path);
  nlohmann::json* node = &doc;
  std::string at;  // the path walked so far
  for (std::size_t s = 0; s < steps.size(); ++s) {
    const JsonPathStep& step = steps[s];
    const bool last = s + 1 == steps.size();
    const std::string where = at.empty() ? std::string("the scene") : concat("'", at, "'");
    if (step.index >= 0) {
      if (!node->is_array())
        throw InvalidArgument(concat("key '", path, "': ", where, " is not an array, so [", step.index,
                                     "] does not exist"));
      if (std::size_t(step.index) >= node->size())
        throw InvalidArgument(concat("key '", path, "': ", where, " has ", node->size(), " elements, so [",
                                     step.index, "] does not exist"));
      node = &(*node)[std::size_t(step.index)];
      at += concat("[", step.index, "]");
      continue;
    }
    if (node->is_array()) {
      // An element of an array of named objects.
      nlohmann::json* found = nullptr;
      std::vector<std::string> names;
      for (nlohmann::json& e : *node)
        if (e.is_object() && e.contains("name") && e["name"].is_string()) {
          names.push_back(e["name"].get<std::string>());
          if (names.back() == step.key) found = &e;
        }
      if (!found) {
        std::string list;
        for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
        throw InvalidArgument(concat("key '", path, "': ", where, " has no element named '", step.key, "'",
                                     names.empty() ? std::string(" (its elements have no names)")
                                                   : concat(" (names: ", list, ")")));
      }
      node = found;
    } else if (node->is_object()) {
      if (!node->contains(step.key)) {
        if (!last)
          throw InvalidArgument(concat("key '", path, "': ", where, " has no key '", step.key, "'"));
        (*node)[step.key] = nullptr;  // a new key: the scene validator judges it
      }
      node = &(*node)[step.key];
    } else {
      throw InvalidArgument(concat("key '", path, "': ", where, " is a value, not an object, so '", step.key,
                                   "' does not exist"));
    }
    at += (at.empty() ? "" : ".") + step.key;
  }
  *node = value;
}

WedgeAxis parseVary(const std::string& text) {
  const std::size_t eq = text.find('=');
  if (eq == std::string::npos)
    throw InvalidArgument(concat("--vary '", text, "': expected KEY=V1,V2,..."));
  WedgeAxis axis;
  axis.key = text.substr(0, eq);
  if (axis.key.empty()) throw InvalidArgument(concat("--vary '", text, "': no key before '='"));
  parseJsonPath(axis.key);  // throws naming the key
  const std::string list = text.substr(eq + 1);
  int depth = 0;
  std::string current;
  const auto flush = [&] {
    if (current.empty())
      throw InvalidArgument(concat("--vary '", text, "': an empty value (values are separated by single commas)"));
    axis.texts.push_back(current);
    nlohmann::json v = nlohmann::json::parse(current, nullptr, false);
    axis.values.push_back(v.is_discarded() ? nlohmann::json(current) : v);
    current.clear();
  };
  for (const char c : list) {
    if (c == '[' || c == '{') ++depth;
    if (c == ']' || c == '}') --depth;
    if (c == ',' && depth == 0)
      flush();
    else
      current += c;
  }
  flush();
  return axis;
}

std::string fileSafe(const std::string& text) {
  std::string out;
  for (const char c : text)
    out += (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '+' || c == '-') ? c : '_';
  return out;
}

std::vector<std::string> axisLabels(const std::vector<WedgeAxis>& axes) {
  std::vector<std::string> last;
  std::map<std::string, int> uses;
  for (const WedgeAxis& a : axes) {
    const std::vector<JsonPathStep> steps = parseJsonPath(a.key);
    const JsonPathStep& s = steps.back();
    last.push_back(s.index >= 0 ? concat(s.index) : fileSafe(s.key));
    ++uses[last.back()];
  }
  std::vector<std::string> labels;
  for (std::size_t a = 0; a < axes.size(); ++a) {
    if (uses[last[a]] == 1) {
      labels.push_back(last[a]);
      continue;
    }
    std::string full;
    for (const char c : axes[a].key) full += std::isalnum(static_cast<unsigned char>(c)) ? c : '.';
    while (!full.empty() && full.back() == '.') full.pop_back();
    labels.push_back(full);
  }
  return labels;
}

std::vector<Wedge> expandWedges(const nlohmann::json& scene, const std::vector<WedgeAxis>& axes, int maxWedges) {
  if (axes.empty()) throw InvalidArgument("no --vary KEY=V1,V2,... given: there is nothing to wedge");
  std::set<std::string> keys;
  long long count = 1;
  for (const WedgeAxis& a : axes) {
    if (!keys.insert(a.key).second) throw InvalidArgument(concat("key '", a.key, "' is varied twice"));
    if (a.values.empty()) throw InvalidArgument(concat("key '", a.key, "' has no values"));
    count *= static_cast<long long>(a.values.size());
    if (count > maxWedges)
      throw InvalidArgument(concat("the --vary values make more than ", maxWedges, " wedges"));
  }
  const std::vector<std::string> labels = axisLabels(axes);
  const int digits = count > 1000 ? 4 : count > 100 ? 3 : 2;
  std::vector<Wedge> wedges;
  std::vector<std::size_t> pick(axes.size(), 0);
  for (long long n = 0; n < count; ++n) {
    Wedge w;
    w.index = int(n);
    w.scene = scene;
    char number[16];
    std::snprintf(number, sizeof number, "w%0*lld", digits, n);
    w.name = number;
    for (std::size_t a = 0; a < axes.size(); ++a) {
      const nlohmann::json& v = axes[a].values[pick[a]];
      setJsonPath(w.scene, axes[a].key, v);
      w.values.emplace_back(axes[a].key, v);
      w.name += "_" + labels[a] + "-" + fileSafe(axes[a].texts[pick[a]]);
    }
    wedges.push_back(std::move(w));
    // The last axis varies fastest.
    for (std::size_t a = axes.size(); a-- > 0;) {
      if (++pick[a] < axes[a].values.size()) break;
      pick[a] = 0;
    }
  }
  return wedges;
}

std::string wedgeSceneFile(const Wedge& w) { return w.name + "/scene.json"; }
std::string wedgeOutDir(const Wedge& w) { return w.name + "/out"; }

nlohmann::json wedgeManifest(const std::string& sourceScene, const std::vector<WedgeAxis>& axes,
                             const std::vector<Wedge>& wedges) {
  nlohmann::json m;
  m["source_scene"] = sourceScene;
  m["order"] = "cartesian product, the first key varying slowest";
  nlohmann::json ax = nlohmann::json::array();
  for (const WedgeAxis& a : axes) ax.push_back({{"key", a.key}, {"values", a.values}});
  m["axes"] = ax;
  nlohmann::json ws = nlohmann::json::array();
  for (const Wedge& w : wedges) {
    nlohmann::json values = nlohmann::json::object();
    for (const auto& [k, v] : w.values) values[k] = v;
    ws.push_back({{"index", w.index}, {"name", w.name}, {"scene", wedgeSceneFile(w)}, {"out", wedgeOutDir(w)},
                  {"values", values}});
  }
  m["wedges"] = ws;
  return m;
}

namespace {
std::string csvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (const char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}
std::string valueText(const nlohmann::json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); }
}  // namespace

std::string wedgeManifestCsv(const nlohmann::json& manifest) {
  std::ostringstream os;
  os << "index,name,scene,out";
  for (const nlohmann::json& a : manifest.at("axes")) os << "," << csvField(a.at("key").get<std::string>());
  os << "\n";
  for (const nlohmann::json& w : manifest.at("wedges")) {
    os << w.at("index").get<int>() << "," << csvField(w.at("name").get<std::string>()) << ","
       << csvField(w.at("scene").get<std::string>()) << "," << csvField(w.at("out").get<std::string>());
    for (const nlohmann::json& a : manifest.at("axes"))
      os << "," << csvField(valueText(w.at("values").at(a.at("key").get<std::string>())));
    os << "\n";
  }
  return os.str();
}

}  // namespace lodestone::examples
