#pragma once
// The registry of node types: every node the library offers, in a fixed
// order. The `lodestone nodes` command, docs/nodes.md, the C ABI's node
// metadata and scene-file validation are all generated from it.
#include <string>
#include <vector>

#include "lodestone/plugin/node.h"

namespace lodestone::plugin {

/// Every registered node declaration (built once, immutable, thread-safe).
const std::vector<NodeDecl>& nodeRegistry();
/// The declaration of `type`, or null.
const NodeDecl* findNode(const std::string& type);
/// The declaration of `type`; throws InvalidArgument naming it, with the
/// closest registered name as a suggestion.
const NodeDecl& requireNode(const std::string& type);

/// Whether VDB import and export are built into this library.
bool vdbBuilt();

/// Plain-text listing of the nodes (the `lodestone nodes` command).
std::string nodesText();
/// The node reference in Markdown (docs/nodes.md).
std::string nodesMarkdown();

}  // namespace lodestone::plugin
