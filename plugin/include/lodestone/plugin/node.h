#pragma once
// SOP-like nodes: a declaration (type name, label, category, help, declared
// parameters, typed inputs and outputs) and a cook that calls the library.
// The node is thin glue: the cook reads its parameters and inputs, calls a
// core (or vdb_io) function that knows nothing of nodes, and returns outputs.
// The registry (node_registry.h) lists every declaration.
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "lodestone/plugin/node_data.h"
#include "lodestone/plugin/param.h"

namespace lodestone::plugin {

struct PortDecl {
  std::string name;
  PortType type = PortType::Particles;
  std::string help;
  bool optional = false;  ///< inputs: the cook runs without a connection
  bool multiple = false;  ///< inputs: several connections are merged
};

/// What a cook sees: its node's name, parameter values and connected inputs.
class CookContext {
 public:
  CookContext(std::string node, const ParamSet& params, std::map<std::string, std::vector<NodeValue>> inputs)
      : node_(std::move(node)), params_(params), inputs_(std::move(inputs)) {}

  const std::string& node() const { return node_; }
  const ParamSet& params() const { return params_; }
  /// All values connected to input `name` (empty when none).
  const std::vector<NodeValue>& inputs(const std::string& name) const;
  /// The one value of input `name` as T, or null when not connected.
  template <typename T>
  std::shared_ptr<const T> input(const std::string& name) const {
    const auto& v = inputs(name);
    if (v.empty()) return nullptr;
    const auto* p = std::get_if<std::shared_ptr<const T>>(&v.front());
    return p ? *p : nullptr;
  }

 private:
  std::string node_;
  const ParamSet& params_;
  std::map<std::string, std::vector<NodeValue>> inputs_;
};

using CookOutputs = std::map<std::string, NodeValue>;
using CookFunction = std::function<CookOutputs(const CookContext&)>;

struct NodeDecl {
  std::string type;      ///< unique name, e.g. "magnetic_force"
  std::string label;     ///< e.g. "Magnetic Force"
  std::string category;  ///< e.g. "magnetism"
  std::string help;
  std::vector<ParamDecl> params;
  std::vector<PortDecl> inputs;
  std::vector<PortDecl> outputs;
  CookFunction cook;

  const ParamDecl* param(const std::string& name) const;
  const PortDecl* input(const std::string& name) const;
  const PortDecl* output(const std::string& name) const;
  std::vector<std::string> paramNames() const;
};

}  // namespace lodestone::plugin
