// The C ABI: lodestone_get_api and the functions of its table. Every entry
// runs its body inside `firewall`, which turns every exception into a status
// and a message; nothing else in this file may throw out of an entry.
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <new>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "handle_table.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/core/sources/cuboid_magnet.h"
#include "lodestone/core/sources/cylinder_magnet.h"
#include "lodestone/core/sources/field_source_set.h"
#include "lodestone/core/sources/point_dipole.h"
#include "lodestone/core/sources/sphere_magnet.h"
#include "lodestone/core/sources/uniform_field.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/plugin/errors.h"
#include "lodestone/plugin/json_reader.h"
#include "lodestone/plugin/lodestone.h"
#include "lodestone/plugin/network.h"
#include "lodestone/plugin/network_json.h"
#include "lodestone/plugin/node_builders.h"
#include "lodestone/plugin/node_registry.h"
#include "lodestone/plugin/param_json.h"

using namespace lodestone;
using namespace lodestone::plugin;

namespace {

// The objects behind the handles (handle_table.h: a handle is an id, not an address).
struct Context {
  std::mutex mutex;
  std::map<std::thread::id, std::string> errors;  // last error per thread
  std::size_t objects = 0;                        // live stages, field sets, networks
};

struct Fields {
  Context* context = nullptr;
  FieldSourceSet set;
};

struct Stage {
  Context* context = nullptr;
  std::unique_ptr<MagneticForceStage> stage;
  MagneticStageReport report;
  bool ran = false;
};

struct NetworkObject {
  Context* context = nullptr;
  Network network;
};

thread_local std::string tlsError;

/// A failure with its status code.
class AbiError : public std::exception {
 public:
  AbiError(lodestone_status code, std::string message) : code_(code), message_(std::move(message)) {}
  const char* what() const noexcept override { return message_.c_str(); }
  lodestone_status code() const { return code_; }

 private:
  lodestone_status code_;
  std::string message_;
};

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

/// Runs `body`, mapping every exception to a status (the exception firewall).
template <typename F>
lodestone_status firewall(Context* context, const char* function, F&& body) noexcept {
  try {
    body();
    return LODESTONE_OK;
  } catch (const AbiError& e) {
    return fail(context, e.code(), function, e.what());
  } catch (const CookFailed& e) {
    return fail(context, e.notBuilt() ? LODESTONE_ERROR_NOT_BUILT : LODESTONE_ERROR_COOK_FAILED, function, e.what());
  } catch (const NotBuilt& e) {
    return fail(context, LODESTONE_ERROR_NOT_BUILT, function, e.what());
  } catch (const TooLarge& e) {
    return fail(context, LODESTONE_ERROR_OUT_OF_MEMORY, function, e.what());
  } catch (const InvalidArgument& e) {
    return fail(context, LODESTONE_ERROR_INVALID_ARGUMENT, function, e.what());
  } catch (const std::bad_alloc&) {
    return fail(context, LODESTONE_ERROR_OUT_OF_MEMORY, function, "out of memory");
  } catch (const std::exception& e) {
    return fail(context, LODESTONE_ERROR_INTERNAL, function, e.what());
  } catch (...) {
    return fail(context, LODESTONE_ERROR_INTERNAL, function, "unknown exception");
  }
}

template <typename T>
T* need(T* p, const char* what) {
  if (!p) throw AbiError(LODESTONE_ERROR_NULL_HANDLE, concat(what, " is NULL"));
  return p;
}

void needSize(std::uint32_t given, std::size_t expected, const char* what) {
  if (given < expected)
    throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT,
                   concat(what, "->struct_size is ", given, " bytes; this library needs at least ", expected,
                          " (set it to sizeof(", what, "))"));
}

// Handles to objects: a NULL handle is LODESTONE_ERROR_NULL_HANDLE, one that
// is not live (destroyed, of another kind, never handed out)
// LODESTONE_ERROR_INVALID_HANDLE.
template <typename Object, typename Handle>
Object* liveOrNull(const Handle* h, HandleKind kind) noexcept {
  return static_cast<Object*>(handleTable().find(reinterpret_cast<std::uintptr_t>(h), kind));
}

template <typename Object, typename Handle>
Object& live(const Handle* h, HandleKind kind, const char* what) {
  need(h, what);
  Object* o = liveOrNull<Object>(h, kind);
  if (!o)
    throw AbiError(LODESTONE_ERROR_INVALID_HANDLE,
                   concat(what, " ", static_cast<const void*>(h),
                          " is not a live handle (already destroyed, or not one this library handed out)"));
  return *o;
}

template <typename Handle>
Handle* newHandle(HandleKind kind, void* object) {
  return reinterpret_cast<Handle*>(handleTable().add(kind, object));
}

Context& contextOf(lodestone_context* h) { return live<Context>(h, HandleKind::Context, "context"); }
Fields& fieldsOf(const lodestone_fields* h) { return live<Fields>(h, HandleKind::Fields, "fields"); }
Stage& stageOf(const lodestone_stage* h) { return live<Stage>(h, HandleKind::Stage, "stage"); }
NetworkObject& networkOf(const lodestone_network* h) { return live<NetworkObject>(h, HandleKind::Network, "network"); }

// The context a failure is also recorded in (null when the handle is not live).
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

/// Copies the host's strided particles into packed arrays.
struct Particles {
  std::vector<Vec3d> x;
  std::vector<double> n;
  ParticleView view() const { return {x.data(), n.data(), x.size()}; }
};

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

void addObject(Context* c) {
  std::lock_guard<std::mutex> lock(c->mutex);
  ++c->objects;
}
void removeObject(Context* c) {
  std::lock_guard<std::mutex> lock(c->mutex);
  --c->objects;
}

/// Creates an object of `context` and its handle.
template <typename Handle, typename Object>
Handle* adopt(Context& context, HandleKind kind, std::unique_ptr<Object> object) {
  object->context = &context;
  Handle* h = newHandle<Handle>(kind, object.get());
  addObject(&context);
  object.release();
  return h;
}

/// Ends a handle and deletes its object (NULL: nothing).
template <typename Object, typename Handle>
void destroy(const Handle* h, HandleKind kind, const char* what) {
  if (!h) return;
  live<Object>(h, kind, what);  // the status of a stale handle
  auto* o = static_cast<Object*>(handleTable().remove(reinterpret_cast<std::uintptr_t>(h), kind));
  if (!o) return;
  removeObject(o->context);
  delete o;
}

const Stage& ranStage(const lodestone_stage* h) {
  const Stage& s = stageOf(h);
  if (!s.ran)
    throw AbiError(LODESTONE_ERROR_NOT_READY,
                   "the stage has not run yet (call stage_run_particles or stage_run_density)");
  return s;
}

std::string needName(const char* s, const char* what) { return std::string(need(s, what)); }

// ---- library ---------------------------------------------------------------------
const char* versionString() { return LODESTONE_VERSION_STRING; }

const char* statusString(lodestone_status s) {
  switch (s) {
    case LODESTONE_OK:
      return "ok";
    case LODESTONE_ERROR_INVALID_ARGUMENT:
      return "invalid argument";
    case LODESTONE_ERROR_NULL_HANDLE:
      return "null handle or pointer";
    case LODESTONE_ERROR_VERSION:
      return "unsupported API version";
    case LODESTONE_ERROR_NOT_BUILT:
      return "feature not built";
    case LODESTONE_ERROR_OUT_OF_MEMORY:
      return "out of memory";
    case LODESTONE_ERROR_NOT_READY:
      return "not ready";
    case LODESTONE_ERROR_BUFFER_TOO_SMALL:
      return "buffer too small";
    case LODESTONE_ERROR_NOT_FOUND:
      return "not found";
    case LODESTONE_ERROR_IO:
      return "input/output error";
    case LODESTONE_ERROR_COOK_FAILED:
      return "node cook failed";
    case LODESTONE_ERROR_INTERNAL:
      return "internal error";
    case LODESTONE_ERROR_INVALID_HANDLE:
      return "invalid handle";
    default:
      return "unknown status";
  }
}

const char* threadLastError() { return tlsError.c_str(); }
int32_t hasVdb() { return vdbBuilt() ? 1 : 0; }

// ---- context ----------------------------------------------------------------------
lodestone_status contextCreate(lodestone_context** out) {
  return firewall(nullptr, "context_create", [&] {
    need(out, "out");
    *out = nullptr;
    auto c = std::make_unique<Context>();
    *out = newHandle<lodestone_context>(HandleKind::Context, c.get());
    c.release();
  });
}

lodestone_status contextDestroy(lodestone_context* h) {
  return firewall(ctxOf(h), "context_destroy", [&] {
    if (!h) return;
    Context& c = contextOf(h);
    std::size_t owned;
    {
      std::lock_guard<std::mutex> lock(c.mutex);
      owned = c.objects;
    }
    if (owned)
      throw AbiError(
          LODESTONE_ERROR_INVALID_ARGUMENT,
          concat("the context still owns ", owned, " stage(s), field set(s) or network(s); destroy them first"));
    delete static_cast<Context*>(handleTable().remove(reinterpret_cast<std::uintptr_t>(h), HandleKind::Context));
  });
}

const char* contextLastError(lodestone_context* h) {
  Context* c = ctxOf(h);
  if (!c) return "";
  try {
    std::lock_guard<std::mutex> lock(c->mutex);
    const auto it = c->errors.find(std::this_thread::get_id());
    return it == c->errors.end() ? "" : it->second.c_str();
  } catch (...) {
    return "";
  }
}

void checkTime(double t) {
  if (!std::isfinite(t)) throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT, concat("time must be finite, got ", t, " s"));
}

// ---- fields ------------------------------------------------------------------------
lodestone_status fieldsCreate(lodestone_context* c, lodestone_fields** out) {
  return firewall(ctxOf(c), "fields_create", [&] {
    if (out) *out = nullptr;
    Context& context = contextOf(c);
    need(out, "out");
    *out = adopt<lodestone_fields>(context, HandleKind::Fields, std::make_unique<Fields>());
  });
}

lodestone_status fieldsDestroy(lodestone_fields* f) {
  return firewall(ctxOf(f), "fields_destroy", [&] { destroy<Fields>(f, HandleKind::Fields, "fields"); });
}

lodestone_status fieldsAddUniform(lodestone_fields* f, const double H[3]) {
  return firewall(ctxOf(f), "fields_add_uniform", [&] {
    Fields& fs = fieldsOf(f);
    fs.set.add(std::make_unique<UniformField>(vec(H, "H")));
  });
}

lodestone_status fieldsAddDipole(lodestone_fields* f, const double position[3], const double moment[3]) {
  return firewall(ctxOf(f), "fields_add_dipole", [&] {
    Fields& fs = fieldsOf(f);
    fs.set.add(std::make_unique<PointDipole>(vec(position, "position"), vec(moment, "moment")));
  });
}

Pose magnetPose(const double center[3], const double axis[3]) {
  const Vec3d a = vec(axis, "axis");
  if (!(norm(a) > 0)) throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT, "axis must be a non-zero vector");
  return poseAlong(vec(center, "center"), a / norm(a));
}

void checkMagnetization(double M) {
  if (!std::isfinite(M) || std::fabs(M) > 3e6)
    throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT, concat("magnetization must be finite, |M| <= 3e6 A/m, got ", M));
}

lodestone_status fieldsAddSphere(lodestone_fields* f, const double center[3], const double axis[3], double radius,
                                 double M) {
  return firewall(ctxOf(f), "fields_add_sphere_magnet", [&] {
    Fields& fs = fieldsOf(f);
    checkMagnetization(M);
    fs.set.add(std::make_unique<SphereMagnet>(magnetPose(center, axis), radius, Vec3d{0, 0, M}));
  });
}

lodestone_status fieldsAddBox(lodestone_fields* f, const double center[3], const double axis[3],
                              const double halfSize[3], double M) {
  return firewall(ctxOf(f), "fields_add_box_magnet", [&] {
    Fields& fs = fieldsOf(f);
    checkMagnetization(M);
    fs.set.add(std::make_unique<CuboidMagnet>(magnetPose(center, axis), vec(halfSize, "half_size"), Vec3d{0, 0, M}));
  });
}

lodestone_status fieldsAddCylinder(lodestone_fields* f, const double center[3], const double axis[3], double radius,
                                   double halfLength, double M) {
  return firewall(ctxOf(f), "fields_add_cylinder_magnet", [&] {
    Fields& fs = fieldsOf(f);
    checkMagnetization(M);
    fs.set.add(std::make_unique<CylinderMagnet>(magnetPose(center, axis), radius, halfLength, Vec3d{0, 0, M}));
  });
}

lodestone_status fieldsAddVdb(lodestone_fields* f, const char* path, const char* grid) {
  return firewall(ctxOf(f), "fields_add_vdb", [&] {
    Fields& fs = fieldsOf(f);
    const std::string file = needName(path, "path"), name = needName(grid, "grid_name");
    try {
      addVdbField(fs.set, file, name);
    } catch (const InvalidArgument& e) {
      throw AbiError(LODESTONE_ERROR_IO, e.what());
    }
  });
}

lodestone_status fieldsCount(const lodestone_fields* f, uint32_t* out) {
  return firewall(ctxOf(f), "fields_count", [&] {
    Fields& fs = fieldsOf(f);
    *need(out, "out") = uint32_t(fs.set.size());
  });
}

lodestone_status fieldsEvaluate(const lodestone_fields* f, const double x[3], double t, double H[3]) {
  return firewall(ctxOf(f), "fields_evaluate", [&] {
    Fields& fs = fieldsOf(f);
    need(H, "H_out");
    checkTime(t);
    const Vec3d h = fs.set.field(vec(x, "x"), t);
    for (int a = 0; a < 3; ++a) H[a] = h[a];
  });
}

// ---- stage ----------------------------------------------------------------------
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
    requireFitsInMemory("params.grid (padded)", nodes, g.dx, 0);
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

// ---- node metadata ------------------------------------------------------------------
/// Strings the metadata functions hand out, built once and kept for the
/// library's lifetime.
struct ParamStrings {
  std::string defaultText, choices;
};
const std::map<const ParamDecl*, ParamStrings>& paramStrings() {
  static const std::map<const ParamDecl*, ParamStrings> strings = [] {
    std::map<const ParamDecl*, ParamStrings> m;
    for (const NodeDecl& d : nodeRegistry())
      for (const ParamDecl& p : d.params) {
        ParamStrings s;
        s.defaultText = p.defaultText();
        for (std::size_t k = 0; k < p.choices.size(); ++k) s.choices += (k ? "|" : "") + p.choices[k];
        m.emplace(&p, std::move(s));
      }
    return m;
  }();
  return strings;
}

const NodeDecl& declNamed(const char* type) {
  const std::string name = needName(type, "type");
  const NodeDecl* d = findNode(name);
  if (!d) throw AbiError(LODESTONE_ERROR_NOT_FOUND, concat("no node type named '", name, "'"));
  return *d;
}

uint32_t nodeTypeCount() { return uint32_t(nodeRegistry().size()); }

lodestone_status nodeTypeInfo(uint32_t index, lodestone_node_info* out) {
  return firewall(nullptr, "node_type_info", [&] {
    need(out, "out");
    needSize(out->struct_size, sizeof(lodestone_node_info), "lodestone_node_info");
    if (index >= nodeRegistry().size())
      throw AbiError(LODESTONE_ERROR_NOT_FOUND, concat("node index ", index, " >= ", nodeRegistry().size()));
    const NodeDecl& d = nodeRegistry()[index];
    out->type = d.type.c_str();
    out->label = d.label.c_str();
    out->category = d.category.c_str();
    out->help = d.help.c_str();
    out->param_count = uint32_t(d.params.size());
    out->input_count = uint32_t(d.inputs.size());
    out->output_count = uint32_t(d.outputs.size());
  });
}

lodestone_param_type abiType(ParamType t) {
  switch (t) {
    case ParamType::Float:
      return LODESTONE_PARAM_FLOAT;
    case ParamType::Int:
      return LODESTONE_PARAM_INT;
    case ParamType::Bool:
      return LODESTONE_PARAM_BOOL;
    case ParamType::String:
      return LODESTONE_PARAM_STRING;
    case ParamType::Choice:
      return LODESTONE_PARAM_CHOICE;
    case ParamType::FloatList:
      return LODESTONE_PARAM_FLOAT_LIST;
    default:
      return LODESTONE_PARAM_VEC3;
  }
}

lodestone_status nodeParamInfo(const char* type, uint32_t index, lodestone_param_info* out) {
  return firewall(nullptr, "node_param_info", [&] {
    const NodeDecl& d = declNamed(type);
    need(out, "out");
    needSize(out->struct_size, sizeof(lodestone_param_info), "lodestone_param_info");
    if (index >= d.params.size())
      throw AbiError(LODESTONE_ERROR_NOT_FOUND,
                     concat("node '", d.type, "' has ", d.params.size(), " parameters, not ", index + 1));
    const ParamDecl& p = d.params[index];
    const ParamStrings& s = paramStrings().at(&p);
    out->name = p.name.c_str();
    out->label = p.label.c_str();
    out->type = abiType(p.type);
    out->unit = p.unit.c_str();
    out->help = p.help.c_str();
    out->default_text = s.defaultText.c_str();
    out->min = p.min;
    out->max = p.max;
    out->choices = s.choices.c_str();
  });
}

void portInfo(const PortDecl& p, lodestone_port_info* out) {
  need(out, "out");
  needSize(out->struct_size, sizeof(lodestone_port_info), "lodestone_port_info");
  out->name = p.name.c_str();
  out->type = toString(p.type);
  out->help = p.help.c_str();
  out->optional = p.optional ? 1 : 0;
  out->multiple = p.multiple ? 1 : 0;
}

lodestone_status nodeInputInfo(const char* type, uint32_t index, lodestone_port_info* out) {
  return firewall(nullptr, "node_input_info", [&] {
    const NodeDecl& d = declNamed(type);
    if (index >= d.inputs.size())
      throw AbiError(LODESTONE_ERROR_NOT_FOUND, concat("node '", d.type, "' has ", d.inputs.size(), " inputs"));
    portInfo(d.inputs[index], out);
  });
}

lodestone_status nodeOutputInfo(const char* type, uint32_t index, lodestone_port_info* out) {
  return firewall(nullptr, "node_output_info", [&] {
    const NodeDecl& d = declNamed(type);
    if (index >= d.outputs.size())
      throw AbiError(LODESTONE_ERROR_NOT_FOUND, concat("node '", d.type, "' has ", d.outputs.size(), " outputs"));
    portInfo(d.outputs[index], out);
  });
}

// ---- networks ------------------------------------------------------------------------
lodestone_status networkCreate(lodestone_context* c, lodestone_network** out) {
  return firewall(ctxOf(c), "network_create", [&] {
    if (out) *out = nullptr;
    Context& context = contextOf(c);
    need(out, "out");
    *out = adopt<lodestone_network>(context, HandleKind::Network, std::make_unique<NetworkObject>());
  });
}

lodestone_status networkDestroy(lodestone_network* n) {
  return firewall(ctxOf(n), "network_destroy", [&] { destroy<NetworkObject>(n, HandleKind::Network, "network"); });
}

Network& net(lodestone_network* n) { return networkOf(n).network; }

void checkNode(Network& network, const std::string& node) {
  if (!network.hasNode(node)) throw AbiError(LODESTONE_ERROR_NOT_FOUND, concat("no node named '", node, "'"));
}

void setParam(lodestone_network* n, const char* node, const char* param, const ParamValue& v) {
  Network& network = net(n);
  const std::string name = needName(node, "node"), key = needName(param, "param");
  checkNode(network, name);
  if (!network.declOf(name).param(key))
    throw AbiError(LODESTONE_ERROR_NOT_FOUND,
                   concat("node '", name, "' (", network.declOf(name).type, ") has no parameter '", key, "'"));
  network.setParam(name, key, v);
}

lodestone_status networkAddNode(lodestone_network* n, const char* type, const char* name) {
  return firewall(ctxOf(n), "network_add_node", [&] {
    Network& network = net(n);
    const std::string t = needName(type, "type"), nm = needName(name, "name");
    if (!findNode(t)) throw AbiError(LODESTONE_ERROR_NOT_FOUND, concat("no node type named '", t, "'"));
    network.addNode(t, nm);
  });
}

lodestone_status networkSetFloat(lodestone_network* n, const char* node, const char* param, double v) {
  return firewall(ctxOf(n), "network_set_float", [&] { setParam(n, node, param, v); });
}
lodestone_status networkSetInt(lodestone_network* n, const char* node, const char* param, int64_t v) {
  return firewall(ctxOf(n), "network_set_int", [&] { setParam(n, node, param, std::int64_t(v)); });
}
lodestone_status networkSetBool(lodestone_network* n, const char* node, const char* param, int32_t v) {
  return firewall(ctxOf(n), "network_set_bool", [&] { setParam(n, node, param, v != 0); });
}
lodestone_status networkSetString(lodestone_network* n, const char* node, const char* param, const char* v) {
  return firewall(ctxOf(n), "network_set_string", [&] { setParam(n, node, param, needName(v, "value")); });
}
lodestone_status networkSetVec3(lodestone_network* n, const char* node, const char* param, const double v[3]) {
  return firewall(ctxOf(n), "network_set_vec3", [&] {
    need(v, "value");
    setParam(n, node, param, Vec3d{v[0], v[1], v[2]});
  });
}

lodestone_status networkSetJson(lodestone_network* n, const char* node, const char* json) {
  return firewall(ctxOf(n), "network_set_json", [&] {
    Network& network = net(n);
    const std::string name = needName(node, "node"), text = needName(json, "json");
    checkNode(network, name);
    // The scene files' strict reading: syntax errors at line:column,
    // duplicate keys, unknown keys with a suggestion, types and ranges.
    const std::string where = concat("node '", name, "' (", network.declOf(name).type, ")");
    setParamsFromJson(network, name, parseJsonText(text, where), where);
  });
}

lodestone_status networkConnect(lodestone_network* n, const char* from, const char* output, const char* to,
                                const char* input) {
  return firewall(ctxOf(n), "network_connect", [&] {
    Network& network = net(n);
    const std::string f = needName(from, "from_node"), o = needName(output, "output"), t = needName(to, "to_node"),
                      i = needName(input, "input");
    checkNode(network, f);
    checkNode(network, t);
    if (!network.declOf(f).output(o) || !network.declOf(t).input(i)) {
      try {
        network.connect(f, o, t, i);  // throws, naming the port and the closest declared one
      } catch (const InvalidArgument& e) {
        throw AbiError(LODESTONE_ERROR_NOT_FOUND, e.what());
      }
    }
    network.connect(f, o, t, i);
  });
}

lodestone_status networkCook(lodestone_network* n, const char* node) {
  return firewall(ctxOf(n), "network_cook", [&] {
    Network& network = net(n);
    const std::string name = needName(node, "node");
    checkNode(network, name);
    network.cook(name);
  });
}

nlohmann::json vecJson(const Vec3d& v) { return {v.x, v.y, v.z}; }

nlohmann::json outputJson(const NodeValue& v) {
  nlohmann::json j;
  j["type"] = toString(typeOf(v));
  if (const auto* p = std::get_if<std::shared_ptr<const ParticlesData>>(&v)) {
    const MpmParticles& q = (*p)->particles;
    double count = 0;
    for (double c : q.count) count += c;
    j["particles"] = q.size();
    j["mass_kg"] = q.totalMass();
    j["micro_particles"] = count;
    j["centre_of_mass_m"] = vecJson(q.centreOfMass());
  } else if (const auto* m = std::get_if<std::shared_ptr<const MaterialData>>(&v)) {
    j["name"] = (*m)->name;
    j["describe"] = (*m)->material.describe();
  } else if (const auto* s = std::get_if<std::shared_ptr<const SourcesData>>(&v)) {
    j["fields"] = (*s)->fields.size();
    j["magnets"] = (*s)->magnets.size();
  } else if (const auto* c = std::get_if<std::shared_ptr<const CollidersData>>(&v)) {
    j["colliders"] = (*c)->colliders.size();
  } else if (const auto* d = std::get_if<std::shared_ptr<const DensityData>>(&v)) {
    const GridSpec& g = (*d)->density.spec();
    j["grid"] = {{"origin_m", vecJson(g.origin)}, {"dx_m", g.dx}, {"dims", {g.dims.i, g.dims.j, g.dims.k}}};
    j["total_count"] = (*d)->totalCount;
  } else if (const auto* f = std::get_if<std::shared_ptr<const FieldData>>(&v)) {
    j["report"] = nlohmann::json::parse(reportJson((*f)->report));
  } else if (const auto* fo = std::get_if<std::shared_ptr<const ForcesData>>(&v)) {
    j["particles"] = (*fo)->particleForces.size();
    j["total_force_N"] = vecJson((*fo)->total);
  } else if (const auto* sim = std::get_if<std::shared_ptr<const SimulationData>>(&v)) {
    j["frames"] = (*sim)->frames;
    j["time_s"] = (*sim)->time;
    j["particles"] = (*sim)->solver->particles().size();
    nlohmann::json com = nlohmann::json::array();
    for (const Vec3d& x : (*sim)->centreOfMass) com.push_back(vecJson(x));
    j["magnetic_centre_of_mass_m"] = com;
    j["frame_times_s"] = (*sim)->frameTimes;
  }
  return j;
}

const NodeValue& cookedOutput(lodestone_network* n, const char* node, const char* output) {
  Network& network = net(n);
  const std::string name = needName(node, "node"), out = needName(output, "output");
  checkNode(network, name);
  if (!network.declOf(name).output(out))
    throw AbiError(LODESTONE_ERROR_NOT_FOUND, concat("node '", name, "' has no output '", out, "'"));
  try {
    return network.output(name, out);
  } catch (const InvalidArgument& e) {
    throw AbiError(LODESTONE_ERROR_NOT_READY, e.what());
  }
}

lodestone_status networkOutputJson(lodestone_network* n, const char* node, const char* output, char* buffer,
                                   size_t capacity, size_t* needed) {
  return firewall(ctxOf(n), "network_output_json",
                  [&] { copyText(outputJson(cookedOutput(n, node, output)).dump(), buffer, capacity, needed); });
}

lodestone_status networkReadPositions(lodestone_network* n, const char* node, const char* output,
                                      lodestone_vec3_out* out, size_t* count) {
  return firewall(ctxOf(n), "network_read_positions", [&] {
    const NodeValue& v = cookedOutput(n, node, output);
    need(count, "count");
    const std::vector<Vec3d>* x = nullptr;
    if (const auto* p = std::get_if<std::shared_ptr<const ParticlesData>>(&v)) x = &(*p)->particles.x;
    if (const auto* s = std::get_if<std::shared_ptr<const SimulationData>>(&v)) x = &(*s)->solver->particles().x;
    if (!x)
      throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT,
                     concat("output '", output, "' carries ", toString(typeOf(v)), ", not particles or a simulation"));
    *count = x->size();
    writeVectors(*x, out);
  });
}

// ---- since minor 1 --------------------------------------------------------------------
lodestone_status stageNumberDensity(const lodestone_stage* s, double* n0) {
  return firewall(ctxOf(s), "stage_number_density", [&] {
    const Stage& st = stageOf(s);
    const MagneticMaterial& m = st.stage->material();
    *need(n0, "n0") = m.law.kind == LawKind::None ? 0.0 : m.numberDensity;
  });
}

lodestone_status networkSetParticles(lodestone_network* n, const char* node, const lodestone_particles* p) {
  return firewall(ctxOf(n), "network_set_particles", [&] {
    Network& network = net(n);
    const std::string name = needName(node, "node");
    checkNode(network, name);
    const Particles particles = readParticles(p, true);
    std::vector<double> x(3 * particles.x.size());
    for (std::size_t k = 0; k < particles.x.size(); ++k)
      for (int a = 0; a < 3; ++a) x[3 * k + std::size_t(a)] = particles.x[k][a];
    setParam(n, node, "positions", x);
    setParam(n, node, "counts", particles.n);
  });
}

lodestone_status networkReadForces(lodestone_network* n, const char* node, const char* output, lodestone_vec3_out* out,
                                   size_t* count) {
  return firewall(ctxOf(n), "network_read_forces", [&] {
    const NodeValue& v = cookedOutput(n, node, output);
    need(count, "count");
    const auto* f = std::get_if<std::shared_ptr<const ForcesData>>(&v);
    if (!f)
      throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT,
                     concat("output '", output, "' carries ", toString(typeOf(v)), ", not forces"));
    *count = (*f)->particleForces.size();
    writeVectors((*f)->particleForces, out);
  });
}

lodestone_status networkCreateFromJson(lodestone_context* c, const char* json, lodestone_network** out) {
  return firewall(ctxOf(c), "network_create_from_json", [&] {
    if (out) *out = nullptr;
    Context& context = contextOf(c);
    const std::string text = needName(json, "json");
    need(out, "out");
    auto network = std::make_unique<NetworkObject>();
    buildNetworkFromJson(network->network, parseJsonText(text, "network"), "network");
    *out = adopt<lodestone_network>(context, HandleKind::Network, std::move(network));
  });
}

const lodestone_api kApi = {
    sizeof(lodestone_api),
    LODESTONE_API_VERSION_MAJOR,
    LODESTONE_API_VERSION_MINOR,
    versionString,
    statusString,
    threadLastError,
    hasVdb,
    contextCreate,
    contextDestroy,
    contextLastError,
    fieldsCreate,
    fieldsDestroy,
    fieldsAddUniform,
    fieldsAddDipole,
    fieldsAddSphere,
    fieldsAddBox,
    fieldsAddCylinder,
    fieldsAddVdb,
    fieldsCount,
    fieldsEvaluate,
    stageParamsDefault,
    stageCreate,
    stageDestroy,
    stageGrid,
    stageRunParticles,
    stageRunDensity,
    stageParticleForces,
    stageSample,
    stageReadField,
    stageReport,
    stageReportJson,
    stageExportVdb,
    nodeTypeCount,
    nodeTypeInfo,
    nodeParamInfo,
    nodeInputInfo,
    nodeOutputInfo,
    networkCreate,
    networkDestroy,
    networkAddNode,
    networkSetFloat,
    networkSetInt,
    networkSetBool,
    networkSetString,
    networkSetVec3,
    networkSetJson,
    networkConnect,
    networkCook,
    networkOutputJson,
    networkReadPositions,
    stageNumberDensity,
    networkSetParticles,
    networkReadForces,
    networkCreateFromJson,
};

}  // namespace

extern "C" LODESTONE_EXPORT lodestone_status lodestone_get_api(uint32_t major, uint32_t minor,
                                                               const lodestone_api** table) {
  return firewall(nullptr, "lodestone_get_api", [&] {
    need(table, "table");
    *table = nullptr;
    if (major != LODESTONE_API_VERSION_MAJOR || minor > LODESTONE_API_VERSION_MINOR)
      throw AbiError(LODESTONE_ERROR_VERSION,
                     concat("API version ", major, ".", minor, " requested; this library provides ",
                            LODESTONE_API_VERSION_MAJOR, ".", LODESTONE_API_VERSION_MINOR,
                            " (same major and a minor up to ", LODESTONE_API_VERSION_MINOR, " are supported)"));
    *table = &kApi;
  });
}
