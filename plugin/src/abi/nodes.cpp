// The C ABI's node metadata entries: node types, their parameters and ports.
#include "support.h"

#include <map>

#include "lodestone/plugin/node_registry.h"

namespace lodestone::plugin::abi {

/// Strings the metadata functions hand out, built once and kept for the
/// library's lifetime.
struct ParamStrings {
  std::string defaultText, choices;
};
const std::map<const ParamDecl*, ParamStrings>& paramStrings() {
  static const std::map<const ParamDecl*, ParamStrings> strings = [] {
    std::map<const ParamDecl*, ParamStrings> m;
    for (const NodeDecl& d : nodeRegistry())
      for (const ParamDecl& p : d.params) {
        ParamStrings s;
        s.defaultText = p.defaultText();
        for (std::size_t k = 0; k < p.choices.size(); ++k) s.choices += (k ? "|" : "") + p.choices[k];
        m.emplace(&p, std::move(s));
      }
    return m;
  }();
  return strings;
}

const NodeDecl& declNamed(const char* type) {
  const std::string name = needName(type, "type");
  const NodeDecl* d = findNode(name);
  if (!d) throw AbiError(LODESTONE_ERROR_NOT_FOUND, concat("no node type named '", name, "'"));
  return *d;
}

uint32_t nodeTypeCount() { return uint32_t(nodeRegistry().size()); }

lodestone_status nodeTypeInfo(uint32_t index, lodestone_node_info* out) {
  return firewall(nullptr, "node_type_info", [&] {
    need(out, "out");
    needSize(out->struct_size, sizeof(lodestone_node_info), "lodestone_node_info");
    if (index >= nodeRegistry().size())
      throw AbiError(LODESTONE_ERROR_NOT_FOUND, concat("node index ", index, " >= ", nodeRegistry().size()));
    const NodeDecl& d = nodeRegistry()[index];
    out->type = d.type.c_str();
    out->label = d.label.c_str();
    out->category = d.category.c_str();
    out->help = d.help.c_str();
    out->param_count = uint32_t(d.params.size());
    out->input_count = uint32_t(d.inputs.size());
    out->output_count = uint32_t(d.outputs.size());
  });
}

lodestone_param_type abiType(ParamType t) {
  switch (t) {
    case ParamType::Float:
      return LODESTONE_PARAM_FLOAT;
    case ParamType::Int:
      return LODESTONE_PARAM_INT;
    case ParamType::Bool:
      return LODESTONE_PARAM_BOOL;
    case ParamType::String:
      return LODESTONE_PARAM_STRING;
    case ParamType::Choice:
      return LODESTONE_PARAM_CHOICE;
    case ParamType::FloatList:
      return LODESTONE_PARAM_FLOAT_LIST;
    default:
      return LODESTONE_PARAM_VEC3;
  }
}

lodestone_status nodeParamInfo(const char* type, uint32_t index, lodestone_param_info* out) {
  return firewall(nullptr, "node_param_info", [&] {
    const NodeDecl& d = declNamed(type);
    need(out, "out");
    needSize(out->struct_size, sizeof(lodestone_param_info), "lodestone_param_info");
    if (index >= d.params.size())
      throw AbiError(LODESTONE_ERROR_NOT_FOUND,
                     concat("node '", d.type, "' has ", d.params.size(), " parameters, not ", index + 1));
    const ParamDecl& p = d.params[index];
    const ParamStrings& s = paramStrings().at(&p);
    out->name = p.name.c_str();
    out->label = p.label.c_str();
    out->type = abiType(p.type);
    out->unit = p.unit.c_str();
    out->help = p.help.c_str();
    out->default_text = s.defaultText.c_str();
    out->min = p.min;
    out->max = p.max;
    out->choices = s.choices.c_str();
  });
}

void portInfo(const PortDecl& p, lodestone_port_info* out) {
  need(out, "out");
  needSize(out->struct_size, sizeof(lodestone_port_info), "lodestone_port_info");
  out->name = p.name.c_str();
  out->type = toString(p.type);
  out->help = p.help.c_str();
  out->optional = p.optional ? 1 : 0;
  out->multiple = p.multiple ? 1 : 0;
}

lodestone_status nodeInputInfo(const char* type, uint32_t index, lodestone_port_info* out) {
  return firewall(nullptr, "node_input_info", [&] {
    const NodeDecl& d = declNamed(type);
    if (index >= d.inputs.size())
      throw AbiError(LODESTONE_ERROR_NOT_FOUND, concat("node '", d.type, "' has ", d.inputs.size(), " inputs"));
    portInfo(d.inputs[index], out);
  });
}

lodestone_status nodeOutputInfo(const char* type, uint32_t index, lodestone_port_info* out) {
  return firewall(nullptr, "node_output_info", [&] {
    const NodeDecl& d = declNamed(type);
    if (index >= d.outputs.size())
      throw AbiError(LODESTONE_ERROR_NOT_FOUND, concat("node '", d.type, "' has ", d.outputs.size(), " outputs"));
    portInfo(d.outputs[index], out);
  });
}

}  // namespace lodestone::plugin::abi
