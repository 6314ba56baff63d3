#include "lodestone/plugin/network.h"

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/errors.h"
#include "lodestone/plugin/json_reader.h"
#include "lodestone/plugin/node_registry.h"

namespace lodestone::plugin {

std::string Network::where(const std::string& name) const {
  const auto it = nodes_.find(name);
  return concat("node '", name, "' (", it == nodes_.end() ? std::string("?") : it->second.decl->type, ")");
}

void Network::addNode(const std::string& type, const std::string& name) { addNode(requireNode(type), name); }

void Network::addNode(const NodeDecl& declIn, const std::string& name) {
  require(!name.empty(), "a node name must not be empty");
  if (hasNode(name))
    throw InvalidArgument(concat("a node named '", name, "' already exists (", nodes_.at(name).decl->type, ")"));
  const NodeDecl* known = findNode(declIn.type);
  if (known != &declIn) {
    require(!declIn.type.empty() && declIn.cook, "a node type needs a name and a cook");
    customDecls_.push_back(std::make_unique<NodeDecl>(declIn));
  }
  const NodeDecl& decl = known == &declIn ? declIn : *customDecls_.back();
  Instance inst;
  inst.decl = &decl;
  inst.params = ParamSet(decl.params);
  nodes_.emplace(name, std::move(inst));
  order_.push_back(name);
}

Network::Instance& Network::instance(const std::string& name) {
  const auto it = nodes_.find(name);
  if (it == nodes_.end()) throw InvalidArgument(concat("no node named '", name, "'", didYouMean(name, order_)));
  return it->second;
}
const Network::Instance& Network::instance(const std::string& name) const {
  return const_cast<Network*>(this)->instance(name);
}

const NodeDecl& Network::declOf(const std::string& node) const { return *instance(node).decl; }
std::vector<std::string> Network::nodeNames() const { return order_; }

void Network::setParam(const std::string& node, const std::string& param, const ParamValue& value) {
  Instance& inst = instance(node);
  const ParamDecl* decl = inst.decl->param(param);
  if (!decl)
    throw InvalidArgument(
        concat(where(node), ": unknown parameter '", param, "'", didYouMean(param, inst.decl->paramNames())));
  inst.params.set(param, decl->check(value, where(node)));
  inst.params.markGiven(param);
  // Of two alternatives (ParamDecl::replaces) the one set last is used.
  for (const ParamDecl& other : inst.decl->params)
    if (other.name != param && (other.replaces == param || decl->replaces == other.name))
      inst.params.clearGiven(other.name);
  markDirty(node);
}

const ParamSet& Network::params(const std::string& node) const { return instance(node).params; }

void Network::markDirty(const std::string& name) {
  instance(name).dirty = true;
  for (auto& [other, inst] : nodes_)
    for (const auto& [input, conns] : inst.inputs)
      for (const Connection& c : conns)
        if (c.from == name && !inst.dirty) markDirty(other);
}

bool Network::dependsOn(const std::string& node, const std::string& upstream) const {
  if (node == upstream) return true;
  for (const auto& [input, conns] : instance(node).inputs)
    for (const Connection& c : conns)
      if (dependsOn(c.from, upstream)) return true;
  return false;
}

void Network::connect(const std::string& from, const std::string& output, const std::string& to,
                      const std::string& input) {
  const Instance& src = instance(from);
  Instance& dst = instance(to);
  const PortDecl* out = src.decl->output(output);
  std::vector<std::string> names;
  if (!out) {
    for (const PortDecl& p : src.decl->outputs) names.push_back(p.name);
    throw InvalidArgument(concat(where(from), ": no output named '", output, "'", didYouMean(output, names)));
  }
  const PortDecl* in = dst.decl->input(input);
  if (!in) {
    for (const PortDecl& p : dst.decl->inputs) names.push_back(p.name);
    throw InvalidArgument(concat(where(to), ": no input named '", input, "'", didYouMean(input, names)));
  }
  require(out->type == in->type, where(to), ": input '", input, "' takes ", toString(in->type), ", but output '",
          output, "' of ", where(from), " gives ", toString(out->type));
  auto& conns = dst.inputs[input];
  require(in->multiple || conns.empty(), where(to), ": input '", input, "' takes one connection and already has one");
  require(!dependsOn(from, to), "connecting ", where(from), " to ", where(to), " would make a cycle");
  conns.push_back({from, output});
  markDirty(to);
}

const CookOutputs& Network::cook(const std::string& node) {
  std::vector<std::string> stack;
  cookInto(node, stack);
  return instance(node).outputs;
}

void Network::cookInto(const std::string& name, std::vector<std::string>& stack) {
  Instance& inst = instance(name);
  if (!inst.dirty) return;
  stack.push_back(name);
  std::map<std::string, std::vector<NodeValue>> inputs;
  for (const PortDecl& port : inst.decl->inputs) {
    const auto it = inst.inputs.find(port.name);
    if (it == inst.inputs.end() || it->second.empty()) {
      require(port.optional, where(name), ": input '", port.name, "' (", toString(port.type), ") is not connected");
      continue;
    }
    for (const Connection& c : it->second) {
      cookInto(c.from, stack);
      inputs[port.name].push_back(instance(c.from).outputs.at(c.output));
    }
  }
  // Parameters that do not apply (their condition fails) keep their values
  // but the cook does not read them.
  CookContext ctx(name, inst.params, std::move(inputs));
  CookOutputs outputs;
  try {
    outputs = inst.decl->cook(ctx);
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const CookFailed&) {
    throw;  // an upstream node's failure, already named
  } catch (const NotBuilt& e) {
    throw CookFailed(concat(where(name), ": ", e.what()), true);
  } catch (const std::exception& e) {
    throw CookFailed(concat(where(name), ": cook failed: ", e.what()), false);
  } catch (...) {
    throw CookFailed(concat(where(name), ": cook failed with an unknown exception"), false);
  }
  for (const PortDecl& port : inst.decl->outputs)
    require(outputs.count(port.name) && !std::holds_alternative<std::monostate>(outputs.at(port.name)), where(name),
            ": cook did not produce output '", port.name, "'");
  inst.outputs = std::move(outputs);
  inst.dirty = false;
  stack.pop_back();
}

const NodeValue& Network::output(const std::string& node, const std::string& output) const {
  const Instance& inst = instance(node);
  require(!inst.dirty, where(node), " has not been cooked since its last change");
  const auto it = inst.outputs.find(output);
  require(it != inst.outputs.end(), where(node), ": no output named '", output, "'");
  return it->second;
}

}  // namespace lodestone::plugin
