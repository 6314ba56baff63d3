#pragma once
// A whole network from JSON, read with the scene files' strict reader
// (json_reader.h) and the node registry:
//   {"nodes": [{"name": "ball", "type": "particle_source", "params": {"shape": "sphere", ...}}, ...],
//    "connections": [{"from": "ball", "output": "particles", "to": "n", "input": "particles"}, ...]}
// Nodes are added in order, their "params" set as network_set_json does
// (setParamsFromJson: types, ranges, unknown keys with a suggestion), then the
// connections are made. Errors name the path: "<where>: nodes[1].type: ...",
// "<where>: connections[0]: node 'n' (magnetization_transfer): no input named 'particle'; did you mean 'particles'?".
#include <string>

#include <nlohmann/json.hpp>

#include "lodestone/plugin/network.h"

namespace lodestone::plugin {

/// Adds the nodes and connections of `doc` to the empty `network`; throws
/// InvalidArgument "<where>: path: ..." (the network is then unusable: build
/// a fresh one).
void buildNetworkFromJson(Network& network, const nlohmann::json& doc, const std::string& where);

}  // namespace lodestone::plugin
