#include "lodestone/plugin/param_json.h"

#include "lodestone/core/base/error.h"

namespace lodestone::plugin {

ParamValue paramFromJson(const ParamDecl& decl, const nlohmann::json& v, const std::string& where) {
  const auto fail = [&](const std::string& expected) {
    std::string found = v.dump();
    if (found.size() > 40) found = found.substr(0, 37) + "...";
    throw InvalidArgument(
        concat(where, ": ", decl.name, ": expected ", expected, ", found ", v.type_name(), " ", found));
  };
  switch (decl.type) {
    case ParamType::Float:
      if (!v.is_number()) fail("a number" + (decl.unit.empty() ? std::string() : " in " + decl.unit));
      return v.get<double>();
    case ParamType::Int:
      if (v.is_number_integer()) return v.get<std::int64_t>();
      if (!v.is_number()) fail("an integer");
      return v.get<double>();  // ParamDecl::check accepts whole numbers only
    case ParamType::Bool:
      if (!v.is_boolean()) fail("a boolean");
      return v.get<bool>();
    case ParamType::String:
    case ParamType::Choice:
      if (!v.is_string()) fail(decl.type == ParamType::Choice ? decl.describeRange() : std::string("a string"));
      return v.get<std::string>();
    case ParamType::Vec3:
    case ParamType::Direction:
      if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
        fail("an array of 3 numbers" + (decl.unit.empty() ? std::string() : " in " + decl.unit));
      return Vec3d{v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
    case ParamType::FloatList: {
      if (!v.is_array()) fail("an array of numbers");
      std::vector<double> list;
      for (const auto& e : v) {
        if (!e.is_number()) fail("an array of numbers");
        list.push_back(e.get<double>());
      }
      return list;
    }
  }
  fail("a value");
  return {};
}

namespace {
void setObject(Network& network, const std::string& node, const nlohmann::json& obj, const std::string& prefix,
               const std::string& where) {
  require(obj.is_object(), where, ": expected an object of parameters, found ", obj.type_name());
  const NodeDecl& decl = network.declOf(node);
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    const std::string name = prefix + it.key();
    if (const ParamDecl* p = decl.param(name)) {
      network.setParam(node, name, paramFromJson(*p, it.value(), where));
      continue;
    }
    bool group = false;
    for (const ParamDecl& p : decl.params) group = group || p.name.rfind(name + ".", 0) == 0;
    if (group && it.value().is_object()) {
      setObject(network, node, it.value(), name + ".", where);
      continue;
    }
    network.setParam(node, name, ParamValue{});  // throws: unknown parameter, with a suggestion
  }
}
}  // namespace

void setParamsFromJson(Network& network, const std::string& node, const nlohmann::json& params,
                       const std::string& where) {
  setObject(network, node, params, "", where);
}

}  // namespace lodestone::plugin
