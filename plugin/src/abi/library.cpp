// The C ABI's library and context entries, and lodestone_get_api with its table.
#include "support.h"

#include <string>

#include "lodestone/plugin/node_registry.h"

namespace lodestone::plugin::abi {

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

}  // namespace lodestone::plugin::abi
