// lodestone_get_api: the one exported symbol. It hands out the table of
// entries, each part filled by the file that holds its functions
// (library.cpp, fields.cpp, stage.cpp, nodes.cpp, network.cpp).
#include "support.h"

using namespace lodestone;
using namespace lodestone::plugin::abi;

namespace {

lodestone_api buildTable() {
  lodestone_api api{};
  api.struct_size = sizeof(lodestone_api);
  api.major = LODESTONE_API_VERSION_MAJOR;
  api.minor = LODESTONE_API_VERSION_MINOR;
  addLibraryEntries(api);
  addFieldsEntries(api);
  addStageEntries(api);
  addNodeEntries(api);
  addNetworkEntries(api);
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
