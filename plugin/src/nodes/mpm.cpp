// The MPM solver node.
#include <cstddef>

#include "lodestone/core/mpm/solver.h"
#include "lodestone/plugin/node_builders.h"

#include "library.h"

namespace lodestone::plugin::nodes {

// ---- MPM solver ------------------------------------------------------------------------
NodeDecl mpmSolverNode() {
  NodeDecl d = declareNode(
      "mpm_solver", "MPM Solver", "mpm",
      "The reference MLS-MPM with the magnetic-force stage: steps the particles for a number of frames in a "
      "box domain with walls, gravity, colliders and magnets.");
  auto& q = d.params;
  q.push_back(required(vec3Param("domain.min", "Domain min", {-0.1, -0.1, -0.1}, "m", "Lower corner of the MPM box.")));
  q.push_back(required(vec3Param("domain.max", "Domain max", {0.1, 0.1, 0.1}, "m", "Upper corner of the MPM box.")));
  q.push_back(required(positive(floatParam("domain.dx", "Grid spacing", 0.02, "m", "MPM grid spacing."))));
  q.push_back(choiceParam("domain.boundary", "Walls", kBoundaryModes, "separate", "Velocity condition at the walls."));
  q.push_back(range(floatParam("domain.friction", "Wall friction", 0.0, "", "Coulomb friction at the walls."), 0, 10));
  q.push_back(intParam("time.start_frame", "Start frame", 1, 1, 1000000,
                       "Number of the first simulated frame. Frame f ends at scene time f / fps: the initial state "
                       "is frame start_frame - 1, at t = (start_frame - 1) / fps, where the simulation starts. "
                       "Keyframes, time profiles and emitter time lines are in scene seconds."));
  q.push_back(required(intParam("time.frames", "Frames", 1, 1, 100000, "Frames to simulate.")));
  q.push_back(range(floatParam("time.fps", "Frame rate", 24.0, "1/s", "Frames per second."), 1, 10000));
  q.push_back(range(floatParam("time.dt", "Time step", 0.0, "s", "Fixed substep; 0: CFL-adaptive."), 0, 1));
  q.push_back(range(floatParam("time.cfl", "CFL", 0.4, "", "Fraction of a cell crossed per substep."), 0.01, 1));
  q.push_back(positive(floatParam("time.dt_max", "Largest step", 1e-3, "s", "Largest CFL substep.")));
  q.push_back(intParam("time.min_substeps", "Min substeps", 1, 1, 1000000,
                       "Substeps per frame at the least (the step is at most the frame over this)."));
  q.push_back(intParam("time.max_substeps", "Max substeps", 0, 0, 100000000,
                       "Substeps per frame at the most; a frame that needs more stops the run with a message naming "
                       "the step and the fastest particle (0: no limit)."));
  q.push_back(intParam("time.field_solve_every", "Solve interval", 0, 0, 1000000,
                       "Substeps between field solves; 0: automatic (see time.field_solve_distance)."));
  q.push_back(range(floatParam("time.field_solve_distance", "Solve distance", 0.25, "cells",
                               "With field_solve_every 0: solve again when material or a magnet moved this far "
                               "since the last solve (and once per frame); 0: once per frame."),
                    0, 100));
  q.push_back(vec3Param("gravity", "Gravity", {0, 0, -9.81}, "m/s^2", "Gravitational acceleration."));
  addSolveParams(q, "magnetic.");
  q.push_back(intParam("magnetic.padding", "Field padding", 4, 0, 64,
                       "Cells of free space added around the MPM box for the field solve."));
  d.inputs = {{"particles", PortType::Particles, "Material points to simulate.", false, true},
              {"sources", PortType::Sources, "Applied fields and magnets.", true, true},
              {"colliders", PortType::Colliders, "Obstacles.", true, true}};
  d.outputs = {{"simulation", PortType::Simulation, "The solver after the frames, with per-frame statistics."}};
  d.cook = [](const CookContext& c) {
    const ParamSet& p = c.params();
    const ParticlesData all = mergeParticles(c.inputs("particles"));
    const int frames = int(p.getInt("time.frames"));
    const double fps = p.getFloat("time.fps");
    const int initialFrame = int(p.getInt("time.start_frame")) - 1;
    const double start = initialFrame / fps;  // s, the scene time of the initial state
    double particles = double(all.particles.size());
    for (const ParticlesData::Emitter& e : all.emitters)
      particles += estimatedEmittedParticles(e.shape, e.settings, start, (initialFrame + frames) / fps);
    MpmSettings s = mpmSettingsFrom(p, particles);
    auto solver = std::make_shared<MpmSolver>(s);
    solver->setTime(start);  // before the magnets and colliders, which take their pose at it
    for (const MpmMaterial& m : all.materials) solver->addMaterial(m);
    solver->particles() = all.particles;
    for (const ParticlesData::Emitter& e : all.emitters) solver->addEmitter(e.shape, e.material, e.settings);
    const SourcesData sources = mergeSources(c.inputs("sources"));
    addSourcesAndColliders(*solver, sources.fields, sources.magnets, mergeColliders(c.inputs("colliders")).colliders);
    SimulationData out;
    const auto comMagnetic = [&]() {
      const MpmParticles& pts = solver->particles();
      Vec3d sum;
      double w = 0;
      for (std::size_t k = 0; k < pts.size(); ++k) {
        const double m = pts.count[k] > 0 ? pts.mass[k] : 0.0;
        sum += m * pts.x[k];
        w += m;
      }
      return w > 0 ? sum / w : pts.centreOfMass();
    };
    out.frameTimes.push_back(solver->time());
    out.centreOfMass.push_back(comMagnetic());
    for (int f = 0; f < frames; ++f) {
      solver->advanceFrame(1.0 / fps);
      out.frameTimes.push_back(solver->time());
      out.centreOfMass.push_back(comMagnetic());
    }
    out.startFrame = initialFrame + 1;
    out.frames = frames;
    out.time = solver->time();
    out.solver = std::move(solver);
    return CookOutputs{{"simulation", value(std::move(out))}};
  };
  return d;
}

}  // namespace lodestone::plugin::nodes
