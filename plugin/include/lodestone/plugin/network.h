#pragma once
// A network of nodes: named node instances with parameter values, connections
// from outputs to inputs, and a cook that evaluates a node after everything
// upstream of it. Parameter values are validated against the declarations
// when set; a cook's exception is rethrown as InvalidArgument naming the
// node. Cooked outputs are cached until a parameter or connection upstream
// changes. Not thread-safe: one network is used by one thread at a time.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "lodestone/plugin/node.h"

namespace lodestone::plugin {

class Network {
 public:
  /// Adds a node of a registered type; throws on an unknown type (with a
  /// suggestion) or a name already used.
  void addNode(const std::string& type, const std::string& name);
  /// Adds a node of a host-defined type (kept by the network).
  void addNode(const NodeDecl& decl, const std::string& name);
  bool hasNode(const std::string& name) const { return nodes_.count(name) != 0; }
  const NodeDecl& declOf(const std::string& node) const;
  std::vector<std::string> nodeNames() const;

  /// Sets a parameter after checking it against its declaration; throws
  /// InvalidArgument "node 'n' (type): param: expected ..., found ...", or
  /// naming an unknown parameter with the closest declared one.
  void setParam(const std::string& node, const std::string& param, const ParamValue& value);
  const ParamSet& params(const std::string& node) const;

  /// Connects output `output` of `from` to input `input` of `to`; throws when
  /// a name is unknown, the types differ, the input is single and already
  /// connected, or the connection would make a cycle.
  void connect(const std::string& from, const std::string& output, const std::string& to, const std::string& input);

  /// Cooks `node` (and what it depends on); returns its outputs.
  const CookOutputs& cook(const std::string& node);
  /// The cooked value of an output; throws when the node has not cooked.
  const NodeValue& output(const std::string& node, const std::string& output) const;

 private:
  struct Connection {
    std::string from, output;
  };
  struct Instance {
    const NodeDecl* decl = nullptr;
    ParamSet params;
    std::map<std::string, std::vector<Connection>> inputs;
    CookOutputs outputs;
    bool dirty = true;
  };
  Instance& instance(const std::string& name);
  const Instance& instance(const std::string& name) const;
  void markDirty(const std::string& name);
  bool dependsOn(const std::string& node, const std::string& upstream) const;
  void cookInto(const std::string& name, std::vector<std::string>& stack);
  std::string where(const std::string& name) const;

  std::map<std::string, Instance> nodes_;
  std::vector<std::unique_ptr<NodeDecl>> customDecls_;
  std::vector<std::string> order_;  // insertion order
};

}  // namespace lodestone::plugin
