#pragma once
// The node library's shared parts: what several node families use, and the
// families' node declarations (one file a family: sources.cpp for materials,
// particles, magnets, fields and colliders; magnetism.cpp for the transfer,
// solve and force; mpm.cpp for the solver; io.cpp for the files a
// simulation or a solve writes). Each cook reads its parameters and inputs
// and calls core (or vdb_io) functions that know nothing of nodes.
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "lodestone/plugin/node.h"
#include "lodestone/plugin/node_data.h"

namespace lodestone::plugin {

/// Every node of the library, in the order the registry lists them.
std::vector<NodeDecl> buildRegistry();

namespace nodes {

/// Velocity conditions of colliders, magnets and the MPM walls.
inline const std::vector<std::string> kBoundaryModes{"sticky", "slip", "separate"};

/// A node's declaration with its identity filled in: its type (the name
/// networks and scene files use), label, category and help; the parameters,
/// ports and cook follow.
NodeDecl declareNode(std::string type, std::string label, std::string category, std::string help);

/// A cook's output value holding `data`.
template <typename T>
NodeValue value(T&& data) {
  return std::shared_ptr<const std::decay_t<T>>(std::make_shared<std::decay_t<T>>(std::forward<T>(data)));
}

/// Merges particle inputs into one set (materials renumbered).
ParticlesData mergeParticles(const std::vector<NodeValue>& inputs);
SourcesData mergeSources(const std::vector<NodeValue>& inputs);
CollidersData mergeColliders(const std::vector<NodeValue>& inputs);
/// The magnetic material shared by the magnetic particles (one law per solve).
MagneticMaterial sharedMagnetic(const ParticlesData& p);
/// The field solve's parameters, each name after `prefix`.
void addSolveParams(std::vector<ParamDecl>& q, const std::string& prefix);

// sources.cpp
NodeDecl materialNode();
NodeDecl particleSourceNode();
NodeDecl particleEmitterNode();
NodeDecl hostParticlesNode();
NodeDecl magnetNode();
NodeDecl appliedFieldNode();
NodeDecl colliderNode();
// magnetism.cpp
NodeDecl transferNode();
NodeDecl fieldSolveNode();
NodeDecl magneticForceNode();
// mpm.cpp
NodeDecl mpmSolverNode();
// io.cpp
NodeDecl vdbExportNode();
NodeDecl fieldLinesNode();
NodeDecl surfaceNode();
NodeDecl meshExportNode();

}  // namespace nodes
}  // namespace lodestone::plugin
