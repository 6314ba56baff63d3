// The node library's shared parts (library.h) and its registry.
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>

#include "lodestone/core/base/error.h"
#include "lodestone/core/field/material.h"
#include "lodestone/plugin/node_builders.h"

#include "library.h"

namespace lodestone::plugin {
namespace nodes {

NodeDecl declareNode(std::string type, std::string label, std::string category, std::string help) {
  NodeDecl d;
  d.type = std::move(type);
  d.label = std::move(label);
  d.category = std::move(category);
  d.help = std::move(help);
  return d;
}

ParticlesData mergeParticles(const std::vector<NodeValue>& inputs) {
  ParticlesData out;
  for (const NodeValue& v : inputs) {
    const auto& in = *std::get<std::shared_ptr<const ParticlesData>>(v);
    const std::uint32_t offset = std::uint32_t(out.materials.size());
    out.materials.insert(out.materials.end(), in.materials.begin(), in.materials.end());
    out.bodies.insert(out.bodies.end(), in.bodies.begin(), in.bodies.end());
    for (ParticlesData::Emitter e : in.emitters) {
      e.material += offset;
      out.emitters.push_back(std::move(e));
    }
    const MpmParticles& p = in.particles;
    for (std::size_t k = 0; k < p.size(); ++k) {
      const std::size_t q =
          out.particles.add(p.x[k], p.v[k], p.mass[k], p.volume0[k], p.count[k], p.material[k] + offset);
      out.particles.F[q] = p.F[k];
      out.particles.J[q] = p.J[k];
      out.particles.C[q] = p.C[k];
    }
  }
  return out;
}

SourcesData mergeSources(const std::vector<NodeValue>& inputs) {
  SourcesData out;
  for (const NodeValue& v : inputs) {
    const auto& in = *std::get<std::shared_ptr<const SourcesData>>(v);
    for (std::size_t k = 0; k < in.fields.size(); ++k) out.fields.add(in.fields.source(k));
    out.magnets.insert(out.magnets.end(), in.magnets.begin(), in.magnets.end());
  }
  return out;
}

CollidersData mergeColliders(const std::vector<NodeValue>& inputs) {
  CollidersData out;
  for (const NodeValue& v : inputs) {
    const auto& in = *std::get<std::shared_ptr<const CollidersData>>(v);
    out.colliders.insert(out.colliders.end(), in.colliders.begin(), in.colliders.end());
  }
  return out;
}

MagneticMaterial sharedMagnetic(const ParticlesData& p) {
  const MagneticMaterial* found = nullptr;
  for (const MpmMaterial& m : p.materials) {
    if (!m.isMagnetic()) continue;
    if (found && found->law != m.magnetic.law)
      throw InvalidArgument("the magnetic materials differ in their magnetization law; one field solve needs one law");
    if (!found) found = &m.magnetic;
  }
  return found ? *found : nonMagneticMaterial();
}

void addSolveParams(std::vector<ParamDecl>& q, const std::string& prefix) {
  q.push_back(choiceParam(prefix + "boundary", "Field boundary", {"open", "shield"}, "open",
                          "open: far-field potential on the outer nodes; shield: the paper's Neumann wall."));
  q.push_back(range(floatParam(prefix + "tolerance", "Tolerance", FieldSolveSettings().tolerance, "",
                               "Relative Newton residual to reach."),
                    1e-14, 1e-1));
  q.push_back(choiceParam(prefix + "preconditioner", "Preconditioner", {"multigrid", "jacobi"}, "multigrid",
                          "Preconditioner of the inner CG."));
  q.push_back(intParam(prefix + "max_newton_iterations", "Newton iterations", FieldSolveSettings().maxNewtonIterations,
                       1, 1000, "Newton iteration cap."));
}

}  // namespace nodes

std::vector<NodeDecl> buildRegistry() {
  using namespace nodes;
  return {particleSourceNode(), particleEmitterNode(), hostParticlesNode(), materialNode(),      magnetNode(),
          appliedFieldNode(),   transferNode(),        fieldSolveNode(),    magneticForceNode(), mpmSolverNode(),
          colliderNode(),       vdbExportNode(),       fieldLinesNode(),    surfaceNode(),       meshExportNode()};
}

}  // namespace lodestone::plugin
