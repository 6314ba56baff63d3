#pragma once
// What the C ABI's entries share: the objects behind the handles, the
// exception firewall that turns every exception into a status and a message,
// handle look-ups, and the conversions of the host's arrays. Every entry runs
// its body inside `firewall`; nothing may throw out of an entry.
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <new>
#include <string>
#include <thread>
#include <vector>

#include "../handle_table.h"
#include "entries.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/vec3.h"
#include "lodestone/core/sources/field_source_set.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/plugin/errors.h"
#include "lodestone/plugin/lodestone.h"
#include "lodestone/plugin/network.h"

namespace lodestone::plugin::abi {

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

/// The calling thread's last error message (lodestone_api::thread_last_error).
extern thread_local std::string tlsError;

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

/// Records `message` as the thread's (and the context's) last error; returns `code`.
lodestone_status fail(Context* context, lodestone_status code, const char* function, const char* message) noexcept;

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

/// Throws INVALID_ARGUMENT unless the host's struct_size is at least `expected`.
void needSize(std::uint32_t given, std::size_t expected, const char* what);

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

Context& contextOf(lodestone_context* h);
Fields& fieldsOf(const lodestone_fields* h);
Stage& stageOf(const lodestone_stage* h);
NetworkObject& networkOf(const lodestone_network* h);

// The context a failure is also recorded in (null when the handle is not live).
Context* ctxOf(lodestone_context* h);
Context* ctxOf(const lodestone_stage* h);
Context* ctxOf(const lodestone_fields* h);
Context* ctxOf(const lodestone_network* h);

/// A finite 3-vector from the host, or INVALID_ARGUMENT naming `what`.
Vec3d vec(const double* v, const char* what);
std::size_t scalarSize(lodestone_scalar_type t, const char* what);
double readScalar(const char* p, lodestone_scalar_type t);
void writeScalar(char* p, lodestone_scalar_type t, double v);

/// Copies the host's strided particles into packed arrays.
struct Particles {
  std::vector<Vec3d> x;
  std::vector<double> n;
  ParticleView view() const { return {x.data(), n.data(), x.size()}; }
};
Particles readParticles(const lodestone_particles* p, bool needCounts);
/// Writes `values` into the host's strided array (BUFFER_TOO_SMALL when it holds fewer).
void writeVectors(const std::vector<Vec3d>& values, lodestone_vec3_out* out);
/// Copies `text` with its terminating NUL; a NULL buffer of capacity 0 only sets *needed.
void copyText(const std::string& text, char* buffer, std::size_t capacity, std::size_t* needed);

/// The stage report as the ABI's struct (its struct_size checked) and as JSON.
void fillReport(const MagneticStageReport& r, lodestone_report* out);
std::string reportJson(const MagneticStageReport& r);

void addObject(Context* c);
void removeObject(Context* c);

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

/// The body of a create entry whose object needs nothing but its context.
template <typename Handle, typename Object>
lodestone_status createEntry(lodestone_context* c, Handle** out, HandleKind kind, const char* function) {
  return firewall(ctxOf(c), function, [&] {
    if (out) *out = nullptr;
    Context& context = contextOf(c);
    need(out, "out");
    *out = adopt<Handle>(context, kind, std::make_unique<Object>());
  });
}

/// The stage, or NOT_READY before its first run.
const Stage& ranStage(const lodestone_stage* h);
std::string needName(const char* s, const char* what);
/// Throws INVALID_ARGUMENT for a non-finite time (s).
void checkTime(double t);


}  // namespace lodestone::plugin::abi
