// The helpers the C ABI's entries share (support.h).
#include "support.h"

#include <cmath>
#include <cstring>

#include <nlohmann/json.hpp>

#include "lodestone/plugin/node_builders.h"

namespace lodestone::plugin::abi {

thread_local std::string tlsError;

lodestone_status fail(Context* context, lodestone_status code, const char* function, const char* message) noexcept {
  try {
    tlsError = std::string(function) + ": " + message;
    if (context) {
      std::lock_guard<std::mutex> lock(context->mutex);
      context->errors[std::this_thread::get_id()] = tlsError;
    }
  } catch (...) {
    // Out of memory while recording the message: the status still tells.
  }
  return code;
}

void needSize(std::uint32_t given, std::size_t expected, const char* what) {
  if (given < expected)
    throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT,
                   concat(what, "->struct_size is ", given, " bytes; this library needs at least ", expected,
                          " (set it to sizeof(", what, "))"));
}

Context& contextOf(lodestone_context* h) { return live<Context>(h, HandleKind::Context, "context"); }
Fields& fieldsOf(const lodestone_fields* h) { return live<Fields>(h, HandleKind::Fields, "fields"); }
Stage& stageOf(const lodestone_stage* h) { return live<Stage>(h, HandleKind::Stage, "stage"); }
NetworkObject& networkOf(const lodestone_network* h) { return live<NetworkObject>(h, HandleKind::Network, "network"); }

Context* ctxOf(lodestone_context* h) { return liveOrNull<Context>(h, HandleKind::Context); }
Context* ctxOf(const lodestone_stage* h) {
  const Stage* s = liveOrNull<Stage>(h, HandleKind::Stage);
  return s ? s->context : nullptr;
}
Context* ctxOf(const lodestone_fields* h) {
  const Fields* f = liveOrNull<Fields>(h, HandleKind::Fields);
  return f ? f->context : nullptr;
}
Context* ctxOf(const lodestone_network* h) {
  const NetworkObject* n = liveOrNull<NetworkObject>(h, HandleKind::Network);
  return n ? n->context : nullptr;
}

Vec3d vec(const double* v, const char* what) {
  need(v, what);
  const Vec3d x{v[0], v[1], v[2]};
  if (!isFinite(x)) throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT, concat(what, " has a non-finite component"));
  return x;
}

std::size_t scalarSize(lodestone_scalar_type t, const char* what) {
  if (t == LODESTONE_FLOAT32) return sizeof(float);
  if (t == LODESTONE_FLOAT64) return sizeof(double);
  throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT,
                 concat(what, ": scalar type ", t, " is neither LODESTONE_FLOAT32 (0) nor LODESTONE_FLOAT64 (1)"));
}

double readScalar(const char* p, lodestone_scalar_type t) {
  if (t == LODESTONE_FLOAT32) {
    float f;
    std::memcpy(&f, p, sizeof f);
    return f;
  }
  double d;
  std::memcpy(&d, p, sizeof d);
  return d;
}

void writeScalar(char* p, lodestone_scalar_type t, double v) {
  if (t == LODESTONE_FLOAT32) {
    const float f = float(v);
    std::memcpy(p, &f, sizeof f);
  } else {
    std::memcpy(p, &v, sizeof v);
  }
}

Particles readParticles(const lodestone_particles* p, bool needCounts) {
  need(p, "particles");
  needSize(p->struct_size, sizeof(lodestone_particles), "lodestone_particles");
  const std::size_t es = scalarSize(p->type, "particles");
  const std::size_t ps = p->position_stride ? p->position_stride : 3 * es;
  const std::size_t cs = p->count_stride ? p->count_stride : es;
  if (ps < 3 * es)
    throw AbiError(
        LODESTONE_ERROR_INVALID_ARGUMENT,
        concat("particles: position_stride ", ps, " bytes is smaller than one position (", 3 * es, " bytes)"));
  if (cs < es)
    throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT,
                   concat("particles: count_stride ", cs, " bytes is smaller than one count (", es, " bytes)"));
  if (p->count > (std::size_t(1) << 40))
    throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT, concat("particles: count ", p->count, " is implausibly large"));
  const double noGrid[3] = {0, 0, 0};
  requireFitsInMemory("particles", noGrid, 0, double(p->count));
  Particles out;
  if (p->count == 0) return out;
  need(p->positions, "particles->positions");
  if (needCounts) need(p->counts, "particles->counts");
  out.x.resize(p->count);
  out.n.assign(p->count, 0.0);
  const char* xb = static_cast<const char*>(p->positions);
  const char* nb = static_cast<const char*>(p->counts);
  for (std::size_t k = 0; k < p->count; ++k) {
    const char* q = xb + k * ps;
    out.x[k] = {readScalar(q, p->type), readScalar(q + es, p->type), readScalar(q + 2 * es, p->type)};
    if (nb) out.n[k] = readScalar(nb + k * cs, p->type);
  }
  return out;
}

void writeVectors(const std::vector<Vec3d>& values, lodestone_vec3_out* out) {
  need(out, "output array");
  needSize(out->struct_size, sizeof(lodestone_vec3_out), "lodestone_vec3_out");
  const std::size_t es = scalarSize(out->type, "output array");
  const std::size_t st = out->stride ? out->stride : 3 * es;
  if (st < 3 * es)
    throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT,
                   concat("output array: stride ", st, " bytes is smaller than one 3-vector (", 3 * es, " bytes)"));
  if (out->capacity < values.size())
    throw AbiError(LODESTONE_ERROR_BUFFER_TOO_SMALL,
                   concat("output array holds ", out->capacity, " elements, ", values.size(), " are needed"));
  if (values.empty()) return;
  char* base = static_cast<char*>(need(out->data, "output array data"));
  for (std::size_t k = 0; k < values.size(); ++k)
    for (int a = 0; a < 3; ++a) writeScalar(base + k * st + std::size_t(a) * es, out->type, values[k][a]);
}

void copyText(const std::string& text, char* buffer, std::size_t capacity, std::size_t* needed) {
  need(needed, "needed");
  *needed = text.size() + 1;
  if (!buffer && capacity == 0) return;  // size query
  need(buffer, "buffer");
  if (capacity < text.size() + 1)
    throw AbiError(LODESTONE_ERROR_BUFFER_TOO_SMALL,
                   concat("buffer holds ", capacity, " bytes, ", text.size() + 1, " are needed"));
  std::memcpy(buffer, text.c_str(), text.size() + 1);
}

void addObject(Context* c) {
  std::lock_guard<std::mutex> lock(c->mutex);
  ++c->objects;
}
void removeObject(Context* c) {
  std::lock_guard<std::mutex> lock(c->mutex);
  --c->objects;
}

const Stage& ranStage(const lodestone_stage* h) {
  const Stage& s = stageOf(h);
  if (!s.ran)
    throw AbiError(LODESTONE_ERROR_NOT_READY,
                   "the stage has not run yet (call stage_run_particles or stage_run_density)");
  return s;
}

std::string needName(const char* s, const char* what) { return std::string(need(s, what)); }

void checkTime(double t) {
  if (!std::isfinite(t)) throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT, concat("time must be finite, got ", t, " s"));
}

void fillReport(const MagneticStageReport& r, lodestone_report* out) {
  needSize(out->struct_size, sizeof(lodestone_report), "lodestone_report");
  const std::uint32_t size = out->struct_size;
  std::memset(out, 0, sizeof(lodestone_report));
  out->struct_size = size;
  out->converged = r.converged() ? 1 : 0;
  out->solve_status = int32_t(r.solve.status);
  out->newton_iterations = r.solve.newtonIterations;
  out->cg_iterations = r.solve.cgIterations;
  out->relative_residual = r.solve.relativeResidual;
  for (int a = 0; a < 3; ++a) out->total_force[a] = r.totalForce[a];
  out->total_count = r.totalCount;
  out->particles_skipped = r.transfer.skipped;
  out->seconds_transfer = r.secondsTransfer;
  out->seconds_solve = r.secondsSolve;
  out->seconds_force = r.secondsForce;
  out->seconds_total = r.secondsTotal;
}

std::string reportJson(const MagneticStageReport& r) {
  nlohmann::json j;
  j["converged"] = r.converged();
  j["status"] = toString(r.solve.status);
  j["message"] = r.solve.message;
  j["newton_iterations"] = r.solve.newtonIterations;
  j["cg_iterations"] = r.solve.cgIterations;
  j["relative_residual"] = r.solve.relativeResidual;
  j["total_force_N"] = {r.totalForce.x, r.totalForce.y, r.totalForce.z};
  j["total_count"] = r.totalCount;
  j["particles"] = r.transfer.particles;
  j["particles_skipped"] = r.transfer.skipped;
  j["seconds"] = {{"transfer", r.secondsTransfer}, {"applied_field", r.secondsAppliedField},
                  {"solve", r.secondsSolve},       {"fields", r.secondsFields},
                  {"force", r.secondsForce},       {"total", r.secondsTotal}};
  j["applied_field_reused"] = r.appliedFieldReused;
  j["warnings"] = r.warnings;
  return j.dump();
}

}  // namespace lodestone::plugin::abi
