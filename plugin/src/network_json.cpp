#include "lodestone/plugin/network_json.h"

#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/json_reader.h"
#include "lodestone/plugin/node_registry.h"
#include "lodestone/plugin/param_json.h"

namespace lodestone::plugin {

void buildNetworkFromJson(Network& network, const nlohmann::json& doc, const std::string& where) {
  require(network.nodeNames().empty(), where, ": a network is built from JSON only when it is empty");
  JsonReader root(doc, "", where);
  std::vector<std::string> types;
  for (const NodeDecl& d : nodeRegistry()) types.push_back(d.type);
  for (JsonReader& node : root.array("nodes")) {
    const std::string name = node.string("name");
    const std::string type = node.string("type", types);
    if (name.empty()) node.failAt("name", "a node name must not be empty");
    if (network.hasNode(name)) node.failAt("name", concat("a node named '", name, "' is already in the network"));
    network.addNode(type, name);
    if (node.has("params")) {
      const nlohmann::json& params = node.raw("params");
      setParamsFromJson(network, name, params,
                        concat(where, ": ", node.pathOf("params"), ": node '", name, "' (", type, ")"));
    }
    node.finish();
  }
  if (root.has("connections"))
    for (JsonReader& c : root.array("connections")) {
      const std::string from = c.string("from"), output = c.string("output"), to = c.string("to"),
                        input = c.string("input");
      c.finish();
      try {
        network.connect(from, output, to, input);
      } catch (const InvalidArgument& e) {
        throw InvalidArgument(concat(where, ": ", c.path(), ": ", e.what()));
      }
    }
  root.finish();
}

}  // namespace lodestone::plugin
