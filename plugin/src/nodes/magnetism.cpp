// Nodes of the magnetic stage: transfer, field solve and force.
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "lodestone/plugin/node_builders.h"

#include "library.h"

namespace lodestone::plugin::nodes {

// ---- magnetization transfer ------------------------------------------------------
NodeDecl transferNode() {
  NodeDecl d =
      declareNode("magnetization_transfer", "Magnetization Transfer", "magnetism",
                  "Deposits the micro-particle density n_i = sum_p w_ip n_p / dx^3 (quadratic B-splines) on a grid "
                  "enclosing the magnetic particles plus a margin of free space.");
  auto& q = d.params;
  q.push_back(positive(floatParam("dx", "Grid spacing", 0.01, "m", "Spacing of the field-solve grid.")));
  q.push_back(intParam("padding", "Padding", 4, 0, 64, "Cells of free space around the particles' bounding box."));
  d.inputs = {{"particles", PortType::Particles, "Material points (only magnetic ones deposit).", false, true}};
  d.outputs = {{"density", PortType::Density, "Nodal micro-particle density, 1/m^3."}};
  d.cook = [](const CookContext& c) {
    const ParamSet& p = c.params();
    const ParticlesData all = mergeParticles(c.inputs("particles"));
    const double dx = p.getFloat("dx");
    const int pad = int(p.getInt("padding")) + 2;  // +2: the stencil's reach
    Vec3d lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (std::size_t k = 0; k < all.particles.size(); ++k)
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], all.particles.x[k][a]);
        hi[a] = std::max(hi[a], all.particles.x[k][a]);
      }
    require(!all.particles.empty(), "no particles to transfer");
    GridSpec g;
    g.dx = dx;
    for (int a = 0; a < 3; ++a) {
      const double o = std::floor(lo[a] / dx) * dx - pad * dx;
      (a == 0 ? g.origin.x : a == 1 ? g.origin.y : g.origin.z) = o;
    }
    g.dims = {int(std::ceil((hi.x - g.origin.x) / dx)) + pad + 1, int(std::ceil((hi.y - g.origin.y) / dx)) + pad + 1,
              int(std::ceil((hi.z - g.origin.z) / dx)) + pad + 1};
    DensityData out;
    out.density.reset(g);
    ParticleView view{all.particles.x.data(), all.particles.count.data(), all.particles.size()};
    out.totalCount = depositNumberDensity(view, out.density.view()).totalCount;
    out.material = sharedMagnetic(all);
    return CookOutputs{{"density", value(std::move(out))}};
  };
  return d;
}

NodeDecl fieldSolveNode() {
  NodeDecl d =
      declareNode("field_solve", "Field Solve", "magnetism",
                  "Solves the nonlinear magnetostatic problem for phi on the density's grid (Newton-PCG) and recovers "
                  "H, M, B and the Einstein-Laub force at the nodes.");
  addSolveParams(d.params, "");
  d.params.push_back(floatParam("time", "Time", 0.0, "s", "Time at which the sources are evaluated."));
  d.inputs = {{"density", PortType::Density, "Micro-particle density and its material."},
              {"sources", PortType::Sources, "Applied-field sources (none: no field).", true, true}};
  d.outputs = {{"field", PortType::Field, "The solved stage: phi, H, M, B, force density and nodal force."}};
  d.cook = [](const CookContext& c) {
    const auto density = c.input<DensityData>("density");
    const SourcesData sources = mergeSources(c.inputs("sources"));
    FieldData out;
    out.stage = std::make_shared<MagneticForceStage>(density->density.spec(), density->material,
                                                     solveSettingsFrom(c.params(), ""));
    out.report = out.stage->runOnDensity(density->density.view(), sources.all(), c.params().getFloat("time"));
    return CookOutputs{{"field", value(std::move(out))}};
  };
  return d;
}

// ---- magnetic force --------------------------------------------------------------------
NodeDecl magneticForceNode() {
  NodeDecl d =
      declareNode("magnetic_force", "Magnetic Force", "magnetism",
                  "Conservative magnetic force on each material point (N): the nodal Einstein-Laub forces shared among "
                  "the particles whose deposit made the density (sum over particles = sum over nodes).");
  d.inputs = {{"field", PortType::Field, "A solved field."},
              {"particles", PortType::Particles, "The particles that were transferred.", false, true}};
  d.outputs = {{"forces", PortType::Forces, "Per-particle forces, N."}};
  d.cook = [](const CookContext& c) {
    const auto field = c.input<FieldData>("field");
    const ParticlesData all = mergeParticles(c.inputs("particles"));
    ForcesData out;
    out.particleForces.resize(all.particles.size());
    field->stage->particleForces({all.particles.x.data(), all.particles.count.data(), all.particles.size()},
                                 out.particleForces.data());
    for (const Vec3d& f : out.particleForces) out.total += f;
    out.report = field->report;
    return CookOutputs{{"forces", value(std::move(out))}};
  };
  return d;
}

}  // namespace lodestone::plugin::nodes
