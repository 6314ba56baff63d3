// The C ABI's stage entries: the magnetic-force stage on a host's particles or density, its fields, forces and report.
#include "support.h"

#include <cstring>

#include "lodestone/core/field/material.h"
#include "lodestone/plugin/node_builders.h"

namespace lodestone::plugin::abi {


lodestone_status stageParamsDefault(lodestone_stage_params* p) {
  return firewall(nullptr, "stage_params_default", [&] {
    need(p, "params");
    needSize(p->struct_size, sizeof(lodestone_stage_params), "lodestone_stage_params");
    const std::uint32_t size = p->struct_size;
    std::memset(p, 0, sizeof(lodestone_stage_params));
    p->struct_size = size;
    p->law = LODESTONE_LAW_PAPER;
    p->moment = 1.09e-19;
    p->temperature = 300;
    p->chi = 0.91;
    p->number_density = 0;
    p->grid.dx = 0.01;
    for (int a = 0; a < 3; ++a) {
      p->grid.origin[a] = -0.1;
      p->grid.dims[a] = 21;
    }
    p->padding = 0;
    const FieldSolveSettings solve;  // the library's one set of defaults
    p->tolerance = solve.tolerance;
    p->max_newton_iterations = solve.maxNewtonIterations;
    p->boundary = LODESTONE_BOUNDARY_OPEN;
    p->out_of_grid = LODESTONE_OUT_OF_GRID_THROW;
    p->warm_start = 1;
  });
}

lodestone_status stageCreate(lodestone_context* c, const lodestone_stage_params* p, lodestone_stage** out) {
  return firewall(ctxOf(c), "stage_create", [&] {
    if (out) *out = nullptr;
    Context& context = contextOf(c);
    need(p, "params");
    need(out, "out");
    needSize(p->struct_size, sizeof(lodestone_stage_params), "lodestone_stage_params");
    // Every field is checked whatever the law (a value the law does not use
    // is still a host's mistake when it is out of its range).
    require(std::isfinite(p->chi) && p->chi >= 0, "chi must be a finite susceptibility >= 0, got ", p->chi);
    require(std::isfinite(p->moment) && p->moment > 0, "moment must be a finite moment > 0 A*m^2, got ", p->moment);
    require(std::isfinite(p->temperature) && p->temperature > 0, "temperature must be finite and > 0 K, got ",
            p->temperature);
    require(std::isfinite(p->number_density) && p->number_density >= 0,
            "number_density must be finite and >= 0 1/m^3 (0: the paper's), got ", p->number_density);
    const double n0 = p->number_density == 0 ? paperMaterial().numberDensity : p->number_density;
    MagneticMaterial material;
    switch (p->law) {
      case LODESTONE_LAW_NONE:
        material = nonMagneticMaterial();
        break;
      case LODESTONE_LAW_LINEAR:
        material = linearMaterial(p->chi, n0);
        break;
      case LODESTONE_LAW_LANGEVIN:
        material = langevinMaterial(p->moment, p->temperature, n0);
        break;
      case LODESTONE_LAW_PAPER:
        material = paperMaterial();
        break;
      default:
        throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT, concat("law ", p->law, " is not one of LODESTONE_LAW_*"));
    }
    require(p->padding >= 0 && p->padding <= 64, "padding must be 0..64 cells, got ", p->padding);
    require(p->boundary == LODESTONE_BOUNDARY_OPEN || p->boundary == LODESTONE_BOUNDARY_SHIELD, "boundary ",
            p->boundary, " is not one of LODESTONE_BOUNDARY_*");
    require(p->out_of_grid == LODESTONE_OUT_OF_GRID_THROW || p->out_of_grid == LODESTONE_OUT_OF_GRID_SKIP,
            "out_of_grid ", p->out_of_grid, " is not one of LODESTONE_OUT_OF_GRID_*");
    require(std::isfinite(p->tolerance) && p->tolerance >= 1e-14 && p->tolerance <= 0.1,
            "tolerance must be in [1e-14, 0.1], got ", p->tolerance);
    require(p->max_newton_iterations >= 1 && p->max_newton_iterations <= 1000,
            "max_newton_iterations must be 1..1000, got ", p->max_newton_iterations);
    GridSpec g;
    g.origin = {p->grid.origin[0], p->grid.origin[1], p->grid.origin[2]};
    g.dx = p->grid.dx;
    g.dims = {p->grid.dims[0], p->grid.dims[1], p->grid.dims[2]};
    g.validate("params.grid");
    const int pad = p->padding;
    // The padded node counts, in 64 bits: dims near INT32_MAX must be named, not wrapped.
    const std::int64_t padded[3] = {std::int64_t(g.dims.i) + 2 * pad, std::int64_t(g.dims.j) + 2 * pad,
                                    std::int64_t(g.dims.k) + 2 * pad};
    const double nodes[3] = {double(padded[0]), double(padded[1]), double(padded[2])};
    requireFitsInMemory("params.grid (padded)", nodes, g.dx, 0, GridUse::FieldSolve);
    g.origin = g.origin - double(pad) * Vec3d{g.dx, g.dx, g.dx};
    g.dims = {int(padded[0]), int(padded[1]), int(padded[2])};
    MagneticStageSettings s;
    s.boundary = p->boundary == LODESTONE_BOUNDARY_OPEN ? BoundaryKind::Open : BoundaryKind::Shield;
    s.solve.tolerance = p->tolerance;
    s.solve.maxNewtonIterations = p->max_newton_iterations;
    s.outOfGrid = p->out_of_grid == LODESTONE_OUT_OF_GRID_SKIP ? OutOfGridPolicy::Skip : OutOfGridPolicy::Throw;
    s.warmStart = p->warm_start != 0;
    auto stage = std::make_unique<Stage>();
    stage->stage = std::make_unique<MagneticForceStage>(g, material, s);
    *out = adopt<lodestone_stage>(context, HandleKind::Stage, std::move(stage));
  });
}

lodestone_status stageDestroy(lodestone_stage* s) {
  return firewall(ctxOf(s), "stage_destroy", [&] { destroy<Stage>(s, HandleKind::Stage, "stage"); });
}

lodestone_status stageGrid(const lodestone_stage* s, lodestone_grid* out) {
  return firewall(ctxOf(s), "stage_grid", [&] {
    Stage& st = stageOf(s);
    need(out, "out");
    const GridSpec& g = st.stage->grid();
    for (int a = 0; a < 3; ++a) {
      out->origin[a] = g.origin[a];
      out->dims[a] = g.dims[a];
    }
    out->dx = g.dx;
  });
}

const FieldSource& sourcesOf(const lodestone_fields* f) {
  static const FieldSourceSet kNone;
  return f ? static_cast<const FieldSource&>(fieldsOf(f).set) : kNone;
}

lodestone_status stageRunParticles(lodestone_stage* s, const lodestone_particles* p, const lodestone_fields* f,
                                   double t, lodestone_report* report) {
  return firewall(ctxOf(s), "stage_run_particles", [&] {
    Stage& st = stageOf(s);
    checkTime(t);
    if (report) needSize(report->struct_size, sizeof(lodestone_report), "lodestone_report");
    const Particles particles = readParticles(p, true);
    st.ran = false;
    st.report = st.stage->run(particles.view(), sourcesOf(f), t);
    st.ran = true;
    if (report) fillReport(st.report, report);
  });
}

lodestone_status stageRunDensity(lodestone_stage* s, const lodestone_grid* grid, const double* density,
                                 const lodestone_fields* f, double t, lodestone_report* report) {
  return firewall(ctxOf(s), "stage_run_density", [&] {
    Stage& st = stageOf(s);
    need(grid, "grid");
    need(density, "density");
    checkTime(t);
    if (report) needSize(report->struct_size, sizeof(lodestone_report), "lodestone_report");
    const GridSpec& g = st.stage->grid();
    GridSpec h;
    h.origin = {grid->origin[0], grid->origin[1], grid->origin[2]};
    h.dx = grid->dx;
    h.dims = {grid->dims[0], grid->dims[1], grid->dims[2]};
    if (!(h == g))
      throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT,
                     concat("the density's grid (origin ", h.origin.x, ", ", h.origin.y, ", ", h.origin.z, " m, dx ",
                            h.dx, " m, ", h.dims.i, " x ", h.dims.j, " x ", h.dims.k,
                            " nodes) is not the stage's grid (stage_grid); give particles instead"));
    st.ran = false;
    st.report = st.stage->runOnDensity({density, g}, sourcesOf(f), t);
    st.ran = true;
    if (report) fillReport(st.report, report);
  });
}

lodestone_status stageParticleForces(const lodestone_stage* s, const lodestone_particles* p,
                                     lodestone_vec3_out* forces) {
  return firewall(ctxOf(s), "stage_particle_forces", [&] {
    const Stage& st = ranStage(s);
    const Particles particles = readParticles(p, true);
    need(forces, "forces");
    needSize(forces->struct_size, sizeof(lodestone_vec3_out), "lodestone_vec3_out");
    if (forces->capacity < particles.x.size())
      throw AbiError(LODESTONE_ERROR_BUFFER_TOO_SMALL,
                     concat("forces holds ", forces->capacity, " elements, ", particles.x.size(), " are needed"));
    std::vector<Vec3d> out(particles.x.size());
    st.stage->particleForces(particles.view(), out.data());
    writeVectors(out, forces);
  });
}

lodestone_status stageSample(const lodestone_stage* s, lodestone_field_kind kind, const lodestone_particles* points,
                             lodestone_vec3_out* out) {
  return firewall(ctxOf(s), "stage_sample", [&] {
    const Stage& st = ranStage(s);
    if (kind != LODESTONE_FIELD_H && kind != LODESTONE_FIELD_FORCE_DENSITY)
      throw AbiError(
          LODESTONE_ERROR_INVALID_ARGUMENT,
          concat("stage_sample samples LODESTONE_FIELD_H or LODESTONE_FIELD_FORCE_DENSITY, not kind ", kind));
    const Particles particles = readParticles(points, false);
    need(out, "out");
    needSize(out->struct_size, sizeof(lodestone_vec3_out), "lodestone_vec3_out");
    if (out->capacity < particles.x.size())
      throw AbiError(LODESTONE_ERROR_BUFFER_TOO_SMALL,
                     concat("out holds ", out->capacity, " elements, ", particles.x.size(), " are needed"));
    std::vector<Vec3d> values(particles.x.size());
    if (kind == LODESTONE_FIELD_H)
      st.stage->sampleField(particles.x.data(), particles.x.size(), values.data());
    else
      st.stage->sampleForceDensity(particles.x.data(), particles.x.size(), values.data());
    writeVectors(values, out);
  });
}

lodestone_status stageReadField(const lodestone_stage* s, lodestone_field_kind kind, lodestone_scalar_type type,
                                void* out, size_t count) {
  return firewall(ctxOf(s), "stage_read_field", [&] {
    const Stage& st = ranStage(s);
    const std::size_t es = scalarSize(type, "stage_read_field");
    const MagneticForceStage& stage = *st.stage;
    const std::size_t nodes = stage.grid().nodeCount();
    const double* scalar = nullptr;
    const Vec3d* vector = nullptr;
    switch (kind) {
      case LODESTONE_FIELD_DENSITY:
        scalar = stage.density().data;
        break;
      case LODESTONE_FIELD_POTENTIAL:
        scalar = stage.potential().data;
        break;
      case LODESTONE_FIELD_APPLIED:
        vector = stage.appliedField().data;
        break;
      case LODESTONE_FIELD_H:
        vector = stage.field().data;
        break;
      case LODESTONE_FIELD_M:
        vector = stage.magnetization().data;
        break;
      case LODESTONE_FIELD_B:
        vector = stage.inductionField().data;
        break;
      case LODESTONE_FIELD_FORCE_DENSITY:
        vector = stage.forceDensity().data;
        break;
      case LODESTONE_FIELD_NODAL_FORCE:
        vector = stage.nodalForce().data;
        break;
      default:
        throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT,
                       concat("field kind ", kind, " is not one of LODESTONE_FIELD_*"));
    }
    const std::size_t needed = scalar ? nodes : 3 * nodes;
    if (count < needed)
      throw AbiError(LODESTONE_ERROR_BUFFER_TOO_SMALL,
                     concat("out holds ", count, " values, the field has ", needed, " (", nodes, " nodes)"));
    char* base = static_cast<char*>(need(out, "out"));
    if (scalar)
      for (std::size_t k = 0; k < nodes; ++k) writeScalar(base + k * es, type, scalar[k]);
    else
      for (std::size_t k = 0; k < nodes; ++k)
        for (int a = 0; a < 3; ++a) writeScalar(base + (3 * k + std::size_t(a)) * es, type, vector[k][a]);
  });
}

lodestone_status stageReport(const lodestone_stage* s, lodestone_report* out) {
  return firewall(ctxOf(s), "stage_report", [&] {
    const Stage& st = ranStage(s);
    fillReport(st.report, need(out, "out"));
  });
}

lodestone_status stageReportJson(const lodestone_stage* s, char* buffer, size_t capacity, size_t* needed) {
  return firewall(ctxOf(s), "stage_report_json", [&] {
    const Stage& st = ranStage(s);
    copyText(reportJson(st.report), buffer, capacity, needed);
  });
}

lodestone_status stageExportVdb(const lodestone_stage* s, const char* path) {
  return firewall(ctxOf(s), "stage_export_vdb", [&] {
    const Stage& st = ranStage(s);
    const std::string file = needName(path, "path");
    try {
      writeStageVdb(file, *st.stage, st.report.summary());
    } catch (const InvalidArgument& e) {
      throw AbiError(LODESTONE_ERROR_IO, e.what());
    }
  });
}

lodestone_status stageNumberDensity(const lodestone_stage* s, double* n0) {
  return firewall(ctxOf(s), "stage_number_density", [&] {
    const Stage& st = stageOf(s);
    const MagneticMaterial& m = st.stage->material();
    *need(n0, "n0") = m.law.kind == LawKind::None ? 0.0 : m.numberDensity;
  });
}

}  // namespace lodestone::plugin::abi
