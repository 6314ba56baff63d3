// lodestone_get_api: the one exported symbol. It hands out the table of
// entries, filled from the one list in entries.h.
#include "support.h"

#include <cstddef>

using namespace lodestone;
using namespace lodestone::plugin::abi;

namespace {

#define LODESTONE_ABI_COUNT(member, function) +1
constexpr std::size_t kEntries = 0 LODESTONE_ABI_ENTRIES(LODESTONE_ABI_COUNT);
#undef LODESTONE_ABI_COUNT
static_assert(sizeof(lodestone_api) == offsetof(lodestone_api, version_string) + kEntries * sizeof(void (*)()),
              "every member of lodestone_api has an entry in LODESTONE_ABI_ENTRIES");

lodestone_api buildTable() {
  lodestone_api api{};
  api.struct_size = sizeof(lodestone_api);
  api.major = LODESTONE_API_VERSION_MAJOR;
  api.minor = LODESTONE_API_VERSION_MINOR;
#define LODESTONE_ABI_FILL(member, function) api.member = &function;
  LODESTONE_ABI_ENTRIES(LODESTONE_ABI_FILL)
#undef LODESTONE_ABI_FILL
  return api;
}

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
    static const lodestone_api kApi = buildTable();  // built once, on first use, thread-safe
    *table = &kApi;
  });
}
